// Bad input through the `ssta` binary, one case per kind of damage a user's files can have: each must end
// with exit status 2 and one line, "ssta: error: ...", naming the file (and line) or the key.
// Each case damages a fresh copy of the EuRoC mini sequence (three frames) and runs build-map
// (or query) on it; per-frame damage runs with --strict, which makes a skipped frame fatal.

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <functional>
#include <sstream>

#include "cli_runner.h"
#include "ssta/core/image.h"
#include "ssta/io/image_io.h"
#include "ssta_test_paths.h"
#include "temp_dir.h"

namespace ssta {
namespace {

namespace fs = std::filesystem;
using testing::RunSsta;

const std::string kEuroc = std::string(SSTA_TEST_DATA_DIR) + "/euroc-v1-01-mini";
const std::string kEurocConfig = std::string(SSTA_CONFIG_DIR) + "/sensors/euroc.yaml";
constexpr char kFirst[] = "1403715274262142976";   // the three frames' timestamps
constexpr char kSecond[] = "1403715274312143104";

std::string Slurp(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(in), {});
}

void Replace(const std::string& path, const std::string& from, const std::string& to) {
  std::string text = Slurp(path);
  const auto at = text.find(from);
  ASSERT_NE(at, std::string::npos) << from << " not in " << path;
  text.replace(at, from.size(), to);
  std::ofstream(path, std::ios::binary) << text;
}

/// One kind of damage: what to do to the copy (`seq` is its mav0 folder, `dir` the test's
/// folder), the ssta arguments after the binary ({seq}, {dir} and {map} are substituted) and
/// what the error line must contain ({seq} and {dir} substituted).
struct BadInput {
  const char* name;
  std::function<void(const std::string& seq, const std::string& dir)> damage;
  std::string arguments;
  std::vector<std::string> expected;
};

std::string Substitute(std::string text, const std::string& seq, const std::string& dir) {
  for (const auto& [key, value] : {std::pair<std::string, std::string>{"{seq}", seq}, {"{dir}", dir},
                                   {"{map}", dir + "/m.ot"}, {"{root}", fs::path(seq).parent_path().string()}}) {
    for (auto at = text.find(key); at != std::string::npos; at = text.find(key)) text.replace(at, key.size(), value);
  }
  return text;
}

const std::string kBuild = "build-map -q --static --config " + kEurocConfig + " --sequence {root} --map {map}";
const std::string kStrict = kBuild + " --strict";

const std::vector<BadInput>& Cases() {
  static const std::vector<BadInput> cases = {
      // Sequence layout.
      {"MissingCameraFolder", [](auto& s, auto&) { fs::remove_all(s + "/cam1"); }, kBuild,
       {"{seq}/cam1: camera folder not found"}},
      {"MissingImageList", [](auto& s, auto&) { fs::remove(s + "/cam0/data.csv"); }, kBuild,
       {"{seq}/cam0/data.csv: file not found"}},
      {"MissingSensorYaml", [](auto& s, auto&) { fs::remove(s + "/cam1/sensor.yaml"); }, kBuild,
       {"{seq}/cam1/sensor.yaml: file not found"}},
      {"EmptySequence", [](auto& s, auto&) { std::ofstream(s + "/cam0/data.csv") << "#timestamp [ns],filename\n"; },
       kBuild, {"{seq}/cam0/data.csv: lists no frames"}},
      {"DuplicatedTimestamp",
       [](auto& s, auto&) { Replace(s + "/cam0/data.csv", std::string(kSecond) + ",", std::string(kFirst) + ","); },
       kBuild, {"{seq}/cam0/data.csv:3: timestamp " + std::string(kFirst) + " is duplicated"}},
      {"TimestampOutOfOrder",
       [](auto& s, auto&) { Replace(s + "/cam0/data.csv", std::string(kSecond) + ",", "1403715274000000000,"); },
       kBuild, {"{seq}/cam0/data.csv:3: timestamp 1403715274000000000 is out of order"}},
      {"MalformedCsvRow", [](auto& s, auto&) { Replace(s + "/cam1/data.csv", std::string(kSecond) + ",", "12x,"); },
       kBuild, {"{seq}/cam1/data.csv:3: bad timestamp '12x'"}},
      // Images (per frame: skipped with the reason, fatal with --strict).
      {"ListedImageMissing",
       [](auto& s, auto&) { fs::remove(s + "/cam1/data/" + std::string(kSecond) + ".png"); }, kStrict,
       {"cam1 image missing: {seq}/cam1/data/" + std::string(kSecond) + ".png", "strict"}},
      {"TruncatedPng",
       [](auto& s, auto&) {
         const std::string png = s + "/cam0/data/" + std::string(kFirst) + ".png";
         const std::string bytes = Slurp(png);
         std::ofstream(png, std::ios::binary) << bytes.substr(0, bytes.size() / 3);
       },
       kStrict, {"{seq}/cam0/data/" + std::string(kFirst) + ".png: truncated PNG"}},
      {"CorruptedPng",
       [](auto& s, auto&) {
         const std::string png = s + "/cam1/data/" + std::string(kSecond) + ".png";
         std::string bytes = Slurp(png);
         bytes[bytes.size() / 2] ^= 0x10;
         std::ofstream(png, std::ios::binary) << bytes;
       },
       kStrict, {"{seq}/cam1/data/" + std::string(kSecond) + ".png: corrupt PNG (CRC error in its IDAT chunk)"}},
      {"UnreadablePng",
       [](auto& s, auto&) { std::ofstream(s + "/cam1/data/" + std::string(kFirst) + ".png") << "not a png"; }, kStrict,
       {"{seq}/cam1/data/" + std::string(kFirst) + ".png: not a PNG, JPEG or PGM image"}},
      {"LeftAndRightOfDifferentSizes",
       [](auto& s, auto&) { WriteImage(ImageU8(640, 480, 128), s + "/cam1/data/" + std::string(kFirst) + ".png"); },
       kStrict, {"{seq}/cam1/data/" + std::string(kFirst) + ".png: image is 640x480 px", "says 752x480"}},
      {"ImageSizeDisagreesWithSensorYaml",
       [](auto& s, auto&) {
         Replace(s + "/cam0/sensor.yaml", "resolution: [752, 480]", "resolution: [800, 600]");
         Replace(s + "/cam1/sensor.yaml", "resolution: [752, 480]", "resolution: [800, 600]");
       },
       kStrict, {"{seq}/cam0/data/" + std::string(kFirst) + ".png: image is 752x480 px", "says 800x600"}},
      // Calibration.
      {"ZeroFocalLength", [](auto& s, auto&) { Replace(s + "/cam0/sensor.yaml", "458.654,", "0.0,"); }, kBuild,
       {"{seq}/cam0/sensor.yaml: intrinsics: focal lengths"}},
      {"NegativeFocalLength", [](auto& s, auto&) { Replace(s + "/cam1/sensor.yaml", "457.587,", "-457.587,"); },
       kBuild, {"{seq}/cam1/sensor.yaml: intrinsics: focal lengths"}},
      {"NanInCalibration", [](auto& s, auto&) { Replace(s + "/cam0/sensor.yaml", "458.654,", ".nan,"); }, kBuild,
       {"{seq}/cam0/sensor.yaml: intrinsics"}},
      {"InfiniteInCalibration",
       [](auto& s, auto&) { Replace(s + "/cam0/sensor.yaml", "distortion_coefficients: [-0.28340811", "distortion_coefficients: [.inf"); },
       kBuild, {"{seq}/cam0/sensor.yaml: distortion_coefficients: NaN or infinite"}},
      {"TbsNotRigid", [](auto& s, auto&) { Replace(s + "/cam1/sensor.yaml", "0.0125552670891", "0.5"); }, kBuild,
       {"{seq}/cam1/sensor.yaml: T_BS: not a rigid transform"}},
      {"ZeroBaseline",
       [](auto& s, auto&) { fs::copy_file(s + "/cam0/sensor.yaml", s + "/cam1/sensor.yaml", fs::copy_options::overwrite_existing); },
       kBuild, {"{seq}/cam0/sensor.yaml, {seq}/cam1/sensor.yaml: T_BS: the baseline between cam0 and cam1 is zero"}},
      {"BaselineAlongTheWrongAxis",
       [](auto& s, auto&) {
         // cam1 0.11 m to the left of cam0 instead of the right: swap the two files.
         fs::rename(s + "/cam0/sensor.yaml", s + "/t.yaml");
         fs::rename(s + "/cam1/sensor.yaml", s + "/cam0/sensor.yaml");
         fs::rename(s + "/t.yaml", s + "/cam1/sensor.yaml");
       },
       kBuild, {"{seq}/cam1/sensor.yaml: T_BS: cam1 must lie to the right of cam0"}},
      {"DistortionOfTheWrongLength",
       [](auto& s, auto&) { Replace(s + "/cam1/sensor.yaml", "-0.28368365,  0.07451284, ", "-0.28368365, "); },
       kBuild, {"{seq}/cam1/sensor.yaml: distortion_coefficients: expected a list of 4 numbers"}},
      // Poses and IMU.
      {"ZeroQuaternion",
       [](auto& s, auto&) {
         fs::create_directory(s + "/pose0");
         std::ofstream(s + "/pose0/data.csv") << "#t,x,y,z,qw,qx,qy,qz\n1403715274000000000,0,0,0,1,0,0,0\n"
                                                 "1403715274100000000,0,0,0,0,0,0,0\n";
       },
       kBuild, {"{seq}/pose0/data.csv:3: zero quaternion"}},
      {"NonUnitQuaternion",
       [](auto& s, auto&) {
         fs::create_directory(s + "/pose0");
         std::ofstream(s + "/pose0/data.csv") << "#t,x,y,z,qw,qx,qy,qz\n1403715274000000000,0,0,0,0.7,0,0,0\n";
       },
       kBuild, {"{seq}/pose0/data.csv:2: quaternion norm 0.7 is not 1"}},
      {"NanInPoses",
       [](auto& s, auto&) {
         fs::create_directory(s + "/pose0");
         std::ofstream(s + "/pose0/data.csv") << "#t,x,y,z,qw,qx,qy,qz\n1403715274000000000,nan,0,0,1,0,0,0\n";
       },
       kBuild, {"{seq}/pose0/data.csv:2: NaN or infinite value"}},
      {"NanInImu",
       [](auto& s, auto&) { Replace(s + "/imu0/data.csv", ",9.2754564583333323,", ",nan,"); }, kBuild,
       {"{seq}/imu0/data.csv:3: NaN or infinite value"}},
      {"PosesOverlapNoFrame",
       [](auto& s, auto&) {
         fs::create_directory(s + "/pose0");
         std::ofstream(s + "/pose0/data.csv") << "#t,x,y,z,qw,qx,qy,qz\n1000,0,0,0,1,0,0,0\n2000,0,0,0,1,0,0,0\n";
       },
       "build-map -q --config " + kEurocConfig + " --sequence {root} --map {map}",
       {"{seq}/pose0/data.csv: the poses (1000 to 2000 ns) overlap none of the 3 frames"}},
      {"FrameInsideAPoseGap",
       [](auto& s, auto&) {
         fs::create_directory(s + "/pose0");
         std::ofstream(s + "/pose0/data.csv") << "#t,x,y,z,qw,qx,qy,qz\n1403715274000000000,0,0,0,1,0,0,0\n"
                                                 "1403715275000000000,0,0,0,1,0,0,0\n";
       },
       "build-map -q --strict --config " + kEurocConfig + " --sequence {root} --map {map}",
       {"frame " + std::string(kFirst) + ": no pose: inside a pose gap of 1 s"}},
      {"ImuOverlapsNoFrame",
       [](auto& s, auto&) {
         std::ofstream(s + "/imu0/data.csv") << "#t,wx,wy,wz,ax,ay,az\n1000,0,0,0,9.81,0,0\n2000,0,0,0,9.81,0,0\n";
       },
       kBuild, {"{seq}/imu0/data.csv: the IMU samples (1000 to 2000 ns) overlap none of the 3 frames"}},
      {"ImuCoversOnlyTheFirstFrame",  // the second frame is skipped (strict: fatal), not guessed
       [](auto& s, auto&) {
         std::ofstream(s + "/imu0/data.csv") << "#t,wx,wy,wz,ax,ay,az\n1403715274261142976,0,0,0,9.81,0,0\n"
                                                "1403715274263142976,0,0,0,9.81,0,0\n";
       },
       kStrict, {"frame " + std::string(kSecond) + ": {seq}/imu0/data.csv: frame " + std::string(kSecond) +
                 " lies outside the IMU samples (1403715274261142976 to 1403715274263142976 ns)"}},
      {"ImuWithoutSamples", [](auto& s, auto&) { std::ofstream(s + "/imu0/data.csv") << "#t,wx,wy,wz,ax,ay,az\n"; },
       kBuild, {"{seq}/imu0/data.csv: no IMU samples"}},
      // Config.
      {"ConfigUnknownKey", [](auto&, auto& d) { std::ofstream(d + "/c.yaml") << "map:\n  resolution: 0.1\n"; },
       kBuild + " --config {dir}/c.yaml", {"{dir}/c.yaml: map.resolution: unknown key"}},
      {"ConfigDuplicateKey",  // yaml-cpp would answer with the first and ignore the second
       [](auto&, auto& d) { std::ofstream(d + "/c.yaml") << "vehicle:\n  max_slope_deg: 20\nvehicle:\n  semi_slope_deg: 10\n"; },
       kBuild + " --config {dir}/c.yaml", {"{dir}/c.yaml:3: key 'vehicle' appears twice in the same mapping"}},
      {"ConfigAliasInsideItsAnchor",  // a cycle: walking it would run out of stack (found by fuzz_sensor_yaml)
       [](auto&, auto& d) { std::ofstream(d + "/c.yaml") << "&a\nvehicle: [*a]\n"; },
       kBuild + " --config {dir}/c.yaml", {"{dir}/c.yaml:", "nested more than 64 levels deep"}},
      {"ConfigIsAFolder", [](auto&, auto& d) { fs::create_directories(d + "/c.yaml"); },
       kBuild + " --config {dir}/c.yaml", {"{dir}/c.yaml: is a folder, not a file"}},
      {"ConfigWrongType", [](auto&, auto& d) { std::ofstream(d + "/c.yaml") << "map:\n  resolution_m: fine\n"; },
       kBuild + " --config {dir}/c.yaml", {"{dir}/c.yaml: map.resolution_m: wrong type"}},
      {"ConfigOutOfRange", [](auto&, auto& d) { std::ofstream(d + "/c.yaml") << "stereo:\n  block_size: -3\n"; },
       kBuild + " --config {dir}/c.yaml", {"{dir}/c.yaml: stereo.block_size"}},
      {"ConfigSemiThresholdAboveMax",
       [](auto&, auto& d) { std::ofstream(d + "/c.yaml") << "vehicle:\n  max_step_m: 0.1\n  semi_step_m: 0.2\n"; },
       kBuild + " --config {dir}/c.yaml", {"{dir}/c.yaml: vehicle.semi_step_m"}},
      // Maps.
      {"TruncatedMap",
       [](auto&, auto& d) {
         ASSERT_EQ(RunSsta(Substitute(kBuild, kEuroc + "/mav0", d)).exit_code, 0);
         const std::string bytes = Slurp(d + "/m.ot");
         std::ofstream(d + "/m.ot", std::ios::binary) << bytes.substr(0, bytes.size() / 2);
       },
       "query --map {map} --at 1,2", {"{dir}/m.ot: truncated or corrupt map"}},
      {"CorruptedMap",
       [](auto&, auto& d) {
         ASSERT_EQ(RunSsta(Substitute(kBuild, kEuroc + "/mav0", d)).exit_code, 0);
         std::string bytes = Slurp(d + "/m.ot");
         bytes[bytes.size() / 2] ^= 0x40;
         std::ofstream(d + "/m.ot", std::ios::binary) << bytes;
       },
       "query --map {map} --at 1,2", {"{dir}/m.ot: truncated or corrupt map (checksum mismatch)"}},
      {"MapOfAnotherTreeType",
       [](auto&, auto& d) {
         std::ofstream(d + "/m.ot") << "# Octomap OcTree file\nid ColorOcTree\nsize 0\nres 0.1\ndata\n";
       },
       "query --map {map} --at 1,2", {"{dir}/m.ot: OctoMap tree type 'ColorOcTree' is not an SSTA traversability map"}},
      {"MapFromANewerFormatVersion",
       [](auto&, auto& d) {
         ASSERT_EQ(RunSsta(Substitute(kBuild, kEuroc + "/mav0", d)).exit_code, 0);
         Replace(d + "/m.ot", "#@ssta format_version: 2", "#@ssta format_version: 9");
       },
       "query --map {map} --at 1,2", {"{dir}/m.ot: map format version 9 is newer than this ssta reads"}},
      {"ResumeWithAnotherResolution",
       [](auto&, auto& d) {
         ASSERT_EQ(RunSsta(Substitute(kBuild, kEuroc + "/mav0", d)).exit_code, 0);
         std::ofstream(d + "/c.yaml") << "map:\n  resolution_m: 0.2\n";
       },
       kBuild + " --resume --config {dir}/c.yaml", {"{dir}/m.ot: map resolution", "differs from map.resolution_m 0.2"}},
      {"MergeMapsOfAnotherWorldFrame",
       [](auto&, auto& d) {
         ASSERT_EQ(RunSsta(Substitute(kBuild + " --world-frame site", kEuroc + "/mav0", d)).exit_code, 0);
         const std::string other = "build-map -q --static --config " + kEurocConfig +
                                   " --sequence {root} --map {dir}/n.ot --world-frame odom";
         ASSERT_EQ(RunSsta(Substitute(other, kEuroc + "/mav0", d)).exit_code, 0);
       },
       "merge-maps {dir}/m.ot {dir}/n.ot --out {dir}/merged.ot",
       {"{dir}/n.ot: world frame 'odom', but {dir}/m.ot has 'site'"}},
      {"MergeMapsACopyOfAMap",
       [](auto&, auto& d) {
         ASSERT_EQ(RunSsta(Substitute(kBuild, kEuroc + "/mav0", d)).exit_code, 0);
         fs::copy_file(d + "/m.ot", d + "/copy.ot");
       },
       "merge-maps {dir}/m.ot {dir}/copy.ot --out {dir}/merged.ot",
       {"{dir}/m.ot and {dir}/copy.ot both hold the recording", "(checksum fnv1a64:",
        "merging them would count its evidence twice"}},
      {"MergeMapsAMapWithAMergeThatHoldsIt",
       [](auto&, auto& d) {
         ASSERT_EQ(RunSsta(Substitute(kBuild, kEuroc + "/mav0", d)).exit_code, 0);
         ASSERT_EQ(RunSsta(Substitute("merge-maps -q {dir}/m.ot --out {dir}/mm.ot", kEuroc + "/mav0", d)).exit_code, 0);
       },
       "merge-maps {dir}/mm.ot {dir}/m.ot --out {dir}/merged.ot",
       {"{dir}/mm.ot and {dir}/m.ot both hold the recording", "merging them would count its evidence twice"}},
      {"DiffMapsOfAnotherWorldFrame",
       [](auto&, auto& d) {
         ASSERT_EQ(RunSsta(Substitute(kBuild + " --world-frame site", kEuroc + "/mav0", d)).exit_code, 0);
         const std::string other = "build-map -q --static --config " + kEurocConfig +
                                   " --sequence {root} --map {dir}/n.ot --world-frame odom";
         ASSERT_EQ(RunSsta(Substitute(other, kEuroc + "/mav0", d)).exit_code, 0);
       },
       "diff-maps {dir}/m.ot {dir}/n.ot --out {dir}/diff",
       {"{dir}/n.ot: world frame 'odom', but {dir}/m.ot has 'site'; maps compare only when"}},
      {"DiffMapsOfAnotherResolution",
       [](auto&, auto& d) {
         ASSERT_EQ(RunSsta(Substitute(kBuild, kEuroc + "/mav0", d)).exit_code, 0);
         std::ofstream(d + "/c.yaml") << "map:\n  resolution_m: 0.2\n";
         const std::string other = "build-map -q --static --config " + kEurocConfig +
                                   " --config {dir}/c.yaml --sequence {root} --map {dir}/n.ot";
         ASSERT_EQ(RunSsta(Substitute(other, kEuroc + "/mav0", d)).exit_code, 0);
       },
       "diff-maps {dir}/m.ot {dir}/n.ot --out {dir}/diff",
       {"{dir}/n.ot: resolution 0.2 m, but {dir}/m.ot has 0.1 m; maps compare only when"}},
  };
  return cases;
}

// Names the case in test output (instead of printing its bytes).
void PrintTo(const BadInput& c, std::ostream* os) { *os << c.name; }

class BadInputTest : public ::testing::TestWithParam<BadInput> {};

TEST_P(BadInputTest, ExitsWithTwoAndOneLineNamingTheFileLineOrKey) {
  const BadInput& c = GetParam();
  testing::TempDir dir;
  const fs::path root = dir.path() / "seq";
  fs::copy(kEuroc, root, fs::copy_options::recursive);
  const std::string seq = (root / "mav0").string();
  c.damage(seq, dir.path().string());
  if (HasFatalFailure()) return;
  const auto r = RunSsta(Substitute(c.arguments, seq, dir.path().string()));
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_EQ(r.output.rfind("ssta: error: ", 0), 0u) << r.output;
  EXPECT_EQ(r.output.find('\n'), r.output.size() - 1) << "one line: " << r.output;
  for (const std::string& fragment : c.expected) {
    EXPECT_NE(r.output.find(Substitute(fragment, seq, dir.path().string())), std::string::npos)
        << "expected '" << Substitute(fragment, seq, dir.path().string()) << "' in: " << r.output;
  }
}

INSTANTIATE_TEST_SUITE_P(Damaged, BadInputTest, ::testing::ValuesIn(Cases()),
                         [](const ::testing::TestParamInfo<BadInput>& info) { return std::string(info.param.name); });

}  // namespace
}  // namespace ssta
