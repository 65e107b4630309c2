// Google Benchmark cases for every stage of the per-frame chain and the map update, on rendered
// 640x480 (yard) and 1242x375 (KITTI-size) frames, end to end, and the same frames through a
// stock chain built from PCL's own classes and OctoMap's insertPointCloud, with the ratios
// printed after the run. Run with
//   stage_benchmark --benchmark_repetitions=5 --benchmark_report_aggregates_only=true
// and read medians (docs/performance.md). PCL and OctoMap headers stay in this file.

#include <benchmark/benchmark.h>
#include <opencv2/core/utility.hpp>

#include <cstdio>
#include <functional>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include <octomap/octomap.h>
#include <pcl/common/centroid.h>
#include <pcl/common/eigen.h>
#include <pcl/features/integral_image_normal.h>
#include <pcl/filters/voxel_grid.h>
#include <pcl/point_cloud.h>
#include <pcl/point_types.h>
#include <pcl/segmentation/ground_plane_comparator.h>
#include <pcl/segmentation/organized_connected_component_segmentation.h>
#include <pcl/segmentation/organized_multi_plane_segmentation.h>
#include <pcl/segmentation/plane_refinement_comparator.h>

#include "ssta/analysis/frame_analysis.h"
#include "ssta/fusion/frame_points.h"
#include "ssta/analysis/surface_analyzer.h"
#include "ssta/core/units.h"
#include "ssta/eval/label_evaluator.h"
#include "ssta/geometry/normal_estimator.h"
#include "ssta/geometry/segmenter.h"
#include "ssta/io/image_io.h"
#include "ssta/io/sequence.h"
#include "ssta/mapping/traversability_map.h"
#include "ssta/pipeline/config.h"
#include "ssta/pipeline/frame_pipeline.h"
#include "ssta/pipeline/map_builder.h"
#include "ssta/mount/ground_evidence.h"
#include "ssta/mount/online_mount_refiner.h"
#include "ssta/stereo/rectifier.h"
#include "ssta/stereo/stereo_matcher.h"
#include "ssta/stereo/triangulator.h"
#include "ssta/synth/scene.h"
#include "ssta/synth/sequence_synthesizer.h"
#include "ssta/synth/stereo_renderer.h"
#include "ssta/synth/vehicle_trajectory.h"

namespace ssta {
namespace {

constexpr int kFramesPerDataset = 4;

/// One rendered frame with everything each stage needs as input, computed once.
struct BenchFrame {
  ImageU8 left, right;
  Eigen::Vector3d up_camera = Eigen::Vector3d::UnitY();  ///< up in cam0
  Eigen::Isometry3d world_T_rectified = Eigen::Isometry3d::Identity();
  std::int64_t timestamp_ns = 0;
  RectifiedPair rectified;
  FrameResult result;  ///< FramePipeline::Process with the dataset's config
  Image3f normals;     ///< NormalEstimator with the dataset's config
  ImageU8 truth;       ///< the renderer's class ids, 255 don't care
};

/// Frames of one rig, rendered in memory from the yard scene, with the pipeline config for it.
struct Dataset {
  std::string name;
  StereoCalibration calibration;
  Config config;
  std::vector<BenchFrame> frames;
};

Dataset Render(const std::string& name, const synth::RigOptions& rig, const Config& config) {
  synth::SynthOptions o;
  o.rig = rig;
  o.vehicle = config.vehicle;
  const synth::Scene scene = synth::MakeScene("yard", o.seed, o.ramp_slope_deg);
  const synth::VehicleTrajectory trajectory(scene, o.motion);
  const synth::StereoRenderer renderer(scene, o.rig, o.render, nullptr, o.seed);
  const Eigen::Isometry3d body_T_cam0 = synth::TrueBodyTCam0(o.rig, o.motion);

  Dataset d;
  d.name = name;
  d.config = config;
  d.calibration.left = renderer.Intrinsics();
  d.calibration.right = renderer.Intrinsics();
  d.calibration.left.body_T_camera = body_T_cam0;
  d.calibration.right.body_T_camera = body_T_cam0 * Eigen::Translation3d(rig.baseline_m, 0, 0);
  FramePipeline pipeline(d.calibration, d.config);
  NormalEstimator normals(d.config.normals);
  const Rectifier rectifier(d.calibration, d.config.rectification);
  Eigen::Isometry3d body_T_rectified = body_T_cam0;
  body_T_rectified.linear() = body_T_cam0.linear() * rectifier.geometry().rectified_R_camera.transpose();
  for (int k = 0; k < kFramesPerDataset; ++k) {
    const double t = 1.0 + k / rig.rate_hz;
    const Eigen::Isometry3d world_T_body = trajectory.WorldTBody(t);
    const synth::StereoFrame pair = renderer.Render(world_T_body * body_T_cam0, k);
    BenchFrame f;
    f.left = pair.left;
    f.right = pair.right;
    f.truth = pair.labels;
    f.up_camera = (body_T_cam0.linear().transpose() * world_T_body.linear().transpose() * Eigen::Vector3d::UnitZ())
                      .normalized();
    f.world_T_rectified = world_T_body * body_T_rectified;
    f.timestamp_ns = static_cast<std::int64_t>(t * 1e9);
    f.rectified = rectifier.Rectify(f.left, f.right);
    f.result = pipeline.Process(f.left, f.right, f.up_camera);
    f.result.timestamp_ns = f.timestamp_ns;
    f.normals = normals.Compute(f.result.cloud);
    d.frames.push_back(std::move(f));
  }
  return d;
}

const Dataset& Vga() {
  static const Dataset d = Render("vga", synth::RigOptions{}, Config{});
  return d;
}

/// KITTI's grey rig: 1242x375, f = 718.856 px, baseline 0.537 m, level, 1.65 m high, with
/// config/sensors/kitti.yaml (96 disparities, 30 m range, camera height 1.2..2.2 m).
const Dataset& Kitti() {
  static const Dataset d = [] {
    synth::RigOptions rig;
    rig.width = 1242;
    rig.height = 375;
    rig.focal_px = 718.856;
    rig.baseline_m = 0.537;
    rig.camera_height_m = 1.65;
    rig.pitch_down_deg = 0.0;
    rig.rate_hz = 10.0;
    Config config;
    ApplyConfigFile(std::string(SSTA_CONFIG_DIR) + "/sensors/kitti.yaml", &config);
    return Render("kitti", rig, config);
  }();
  return d;
}

/// Cycles through a dataset's frames, one per iteration.
class FrameCycle {
 public:
  explicit FrameCycle(const Dataset& d) : d_(d) {}
  const BenchFrame& Next() { return d_.frames[i_++ % d_.frames.size()]; }

