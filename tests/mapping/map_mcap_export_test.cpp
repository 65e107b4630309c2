// The `mcap` export read back with SSTA's own MCAP reader (src/bags/mcap_bag.h) and a CDR
// decoder written here from the ROS 2 message definitions. tests/mcap_reader/ reads it with
// Foxglove's libraries instead.

#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>
#include <map>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "bags/mcap_bag.h"
#include "bags/ros_messages.h"
#include "map_test_util.h"
#include "ssta/io/image_io.h"
#include "ssta/mapping/map_export.h"
#include "temp_dir.h"

namespace ssta {
namespace {

using testing::C;
using testing::TempDir;

/// Reads CDR (little endian, after the 4-byte encapsulation header), aligning each primitive to
/// its size as counted from after that header.
class Cdr {
 public:
  explicit Cdr(std::vector<std::uint8_t> bytes) : bytes_(std::move(bytes)) {
    EXPECT_GE(bytes_.size(), 4u);
    EXPECT_EQ(bytes_[1], 0x01);  // CDR, little endian
  }
  template <typename T>
  T Get() {
    while ((at_ - 4) % sizeof(T) != 0) ++at_;
    T v{};
    if (at_ + sizeof(T) > bytes_.size()) {
      ADD_FAILURE() << "CDR message ends early";
      return v;
    }
    std::memcpy(&v, bytes_.data() + at_, sizeof(T));
    at_ += sizeof(T);
    return v;
  }
  std::string String() {
    const auto n = Get<std::uint32_t>();
    if (n == 0 || at_ + n > bytes_.size()) {
      ADD_FAILURE() << "bad CDR string";
      return "";
    }
    std::string s(reinterpret_cast<const char*>(bytes_.data() + at_), n - 1);
    at_ += n;
    return s;
  }
  std::string Header() {
    Get<std::int32_t>();
    Get<std::uint32_t>();
    return String();
  }
  bool AtEnd() const { return at_ == bytes_.size(); }

