// OpenRos2Bag: a rosbag2 folder (metadata.yaml and the storage files it lists) or one .mcap /
// .db3 file, read as one bag.

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>
#include <tuple>

#include "bags/bag_reader.h"
#include "bags/db3_bag.h"
#include "bags/mcap_bag.h"
#include "ssta/files/yaml_reader.h"
#include "ssta/core/error.h"

namespace fs = std::filesystem;

namespace ssta::internal {
namespace {

// A merged reference keeps its file's index in the top bits of `position`: MCAP chunk offsets
// and sqlite row ids stay far below 2^48.
constexpr int kFileShift = 48;
constexpr std::uint64_t kPositionMask = (std::uint64_t{1} << kFileShift) - 1;

enum class Storage { kMcap, kSqlite3 };

/// The files of one bag (a rosbag2 folder splits a recording into several) read as one: their
/// connections merged by (topic, type, encoding), their messages listed in one time order.
class Ros2Bag : public BagReader {
 public:
  /// `metadata_count`: the messages metadata.yaml says the files hold (0: not said).
  Ros2Bag(std::string path, Storage storage, std::vector<std::unique_ptr<BagReader>> files,
          std::uint64_t metadata_count = 0);

  const std::string& path() const override { return path_; }
  std::string format() const override { return storage_ == Storage::kMcap ? "ros2 mcap" : "ros2 sqlite3"; }
  const std::vector<BagConnection>& connections() const override { return connections_; }
  std::vector<BagMessageRef> List(const std::vector<int>& connections) const override;
  std::vector<std::uint8_t> Read(const BagMessageRef& ref) const override;
  std::string Truncation() const override;

