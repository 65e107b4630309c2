#include <gtest/gtest.h>

#include <algorithm>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <set>
#include <thread>
#include <tuple>

#include <sqlite3.h>

#include "bags/bag_reader.h"
#include "mcap/crc32.h"
#include "bags/support/ros2_bag_writer.h"
#include "bags/support/ros_cdr_encoder.h"
#include "ssta/core/error.h"
#include "temp_dir.h"

namespace ssta {
namespace {

namespace fs = std::filesystem;
using internal::BagMessageRef;
using internal::BagReader;
using internal::OpenRos2Bag;
using testing::McapChunkSpan;
using testing::McapCompression;
using testing::Ros2BagWriter;
using testing::Ros2BagWriterOptions;
using testing::Ros2Storage;

constexpr std::int64_t kStart = 1700000000000000000;  // 2023-11-14, ns since the epoch
constexpr std::int64_t kMs = 1000000;

struct Sent {
  std::string topic;
  std::int64_t log_time_ns;
  std::vector<std::uint8_t> bytes;
};

internal::RosHeader Header(std::int64_t t, const std::string& frame) { return internal::RosHeader{t, frame}; }

// 0.5 s of a stereo rig's recording: a 16x8 mono8 image every 100 ms, IMU every 5 ms, the static
// transform once at the start (all three share the first time stamp: ties keep write order),
// and one odometry message written last although it was received at 250 ms (out of order).
std::vector<Sent> Recording() {
  std::vector<Sent> sent;
  sent.push_back({"/tf_static", kStart,
                  testing::EncodeCdr(std::vector<internal::RosTransform>{
                      {Header(kStart, "base_link"), "cam0", {0.1, 0.0, 0.5}, {0, 0, 0, 1}}})});
  for (int i = 0; i < 100; ++i) {
    const std::int64_t t = kStart + i * 5 * kMs;
    if (i % 20 == 0) {
      internal::RosImage image;
      image.header = Header(t, "cam0");
      image.height = 8;
      image.width = 16;
      image.encoding = "mono8";
      image.step = 16;
      for (int p = 0; p < 128; ++p) image.data.push_back(static_cast<std::uint8_t>(p * 3 + i));
      sent.push_back({"/cam0/image_raw", t, testing::EncodeCdr(image)});
    }
    internal::RosImu imu;
    imu.header = Header(t, "imu0");
    imu.angular_velocity = {0.01 * i, 0.0, -0.02};
    imu.linear_acceleration = {0.0, 0.1, 9.81};
    sent.push_back({"/imu0", t, testing::EncodeCdr(imu)});
  }
  internal::RosOdometry odometry;
  odometry.header = Header(kStart + 250 * kMs, "odom");
  odometry.child_frame_id = "base_link";
  odometry.position = {1.0, 2.0, 0.0};
  sent.push_back({"/odom", kStart + 250 * kMs, testing::EncodeCdr(odometry)});
  return sent;
}

const std::vector<std::pair<std::string, std::string>> kTopics = {{"/tf_static", "tf2_msgs/msg/TFMessage"},
                                                                  {"/cam0/image_raw", "sensor_msgs/msg/Image"},
                                                                  {"/imu0", "sensor_msgs/msg/Imu"},
                                                                  {"/odom", "nav_msgs/msg/Odometry"}};

struct Written {
  std::vector<std::string> files;
  std::vector<McapChunkSpan> chunks;
};

// Writes `sent` to a bag at `folder`; with `split_at` > 0 a second file starts before that
// message, and /odom is registered only then (a topic of the second file alone).
Written WriteBag(const std::string& folder, const Ros2BagWriterOptions& options, const std::vector<Sent>& sent,
                 std::size_t split_at = 0) {
  Ros2BagWriter writer(folder, options);
  for (const auto& [topic, type] : kTopics) {
    if (split_at == 0 || topic != "/odom") writer.AddTopic(topic, type);
  }
  for (std::size_t i = 0; i < sent.size(); ++i) {
    if (split_at != 0 && i == split_at) {
      writer.SplitFile();
      writer.AddTopic("/odom", "nav_msgs/msg/Odometry");
    }
    writer.Write(sent[i].topic, sent[i].log_time_ns, sent[i].bytes);
  }
  writer.Close();
  return Written{writer.files(), writer.chunks()};
}

std::vector<int> AllConnections(const BagReader& bag) {
  std::vector<int> all(bag.connections().size());
  for (std::size_t i = 0; i < all.size(); ++i) all[i] = static_cast<int>(i);
  return all;
}

// The order List must give: by log time, ties in write order.
std::vector<Sent> InTimeOrder(std::vector<Sent> sent) {
  std::stable_sort(sent.begin(), sent.end(),
                   [](const Sent& a, const Sent& b) { return a.log_time_ns < b.log_time_ns; });
  return sent;
}

void ExpectReadsBack(const BagReader& bag, const std::vector<Sent>& sent) {
  const std::vector<Sent> expected = InTimeOrder(sent);
  const std::vector<BagMessageRef> refs = bag.List(AllConnections(bag));
  ASSERT_EQ(refs.size(), expected.size());
  for (std::size_t i = 0; i < refs.size(); ++i) {
    SCOPED_TRACE("message " + std::to_string(i));
    ASSERT_EQ(bag.connections()[static_cast<std::size_t>(refs[i].connection)].topic, expected[i].topic);
    EXPECT_EQ(refs[i].log_time_ns, expected[i].log_time_ns);
    EXPECT_EQ(bag.Read(refs[i]), expected[i].bytes);
  }
}

std::set<std::tuple<std::string, std::string, std::string>> ConnectionSet(const BagReader& bag) {
  std::set<std::tuple<std::string, std::string, std::string>> out;
  for (const auto& c : bag.connections()) out.emplace(c.topic, c.type, c.encoding);
  return out;
}

std::set<std::tuple<std::string, std::string, std::string>> ExpectedConnections() {
  std::set<std::tuple<std::string, std::string, std::string>> out;
  for (const auto& [topic, type] : kTopics) out.emplace(topic, type, "cdr");
  return out;
}

// The ssta::Error message `f` throws ("" and a test failure when it throws none).
template <typename F>
std::string ErrorOf(F&& f) {
  try {
    f();
  } catch (const Error& e) {
    return e.what();
  }
  ADD_FAILURE() << "no ssta::Error thrown";
  return "";
}

#define EXPECT_CONTAINS(text, part) \
  EXPECT_NE(std::string(text).find(part), std::string::npos) << "'" << (text) << "' lacks '" << (part) << "'"

void Patch(const std::string& path, std::uint64_t offset, const std::vector<std::uint8_t>& bytes) {
  std::fstream f(path, std::ios::binary | std::ios::in | std::ios::out);
  f.seekp(static_cast<std::streamoff>(offset));
  f.write(reinterpret_cast<const char*>(bytes.data()), static_cast<std::streamsize>(bytes.size()));
  ASSERT_TRUE(f.good());
}

TEST(Crc32, MatchesTheStandardCheckValue) {
  const std::string text = "123456789";
  EXPECT_EQ(internal::Crc32(reinterpret_cast<const std::uint8_t*>(text.data()), text.size()), 0xCBF43926u);
}

// ---- CDR encoders: byte layouts worked out by hand from the ROS 2 Humble .msg files ----------

std::vector<std::uint8_t> Le32(std::uint32_t v) {
  return {static_cast<std::uint8_t>(v), static_cast<std::uint8_t>(v >> 8), static_cast<std::uint8_t>(v >> 16),
          static_cast<std::uint8_t>(v >> 24)};
}

std::vector<std::uint8_t> Cat(std::initializer_list<std::vector<std::uint8_t>> parts) {
  std::vector<std::uint8_t> out;
  for (const auto& p : parts) out.insert(out.end(), p.begin(), p.end());
  return out;
}

double DoubleAt(const std::vector<std::uint8_t>& bytes, std::size_t offset) {
  double v = 0;
  std::memcpy(&v, bytes.data() + offset, sizeof(v));
  return v;
}

TEST(RosCdrEncoder, CompressedImageBytesAreExact) {
  internal::RosCompressedImage image;
  image.header = Header(1500000000, "cam");  // 1.5 s: sec 1, nanosec 500000000
  image.format = "png";
  image.data = {1, 2, 3};
  const std::vector<std::uint8_t> expected =
      Cat({{0x00, 0x01, 0x00, 0x00}, Le32(1), Le32(500000000), Le32(4), {'c', 'a', 'm', 0}, Le32(4),
           {'p', 'n', 'g', 0}, Le32(3), {1, 2, 3}});
  EXPECT_EQ(testing::EncodeCdr(image), expected);
}

TEST(RosCdrEncoder, ImageBytesAreExact) {
  internal::RosImage image;
  image.header = Header(-1, "c");  // 1 ns before the epoch: sec -1, nanosec 999999999
  image.height = 2;
  image.width = 3;
  image.encoding = "mono8";
  image.big_endian = true;
  image.step = 3;
  image.data = {10, 11, 12, 13, 14, 15};
  // "c\0" ends at 14: height aligns to 16; is_bigendian at 34, step aligns to 36.
  const std::vector<std::uint8_t> expected =
      Cat({{0x00, 0x01, 0x00, 0x00}, Le32(0xFFFFFFFFu), Le32(999999999), Le32(2), {'c', 0, 0, 0}, Le32(2), Le32(3),
           Le32(6), {'m', 'o', 'n', 'o', '8', 0}, {1, 0}, Le32(3), Le32(6), {10, 11, 12, 13, 14, 15}});
  EXPECT_EQ(testing::EncodeCdr(image), expected);
}

TEST(RosCdrEncoder, ImuAlignsOrientationToEightBytesAfterTheHeader) {
  internal::RosImu imu;
  imu.header = Header(0, "imu");  // header ends at 16 (after the encapsulation): no padding
  imu.orientation_xyzw = {0.1, 0.2, 0.3, 0.9};
  imu.angular_velocity = {1, 2, 3};
  imu.linear_acceleration = {4, 5, 9.81};
  std::vector<std::uint8_t> bytes = testing::EncodeCdr(imu);
  // 16 + 4 quaternion + 9 cov + 3 + 9 + 3 + 9 doubles = 312, plus the encapsulation.
  ASSERT_EQ(bytes.size(), 316u);
  EXPECT_EQ(DoubleAt(bytes, 4 + 16), 0.1);
  EXPECT_EQ(DoubleAt(bytes, 4 + 40), 0.9);         // w
  EXPECT_EQ(DoubleAt(bytes, 4 + 48), 0.0);         // orientation_covariance[0]
  EXPECT_EQ(DoubleAt(bytes, 4 + 120), 1.0);        // angular_velocity.x
  EXPECT_EQ(DoubleAt(bytes, 4 + 216 + 16), 9.81);  // linear_acceleration.z
  imu.header.frame_id = "imu0";  // header ends at 17: padded to 24
  bytes = testing::EncodeCdr(imu);
  ASSERT_EQ(bytes.size(), 324u);
  EXPECT_EQ(DoubleAt(bytes, 4 + 24), 0.1);
}

TEST(RosCdrEncoder, CameraInfoCarriesBinningAndRoiAfterP) {
  internal::RosCameraInfo info;
  info.header = Header(0, "cam");
  info.height = 480;
  info.width = 752;
  info.distortion_model = "plumb_bob";  // ends at 38: d's count at 40, its doubles at 48
  info.d = {0.1, 0.2, 0.3, 0.4, 0.5};
  info.k = {458, 0, 367, 0, 457, 248, 0, 0, 1};
  info.r = {1, 0, 0, 0, 1, 0, 0, 0, 1};
  for (int i = 0; i < 12; ++i) info.p[static_cast<std::size_t>(i)] = i + 1;
  const std::vector<std::uint8_t> bytes = testing::EncodeCdr(info);
  // d 48..88, k ..160, r ..232, p ..328, binning 2 x 4, roi 4 x 4 + bool = 353.
  ASSERT_EQ(bytes.size(), 4u + 353u);
  EXPECT_EQ(std::vector<std::uint8_t>(bytes.begin() + 44, bytes.begin() + 48), Le32(5));
  EXPECT_EQ(DoubleAt(bytes, 4 + 48), 0.1);
  EXPECT_EQ(DoubleAt(bytes, 4 + 88), 458.0);
  EXPECT_EQ(DoubleAt(bytes, 4 + 232), 1.0);   // p[0]
  EXPECT_EQ(DoubleAt(bytes, 4 + 320), 12.0);  // p[11]
}

TEST(RosCdrEncoder, OdometryCarriesCovariancesAndTwist) {
  internal::RosOdometry odometry;
  odometry.header = Header(0, "odom");  // ends at 17
  odometry.child_frame_id = "base";     // count at 20, text to 29; pose at 32
  odometry.position = {1, 2, 3};
  odometry.orientation_xyzw = {0, 0, 0.6, 0.8};
  const std::vector<std::uint8_t> bytes = testing::EncodeCdr(odometry);
  // pose 32..88, its covariance ..376, twist ..424, its covariance ..712.
  ASSERT_EQ(bytes.size(), 4u + 712u);
  EXPECT_EQ(DoubleAt(bytes, 4 + 32), 1.0);
  EXPECT_EQ(DoubleAt(bytes, 4 + 80), 0.8);  // orientation w
}

TEST(RosCdrEncoder, TfMessageAlignsEachTransform) {
  const std::vector<internal::RosTransform> transforms = {
      {Header(0, "map"), "base", {1, 2, 3}, {0, 0, 0, 1}},
      {Header(0, "base"), "cam", {4, 5, 6}, {0.5, 0.5, 0.5, 0.5}}};
  const std::vector<std::uint8_t> bytes = testing::EncodeCdr(transforms);
  // count 0..4; first: header ..20, child ..29, translation at 32, rotation ..88;
  // second: header 88..105, child at 108..116, translation at 120, rotation 144..176.
  ASSERT_EQ(bytes.size(), 4u + 176u);
  EXPECT_EQ(std::vector<std::uint8_t>(bytes.begin() + 4, bytes.begin() + 8), Le32(2));
  EXPECT_EQ(DoubleAt(bytes, 4 + 32), 1.0);
  EXPECT_EQ(DoubleAt(bytes, 4 + 120), 4.0);
  EXPECT_EQ(DoubleAt(bytes, 4 + 168), 0.5);
}

// ---- MCAP -------------------------------------------------------------------------------------

struct McapCase {
  McapCompression compression;
  bool summary;
};

std::string McapCaseName(const ::testing::TestParamInfo<McapCase>& info) {
  static const char* const kNames[] = {"None", "Zstd", "Lz4"};
  return std::string(kNames[static_cast<int>(info.param.compression)]) +
         (info.param.summary ? "WithSummary" : "WithoutSummary");
}

class Ros2McapBag : public ::testing::TestWithParam<McapCase> {};

TEST_P(Ros2McapBag, ReadsBackEveryMessageInTimeOrder) {
  testing::TempDir dir;
  Ros2BagWriterOptions options;
  options.compression = GetParam().compression;
  options.summary = GetParam().summary;
  const Written written = WriteBag(dir / "bag", options, Recording());
  ASSERT_GE(written.chunks.size(), 5u);  // small chunks: the index spans many

  const auto bag = OpenRos2Bag(dir / "bag");
  EXPECT_EQ(bag->format(), "ros2 mcap");
  EXPECT_EQ(bag->path(), dir / "bag");
  EXPECT_EQ(ConnectionSet(*bag), ExpectedConnections());
  ExpectReadsBack(*bag, Recording());
}

INSTANTIATE_TEST_SUITE_P(Compressions, Ros2McapBag,
                         ::testing::Values(McapCase{McapCompression::kNone, true}, McapCase{McapCompression::kZstd, true},
                                           McapCase{McapCompression::kLz4, true}, McapCase{McapCompression::kNone, false},
                                           McapCase{McapCompression::kZstd, false}, McapCase{McapCompression::kLz4, false}),
                         McapCaseName);

int ConnectionOf(const BagReader& bag, const std::string& topic) {
  for (std::size_t i = 0; i < bag.connections().size(); ++i) {
    if (bag.connections()[i].topic == topic) return static_cast<int>(i);
  }
  return -1;
}

TEST(Ros2Bag, ListOfOneTopicHoldsOnlyItsMessages) {
  for (bool summary : {true, false}) {
    SCOPED_TRACE(summary ? "with summary" : "without summary");
    testing::TempDir dir;
    Ros2BagWriterOptions options;
    options.summary = summary;
    WriteBag(dir / "bag", options, Recording());
    const auto bag = OpenRos2Bag(dir / "bag");
    const int imu = ConnectionOf(*bag, "/imu0");
    ASSERT_GE(imu, 0);
    const std::vector<BagMessageRef> refs = bag->List({imu});
    ASSERT_EQ(refs.size(), 100u);
    for (std::size_t i = 0; i < refs.size(); ++i) {
      EXPECT_EQ(refs[i].connection, imu);
      EXPECT_EQ(refs[i].log_time_ns, kStart + static_cast<std::int64_t>(i) * 5 * kMs);
    }
    EXPECT_TRUE(bag->List({}).empty());
  }
}

TEST(Ros2Bag, ListReadsTheIndexWithoutDecompressing) {
  testing::TempDir dir;
  Ros2BagWriterOptions options;
  options.compression = McapCompression::kZstd;
  const Written written = WriteBag(dir / "bag", options, Recording());
  // Garbage over the second chunk's zstd stream: List, reading the index only, does not notice;
  // reading a message of that chunk does.
  const McapChunkSpan& chunk = written.chunks[1];
  Patch(written.files[0], chunk.records_offset, std::vector<std::uint8_t>(chunk.records_size, 0xAB));
  const auto bag = OpenRos2Bag(dir / "bag");
  const std::vector<BagMessageRef> refs = bag->List(AllConnections(*bag));
  ASSERT_EQ(refs.size(), Recording().size());
  const auto in_chunk = std::find_if(refs.begin(), refs.end(),
                                     [&](const BagMessageRef& r) { return r.position == chunk.offset; });
  ASSERT_NE(in_chunk, refs.end());
  const std::string error = ErrorOf([&] { bag->Read(*in_chunk); });
  EXPECT_CONTAINS(error, written.files[0]);
  EXPECT_CONTAINS(error, "offset " + std::to_string(chunk.offset));
  EXPECT_CONTAINS(error, "corrupt zstd");
  EXPECT_EQ(bag->Read(refs.front()), InTimeOrder(Recording()).front().bytes);  // other chunks still read
}

TEST(Ros2Bag, CutMcapKeepsItsCompleteChunks) {
  testing::TempDir dir;
  Ros2BagWriterOptions options;
  options.compression = McapCompression::kLz4;
  const Written written = WriteBag(dir / "bag", options, Recording());
  const McapChunkSpan& third = written.chunks[2];
  fs::resize_file(written.files[0], third.offset + third.length / 2);  // the crash hit mid-chunk

  const auto bag = OpenRos2Bag(dir / "bag");
  const std::size_t complete = written.chunks[0].messages + written.chunks[1].messages;
  const std::vector<Sent> sent = Recording();
  ExpectReadsBack(*bag, std::vector<Sent>(sent.begin(), sent.begin() + static_cast<std::ptrdiff_t>(complete)));
  // Read, and said to be truncated: the sequence reader refuses it unless asked.
  EXPECT_CONTAINS(bag->Truncation(), written.files[0] + ": truncated: the file ends inside a Chunk record at offset " +
                                         std::to_string(third.offset));
  const auto whole = WriteBag(dir / "whole", options, Recording());
  EXPECT_EQ(OpenRos2Bag(dir / "whole")->Truncation(), "");
}

TEST(Ros2Bag, McapCutInsideItsFirstChunkFailsNamingTheFile) {
  testing::TempDir dir;
  const Written written = WriteBag(dir / "bag", {}, Recording());
  fs::resize_file(written.files[0], written.chunks[0].offset + 20);
  const std::string error = ErrorOf([&] { OpenRos2Bag(dir / "bag"); });
  EXPECT_CONTAINS(error, written.files[0] + ": truncated: ");
  EXPECT_CONTAINS(error, "before any complete message");
}

TEST(Ros2Bag, McapWithoutMagicFails) {
  testing::TempDir dir;
  const Written written = WriteBag(dir / "bag", {}, Recording());
  Patch(written.files[0], 1, {'X'});
  const std::string error = ErrorOf([&] { OpenRos2Bag(dir / "bag"); });
  EXPECT_CONTAINS(error, written.files[0]);
  EXPECT_CONTAINS(error, "magic");
}

TEST(Ros2Bag, McapRecordLengthPastTheEndFails) {
  testing::TempDir dir;
  Ros2BagWriterOptions options;
  options.summary = false;  // the data section is scanned: the bad length is met at open
  const Written written = WriteBag(dir / "bag", options, Recording());
  const std::uint64_t at = written.chunks[1].offset;
  Patch(written.files[0], at + 1, {0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0x7F});
  const std::string error = ErrorOf([&] { OpenRos2Bag(dir / "bag"); });
  EXPECT_CONTAINS(error, written.files[0]);
  EXPECT_CONTAINS(error, "offset " + std::to_string(at));
  EXPECT_CONTAINS(error, "runs past");
}

TEST(Ros2Bag, McapChunkCrcMismatchFails) {
  testing::TempDir dir;
  const Written written = WriteBag(dir / "bag", {}, Recording());  // uncompressed, with summary
  const McapChunkSpan& chunk = written.chunks[1];
  Patch(written.files[0], chunk.records_offset + chunk.records_size - 1, {0x5A});  // in a message's data
  const auto bag = OpenRos2Bag(dir / "bag");
  const std::vector<BagMessageRef> refs = bag->List(AllConnections(*bag));
  const auto in_chunk = std::find_if(refs.begin(), refs.end(),
                                     [&](const BagMessageRef& r) { return r.position == chunk.offset; });
  ASSERT_NE(in_chunk, refs.end());
  const std::string error = ErrorOf([&] { bag->Read(*in_chunk); });
  EXPECT_CONTAINS(error, written.files[0]);
  EXPECT_CONTAINS(error, "Chunk record at offset " + std::to_string(chunk.offset));
  EXPECT_CONTAINS(error, "CRC");
}

TEST(Ros2Bag, McapUnknownCompressionFails) {
  testing::TempDir dir;
  Ros2BagWriterOptions options;
  options.compression = McapCompression::kZstd;
  options.summary = false;
  const Written written = WriteBag(dir / "bag", options, Recording());
  // The compression string follows the opcode, the length and 28 bytes of fixed fields.
  Patch(written.files[0], written.chunks[0].offset + 9 + 28 + 4, {'b', 'r', 'o', 't'});
  const std::string error = ErrorOf([&] { OpenRos2Bag(dir / "bag"); });
  EXPECT_CONTAINS(error, written.files[0]);
  EXPECT_CONTAINS(error, "'brot' is not supported");
}

TEST(Ros2Bag, McapSummaryOutsideTheFileFails) {
  testing::TempDir dir;
  const Written written = WriteBag(dir / "bag", {}, Recording());
  const std::uint64_t size = fs::file_size(written.files[0]);
  // Footer: opcode, length, summary_start ... then the 8 magic bytes.
  Patch(written.files[0], size - 8 - 20, {0xFF, 0xFF, 0xFF, 0x00, 0x00, 0x00, 0x00, 0x00});
  const std::string error = ErrorOf([&] { OpenRos2Bag(dir / "bag"); });
  EXPECT_CONTAINS(error, written.files[0]);
  EXPECT_CONTAINS(error, "summary section");
}

// ---- sqlite3, folders, several files ----------------------------------------------------------

TEST(Ros2Bag, Sqlite3ReadsBackEveryMessageInTimeOrder) {
  testing::TempDir dir;
  Ros2BagWriterOptions options;
  options.storage = Ros2Storage::kSqlite3;
  WriteBag(dir / "bag", options, Recording());
  const auto bag = OpenRos2Bag(dir / "bag");
  EXPECT_EQ(bag->format(), "ros2 sqlite3");
  EXPECT_EQ(ConnectionSet(*bag), ExpectedConnections());
  ExpectReadsBack(*bag, Recording());
}

TEST(Ros2Bag, SplitBagReadsAsOne) {
  for (Ros2Storage storage : {Ros2Storage::kMcap, Ros2Storage::kSqlite3}) {
    SCOPED_TRACE(storage == Ros2Storage::kMcap ? "mcap" : "sqlite3");
    testing::TempDir dir;
    Ros2BagWriterOptions options;
    options.storage = storage;
    const Written written = WriteBag(dir / "bag", options, Recording(), 60);
    ASSERT_EQ(written.files.size(), 2u);
    const auto bag = OpenRos2Bag(dir / "bag");
    EXPECT_EQ(bag->connections().size(), 4u);  // the topics of both files, each once
    EXPECT_EQ(ConnectionSet(*bag), ExpectedConnections());
    ExpectReadsBack(*bag, Recording());
  }
}

TEST(Ros2Bag, OpensASingleStorageFile) {
  for (Ros2Storage storage : {Ros2Storage::kMcap, Ros2Storage::kSqlite3}) {
    testing::TempDir dir;
    Ros2BagWriterOptions options;
    options.storage = storage;
    const Written written = WriteBag(dir / "bag", options, Recording());
    const auto bag = OpenRos2Bag(written.files[0]);
    EXPECT_EQ(bag->format(), storage == Ros2Storage::kMcap ? "ros2 mcap" : "ros2 sqlite3");
    EXPECT_EQ(bag->path(), written.files[0]);
    ExpectReadsBack(*bag, Recording());
  }
}

TEST(Ros2Bag, Db3WithoutRosbagTablesFails) {
  testing::TempDir dir;
  const std::string path = dir / "other.db3";
  sqlite3* db = nullptr;
  ASSERT_EQ(sqlite3_open(path.c_str(), &db), SQLITE_OK);
  sqlite3_exec(db, "CREATE TABLE notes(id INTEGER, text TEXT);", nullptr, nullptr, nullptr);
  sqlite3_close(db);
  std::string error = ErrorOf([&] { OpenRos2Bag(path); });
  EXPECT_CONTAINS(error, path);
  EXPECT_CONTAINS(error, "not a rosbag2 sqlite3 bag");
  EXPECT_CONTAINS(error, "topics");

  const std::string text = dir / "text.db3";
  std::ofstream(text) << "this is not a database, only text long enough to look at";
  error = ErrorOf([&] { OpenRos2Bag(text); });
  EXPECT_CONTAINS(error, text);
}

TEST(Ros2Bag, MetadataNamingAMissingFileFails) {
  testing::TempDir dir;
  const Written written = WriteBag(dir / "bag", {}, Recording(), 60);
  fs::remove(written.files[1]);
  const std::string error = ErrorOf([&] { OpenRos2Bag(dir / "bag"); });
  EXPECT_CONTAINS(error, written.files[1]);
  EXPECT_CONTAINS(error, "relative_file_paths");
}

TEST(Ros2Bag, MetadataWithoutStorageIdentifierFails) {
  testing::TempDir dir;
  WriteBag(dir / "bag", {}, Recording());
  const std::string yaml = dir / "bag/metadata.yaml";
  std::ifstream in(yaml);
  std::string text, line;
  while (std::getline(in, line)) {
    if (line.find("storage_identifier") == std::string::npos) text += line + "\n";
  }
  in.close();
  std::ofstream(yaml) << text;
  const std::string error = ErrorOf([&] { OpenRos2Bag(dir / "bag"); });
  EXPECT_CONTAINS(error, yaml);
  EXPECT_CONTAINS(error, "rosbag2_bagfile_information.storage_identifier: missing key");
}

TEST(Ros2Bag, MissingPathsFailNamingThem) {
  testing::TempDir dir;
  std::string error = ErrorOf([&] { OpenRos2Bag(dir / "nothing_here"); });
  EXPECT_CONTAINS(error, dir / "nothing_here");
  fs::create_directories(dir / "empty_folder");
  error = ErrorOf([&] { OpenRos2Bag(dir / "empty_folder"); });
  EXPECT_CONTAINS(error, dir / "empty_folder");
  EXPECT_CONTAINS(error, "metadata.yaml");
}

TEST(Ros2Bag, ConcurrentReadsReturnTheWrittenBytes) {
  for (Ros2Storage storage : {Ros2Storage::kMcap, Ros2Storage::kSqlite3}) {
    testing::TempDir dir;
    Ros2BagWriterOptions options;
    options.storage = storage;
    options.compression = McapCompression::kZstd;
    WriteBag(dir / "bag", options, Recording());
    const auto bag = OpenRos2Bag(dir / "bag");
    const std::vector<BagMessageRef> refs = bag->List(AllConnections(*bag));
    const std::vector<Sent> expected = InTimeOrder(Recording());
    ASSERT_EQ(refs.size(), expected.size());
    // One thread reads forwards, the other backwards: they keep evicting each other's chunks.
    std::vector<std::vector<std::uint8_t>> forward(refs.size()), backward(refs.size());
    std::thread a([&] {
      for (std::size_t i = 0; i < refs.size(); ++i) forward[i] = bag->Read(refs[i]);
    });
    std::thread b([&] {
      for (std::size_t i = refs.size(); i-- > 0;) backward[i] = bag->Read(refs[i]);
    });
    a.join();
    b.join();
    for (std::size_t i = 0; i < refs.size(); ++i) {
      EXPECT_EQ(forward[i], expected[i].bytes) << i;
      EXPECT_EQ(backward[i], expected[i].bytes) << i;
    }
  }
}

}  // namespace
}  // namespace ssta
