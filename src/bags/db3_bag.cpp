#include "bags/db3_bag.h"

#include <filesystem>
#include <map>
#include <mutex>
#include <tuple>

#include <sqlite3.h>

#include "ssta/core/error.h"

namespace ssta::internal {
namespace {

using Statement = std::unique_ptr<sqlite3_stmt, decltype(&sqlite3_finalize)>;

class Db3Bag : public BagReader {
 public:
  explicit Db3Bag(std::string path);
  const std::string& path() const override { return path_; }
  std::string format() const override { return "ros2 sqlite3"; }
  const std::vector<BagConnection>& connections() const override { return connections_; }
  std::vector<BagMessageRef> List(const std::vector<int>& connections) const override;
  std::vector<std::uint8_t> Read(const BagMessageRef& ref) const override;

 private:
  [[noreturn]] void Fail(const std::string& what) const {
    throw Error(path_ + ": " + what + " (sqlite: " + sqlite3_errmsg(db_.get()) + ")");
  }
  Statement Prepare(const std::string& sql) const;
  /// sqlite3_step, throwing on anything but a row or the end; true on a row.
  bool Step(sqlite3_stmt* statement) const;
  void ReadTopics();

  std::string path_;
  std::unique_ptr<sqlite3, decltype(&sqlite3_close)> db_{nullptr, &sqlite3_close};
  std::vector<BagConnection> connections_;
  std::map<std::int64_t, int> topic_connection_;
  mutable std::mutex mutex_;
  Statement read_{nullptr, &sqlite3_finalize};  ///< prepared once: Read runs at IMU rates
};

Db3Bag::Db3Bag(std::string path) : path_(std::move(path)) {
  std::error_code ec;
  if (!std::filesystem::is_regular_file(path_, ec)) throw Error(path_ + ": no such file");
  sqlite3* db = nullptr;
  const int rc = sqlite3_open_v2(path_.c_str(), &db, SQLITE_OPEN_READONLY, nullptr);
  db_.reset(db);  // closed also when opening failed
  if (rc != SQLITE_OK) Fail("cannot open as an sqlite3 database");
  ReadTopics();
  // Preparing checks the messages table now, not at the first List.
  read_ = Prepare("SELECT data FROM messages WHERE id = ?");
}

Statement Db3Bag::Prepare(const std::string& sql) const {
  sqlite3_stmt* raw = nullptr;
  if (sqlite3_prepare_v2(db_.get(), sql.c_str(), -1, &raw, nullptr) != SQLITE_OK) {
    Fail("not a rosbag2 sqlite3 bag");
  }
  return Statement(raw, &sqlite3_finalize);
}

bool Db3Bag::Step(sqlite3_stmt* statement) const {
  const int rc = sqlite3_step(statement);
  if (rc == SQLITE_ROW) return true;
  if (rc == SQLITE_DONE) return false;
  Fail("cannot read the bag");
}

void Db3Bag::ReadTopics() {
  Statement topics = Prepare("SELECT id, name, type, serialization_format FROM topics ORDER BY id");
  // One connection per (topic, type, encoding), as in the MCAP reader.
  std::map<std::tuple<std::string, std::string, std::string>, int> known;
  while (Step(topics.get())) {
    auto text = [&](int column) {
      const unsigned char* value = sqlite3_column_text(topics.get(), column);
      return value ? std::string(reinterpret_cast<const char*>(value)) : std::string();
    };
    BagConnection connection{text(1), text(2), text(3)};
    const auto key = std::make_tuple(connection.topic, connection.type, connection.encoding);
    auto it = known.find(key);
    if (it == known.end()) {
      it = known.emplace(key, static_cast<int>(connections_.size())).first;
      connections_.push_back(std::move(connection));
    }
    topic_connection_[sqlite3_column_int64(topics.get(), 0)] = it->second;
  }
}

std::vector<BagMessageRef> Db3Bag::List(const std::vector<int>& connections) const {
  // Topic ids are integers from the file itself: the IN list holds no text from outside.
  std::string ids;
  for (const auto& [topic_id, connection] : topic_connection_) {
    for (int wanted : connections) {
      if (wanted == connection) {
        ids += (ids.empty() ? "" : ",") + std::to_string(topic_id);
        break;
      }
    }
  }
  std::vector<BagMessageRef> out;
  if (ids.empty()) return out;
  std::lock_guard<std::mutex> lock(mutex_);
  Statement rows = Prepare("SELECT id, topic_id, timestamp FROM messages WHERE topic_id IN (" + ids +
                           ") ORDER BY timestamp, id");
  while (Step(rows.get())) {
    BagMessageRef ref;
    ref.position = static_cast<std::uint64_t>(sqlite3_column_int64(rows.get(), 0));
    ref.connection = topic_connection_.at(sqlite3_column_int64(rows.get(), 1));
    ref.log_time_ns = sqlite3_column_int64(rows.get(), 2);
    out.push_back(ref);
  }
  return out;
}

std::vector<std::uint8_t> Db3Bag::Read(const BagMessageRef& ref) const {
  std::lock_guard<std::mutex> lock(mutex_);
  sqlite3_stmt* row = read_.get();
  sqlite3_reset(row);
  sqlite3_bind_int64(row, 1, static_cast<sqlite3_int64>(ref.position));
  if (!Step(row)) throw Error(path_ + ": no message with row id " + std::to_string(ref.position));
  const auto* data = static_cast<const std::uint8_t*>(sqlite3_column_blob(row, 0));
  const int size = sqlite3_column_bytes(row, 0);
  std::vector<std::uint8_t> out = data ? std::vector<std::uint8_t>(data, data + size) : std::vector<std::uint8_t>();
  sqlite3_reset(row);  // ends the read transaction
  return out;
}

}  // namespace

std::unique_ptr<BagReader> OpenDb3File(const std::string& path) { return std::make_unique<Db3Bag>(path); }

}  // namespace ssta::internal