 private:
  const Dataset& d_;
  std::size_t i_ = 0;
};

void CountFrames(benchmark::State& state) {
  state.counters["frames/s"] = benchmark::Counter(static_cast<double>(state.iterations()),
                                                  benchmark::Counter::kIsRate);
}

// ---- Our stages ---------------------------------------------------------------------------

void BM_Rectify(benchmark::State& state, const Dataset* d) {
  const Rectifier rectifier(d->calibration, d->config.rectification);
  FrameCycle frames(*d);
  for (auto _ : state) {
    const BenchFrame& f = frames.Next();
    benchmark::DoNotOptimize(rectifier.Rectify(f.left, f.right));
  }
  CountFrames(state);
}

void BM_Match(benchmark::State& state, const Dataset* d, MatcherType type) {
  StereoMatcherOptions options = d->config.stereo;
  options.algorithm = type;
  const StereoMatcher matcher(options);
  FrameCycle frames(*d);
  for (auto _ : state) {
    const BenchFrame& f = frames.Next();
    benchmark::DoNotOptimize(matcher.Compute(f.rectified.left, f.rectified.right));
  }
  CountFrames(state);
}

void BM_Triangulate(benchmark::State& state, const Dataset* d) {
  const Rectifier rectifier(d->calibration, d->config.rectification);
  FrameCycle frames(*d);
  for (auto _ : state) {
    benchmark::DoNotOptimize(Triangulate(frames.Next().result.disparity, rectifier.geometry(), d->config.triangulation));
  }
  CountFrames(state);
}

/// threads: NormalOptions::threads (0 = the config's own value).
void BM_Normals(benchmark::State& state, const Dataset* d, NormalMethod method, int threads = 0) {
  NormalOptions options = d->config.normals;
  options.method = method;
  if (threads > 0) options.threads = threads;
  NormalEstimator estimator(options);
  FrameCycle frames(*d);
  for (auto _ : state) {
    benchmark::DoNotOptimize(&estimator.Compute(frames.Next().result.cloud));
  }
  CountFrames(state);
}

void BM_Segment(benchmark::State& state, const Dataset* d) {
  Segmenter segmenter(d->config.segmentation);
  FrameCycle frames(*d);
  for (auto _ : state) {
    const BenchFrame& f = frames.Next();
    benchmark::DoNotOptimize(&segmenter.Compute(f.normals, &f.result.disparity));
  }
  CountFrames(state);
}

/// The whole analysis after segmentation, as FramePipeline runs it (FrameAnalyzer: planes, classes
/// and every label refinement of the config).
void BM_Analyze(benchmark::State& state, const Dataset* d) {
  const RectifiedGeometry geometry = Rectifier(d->calibration, d->config.rectification).geometry();
  FrameAnalyzer analyzer(d->config.vehicle, d->config.analysis);
  FrameCycle frames(*d);
  for (auto _ : state) {
    const BenchFrame& f = frames.Next();
    benchmark::DoNotOptimize(analyzer.Analyze({&geometry, &f.result.disparity, &f.result.cloud, &f.normals,
                                               &f.result.segment_ids, f.result.num_segments, f.result.up_rectified}));
  }
  CountFrames(state);
}

/// The texture test of analysis.label_min_texture (and map.min_texture) on one frame.
void BM_TextureMask(benchmark::State& state, const Dataset* d) {
  const RectifiedGeometry geometry = Rectifier(d->calibration, d->config.rectification).geometry();
  FrameCycle frames(*d);
  for (auto _ : state) {
    benchmark::DoNotOptimize(TexturedPixels(frames.Next().rectified.left_full, geometry, d->config.stereo.block_size,
                                            d->config.analysis.label_min_texture));
  }
  CountFrames(state);
}

/// Normals through classes: the "geometry" budget. threads as BM_Normals.
void BM_Geometry(benchmark::State& state, const Dataset* d, int threads = 0) {
  const RectifiedGeometry geometry = Rectifier(d->calibration, d->config.rectification).geometry();
  NormalOptions normal_options = d->config.normals;
  if (threads > 0) normal_options.threads = threads;
  NormalEstimator estimator(normal_options);
  Segmenter segmenter(d->config.segmentation);
  FrameAnalyzer analyzer(d->config.vehicle, d->config.analysis);
  FrameCycle frames(*d);
  for (auto _ : state) {
    const BenchFrame& f = frames.Next();
    const Image3f& normals = estimator.Compute(f.result.cloud);
    const Segmentation& s = segmenter.Compute(normals, &f.result.disparity);
    benchmark::DoNotOptimize(analyzer.Analyze({&geometry, &f.result.disparity, &f.result.cloud, &normals, &s.labels,
                                               s.num_segments(), f.result.up_rectified}));
  }
  CountFrames(state);
}

/// The map's sub-pixel refinement of one frame's disparity (map.subpixel_window_px, one step,
/// within segments), as MapPointsOfFrame runs it.
void BM_MapSubpixel(benchmark::State& state, const Dataset* d) {
  FrameCycle frames(*d);
  ImageF refined;
  for (auto _ : state) {
    const BenchFrame& f = frames.Next();
    refined = f.result.disparity;
    RefineDisparitySubpixel(f.rectified.left, f.rectified.right, d->config.map.subpixel_window_px, kMapSubpixelSteps,
                            &refined, &f.result.segment_ids);
    benchmark::DoNotOptimize(refined.data());
  }
  CountFrames(state);
}

/// MapPointsOfFrame alone: the points a frame inserts (texture mask, sub-pixel refinement).
void BM_MapPoints(benchmark::State& state, const Dataset* d) {
  const RectifiedGeometry geometry = Rectifier(d->calibration, d->config.rectification).geometry();
  FrameCycle frames(*d);
  std::vector<ClassifiedPoint> points;
  for (auto _ : state) {
    const BenchFrame& f = frames.Next();
    MapPointsOfFrame(f.result, f.world_T_rectified, d->config.map, geometry, d->config.vehicle, &points);
    benchmark::DoNotOptimize(points.data());
  }
  CountFrames(state);
}

/// MapPointsOfFrame + InsertFrame into one map that keeps growing over the iterations
/// (the frames cycle, so after the first round it revisits the same voxels).
void BM_MapUpdate(benchmark::State& state, const Dataset* d) {
  TraversabilityMap map(d->config.map.fusion);
  const RectifiedGeometry geometry = Rectifier(d->calibration, d->config.rectification).geometry();
  FrameCycle frames(*d);
  for (auto _ : state) {
    const BenchFrame& f = frames.Next();
    const auto points = MapPointsOfFrame(f.result, f.world_T_rectified, d->config.map, geometry, d->config.vehicle);
    benchmark::DoNotOptimize(map.InsertFrame(points, f.world_T_rectified.translation(), f.timestamp_ns));
  }
  CountFrames(state);
  state.counters["map_nodes"] = static_cast<double>(map.NumNodes());
}

/// A map of the dataset's frames, each inserted once: what the query cases ask.
TraversabilityMap MapOfFrames(const Dataset& d, bool smeared_surface_hazards = true) {
  MapOptions options = d.config.map.fusion;
  options.class_smeared_surface_hazards = smeared_surface_hazards;
  TraversabilityMap map(options);
  const RectifiedGeometry geometry = Rectifier(d.calibration, d.config.rectification).geometry();
  for (const BenchFrame& f : d.frames) {
    map.InsertFrame(MapPointsOfFrame(f.result, f.world_T_rectified, d.config.map, geometry, d.config.vehicle),
                    f.world_T_rectified.translation(), f.timestamp_ns);
  }
  return map;
}

/// The centres of the map's columns over its surface's bounds, row by row.
std::vector<Eigen::Vector2d> ColumnCentres(const TraversabilityMap& map) {
  const Eigen::AlignedBox3d box = map.SurfaceBounds();
  const double res = map.options().resolution_m;
  std::vector<Eigen::Vector2d> centres;
  for (double y = box.min().y() + 0.5 * res; y < box.max().y(); y += res) {
    for (double x = box.min().x() + 0.5 * res; x < box.max().x(); x += res) centres.emplace_back(x, y);
  }
  return centres;
}

/// TopSurfaceAt of every column over the map's bounds (one iteration: the whole sweep), the
/// judge behind `export`, `query` and `eval footprints`: the fused surface within the step
/// radius and the frames' votes of each column, far columns judged again over their smear
/// (map.class_smeared_surface_hazards, shipped on); MapJudgeUnsmeared with that key off.
void BM_MapJudge(benchmark::State& state, const Dataset* d, bool smeared_surface_hazards) {
  const TraversabilityMap map = MapOfFrames(*d, smeared_surface_hazards);
  const std::vector<Eigen::Vector2d> centres = ColumnCentres(map);
  std::size_t observed = 0;
  for (auto _ : state) {
    observed = 0;
    for (const Eigen::Vector2d& c : centres) observed += map.TopSurfaceAt(c.x(), c.y()).observed ? 1 : 0;
    benchmark::DoNotOptimize(observed);
  }
  state.counters["columns/s"] = benchmark::Counter(static_cast<double>(state.iterations() * centres.size()),
                                                   benchmark::Counter::kIsRate);
  state.counters["observed_columns"] = static_cast<double>(observed);
}

/// QueryFootprint of a 1.0 x 0.6 m robot every 0.5 m over the map's bounds at headings 0, 45,
/// 90 and 135 deg (one iteration: all of them), as `eval footprints` asks the map.
void BM_MapFootprints(benchmark::State& state, const Dataset* d) {
  const TraversabilityMap map = MapOfFrames(*d);
  const Eigen::AlignedBox3d box = map.SurfaceBounds();
  std::vector<FootprintQuery> queries;
  for (double y = box.min().y(); y <= box.max().y(); y += 0.5) {
    for (double x = box.min().x(); x <= box.max().x(); x += 0.5) {
      for (const double yaw_deg : {0.0, 45.0, 90.0, 135.0}) queries.push_back({x, y, DegToRad(yaw_deg), 1.0, 0.6});
    }
  }
  for (auto _ : state) {
    int blocked = 0;
    for (const FootprintQuery& q : queries) {
      blocked += map.QueryFootprint(q).worst == TravClass::kNonTraversable ? 1 : 0;
    }
    benchmark::DoNotOptimize(blocked);
  }
  state.counters["footprints/s"] = benchmark::Counter(static_cast<double>(state.iterations() * queries.size()),
                                                      benchmark::Counter::kIsRate);
}

/// The online mount refinement's cost per frame (build-map --refine): ground evidence from the
/// processed frame, the sliding-window update and, every refinement.solve_every_frames frames,
/// the Ceres solve + covariance over refinement.window_frames frames, amortized over the frames.
void BM_OnlineRefinement(benchmark::State& state, const Dataset* d) {
  const Eigen::Matrix3d camera_R_rectified =
      Rectifier(d->calibration, d->config.rectification).geometry().rectified_R_camera.transpose();
  const Eigen::Isometry3d& mount = d->calibration.left.body_T_camera;
  OnlineMountRefiner online(d->config.refinement, mount, mount);
  FrameCycle frames(*d);
  for (auto _ : state) {
    const BenchFrame& f = frames.Next();
    GroundEvidence evidence =
        ExtractGroundEvidence(f.result, camera_R_rectified, Eigen::Vector3d::UnitZ(), d->config.refinement);
    benchmark::DoNotOptimize(online.AddFrame(std::move(evidence)));
  }
  CountFrames(state);
  state.counters["solves"] = online.summary().solves;
  state.counters["solve_ms"] = online.summary().solves > 0 ? online.summary().solve_ms / online.summary().solves : 0.0;
}

void BM_EndToEnd(benchmark::State& state, const Dataset* d) {
  FramePipeline pipeline(d->calibration, d->config);
  FrameCycle frames(*d);
  for (auto _ : state) {
    const BenchFrame& f = frames.Next();
    benchmark::DoNotOptimize(pipeline.Process(f.left, f.right, f.up_camera));
  }
  CountFrames(state);
}

void BM_EndToEndWithMap(benchmark::State& state, const Dataset* d) {
  FramePipeline pipeline(d->calibration, d->config);
  TraversabilityMap map(d->config.map.fusion);
  FrameCycle frames(*d);
  for (auto _ : state) {
    const BenchFrame& f = frames.Next();
    const FrameResult r = pipeline.Process(f.left, f.right, f.up_camera);
    const auto points = MapPointsOfFrame(r, f.world_T_rectified, d->config.map, pipeline.geometry(), d->config.vehicle);
    benchmark::DoNotOptimize(map.InsertFrame(points, f.world_T_rectified.translation(), f.timestamp_ns));
  }
  CountFrames(state);
}

// ---- Recorded pairs ------------------------------------------------------------------------

/// The first frame of a recorded sequence under tests/data, with its calibration.
struct RecordedPair {
  StereoCalibration calibration;
  Config config;
  ImageU8 left, right;
};

RecordedPair LoadRecorded(const std::string& folder, const std::vector<std::string>& configs) {
  const Sequence sequence = Sequence::Open(std::string(SSTA_TEST_DATA_DIR) + "/" + folder);
  RecordedPair p;
  p.calibration = sequence.calibration();
  if (sequence.vehicle_config()) ApplyConfigFile(*sequence.vehicle_config(), &p.config);
  for (const std::string& c : configs) ApplyConfigFile(std::string(SSTA_CONFIG_DIR) + "/" + c, &p.config);
  p.left = ReadGreyImage(sequence.frames().front().left_path);
  p.right = ReadGreyImage(sequence.frames().front().right_path);
  return p;
}

/// Rectification with a real remap: EuRoC's 752x480 rig has radial distortion (k1 = -0.28),
/// where the rendered rigs above are already rectified and only get cropped.
void BM_RectifyEuroc(benchmark::State& state) {
  static const RecordedPair p = LoadRecorded("euroc-v1-01-mini", {"sensors/euroc.yaml"});
  const Rectifier rectifier(p.calibration, p.config.rectification);
  for (auto _ : state) benchmark::DoNotOptimize(rectifier.Rectify(p.left, p.right));
  CountFrames(state);
}

/// The whole chain on a real KITTI street pair (1241x376) with config/sensors/kitti.yaml.
void BM_EndToEndKittiPair(benchmark::State& state) {
  static const RecordedPair p = LoadRecorded("kitti-street-pair", {"sensors/kitti.yaml"});
  FramePipeline pipeline(p.calibration, p.config);
  const Eigen::Vector3d up_camera = pipeline.UpInCamera(Eigen::Vector3d::UnitZ());
  for (auto _ : state) benchmark::DoNotOptimize(pipeline.Process(p.left, p.right, up_camera));
  CountFrames(state);
}

// ---- The stock chain: PCL's classes as its stereo_ground_segmentation demo chains them ------

/// Labels of one frame from PCL's classes, with the demo's parameters: integral-image normals
/// (covariance, depth change 0.03, smoothing 40), connected components under a ground-plane
/// comparator (expected normal = up, 10 degrees to it, 3 degrees between neighbours), a plane
/// per region of more than 1000 points, OrganizedMultiPlaneSegmentation::refine with a
/// plane-refinement comparator (0.15 m). Regions of more than 1000 points after the
/// refinement are traversable, every other point non-traversable, no point unknown.
class StockLabeller {
 public:
  using Cloud = pcl::PointCloud<pcl::PointXYZ>;