 private:
  std::string path_;
  Storage storage_;
  std::uint64_t metadata_count_ = 0;
  std::vector<std::unique_ptr<BagReader>> files_;
  std::vector<BagConnection> connections_;
  /// [file][merged connection] -> the file's own connection, or -1 where it has none.
  std::vector<std::vector<int>> local_connection_;
};

Ros2Bag::Ros2Bag(std::string path, Storage storage, std::vector<std::unique_ptr<BagReader>> files,
                 std::uint64_t metadata_count)
    : path_(std::move(path)), storage_(storage), metadata_count_(metadata_count), files_(std::move(files)) {
  std::map<std::tuple<std::string, std::string, std::string>, int> merged;
  std::vector<std::vector<int>> to_merged(files_.size());
  for (std::size_t f = 0; f < files_.size(); ++f) {
    for (const BagConnection& c : files_[f]->connections()) {
      const auto key = std::make_tuple(c.topic, c.type, c.encoding);
      auto it = merged.find(key);
      if (it == merged.end()) {
        it = merged.emplace(key, static_cast<int>(connections_.size())).first;
        connections_.push_back(c);
      }
      to_merged[f].push_back(it->second);
    }
  }
  local_connection_.assign(files_.size(), std::vector<int>(connections_.size(), -1));
  for (std::size_t f = 0; f < files_.size(); ++f) {
    for (std::size_t local = 0; local < to_merged[f].size(); ++local) {
      local_connection_[f][static_cast<std::size_t>(to_merged[f][local])] = static_cast<int>(local);
    }
  }
}

std::vector<BagMessageRef> Ros2Bag::List(const std::vector<int>& connections) const {
  std::vector<BagMessageRef> out;
  for (std::size_t f = 0; f < files_.size(); ++f) {
    std::vector<int> local;
    std::vector<int> merged_of_local(files_[f]->connections().size(), -1);
    for (int c : connections) {
      if (c < 0 || c >= static_cast<int>(connections_.size())) continue;
      const int l = local_connection_[f][static_cast<std::size_t>(c)];
      if (l < 0) continue;
      local.push_back(l);
      merged_of_local[static_cast<std::size_t>(l)] = c;
    }
    if (local.empty()) continue;
    for (BagMessageRef ref : files_[f]->List(local)) {
      if (ref.position > kPositionMask) {
        throw Error(files_[f]->path() + ": message position " + std::to_string(ref.position) +
                    " is too large for a bag of several files");
      }
      ref.position |= static_cast<std::uint64_t>(f) << kFileShift;
      ref.connection = merged_of_local[static_cast<std::size_t>(ref.connection)];
      out.push_back(ref);
    }
  }
  // Each file's list is in time order already; the files of a bag follow each other in time but
  // may overlap at their seams, so the whole list is sorted once (ties: file, then file order).
  std::sort(out.begin(), out.end(), [](const BagMessageRef& a, const BagMessageRef& b) {
    return std::tie(a.log_time_ns, a.position, a.offset) < std::tie(b.log_time_ns, b.position, b.offset);
  });
  return out;
}

std::vector<std::uint8_t> Ros2Bag::Read(const BagMessageRef& ref) const {
  const std::uint64_t f = ref.position >> kFileShift;
  SSTA_CHECK(f < files_.size() && ref.connection >= 0 && ref.connection < static_cast<int>(connections_.size()),
             "BagMessageRef of another bag");
  BagMessageRef local = ref;
  local.position = ref.position & kPositionMask;
  local.connection = local_connection_[f][static_cast<std::size_t>(ref.connection)];
  SSTA_CHECK(local.connection >= 0, "BagMessageRef of another bag");
  return files_[f]->Read(local);
}

std::string Ros2Bag::Truncation() const {
  for (const auto& file : files_) {
    if (std::string cut = file->Truncation(); !cut.empty()) return cut;
  }
  if (metadata_count_ == 0) return "";
  // A file can be whole and yet hold fewer messages than the recorder wrote (a split file cut
  // at a record boundary, a database whose last transactions were lost).
  std::vector<int> all(connections_.size());
  for (std::size_t i = 0; i < all.size(); ++i) all[i] = static_cast<int>(i);
  const std::vector<BagMessageRef> held = List(all);
  if (held.size() >= metadata_count_) return "";
  return TruncationText(path_,
                        "metadata.yaml lists " + std::to_string(metadata_count_) + " messages, its files hold " +
                            std::to_string(held.size()),
                        held.empty() ? -1 : held.back().log_time_ns);
}

std::unique_ptr<BagReader> OpenStorageFile(const std::string& path, Storage storage) {
  return storage == Storage::kMcap ? OpenMcapFile(path) : OpenDb3File(path);
}

/// A single file's storage by its first bytes, else by its extension.
Storage StorageOfFile(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw Error(path + ": cannot open");
  char head[16] = {};
  in.read(head, sizeof(head));
  const std::string start(head, static_cast<std::size_t>(in.gcount()));
  if (start.rfind("\x89MCAP", 0) == 0) return Storage::kMcap;
  if (start.rfind(std::string("SQLite format 3\0", 16), 0) == 0) return Storage::kSqlite3;
  const std::string ext = fs::path(path).extension().string();
  if (ext == ".mcap") return Storage::kMcap;
  if (ext == ".db3") return Storage::kSqlite3;
  throw Error(path + ": neither an MCAP file nor an sqlite3 database (a ROS 2 bag is a folder with "
              "metadata.yaml, or a .mcap or .db3 file)");
}

/// The storage file `relative` of the bag folder `folder`. rosbag2 of ROS 2 Foxy wrote the paths
/// with the folder's name in front; those are found by their file name too.
std::string BagFilePath(const fs::path& folder, const std::string& relative, const std::string& key_name) {
  std::error_code ec;
  const fs::path direct = folder / relative;
  if (fs::is_regular_file(direct, ec)) return direct.string();
  const fs::path by_name = folder / fs::path(relative).filename();
  if (fs::is_regular_file(by_name, ec)) return by_name.string();
  throw Error(key_name + ": the bag file " + direct.string() + " does not exist");
}

std::unique_ptr<BagReader> OpenBagFolder(const std::string& folder) {
  const std::string yaml_path = (fs::path(folder) / "metadata.yaml").string();
  std::ifstream in(yaml_path);
  if (!in) throw Error(folder + ": a ROS 2 bag folder needs metadata.yaml, which is missing");
  std::stringstream text;
  text << in.rdbuf();
  YamlSection top(ParseYaml(text.str(), yaml_path), yaml_path, "");
  const std::string info_key = "rosbag2_bagfile_information";
  if (!top.Has(info_key)) throw Error(top.Name(info_key) + ": missing key");
  YamlSection info = top.Child(info_key);

  const auto storage_name = info.Require<std::string>("storage_identifier");
  if (storage_name != "mcap" && storage_name != "sqlite3") {
    throw Error(info.Name("storage_identifier") + ": '" + storage_name + "' is not a storage SSTA reads (mcap, sqlite3)");
  }
  const Storage storage = storage_name == "mcap" ? Storage::kMcap : Storage::kSqlite3;
  // Whole-file or per-message compression (rosbag2's --compression-mode) wraps the storage in
  // another layer this reader does not undo.
  std::string compression_mode;
  info.Read("compression_mode", &compression_mode);
  if (!compression_mode.empty() && compression_mode != "NONE" && compression_mode != "none") {
    throw Error(info.Name("compression_mode") + ": '" + compression_mode +
                "' bags are not read; decompress it first (ros2 bag convert)");
  }
  const auto relative_paths = info.Require<std::vector<std::string>>("relative_file_paths");
  if (relative_paths.empty()) throw Error(info.Name("relative_file_paths") + ": lists no file");

  std::vector<std::unique_ptr<BagReader>> files;
  for (const std::string& relative : relative_paths) {
    files.push_back(OpenStorageFile(BagFilePath(folder, relative, info.Name("relative_file_paths")), storage));
  }
  std::uint64_t message_count = 0;
  info.Read("message_count", &message_count);
  return std::make_unique<Ros2Bag>(folder, storage, std::move(files), message_count);
}

}  // namespace

std::unique_ptr<BagReader> OpenRos2Bag(const std::string& path) {
  std::error_code ec;
  if (fs::is_directory(path, ec)) return OpenBagFolder(path);
  if (!fs::exists(path, ec)) throw Error(path + ": no such file or folder");
  const Storage storage = StorageOfFile(path);
  std::vector<std::unique_ptr<BagReader>> files;
  files.push_back(OpenStorageFile(path, storage));
  return std::make_unique<Ros2Bag>(path, storage, std::move(files));
}

}  // namespace ssta::internal