 private:
  std::vector<std::uint8_t> bytes_;
  std::size_t at_ = 4;
};

/// One message per topic of the export, read with the project's MCAP reader.
struct ReadBack {
  std::map<std::string, std::string> types;
  std::map<std::string, std::vector<std::uint8_t>> messages;
};

ReadBack ReadMcap(const std::string& path) {
  const std::unique_ptr<internal::BagReader> bag = internal::OpenMcapFile(path);
  ReadBack out;
  EXPECT_EQ(bag->Truncation(), "");
  std::vector<int> all;
  for (std::size_t i = 0; i < bag->connections().size(); ++i) {
    const internal::BagConnection& c = bag->connections()[i];
    EXPECT_EQ(c.encoding, "cdr");
    out.types[c.topic] = c.type;
    all.push_back(static_cast<int>(i));
  }
  for (const internal::BagMessageRef& ref : bag->List(all)) {
    const std::string& topic = bag->connections()[ref.connection].topic;
    EXPECT_EQ(out.messages.count(topic), 0u) << topic << " holds more than one message";
    out.messages[topic] = bag->Read(ref);
  }
  return out;
}

/// The floor-and-box world (map_test_util.h) seen from two origins 0.5 m apart, so the sensor
/// path holds two poses.
TraversabilityMap TwoViewMap() {
  TraversabilityMap map = testing::FloorAndBoxMap();
  map.InsertFrame(testing::FloorAndBox(), testing::FloorAndBoxOrigin() - Eigen::Vector3d(0.5, 0.0, 0.0), 2000);
  return map;
}

TEST(McapExport, ReadBackHoldsTheGridOfThePgmExportTheLayersTheVoxelsAndThePath) {
  TempDir dir;
  const TraversabilityMap map = TwoViewMap();
  const GridProjection grid = ExportGrid(map, dir / "grid");
  const McapExportSummary summary = ExportMcap(map, dir / "map.mcap");
  // Written atomically: nothing beside the exports.
  EXPECT_EQ(std::distance(std::filesystem::directory_iterator(dir.path()), std::filesystem::directory_iterator{}), 5);
  EXPECT_EQ(summary.bytes, std::filesystem::file_size(dir / "map.mcap"));
  EXPECT_EQ(summary.grid_width, grid.width());
  EXPECT_EQ(summary.grid_height, grid.height());

  const ReadBack bag = ReadMcap(dir / "map.mcap");
  const std::map<std::string, std::string> types = {
      {"/map", "nav_msgs/msg/OccupancyGrid"},
      {"/traversability", "grid_map_msgs/msg/GridMap"},
      {"/traversability/voxels", "sensor_msgs/msg/PointCloud2"},
      {"/sensor_path", "nav_msgs/msg/Path"},
      {"/tf_static", "tf2_msgs/msg/TFMessage"}};
  EXPECT_EQ(bag.types, types);
  ASSERT_EQ(bag.messages.size(), 5u);

  // /map: the PGM cell for cell (0 -> 100, 205 -> -1, 254 -> a cost below 100), rows from the
  // smallest y; the YAML's resolution and origin.
  const ImageU8 pgm = ReadGreyImage(dir / "grid.pgm");
  Cdr occupancy(bag.messages.at("/map"));
  EXPECT_EQ(occupancy.Header(), "map");
  occupancy.Get<std::int32_t>();
  occupancy.Get<std::uint32_t>();
  EXPECT_FLOAT_EQ(occupancy.Get<float>(), 0.1f);
  const auto w = static_cast<int>(occupancy.Get<std::uint32_t>());
  const auto h = static_cast<int>(occupancy.Get<std::uint32_t>());
  ASSERT_EQ(w, pgm.width());
  ASSERT_EQ(h, pgm.height());
  EXPECT_NEAR(occupancy.Get<double>(), grid.origin.x(), 1e-12);
  EXPECT_NEAR(occupancy.Get<double>(), grid.origin.y(), 1e-12);
  for (int k = 0; k < 4; ++k) occupancy.Get<double>();  // z, orientation x y z
  EXPECT_EQ(occupancy.Get<double>(), 1.0);                // orientation w
  ASSERT_EQ(occupancy.Get<std::uint32_t>(), static_cast<std::uint32_t>(w * h));
  int occupied = 0, differing = 0;
  for (int row = 0; row < h; ++row) {
    for (int u = 0; u < w; ++u) {
      const auto value = occupancy.Get<std::int8_t>();
      const int v = h - 1 - row;
      const std::uint8_t nav = pgm(v, u);
      const bool agrees = nav == 0 ? value == 100 : nav == 205 ? value == -1 : (value >= 0 && value < 100);
      differing += agrees ? 0 : 1;
      EXPECT_EQ(value, OccupancyGridValue(grid.classes(v, u), grid.cost(v, u)));
      occupied += value == 100 ? 1 : 0;
    }
  }
  EXPECT_EQ(differing, 0);
  EXPECT_EQ(occupied, 9);  // the box's 3 x 3 columns
  EXPECT_TRUE(occupancy.AtEnd());

  // /traversability: six layers in grid_map's order (i along -x, j along -y, column-major).
  Cdr grid_map(bag.messages.at("/traversability"));
  EXPECT_EQ(grid_map.Header(), "map");
  EXPECT_DOUBLE_EQ(grid_map.Get<double>(), 0.1);
  EXPECT_NEAR(grid_map.Get<double>(), w * 0.1, 1e-9);
  EXPECT_NEAR(grid_map.Get<double>(), h * 0.1, 1e-9);
  const double centre_x = grid_map.Get<double>(), centre_y = grid_map.Get<double>();
  EXPECT_NEAR(centre_x, grid.origin.x() + 0.05 * w, 1e-9);
  EXPECT_NEAR(centre_y, grid.origin.y() + 0.05 * h, 1e-9);
  for (int k = 0; k < 5; ++k) grid_map.Get<double>();  // z, orientation
  const std::vector<std::string> names = {"class", "cost", "confidence", "elevation", "slope", "step"};
  ASSERT_EQ(grid_map.Get<std::uint32_t>(), names.size());
  for (const std::string& name : names) EXPECT_EQ(grid_map.String(), name);
  ASSERT_EQ(grid_map.Get<std::uint32_t>(), 1u);
  EXPECT_EQ(grid_map.String(), "class");
  ASSERT_EQ(grid_map.Get<std::uint32_t>(), names.size());
  std::map<std::string, std::vector<float>> layers;
  for (const std::string& name : names) {
    ASSERT_EQ(grid_map.Get<std::uint32_t>(), 2u);
    EXPECT_EQ(grid_map.String(), "column_index");
    EXPECT_EQ(grid_map.Get<std::uint32_t>(), static_cast<std::uint32_t>(h));
    EXPECT_EQ(grid_map.Get<std::uint32_t>(), static_cast<std::uint32_t>(w * h));
    EXPECT_EQ(grid_map.String(), "row_index");
    EXPECT_EQ(grid_map.Get<std::uint32_t>(), static_cast<std::uint32_t>(w));
    EXPECT_EQ(grid_map.Get<std::uint32_t>(), static_cast<std::uint32_t>(w));
    EXPECT_EQ(grid_map.Get<std::uint32_t>(), 0u);  // data_offset
    ASSERT_EQ(grid_map.Get<std::uint32_t>(), static_cast<std::uint32_t>(w * h));
    for (int k = 0; k < w * h; ++k) layers[name].push_back(grid_map.Get<float>());
  }
  EXPECT_EQ(grid_map.Get<std::uint16_t>(), 0u);
  EXPECT_EQ(grid_map.Get<std::uint16_t>(), 0u);
  EXPECT_TRUE(grid_map.AtEnd());
  // The cell at (x, y): i = (x_max - x) / r, j = (y_max - y) / r.
  auto at = [&](const std::string& layer, double x, double y) {
    const int i = static_cast<int>(std::floor((centre_x + 0.05 * w - x) / 0.1));
    const int j = static_cast<int>(std::floor((centre_y + 0.05 * h - y) / 0.1));
    return layers.at(layer)[static_cast<std::size_t>(i + j * w)];
  };
  EXPECT_EQ(at("class", C(11), C(12)), 3.0f);  // the box
  EXPECT_NEAR(at("elevation", C(11), C(12)), C(2), 1e-6);
  EXPECT_EQ(at("cost", C(11), C(12)), 1.0f);
  EXPECT_EQ(at("class", C(25), C(3)), 1.0f);  // the floor
  EXPECT_NEAR(at("elevation", C(25), C(3)), C(0), 1e-6);
  const CellInfo floor = map.TopSurfaceAt(C(25), C(3));
  // The slope and step that decided the class: none where the frames' votes did (NaN).
  ASSERT_EQ(floor.decided_by, ClassJudge::kFrames);
  EXPECT_TRUE(std::isnan(at("slope", C(25), C(3))) && std::isnan(at("step", C(25), C(3))));
  EXPECT_NEAR(at("confidence", C(25), C(3)), floor.confidence, 1e-6);
  EXPECT_NEAR(at("cost", C(25), C(3)), floor.cost, 1e-6);
  int classified = 0, with_class = 0;
  for (std::size_t k = 0; k < grid.classes.size(); ++k) classified += grid.classes[k] != 0 ? 1 : 0;
  for (float c : layers.at("class")) with_class += std::isfinite(c) ? 1 : 0;
  EXPECT_EQ(with_class, classified);  // NaN where the grid has no class

  // /traversability/voxels: every occupied voxel, x y z class cost confidence.
  const std::vector<CellInfo> cells = map.SurfaceCells();
  Cdr cloud(bag.messages.at("/traversability/voxels"));
  EXPECT_EQ(cloud.Header(), "map");
  EXPECT_EQ(cloud.Get<std::uint32_t>(), 1u);
  const auto points = cloud.Get<std::uint32_t>();
  EXPECT_EQ(points, cells.size());
  EXPECT_EQ(points, summary.voxels);
  ASSERT_EQ(cloud.Get<std::uint32_t>(), 6u);
  for (const char* field : {"x", "y", "z", "class", "cost", "confidence"}) {
    EXPECT_EQ(cloud.String(), field);
    cloud.Get<std::uint32_t>();
    cloud.Get<std::uint8_t>();
    EXPECT_EQ(cloud.Get<std::uint32_t>(), 1u);
  }
  cloud.Get<std::uint8_t>();
  const auto point_step = cloud.Get<std::uint32_t>();
  EXPECT_EQ(cloud.Get<std::uint32_t>(), point_step * points);
  ASSERT_EQ(cloud.Get<std::uint32_t>(), point_step * points);
  int box_voxels = 0;
  for (std::uint32_t k = 0; k < points; ++k) {
    std::vector<std::uint8_t> point(point_step);
    for (auto& b : point) b = cloud.Get<std::uint8_t>();
    float x, z;
    std::memcpy(&x, point.data(), 4);
    std::memcpy(&z, point.data() + 8, 4);
    EXPECT_NEAR(x, cells[k].center.x(), 1e-6);
    EXPECT_NEAR(z, cells[k].center.z(), 1e-6);
    EXPECT_EQ(point[12], static_cast<std::uint8_t>(cells[k].cls));
    box_voxels += point[12] == 3 ? 1 : 0;
  }
  EXPECT_EQ(box_voxels, 27);  // 3 x 3 x 3
  cloud.Get<std::uint8_t>();
  EXPECT_TRUE(cloud.AtEnd());

  // /sensor_path: the two origins, the first facing the second (-x: yaw pi).
  Cdr path(bag.messages.at("/sensor_path"));
  EXPECT_EQ(path.Header(), "map");
  ASSERT_EQ(path.Get<std::uint32_t>(), 2u);
  EXPECT_EQ(path.Header(), "map");
  EXPECT_NEAR(path.Get<double>(), testing::FloorAndBoxOrigin().x(), 1e-9);
  path.Get<double>();
  path.Get<double>();
  path.Get<double>();
  path.Get<double>();
  EXPECT_NEAR(std::abs(path.Get<double>()), 1.0, 1e-9);  // quaternion z: yaw pi
  EXPECT_NEAR(path.Get<double>(), 0.0, 1e-9);

  // /tf_static: map -> the world frame (unnamed: "world"), identity.
  const std::vector<internal::RosTransform> tf =
      internal::DecodeTfMessage(bag.messages.at("/tf_static"), internal::RosEncoding::kCdr, "tf");
  ASSERT_EQ(tf.size(), 1u);
  EXPECT_EQ(tf[0].header.frame_id, "map");
  EXPECT_EQ(tf[0].child_frame_id, "world");
  EXPECT_EQ(tf[0].translation, (std::array<double, 3>{0, 0, 0}));
  EXPECT_EQ(tf[0].rotation_xyzw, (std::array<double, 4>{0, 0, 0, 1}));
}

TEST(McapExport, HeadingsAddACostLayerPerHeadingEqualToHeadingCosts) {
  // The 20 deg hillside of vehicle_attitude_test.cpp: eight cost_heading layers after the six,
  // each HeadingCosts of the exported grid; across the slope the 15 deg roll limit refuses it.
  TempDir dir;
  const TraversabilityMap map = testing::HillsideMap(20.0, testing::HillsideVehicle());
  McapExportOptions options;
  options.grid.headings.headings = 8;
  ExportMcap(map, dir / "h.mcap", options);
  const GridProjection grid = ProjectAsExported(map, options.grid);
  const std::vector<ImageF> expected = HeadingCosts(grid, map.metadata().vehicle, options.grid.headings);
  const int w = grid.width(), h = grid.height();

  Cdr grid_map(ReadMcap(dir / "h.mcap").messages.at("/traversability"));
  grid_map.Header();
  for (int k = 0; k < 3 + 7; ++k) grid_map.Get<double>();  // resolution, lengths, pose
  std::vector<std::string> names = {"class", "cost", "confidence", "elevation", "slope", "step"};
  for (const char* deg : {"0", "45", "90", "135", "180", "225", "270", "315"}) names.push_back(std::string("cost_heading_") + deg);
  ASSERT_EQ(grid_map.Get<std::uint32_t>(), names.size());
  for (const std::string& name : names) EXPECT_EQ(grid_map.String(), name);
  ASSERT_EQ(grid_map.Get<std::uint32_t>(), 1u);
  grid_map.String();
  ASSERT_EQ(grid_map.Get<std::uint32_t>(), names.size());
  int refused = 0;
  for (std::size_t l = 0; l < names.size(); ++l) {
    ASSERT_EQ(grid_map.Get<std::uint32_t>(), 2u);
    for (int d = 0; d < 2; ++d) {
      grid_map.String();
      grid_map.Get<std::uint32_t>();
      grid_map.Get<std::uint32_t>();
    }
    grid_map.Get<std::uint32_t>();
    ASSERT_EQ(grid_map.Get<std::uint32_t>(), static_cast<std::uint32_t>(w * h));
    for (int j = 0; j < h; ++j) {
      for (int i = 0; i < w; ++i) {
        const float value = grid_map.Get<float>();
        if (l < 6) continue;
        const float want = expected[l - 6](j, w - 1 - i);  // (i, j) is pixel (v, u) = (j, w - 1 - i)
        if (std::isnan(want)) {
          EXPECT_TRUE(std::isnan(value));
        } else {
          EXPECT_EQ(value, want);
          refused += (l == 8 || l == 12) && value == 1.0f ? 1 : 0;
        }
      }
    }
  }
  // Away from the edges (where the footprint runs off the map and its plane is still fine)
  // every cell is refused across: 90 and 270 deg.
  EXPECT_GE(refused, 2 * 30 * 30);
}

TEST(McapExport, UncompressedAndZstdFilesHoldTheSameMessages) {
  TempDir dir;
  const TraversabilityMap map = TwoViewMap();
  McapExportOptions options;
  options.map_frame = "odom";
  options.world_frame = "utm";
  const McapExportSummary zstd = ExportMcap(map, dir / "zstd.mcap", options);
  options.zstd = false;
  const McapExportSummary none = ExportMcap(map, dir / "none.mcap", options);
  EXPECT_LT(zstd.bytes, none.bytes);
  const ReadBack a = ReadMcap(dir / "zstd.mcap"), b = ReadMcap(dir / "none.mcap");
  EXPECT_EQ(a.messages, b.messages);
  Cdr occupancy(a.messages.at("/map"));
  EXPECT_EQ(occupancy.Header(), "odom");
  const std::vector<internal::RosTransform> tf =
      internal::DecodeTfMessage(a.messages.at("/tf_static"), internal::RosEncoding::kCdr, "tf");
  ASSERT_EQ(tf.size(), 1u);
  EXPECT_EQ(tf[0].header.frame_id, "odom");
  EXPECT_EQ(tf[0].child_frame_id, "utm");
}

TEST(McapExport, ACorruptChunkIsFoundByItsCrc) {
  TempDir dir;
  McapExportOptions options;
  options.zstd = false;
  ExportMcap(TwoViewMap(), dir / "map.mcap", options);
  std::fstream file(dir / "map.mcap", std::ios::in | std::ios::out | std::ios::binary);
  file.seekp(2000);  // inside the one uncompressed chunk's records (the grid's message)
  char byte = 0;
  file.read(&byte, 1);
  file.seekp(2000);
  byte = static_cast<char>(byte ^ 0x5A);
  file.write(&byte, 1);
  file.close();
  const std::unique_ptr<internal::BagReader> bag = internal::OpenMcapFile(dir / "map.mcap");
  std::vector<int> all(bag->connections().size());
  for (std::size_t i = 0; i < all.size(); ++i) all[i] = static_cast<int>(i);
  EXPECT_THROW(
      {
        for (const internal::BagMessageRef& ref : bag->List(all)) bag->Read(ref);
      },
      Error);
}

TEST(McapExport, OccupancyValuesFollowTheClassAndCost) {
  const float nan = std::numeric_limits<float>::quiet_NaN();
  EXPECT_EQ(OccupancyGridValue(3, 1.0f), 100);
  EXPECT_EQ(OccupancyGridValue(1, 0.0f), 0);
  EXPECT_EQ(OccupancyGridValue(1, 0.124f), 12);
  EXPECT_EQ(OccupancyGridValue(2, 0.75f), 75);
  EXPECT_EQ(OccupancyGridValue(1, nan), 25);  // a filled hole
  EXPECT_EQ(OccupancyGridValue(2, nan), 75);
  EXPECT_EQ(OccupancyGridValue(0, nan), -1);
  EXPECT_EQ(OccupancyGridValue(4, nan), -1);
}

TEST(McapExport, AMapWithoutSurfaceOrAnEmptyFrameIsRefusedNamingTheFile) {
  TempDir dir;
  try {
    ExportMcap(TraversabilityMap(), dir / "empty.mcap");
    FAIL() << "no error";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("empty.mcap: the map has no observed surface"), std::string::npos) << e.what();
  }
  McapExportOptions options;
  options.map_frame = "";
  EXPECT_THROW(ExportMcap(TwoViewMap(), dir / "m.mcap", options), Error);
  EXPECT_FALSE(std::filesystem::exists(dir / "empty.mcap"));
  EXPECT_FALSE(std::filesystem::exists(dir / "m.mcap"));
}

}  // namespace
}  // namespace ssta