  StockLabeller() : ground_(new pcl::GroundPlaneComparator<pcl::PointXYZ, pcl::Normal>), components_(ground_) {
    normals_.setNormalEstimationMethod(normals_.COVARIANCE_MATRIX);
    normals_.setMaxDepthChangeFactor(0.03f);
    normals_.setNormalSmoothingSize(40.0f);
    ground_->setGroundAngularThreshold(pcl::deg2rad(10.0f));
    ground_->setAngularThreshold(pcl::deg2rad(3.0f));
  }

  ImageU8 Label(const Image3f& cloud_camera, const Eigen::Vector3d& up_camera) {
    Cloud::Ptr cloud(new Cloud(static_cast<std::uint32_t>(cloud_camera.width()),
                               static_cast<std::uint32_t>(cloud_camera.height())));
    cloud->is_dense = false;
    for (std::size_t i = 0; i < cloud_camera.size(); ++i) {
      const Eigen::Vector3f& p = cloud_camera[i];
      (*cloud)[i].x = p.x();
      (*cloud)[i].y = p.y();
      (*cloud)[i].z = p.z();
    }
    pcl::PointCloud<pcl::Normal>::Ptr normals(new pcl::PointCloud<pcl::Normal>);
    normals_.setInputCloud(cloud);
    normals_.compute(*normals);

    ground_->setExpectedGroundNormal(up_camera.cast<float>());
    ground_->setInputCloud(cloud);
    ground_->setInputNormals(normals);
    pcl::PointCloud<pcl::Label>::Ptr labels(new pcl::PointCloud<pcl::Label>);
    std::vector<pcl::PointIndices> regions;
    components_.setInputCloud(cloud);
    components_.segment(*labels, regions);

    // A plane per large region, then the refinement that grows those planes.
    std::vector<pcl::ModelCoefficients> models;
    std::vector<pcl::PointIndices> inliers;
    std::vector<bool> refine(regions.size(), false);
    std::vector<int> label_to_model(regions.size(), 0);
    for (const pcl::PointIndices& region : regions) {
      if (region.indices.size() <= kMinRegion) continue;
      Eigen::Matrix3f covariance = Eigen::Matrix3f::Zero();
      Eigen::Vector4f centroid = Eigen::Vector4f::Zero();
      pcl::computeMeanAndCovarianceMatrix(*cloud, region.indices, covariance, centroid);
      float eigenvalue = 0;
      Eigen::Vector3f normal;
      pcl::eigen33(covariance, eigenvalue, normal);
      if (normal.dot(-centroid.head<3>()) < 0) normal = -normal;  // towards the camera
      pcl::ModelCoefficients model;
      model.values = {normal.x(), normal.y(), normal.z(), -normal.dot(centroid.head<3>())};
      const int label = static_cast<int>((*labels)[region.indices.front()].label);
      label_to_model[label] = static_cast<int>(models.size());
      refine[label] = true;
      models.push_back(model);
      inliers.push_back(region);
    }
    auto refinement = pcl::make_shared<pcl::PlaneRefinementComparator<pcl::PointXYZ, pcl::Normal, pcl::Label>>();
    refinement->setInputCloud(cloud);
    refinement->setDistanceThreshold(0.15f);
    refinement->setLabels(labels);
    refinement->setModelCoefficients(models);
    refinement->setRefineLabels(refine);
    refinement->setLabelToModel(label_to_model);
    pcl::OrganizedMultiPlaneSegmentation<pcl::PointXYZ, pcl::Normal, pcl::Label> planes;
    planes.setRefinementComparator(refinement);
    planes.setMinInliers(500);
    planes.setAngularThreshold(pcl::deg2rad(3.0));
    planes.setDistanceThreshold(0.02);
    planes.setInputCloud(cloud);
    planes.setInputNormals(normals);
    planes.refine(models, inliers, labels, regions);

    ImageU8 out(cloud_camera.width(), cloud_camera.height(), static_cast<std::uint8_t>(TravClass::kUnknown));
    for (std::size_t i = 0; i < cloud_camera.size(); ++i) {
      if (IsFinite(cloud_camera[i])) out[i] = static_cast<std::uint8_t>(TravClass::kNonTraversable);
    }
    for (const pcl::PointIndices& region : regions) {
      if (region.indices.size() <= kMinRegion) continue;
      for (const int i : region.indices) out[static_cast<std::size_t>(i)] = static_cast<std::uint8_t>(TravClass::kTraversable);
    }
    return out;
  }

