// The `mcap` export: the map as a ROS 2 bag of latched topics (see ExportMcap).

#include <algorithm>
#include <cmath>
#include <cstring>
#include <fstream>
#include <iterator>
#include <limits>
#include <map>
#include <string>
#include <vector>

#include "mcap/cdr_writer.h"
#include "mcap/mcap_writer.h"
#include "ssta/core/error.h"
#include "ssta/files/file_util.h"
#include "ssta/mapping/map_export.h"

#ifndef SSTA_VERSION
#define SSTA_VERSION "unknown"
#endif

namespace ssta {
namespace {

using internal::CdrWriter;

// The ros2msg definitions (ROS 2 Humble and later; comments dropped). A schema is its message's
// definition followed by those of every type it uses, each after a separator line and
// "MSG: package/Type", as rosbag2 stores them.
const std::map<std::string, std::string>& Definitions() {
  static const std::map<std::string, std::string> kDefinitions = {
      {"builtin_interfaces/Time", "int32 sec\nuint32 nanosec\n"},
      {"std_msgs/Header", "builtin_interfaces/Time stamp\nstring frame_id\n"},
      {"geometry_msgs/Point", "float64 x\nfloat64 y\nfloat64 z\n"},
      {"geometry_msgs/Vector3", "float64 x\nfloat64 y\nfloat64 z\n"},
      {"geometry_msgs/Quaternion", "float64 x 0\nfloat64 y 0\nfloat64 z 0\nfloat64 w 1\n"},
      {"geometry_msgs/Pose", "Point position\nQuaternion orientation\n"},
      {"geometry_msgs/PoseStamped", "std_msgs/Header header\nPose pose\n"},
      {"geometry_msgs/Transform", "Vector3 translation\nQuaternion rotation\n"},
      {"geometry_msgs/TransformStamped", "std_msgs/Header header\nstring child_frame_id\nTransform transform\n"},
      {"nav_msgs/MapMetaData",
       "builtin_interfaces/Time map_load_time\nfloat32 resolution\nuint32 width\nuint32 height\n"
       "geometry_msgs/Pose origin\n"},
      {"nav_msgs/OccupancyGrid", "std_msgs/Header header\nMapMetaData info\nint8[] data\n"},
      {"nav_msgs/Path", "std_msgs/Header header\ngeometry_msgs/PoseStamped[] poses\n"},
      {"std_msgs/MultiArrayDimension", "string label\nuint32 size\nuint32 stride\n"},
      {"std_msgs/MultiArrayLayout", "MultiArrayDimension[] dim\nuint32 data_offset\n"},
      {"std_msgs/Float32MultiArray", "MultiArrayLayout layout\nfloat32[] data\n"},
      {"grid_map_msgs/GridMapInfo",
       "float64 resolution\nfloat64 length_x\nfloat64 length_y\ngeometry_msgs/Pose pose\n"},
      {"grid_map_msgs/GridMap",
       "std_msgs/Header header\nGridMapInfo info\nstring[] layers\nstring[] basic_layers\n"
       "std_msgs/Float32MultiArray[] data\nuint16 outer_start_index\nuint16 inner_start_index\n"},
      {"sensor_msgs/PointField",
       "uint8 INT8=1\nuint8 UINT8=2\nuint8 INT16=3\nuint8 UINT16=4\nuint8 INT32=5\nuint8 UINT32=6\n"
       "uint8 FLOAT32=7\nuint8 FLOAT64=8\nstring name\nuint32 offset\nuint8 datatype\nuint32 count\n"},
      {"sensor_msgs/PointCloud2",
       "std_msgs/Header header\nuint32 height\nuint32 width\nPointField[] fields\nbool is_bigendian\n"
       "uint32 point_step\nuint32 row_step\nuint8[] data\nbool is_dense\n"},
      {"tf2_msgs/TFMessage", "geometry_msgs/TransformStamped[] transforms\n"},
  };
  return kDefinitions;
}

/// The schema text of `type` ("nav_msgs/OccupancyGrid") with the definitions of `uses`.
std::string SchemaText(const std::string& type, const std::vector<std::string>& uses) {
  std::string text = Definitions().at(type);
  for (const std::string& used : uses) {
    text += "================================================================================\nMSG: " + used +
            "\n" + Definitions().at(used);
  }
  return text;
}

/// rosbag2's offered_qos_profiles of a latched publisher (a map server's): keep last 1,
/// reliable, transient local, automatic liveliness, no deadline or lifespan.
const char kLatchedQos[] =
    "- history: 1\n"
    "  depth: 1\n"
    "  reliability: 1\n"
    "  durability: 1\n"
    "  deadline:\n"
    "    sec: 2147483647\n"
    "    nsec: 4294967295\n"
    "  lifespan:\n"
    "    sec: 2147483647\n"
    "    nsec: 4294967295\n"
    "  liveliness: 1\n"
    "  liveliness_lease_duration:\n"
    "    sec: 2147483647\n"
    "    nsec: 4294967295\n"
    "  avoid_ros_namespace_conventions: false\n";

void Pose(CdrWriter* w, double x, double y, double z, double yaw) {
  w->F64(x);
  w->F64(y);
  w->F64(z);
  w->F64(0.0);
  w->F64(0.0);
  w->F64(std::sin(0.5 * yaw));
  w->F64(std::cos(0.5 * yaw));
}

std::vector<std::uint8_t> OccupancyGridMessage(const GridProjection& grid, std::int64_t stamp_ns,
                                               const std::string& frame) {
  const int w = grid.width(), h = grid.height();
  CdrWriter m;
  m.Header(stamp_ns, frame);
  m.Time(stamp_ns);  // map_load_time
  m.F32(static_cast<float>(grid.resolution_m));
  m.U32(static_cast<std::uint32_t>(w));
  m.U32(static_cast<std::uint32_t>(h));
  Pose(&m, grid.origin.x(), grid.origin.y(), 0.0, 0.0);
  m.U32(static_cast<std::uint32_t>(w) * static_cast<std::uint32_t>(h));
  // Row 0 of the message is the smallest y, the image's last row.
  for (int v = h - 1; v >= 0; --v) {
    for (int u = 0; u < w; ++u) m.I8(OccupancyGridValue(grid.classes(v, u), grid.cost(v, u)));
  }
  return m.Take();
}

std::vector<std::uint8_t> GridMapMessage(const GridProjection& grid, const std::vector<ImageF>& heading_costs,
                                         std::int64_t stamp_ns, const std::string& frame) {
  const int w = grid.width(), h = grid.height();
  const double res = grid.resolution_m;
  const float nan = std::numeric_limits<float>::quiet_NaN();
  CdrWriter m;
  m.Header(stamp_ns, frame);
  m.F64(res);
  m.F64(w * res);  // length_x
  m.F64(h * res);  // length_y
  Pose(&m, grid.origin.x() + 0.5 * w * res, grid.origin.y() + 0.5 * h * res, 0.0, 0.0);
  std::vector<std::string> layers = {"class", "cost", "confidence", "elevation", "slope", "step"};
  const int headings = static_cast<int>(heading_costs.size());
  for (int k = 0; k < headings; ++k) layers.push_back("cost_heading_" + HeadingName(k, headings));
  m.U32(static_cast<std::uint32_t>(layers.size()));
  for (const std::string& layer : layers) m.String(layer);
  m.U32(1);
  m.String("class");  // basic_layers: a cell is valid where it has a class
  m.U32(static_cast<std::uint32_t>(layers.size()));
  // grid_map index (i, j): i along -x from the largest x (rows, size w), j along -y from the
  // largest y (columns, size h); stored column-major, so i runs fastest. Image pixel (v, u) is
  // (i, j) = (w - 1 - u, v).
  std::vector<float> values(static_cast<std::size_t>(w) * static_cast<std::size_t>(h));
  for (std::size_t l = 0; l < layers.size(); ++l) {
    const std::string& layer = layers[l];
    const ImageF* heading = l >= 6 ? &heading_costs[l - 6] : nullptr;
    for (int j = 0; j < h; ++j) {
      for (int i = 0; i < w; ++i) {
        const int v = j, u = w - 1 - i;
        float value = nan;
        if (heading != nullptr) {
          value = (*heading)(v, u);
        } else if (layer == "class") {
          const std::uint8_t c = grid.classes(v, u);
          value = c == static_cast<std::uint8_t>(TravClass::kUnknown) ? nan : static_cast<float>(c);
        } else if (layer == "cost") {
          value = grid.cost(v, u);
        } else if (layer == "confidence") {
          value = grid.confidence.size() == grid.classes.size() ? grid.confidence(v, u) : nan;
        } else if (layer == "elevation") {
          value = grid.height_m(v, u);
        } else if (layer == "slope") {
          value = grid.slope_deg(v, u);
        } else {
          value = grid.step_m(v, u);
        }
        values[static_cast<std::size_t>(i) + static_cast<std::size_t>(j) * static_cast<std::size_t>(w)] = value;
      }
    }
    m.U32(2);  // layout.dim
    m.String("column_index");
    m.U32(static_cast<std::uint32_t>(h));
    m.U32(static_cast<std::uint32_t>(w * h));
    m.String("row_index");
    m.U32(static_cast<std::uint32_t>(w));
    m.U32(static_cast<std::uint32_t>(w));
    m.U32(0);  // layout.data_offset
    m.U32(static_cast<std::uint32_t>(values.size()));
    m.F32s(values.data(), values.size());
  }
  m.U16(0);  // outer_start_index
  m.U16(0);  // inner_start_index
  return m.Take();
}

std::vector<std::uint8_t> VoxelCloudMessage(const std::vector<CellInfo>& cells, std::int64_t stamp_ns,
                                            const std::string& frame) {
  struct Field {
    const char* name;
    std::uint32_t offset;
    std::uint8_t datatype;  // sensor_msgs/PointField: UINT8 2, FLOAT32 7
  };
  constexpr Field kFields[] = {{"x", 0, 7},      {"y", 4, 7},     {"z", 8, 7},
                               {"class", 12, 2}, {"cost", 16, 7}, {"confidence", 20, 7}};
  constexpr std::uint32_t kPointStep = 24;
  CdrWriter m;
  m.Header(stamp_ns, frame);
  m.U32(1);  // height
  m.U32(static_cast<std::uint32_t>(cells.size()));
  m.U32(static_cast<std::uint32_t>(std::size(kFields)));
  for (const Field& f : kFields) {
    m.String(f.name);
    m.U32(f.offset);
    m.U8(f.datatype);
    m.U32(1);
  }
  m.U8(0);  // is_bigendian
  m.U32(kPointStep);
  m.U32(kPointStep * static_cast<std::uint32_t>(cells.size()));
  std::vector<std::uint8_t> data(kPointStep * cells.size(), 0);
  for (std::size_t k = 0; k < cells.size(); ++k) {
    const CellInfo& c = cells[k];
    const float xyz[3] = {static_cast<float>(c.center.x()), static_cast<float>(c.center.y()),
                          static_cast<float>(c.center.z())};
    const float cost = static_cast<float>(c.cost), confidence = static_cast<float>(c.confidence);
    std::uint8_t* p = data.data() + k * kPointStep;
    std::memcpy(p, xyz, sizeof(xyz));
    p[12] = static_cast<std::uint8_t>(c.cls);
    std::memcpy(p + 16, &cost, 4);
    std::memcpy(p + 20, &confidence, 4);
  }
  m.U32(static_cast<std::uint32_t>(data.size()));
  m.Bytes(data.data(), data.size());
  m.U8(0);  // is_dense: cost and confidence are NaN for voxels without a class 1..3
  return m.Take();
}

std::vector<std::uint8_t> PathMessage(const std::vector<Eigen::Vector3d>& path, std::int64_t stamp_ns,
                                      const std::string& frame) {
  CdrWriter m;
  m.Header(stamp_ns, frame);
  m.U32(static_cast<std::uint32_t>(path.size()));
  double yaw = 0.0;
  for (std::size_t k = 0; k < path.size(); ++k) {
    // Facing the next pose (the last keeps the heading it came with).
    if (k + 1 < path.size()) {
      const Eigen::Vector3d d = path[k + 1] - path[k];
      if (d.head<2>().norm() > 0.0) yaw = std::atan2(d.y(), d.x());
    }
    m.Header(stamp_ns, frame);
    Pose(&m, path[k].x(), path[k].y(), path[k].z(), yaw);
  }
  return m.Take();
}

std::vector<std::uint8_t> TfStaticMessage(const std::string& parent, const std::string& child, std::int64_t stamp_ns) {
  CdrWriter m;
  if (parent == child) {
    m.U32(0);
    return m.Take();
  }
  m.U32(1);
  m.Header(stamp_ns, parent);
  m.String(child);
  for (int k = 0; k < 3; ++k) m.F64(0.0);      // translation
  for (double q : {0.0, 0.0, 0.0, 1.0}) m.F64(q);  // rotation
  return m.Take();
}

}  // namespace

std::int8_t OccupancyGridValue(std::uint8_t cls, float cost) {
  switch (static_cast<TravClass>(cls)) {
    case TravClass::kNonTraversable: return 100;
    case TravClass::kTraversable:
      return std::isfinite(cost) ? static_cast<std::int8_t>(std::lround(std::clamp(cost, 0.0f, 0.99f) * 100.0f)) : 25;
    case TravClass::kSemiTraversable:
      return std::isfinite(cost) ? static_cast<std::int8_t>(std::lround(std::clamp(cost, 0.0f, 0.99f) * 100.0f)) : 75;
    default: return -1;
  }
}

McapExportSummary ExportMcap(const TraversabilityMap& map, const std::string& path, const McapExportOptions& options) {
  if (options.map_frame.empty()) throw Error(path + ": the map frame must not be empty");
  McapExportSummary summary;
  GridExportOptions grid_options = options.grid;
  if (grid_options.region.isEmpty()) {
    const Eigen::AlignedBox3d bounds = map.SurfaceBounds();
    if (bounds.isEmpty()) throw Error(path + ": the map has no observed surface to export (give a region)");
    grid_options.region = Eigen::AlignedBox2d(bounds.min().head<2>(), bounds.max().head<2>());
  }
  std::string error;
  if (!grid_options.headings.IsValid(&error)) throw Error(path + ": heading costs: " + error);
  const GridProjection grid = ProjectAsExported(map, grid_options, &summary.changes);
  const std::vector<ImageF> heading_costs = grid_options.headings.headings > 0
                                                ? HeadingCosts(grid, map.metadata().vehicle, grid_options.headings)
                                                : std::vector<ImageF>{};
  const std::vector<CellInfo> voxels = map.SurfaceCells();
  const std::string world_frame = !options.world_frame.empty()          ? options.world_frame
                                  : !map.metadata().world_frame.empty() ? map.metadata().world_frame
                                                                        : std::string("world");
  const std::int64_t stamp_ns = std::max<std::int64_t>(map.last_timestamp_ns(), 0);
  const auto log_time = static_cast<std::uint64_t>(stamp_ns);

  WriteFileAtomically(path, [&](const std::string& tmp) {
    std::ofstream out(tmp, std::ios::binary);
    if (!out) throw Error(path + ": cannot open for writing");
    internal::McapWriterOptions writer_options;
    writer_options.compression = options.zstd ? internal::McapCompression::kZstd : internal::McapCompression::kNone;
    writer_options.library = std::string("ssta ") + SSTA_VERSION;
    internal::McapWriter writer(&out, path, writer_options);
    const std::map<std::string, std::string> latched = {{"offered_qos_profiles", kLatchedQos}};
    auto channel = [&](const std::string& topic, const std::string& type, const std::vector<std::string>& uses) {
      const std::string ros2_type = type.substr(0, type.find('/')) + "/msg" + type.substr(type.find('/'));
      const std::uint16_t schema = writer.AddSchema(ros2_type, "ros2msg", SchemaText(type, uses));
      return writer.AddChannel(schema, topic, "cdr", latched);
    };
    const std::vector<std::string> pose = {"geometry_msgs/Point", "geometry_msgs/Quaternion"};
    const std::vector<std::string> header = {"std_msgs/Header", "builtin_interfaces/Time"};
    auto join = [](std::vector<std::string> a, const std::vector<std::string>& b) {
      a.insert(a.end(), b.begin(), b.end());
      return a;
    };
    const std::uint16_t tf = channel(
        "/tf_static", "tf2_msgs/TFMessage",
        join(join({"geometry_msgs/TransformStamped"}, header),
             {"geometry_msgs/Transform", "geometry_msgs/Vector3", "geometry_msgs/Quaternion"}));
    const std::uint16_t occupancy =
        channel("/map", "nav_msgs/OccupancyGrid",
                join(join(header, {"nav_msgs/MapMetaData", "geometry_msgs/Pose"}), pose));
    const std::uint16_t grid_map = channel(
        "/traversability", "grid_map_msgs/GridMap",
        join(join(join(header, {"grid_map_msgs/GridMapInfo", "geometry_msgs/Pose"}), pose),
             {"std_msgs/Float32MultiArray", "std_msgs/MultiArrayLayout", "std_msgs/MultiArrayDimension"}));
    const std::uint16_t cloud =
        channel("/traversability/voxels", "sensor_msgs/PointCloud2", join(header, {"sensor_msgs/PointField"}));
    const std::uint16_t sensor_path = channel(
        "/sensor_path", "nav_msgs/Path",
        join(join(header, {"geometry_msgs/PoseStamped", "geometry_msgs/Pose"}), pose));

    writer.Write(tf, log_time, log_time, TfStaticMessage(options.map_frame, world_frame, stamp_ns));
    writer.Write(occupancy, log_time, log_time, OccupancyGridMessage(grid, stamp_ns, options.map_frame));
    writer.Write(grid_map, log_time, log_time, GridMapMessage(grid, heading_costs, stamp_ns, options.map_frame));
    writer.Write(cloud, log_time, log_time, VoxelCloudMessage(voxels, stamp_ns, options.map_frame));
    writer.Write(sensor_path, log_time, log_time, PathMessage(map.sensor_path(), stamp_ns, options.map_frame));
    const internal::McapWriteSummary written = writer.Finish();
    summary.bytes = written.bytes;
    summary.chunks = written.chunks;
    out.close();
    if (!out) throw Error(path + ": write failed (disk full?)");
  });
  summary.grid_width = grid.width();
  summary.grid_height = grid.height();
  summary.voxels = voxels.size();
  summary.path_poses = map.sensor_path().size();
  return summary;
}

}  // namespace ssta
