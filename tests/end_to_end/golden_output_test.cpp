// The outputs of the shipped defaults, pinned: the labels of the demo sequence (the 20-frame
// rendered yard, seed 1) and the map built from it are compared, byte for byte, with digests
// kept in tests/data/golden/yard20.txt. A change that is meant to leave behaviour as it is
// (a refactoring, a speed-up) must pass unchanged; a change that is meant to alter the outputs
// updates the file in the same commit:
//   SSTA_UPDATE_GOLDEN=1 build/tests/end_to_end_test --gtest_filter='GoldenOutput.*'

#include <cstdint>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>
#include <string>

#include <gtest/gtest.h>

#include "ssta/io/image_io.h"
#include "ssta/pipeline/config.h"
#include "ssta/pipeline/map_builder.h"
#include "ssta/pipeline/sequence_classifier.h"
#include "ssta/synth/sequence_synthesizer.h"
#include "ssta_test_paths.h"
#include "temp_dir.h"

namespace ssta {
namespace {

constexpr char kGoldenFile[] = SSTA_TEST_DATA_DIR "/golden/yard20.txt";

/// FNV-1a, 64 bit, as hex.
class Digest {
 public:
  void Add(const void* data, std::size_t n) {
    const auto* p = static_cast<const unsigned char*>(data);
    for (std::size_t i = 0; i < n; ++i) {
      hash_ ^= p[i];
      hash_ *= 1099511628211ull;
    }
  }
  std::string Hex() const {
    std::ostringstream s;
    s << std::hex << hash_;
    return s.str();
  }

 private:
  std::uint64_t hash_ = 14695981039346656037ull;
};

std::string FileDigest(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  const std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  Digest d;
  d.Add(bytes.data(), bytes.size());
  return d.Hex();
}

/// The decoded label images of a classify run, in timestamp order (the PNG encoder's bytes are
/// not the labels' business).
std::string LabelsDigest(const std::string& labels_dir) {
  std::map<std::string, std::string> files;  // sorted by name = timestamp
  for (const auto& e : std::filesystem::directory_iterator(labels_dir)) {
    files[e.path().filename().string()] = e.path().string();
  }
  Digest d;
  for (const auto& [name, path] : files) {
    const ImageU8 labels = ReadLabelImage(path);
    d.Add(name.data(), name.size());
    d.Add(labels.data(), labels.size());
  }
  return std::to_string(files.size()) + ":" + d.Hex();
}

std::map<std::string, std::string> ReadGolden() {
  std::map<std::string, std::string> values;
  std::ifstream in(kGoldenFile);
  std::string key, value;
  while (in >> key >> value) values[key] = value;
  return values;
}

TEST(GoldenOutput, DemoLabelsAndYardMapAreUnchanged) {
  testing::TempDir dir;
  synth::SynthOptions yard;
  yard.scene = "yard";
  yard.frames = 20;
  yard.seed = 1;
  synth::WriteSyntheticSequence(yard, dir / "seq");
  const Sequence sequence = Sequence::Open(dir / "seq");

  ClassifyOptions classify;
  classify.out_dir = dir / "classified";
  ClassifySequence(sequence, Config{}, classify);

  BuildMapOptions build;
  build.map_path = dir / "yard.ot";
  BuildMap(sequence, "yard", Config{}, build);

  const std::map<std::string, std::string> now = {{"labels", LabelsDigest(dir / "classified/labels")},
                                                  {"map", FileDigest(build.map_path)}};
  if (std::getenv("SSTA_UPDATE_GOLDEN") != nullptr) {
    std::ofstream out(kGoldenFile);
    for (const auto& [key, value] : now) out << key << " " << value << "\n";
    GTEST_FAIL() << "wrote " << kGoldenFile << "; run again without SSTA_UPDATE_GOLDEN";
  }
  const std::map<std::string, std::string> golden = ReadGolden();
  ASSERT_FALSE(golden.empty()) << kGoldenFile << " is missing or empty";
  for (const auto& [key, value] : now) {
    EXPECT_EQ(value, golden.count(key) ? golden.at(key) : "") << key << " differ from " << kGoldenFile;
  }
}

}  // namespace
}  // namespace ssta