 private:
  static constexpr std::size_t kMinRegion = 1000;
  pcl::IntegralImageNormalEstimation<pcl::PointXYZ, pcl::Normal> normals_;
  pcl::GroundPlaneComparator<pcl::PointXYZ, pcl::Normal>::Ptr ground_;
  pcl::OrganizedConnectedComponentSegmentation<pcl::PointXYZ, pcl::Label> components_;
};

/// OctoMap's plain update: the frame's points in the world, thinned to 5 cm (pcl::VoxelGrid),
/// inserted with OcTree::insertPointCloud (ray casting per point) at the map's resolution and
/// range (config map.fusion: 0.10 m and 12 m by default).
class StockMap {
 public:
  explicit StockMap(const MapOptions& options) : tree_(options.resolution_m), range_m_(options.max_range_m) {}

  void Insert(const Image3f& cloud_camera, const Eigen::Isometry3d& world_T_camera) {
    pcl::PointCloud<pcl::PointXYZ>::Ptr world(new pcl::PointCloud<pcl::PointXYZ>);
    world->reserve(cloud_camera.size());
    const Eigen::Isometry3f transform = world_T_camera.cast<float>();
    for (std::size_t i = 0; i < cloud_camera.size(); ++i) {
      if (!IsFinite(cloud_camera[i])) continue;
      const Eigen::Vector3f p = transform * cloud_camera[i];
      world->push_back(pcl::PointXYZ(p.x(), p.y(), p.z()));
    }
    pcl::VoxelGrid<pcl::PointXYZ> thin;
    thin.setLeafSize(0.05f, 0.05f, 0.05f);
    thin.setInputCloud(world);
    pcl::PointCloud<pcl::PointXYZ> thinned;
    thin.filter(thinned);
    octomap::Pointcloud scan;
    scan.reserve(thinned.size());
    for (const pcl::PointXYZ& p : thinned) scan.push_back(p.x, p.y, p.z);
    const Eigen::Vector3d o = world_T_camera.translation();
    tree_.insertPointCloud(scan, octomap::point3d(static_cast<float>(o.x()), static_cast<float>(o.y()),
                                                  static_cast<float>(o.z())),
                           range_m_);
  }
  std::size_t NumNodes() const { return tree_.size(); }

 private:
  octomap::OcTree tree_;
  double range_m_;
};

void BM_StockLabels(benchmark::State& state, const Dataset* d) {
  StockLabeller stock;
  FrameCycle frames(*d);
  for (auto _ : state) {
    const BenchFrame& f = frames.Next();
    benchmark::DoNotOptimize(stock.Label(f.result.cloud, f.result.up_rectified));
  }
  CountFrames(state);
}

void BM_StockMap(benchmark::State& state, const Dataset* d) {
  StockMap map(d->config.map.fusion);
  FrameCycle frames(*d);
  for (auto _ : state) {
    const BenchFrame& f = frames.Next();
    map.Insert(f.result.cloud, f.world_T_rectified);
  }
  CountFrames(state);
  state.counters["map_nodes"] = static_cast<double>(map.NumNodes());
}

/// The stock chain end to end on the same SGBM disparity: our rectifier, matcher and
/// triangulation (a user would run the same OpenCV calls), then the stock labels and map.
void BM_StockEndToEnd(benchmark::State& state, const Dataset* d) {
  const Rectifier rectifier(d->calibration, d->config.rectification);
  const StereoMatcher matcher(d->config.stereo);
  StockLabeller labeller;
  StockMap map(d->config.map.fusion);
  FrameCycle frames(*d);
  for (auto _ : state) {
    const BenchFrame& f = frames.Next();
    const RectifiedPair pair = rectifier.Rectify(f.left, f.right);
    const Image3f cloud = Triangulate(matcher.Compute(pair.left, pair.right), rectifier.geometry(),
                                      d->config.triangulation);
    benchmark::DoNotOptimize(labeller.Label(cloud, f.result.up_rectified));
    map.Insert(cloud, f.world_T_rectified);
  }
  CountFrames(state);
}

// ---- Registration and the ratio report -----------------------------------------------------

/// The console report, and after it the ratios of stock to own times (medians when the run
/// has repetitions), from the real time of each case.
class RatioReporter : public benchmark::ConsoleReporter {
 public:
  void ReportRuns(const std::vector<Run>& runs) override {
    ConsoleReporter::ReportRuns(runs);
    for (const Run& run : runs) {
      if (run.error_occurred) continue;
      const bool median = run.run_type == Run::RT_Aggregate && run.aggregate_name == "median";
      if (run.run_type == Run::RT_Aggregate && !median) continue;
      const std::string name = run.run_name.str();
      // A median replaces single runs of the same case; single runs are kept as the first seen.
      if (median || !real_ms_.count(name)) real_ms_[name] = ToMs(run.GetAdjustedRealTime(), run.time_unit);
    }
  }

  bool saw_stock() const {
    for (const auto& entry : real_ms_) {
      if (entry.first.rfind("Stock", 0) == 0) return true;
    }
    return false;
  }

  void Finalize() override {
    ConsoleReporter::Finalize();
    std::printf("\nStock chain / SSTA, wall time per frame (medians when repeated):\n");
    for (const char* d : {"vga", "kitti"}) {
      Ratio(d, "labels (stock normals..refine vs SSTA normals..classes)", "StockLabels/", "Geometry/");
      Ratio(d, "labels, SSTA on one thread as the stock chain", "StockLabels/", "GeometryOneThread/");
      Ratio(d, "map update (stock 5 cm + insertPointCloud vs SSTA InsertFrame)", "StockMap/", "MapUpdate/");
      Ratio(d, "end to end with map", "StockEndToEnd/", "EndToEndWithMap/");
    }
  }

 private:
  static double ToMs(double t, benchmark::TimeUnit unit) {
    switch (unit) {
      case benchmark::kNanosecond: return t * 1e-6;
      case benchmark::kMicrosecond: return t * 1e-3;
      case benchmark::kMillisecond: return t;
      case benchmark::kSecond: return t * 1e3;
    }
    return t;
  }
  void Ratio(const std::string& dataset, const char* what, const std::string& stock, const std::string& own) {
    const auto s = Find(stock + dataset), o = Find(own + dataset);
    if (s < 0 || o < 0) return;
    std::printf("  %-5s %-66s %9.2f ms / %8.2f ms = %6.1fx\n", dataset.c_str(), what, s, o, s / o);
  }
  double Find(const std::string& prefix) const {
    for (const auto& [name, ms] : real_ms_) {
      if (name.rfind(prefix, 0) == 0) return ms;
    }
    return -1;
  }
  std::map<std::string, double> real_ms_;
};

/// Not a speed figure: a sanity check that both chains label the benchmark's frames sensibly
/// (the project's accuracy figures are in docs/accuracy.md, from `ssta eval` over whole
/// sequences). Scores the few rendered frames against the renderer's truth.
void PrintAccuracy() {
  std::printf("\nLabels on the benchmark's own %d rendered frames per rig vs the renderer's truth "
              "(a sanity check; see docs/accuracy.md):\n", kFramesPerDataset);
  for (const Dataset* d : {&Vga(), &Kitti()}) {
    ConfusionMatrix own, stock;
    StockLabeller labeller;
    int passed = 0;
    std::string reason;
    for (const BenchFrame& f : d->frames) {
      if (f.result.analysis.quality.passed) {
        ++passed;
      } else {
        reason = f.result.analysis.quality.reason;
      }
      own += ScoreLabels(f.truth, f.result.labels);
      const ImageU8 s = labeller.Label(f.result.cloud, f.result.up_rectified);
      if (s.width() == f.truth.width() && s.height() == f.truth.height()) stock += ScoreLabels(f.truth, s);
    }
    std::printf("  %-5s SSTA  accuracy %5.1f%%  mean IoU %.3f  coverage %5.1f%%  (quality check passed on %d of "
                "%zu frames%s%s)\n",
                d->name.c_str(), 100 * own.Accuracy(), own.MeanIou(), 100 * own.Coverage(), passed, d->frames.size(),
                reason.empty() ? "" : "; last failure: ", reason.c_str());
    std::printf("  %-5s stock accuracy %5.1f%%  mean IoU %.3f  coverage %5.1f%%\n", d->name.c_str(),
                100 * stock.Accuracy(), stock.MeanIou(), 100 * stock.Coverage());
  }
}

/// OpenCV's parallel loops (the normals' bands, the analysis's concurrent face search) on the
/// calling thread only, for the life of the object.
class OneOpenCvThread {
 public:
  OneOpenCvThread() : saved_(cv::getNumThreads()) { cv::setNumThreads(1); }
  ~OneOpenCvThread() { cv::setNumThreads(saved_); }
  OneOpenCvThread(const OneOpenCvThread&) = delete;
  OneOpenCvThread& operator=(const OneOpenCvThread&) = delete;

 private:
  int saved_;
};

void RegisterAll() {
  using Fn = std::function<void(benchmark::State&)>;
  auto add = [](const std::string& name, Fn fn) {
    benchmark::RegisterBenchmark(name.c_str(), [fn](benchmark::State& s) { fn(s); })
        ->Unit(benchmark::kMillisecond)
        ->MeasureProcessCPUTime()  // OpenCV's matchers run on worker threads: count their CPU too
        ->UseRealTime();
  };
  const std::vector<std::pair<std::string, const Dataset* (*)()>> datasets = {
      {"vga", [] { return &Vga(); }}, {"kitti", [] { return &Kitti(); }}};
  for (const auto& [name, get] : datasets) {
    add("Rectify/" + name, [get = get](benchmark::State& s) { BM_Rectify(s, get()); });
    for (const MatcherType m : {MatcherType::kSemiGlobal, MatcherType::kBlockMatching, MatcherType::kPclBlockBased,
                                MatcherType::kPclAdaptiveCost}) {
      add("Match/" + name + "/" + MatcherTypeName(m), [get = get, m](benchmark::State& s) { BM_Match(s, get(), m); });
    }
    add("Triangulate/" + name, [get = get](benchmark::State& s) { BM_Triangulate(s, get()); });
    for (const NormalMethod m : {NormalMethod::kCovarianceMatrix, NormalMethod::kAverage3dGradient,
                                 NormalMethod::kAverageDepthChange}) {
      add(std::string("Normals/") + name + "/" + NormalMethodName(m),
          [get = get, m](benchmark::State& s) { BM_Normals(s, get(), m); });
    }
    add("Segment/" + name, [get = get](benchmark::State& s) { BM_Segment(s, get()); });
    add("Analyze/" + name, [get = get](benchmark::State& s) { BM_Analyze(s, get()); });
    add("Geometry/" + name, [get = get](benchmark::State& s) { BM_Geometry(s, get()); });
    // The same on the calling thread only: what the bands of rows buy, and the like-for-like
    // figure against the stock chain, whose normals run on one thread.
    add("NormalsOneThread/" + name + "/covariance", [get = get](benchmark::State& s) {
      const OneOpenCvThread one;
      BM_Normals(s, get(), NormalMethod::kCovarianceMatrix, 1);
    });
    add("AnalyzeOneThread/" + name, [get = get](benchmark::State& s) {
      const OneOpenCvThread one;
      BM_Analyze(s, get());
    });
    add("GeometryOneThread/" + name, [get = get](benchmark::State& s) {
      const OneOpenCvThread one;
      BM_Geometry(s, get(), 1);
    });
    add("TextureMask/" + name, [get = get](benchmark::State& s) { BM_TextureMask(s, get()); });
    add("MapSubpixel/" + name, [get = get](benchmark::State& s) { BM_MapSubpixel(s, get()); });
    add("MapPoints/" + name, [get = get](benchmark::State& s) { BM_MapPoints(s, get()); });
    add("MapUpdate/" + name, [get = get](benchmark::State& s) { BM_MapUpdate(s, get()); });
    add("MapJudge/" + name, [get = get](benchmark::State& s) { BM_MapJudge(s, get(), true); });
    add("MapJudgeUnsmeared/" + name, [get = get](benchmark::State& s) { BM_MapJudge(s, get(), false); });
    add("MapFootprints/" + name, [get = get](benchmark::State& s) { BM_MapFootprints(s, get()); });
    add("OnlineRefinement/" + name, [get = get](benchmark::State& s) { BM_OnlineRefinement(s, get()); });
    add("EndToEnd/" + name, [get = get](benchmark::State& s) { BM_EndToEnd(s, get()); });
    add("EndToEndWithMap/" + name, [get = get](benchmark::State& s) { BM_EndToEndWithMap(s, get()); });
    add("StockLabels/" + name, [get = get](benchmark::State& s) { BM_StockLabels(s, get()); });
    add("StockMap/" + name, [get = get](benchmark::State& s) { BM_StockMap(s, get()); });
    add("StockEndToEnd/" + name, [get = get](benchmark::State& s) { BM_StockEndToEnd(s, get()); });
  }
  add("Rectify/euroc_752x480_distorted", BM_RectifyEuroc);
  add("EndToEnd/kitti_street_pair_real", BM_EndToEndKittiPair);
}

}  // namespace
}  // namespace ssta

int main(int argc, char** argv) {
  benchmark::Initialize(&argc, argv);
  if (benchmark::ReportUnrecognizedArguments(argc, argv)) return 1;
  ssta::RegisterAll();
  ssta::RatioReporter reporter;
  benchmark::RunSpecifiedBenchmarks(&reporter);
  if (reporter.saw_stock()) ssta::PrintAccuracy();
  benchmark::Shutdown();
  return 0;
}
