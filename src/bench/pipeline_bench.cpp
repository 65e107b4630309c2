#include "ssta/bench/pipeline_bench.h"

#include <sys/resource.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <ctime>
#include <memory>
#include <numeric>
#include <optional>
#include <sstream>
#include <thread>

#include "ssta/core/json_writer.h"
#include "core/ordered_worker.h"
#include "ssta/io/image_io.h"
#include "ssta/fusion/frame_points.h"
#include "ssta/mapping/traversability_map.h"
#include "ssta/pipeline/map_builder.h"
#include "ssta/pipeline/sequence_run.h"
#include "ssta/sensors/attitude_filter.h"
#include "ssta/mount/ground_evidence.h"
#include "ssta/mount/online_mount_refiner.h"

namespace ssta {
namespace {

/// Wall and process CPU time since construction [ms].
class Timer {
 public:
  double WallMs() const {
    return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - wall_).count();
  }
  double CpuMs() const { return 1000.0 * static_cast<double>(std::clock() - cpu_) / CLOCKS_PER_SEC; }

 private:
  std::chrono::steady_clock::time_point wall_ = std::chrono::steady_clock::now();
  std::clock_t cpu_ = std::clock();
};

std::string Fixed(double value, int width, int decimals) {
  if (!std::isfinite(value)) return std::string(static_cast<std::size_t>(std::max(0, width - 1)), ' ') + "-";
  char buffer[64];
  std::snprintf(buffer, sizeof(buffer), "%*.*f", width, decimals, value);
  return buffer;
}

double FramesPerSecond(double median_ms) { return median_ms > 0 ? 1000.0 / median_ms : std::nan(""); }

void WriteStats(const SampleStats& s, internal::JsonWriter* j) {
  j->BeginObject();
  j->Key("count");
  j->Integer(s.count);
  j->Key("median");
  j->Number(s.median);
  j->Key("p90");
  j->Number(s.p90);
  j->Key("mean");
  j->Number(s.mean);
  j->Key("min");
  j->Number(s.min);
  j->Key("max");
  j->Number(s.max);
  j->EndObject();
}

/// The frame's pose as build-map takes it; a frame without one at the origin, levelled by gravity.
Eigen::Isometry3d PoseOrLevelled(const SequenceRun& run, std::int64_t t) {
  return run.gravity().WorldTBodyAt(t).value_or(CorrectRollPitch(Eigen::Isometry3d::Identity(), run.gravity().UpInBody(t)));
}

/// The second pass of RunPipelineBench, the whole run (see there): the measured frames read,
/// classified and fused as `ssta build-map` does by default.
void AddWholeRun(const Sequence& sequence, const Config& config, int warmup, int measured, BenchReport* report) {
  using Clock = std::chrono::steady_clock;
  const int frames = warmup + measured;
  SequenceRun run(sequence, config, {1, frames, false});
  run.set_read_ahead(true);
  const Eigen::Isometry3d& body_T_camera = sequence.calibration().left.body_T_camera;
  const RigChain chain(body_T_camera, run.geometry());
  MapMetadata metadata;
  metadata.vehicle = config.vehicle;
  TraversabilityMap map(config.map.FusionFor(run.geometry().f * run.geometry().baseline_m, config.stereo.disparity_sigma_px),
                        metadata);
  std::optional<OnlineMountRefiner> refiner;
  if (config.refinement.online) refiner.emplace(config.refinement, body_T_camera, body_T_camera);
  std::vector<Clock::time_point> started(static_cast<std::size_t>(frames)), finished(static_cast<std::size_t>(frames));
  std::vector<ClassifiedPoint> map_points;  // reused as build-map does (one fusion job at a time)
  Clock::time_point whole_start = Clock::now();
  std::clock_t whole_cpu_start = std::clock();
  {
    internal::OrderedWorker fusion(1);
    for (int k = 0; k < frames; ++k) {
      if (k == warmup) {  // the clock of the whole run starts with the first measured frame
        fusion.Drain();
        whole_start = Clock::now();
        whole_cpu_start = std::clock();
      }
      const std::size_t i = static_cast<std::size_t>(k);
      const StereoFrame& frame = run.frames()[i];
      started[i] = Clock::now();
      const Eigen::Isometry3d world_T_body = PoseOrLevelled(run, frame.timestamp_ns);
      std::uint64_t image_hash = 0;  // build-map hashes the left image for the map's fingerprint
      auto result = std::make_shared<FrameResult>(
          run.Classify(frame, chain.UpInCamera(UpInBody(world_T_body)), &image_hash));
      const Eigen::Isometry3d world_T_rectified = chain.WorldTRectified(world_T_body);
      fusion.Submit([&, i, result, world_T_rectified] {
        FuseFrame(*result, world_T_rectified, config, run.geometry(), &map_points, &map);
        finished[i] = Clock::now();
      });
      if (refiner) {
        refiner->AddFrame(ExtractGroundEvidence(*result, chain.camera_R_rectified(), UpInBody(world_T_body),
                                                config.refinement));
      }
    }
    fusion.Drain();
  }
  report->whole_run_frames = measured;
  report->whole_run_wall_ms = std::chrono::duration<double, std::milli>(Clock::now() - whole_start).count();
  report->whole_run_cpu_ms = 1000.0 * static_cast<double>(std::clock() - whole_cpu_start) / CLOCKS_PER_SEC;
  BenchRow interval{"pipelined interval", {}, {}}, latency{"pipelined latency", {}, {}};
  for (std::size_t k = static_cast<std::size_t>(warmup); k < finished.size(); ++k) {
    if (k > 0) interval.wall_ms.push_back(std::chrono::duration<double, std::milli>(finished[k] - finished[k - 1]).count());
    latency.wall_ms.push_back(std::chrono::duration<double, std::milli>(finished[k] - started[k]).count());
  }
  report->rows.push_back(std::move(interval));
  report->rows.push_back(std::move(latency));
}

}  // namespace

double Quantile(std::vector<double> samples, double q) {
  SSTA_CHECK(q >= 0.0 && q <= 1.0, "quantile must be in [0, 1]");
  if (samples.empty()) return std::nan("");
  std::sort(samples.begin(), samples.end());
  const double rank = q * static_cast<double>(samples.size() - 1);
  const std::size_t lo = static_cast<std::size_t>(std::floor(rank));
  const std::size_t hi = std::min(lo + 1, samples.size() - 1);
  return samples[lo] + (rank - static_cast<double>(lo)) * (samples[hi] - samples[lo]);
}

SampleStats Summarize(const std::vector<double>& samples) {
  SampleStats s;
  s.count = static_cast<int>(samples.size());
  if (samples.empty()) return s;
  s.median = Quantile(samples, 0.5);
  s.p90 = Quantile(samples, 0.9);
  s.mean = std::accumulate(samples.begin(), samples.end(), 0.0) / static_cast<double>(samples.size());
  const auto [lo, hi] = std::minmax_element(samples.begin(), samples.end());
  s.min = *lo;
  s.max = *hi;
  return s;
}

double BenchReport::WholeRunFramesPerSecond() const {
  return whole_run_frames > 0 && whole_run_wall_ms > 0 ? 1000.0 * whole_run_frames / whole_run_wall_ms : std::nan("");
}

int BenchReport::frames() const { return rows.empty() ? 0 : static_cast<int>(rows.front().wall_ms.size()); }

std::string BenchReport::Table() const {
  std::ostringstream t;
  t << source << ": " << width << "x" << height << ", " << matcher << ", " << frames() << " frames measured ("
    << warmup_frames << " warm-up not counted), " << threads << " hardware threads\n";
  t << "stage               wall median ms  wall p90 ms  CPU median ms   frames/s\n";
  for (const BenchRow& row : rows) {
    const SampleStats wall = Summarize(row.wall_ms);
    const SampleStats cpu = Summarize(row.cpu_ms);
    std::string name = row.name;
    name.resize(std::max<std::size_t>(name.size(), 18), ' ');
    t << name << Fixed(wall.median, 16, 2) << Fixed(wall.p90, 13, 2) << Fixed(cpu.median, 15, 2)
      << Fixed(FramesPerSecond(wall.median), 11, 1) << "\n";
  }
  if (whole_run_frames > 0) {
    t << "whole run (images read, classified, fused as build-map does): " << whole_run_frames << " frames in "
      << Fixed(whole_run_wall_ms, 0, 1) << " ms (CPU " << Fixed(whole_run_cpu_ms, 0, 1)
      << " ms): " << Fixed(WholeRunFramesPerSecond(), 0, 1) << " frames/s, "
      << Fixed(whole_run_wall_ms / whole_run_frames, 0, 2) << " ms per frame\n";
  }
  t << "peak memory (max RSS): " << Fixed(peak_rss_mib, 0, 1) << " MiB";
  if (!series.empty()) {
    t << "; resident " << Fixed(series.front().rss_mib, 0, 1) << " MiB after the first measured frame, "
      << Fixed(series.back().rss_mib, 0, 1) << " MiB after the last";
  }
  t << "\n";
  if (with_map && !series.empty()) {
    const FrameSample& first = series.front();
    const FrameSample& last = series.back();
    const std::size_t half = series.size() / 2;
    std::vector<double> early, late;
    for (std::size_t i = 0; i < series.size(); ++i) (i < half ? early : late).push_back(series[i].update_ms);
    const double per_frame = series.size() > 1
                                 ? (static_cast<double>(last.nodes) - static_cast<double>(first.nodes)) /
                                       static_cast<double>(series.size() - 1)
                                 : 0.0;
    t << "map: " << first.nodes << " nodes after the first measured frame, " << last.nodes << " after the last ("
      << Fixed(per_frame, 0, 0) << " per frame); update median " << Fixed(Quantile(early, 0.5), 0, 2)
      << " ms in the first half, " << Fixed(Quantile(late, 0.5), 0, 2) << " ms in the second\n";
  }
  return t.str();
}

std::string BenchReport::Json() const {
  internal::JsonWriter j;
  j.BeginObject();
  j.Key("source");
  j.String(source);
  j.Key("width");
  j.Integer(width);
  j.Key("height");
  j.Integer(height);
  j.Key("matcher");
  j.String(matcher);
  j.Key("frames");
  j.Integer(frames());
  j.Key("warmup_frames");
  j.Integer(warmup_frames);
  j.Key("hardware_threads");
  j.Integer(threads);
  j.Key("peak_rss_mib");
  j.Number(peak_rss_mib);
  j.Key("stages");
  j.BeginArray();
  for (const BenchRow& row : rows) {
    const SampleStats wall = Summarize(row.wall_ms);
    j.BeginObject();
    j.Key("name");
    j.String(row.name);
    j.Key("wall_ms");
    WriteStats(wall, &j);
    j.Key("cpu_ms");
    if (row.cpu_ms.empty()) {
      j.Null();
    } else {
      WriteStats(Summarize(row.cpu_ms), &j);
    }
    j.Key("frames_per_s");
    j.Number(FramesPerSecond(wall.median));
    j.EndObject();
  }
  j.EndArray();
  j.Key("whole_run");
  j.BeginObject();
  j.Key("frames");
  j.Integer(whole_run_frames);
  j.Key("wall_ms");
  j.Number(whole_run_wall_ms);
  j.Key("cpu_ms");
  j.Number(whole_run_cpu_ms);
  j.Key("frames_per_s");
  j.Number(WholeRunFramesPerSecond());
  j.EndObject();
  j.Key("with_map");
  j.Bool(with_map);
  j.Key("series_columns");
  j.BeginInlineArray();
  for (const char* c : {"frame", "map_update_ms", "map_points", "map_nodes", "rss_mib"}) j.String(c);
  j.EndArray();
  j.Key("series");
  j.BeginArray();
  for (const FrameSample& m : series) {
    j.BeginInlineArray();
    j.Integer(m.frame);
    j.Number(m.update_ms);
    j.Integer(static_cast<std::int64_t>(m.points));
    j.Integer(static_cast<std::int64_t>(m.nodes));
    j.Number(m.rss_mib);
    j.EndArray();
  }
  j.EndArray();
  j.EndObject();
  return j.Take();
}

bool PipelineBenchOptions::IsValid(std::string* error) const {
  if (max_frames < 0) return Fail(error, "frames: must not be negative");
  if (warmup_frames < 0) return Fail(error, "warmup: must not be negative");
  return true;
}

double CurrentResidentMib() {
  std::FILE* statm = std::fopen("/proc/self/statm", "r");
  if (statm == nullptr) return std::nan("");
  long size_pages = 0, resident_pages = 0;
  const int read = std::fscanf(statm, "%ld %ld", &size_pages, &resident_pages);
  std::fclose(statm);
  if (read != 2) return std::nan("");
  return static_cast<double>(resident_pages) * static_cast<double>(sysconf(_SC_PAGESIZE)) / (1024.0 * 1024.0);
}

double PeakResidentMib() {
  rusage usage{};
  if (getrusage(RUSAGE_SELF, &usage) != 0) return std::nan("");
  return static_cast<double>(usage.ru_maxrss) / 1024.0;  // Linux reports KiB
}

BenchReport RunPipelineBench(const Sequence& sequence, const Config& config, const PipelineBenchOptions& options) {
  std::string error;
  if (!options.IsValid(&error)) throw Error(error);
  if (!config.IsValid(&error)) throw Error("config: " + error);
  const int available = static_cast<int>(sequence.frames().size());
  if (available < options.warmup_frames + 1) {
    throw Error(sequence.root() + ": " + std::to_string(available) + " frames, the bench needs at least " +
                std::to_string(options.warmup_frames + 1) + " (warm-up + 1)");
  }
  const int measured = options.max_frames > 0 ? std::min(options.max_frames, available - options.warmup_frames)
                                              : available - options.warmup_frames;

  SequenceRun run(sequence, config, {1, options.warmup_frames + measured, false});
  const Eigen::Isometry3d& body_T_camera = sequence.calibration().left.body_T_camera;
  const RigChain chain(body_T_camera, run.geometry());
  MapMetadata metadata;
  metadata.vehicle = config.vehicle;
  TraversabilityMap map(config.map.FusionFor(run.geometry().f * run.geometry().baseline_m, config.stereo.disparity_sigma_px),
                        metadata);
  std::vector<ClassifiedPoint> points;  // the map points of the frame, reused as build-map does

  BenchReport report;
  report.source = sequence.root();
  report.width = sequence.calibration().left.width;
  report.height = sequence.calibration().left.height;
  report.matcher = MatcherTypeName(config.stereo.algorithm);
  report.warmup_frames = options.warmup_frames;
  report.threads = static_cast<int>(std::thread::hardware_concurrency());
  report.with_map = options.with_map;
  enum Row { kRead, kRectify, kMatch, kTriangulate, kNormals, kSegment, kAnalyze, kFrame, kMap, kEndToEnd };
  for (const char* name :
       {"read images", "rectify", "match", "triangulate", "normals", "segment", "analyze", "frame (Process)"}) {
    report.rows.push_back({name, {}, {}});
  }
  if (options.with_map) {
    report.rows.push_back({"map update", {}, {}});
    report.rows.push_back({"end to end", {}, {}});
  }
  // With refinement.online: ground evidence + window update + the solves when due (every
  // solve_every_frames frames: the median is a frame without a solve, the mean amortizes them).
  // The bench keeps the configured mount; it measures the cost only.
  std::optional<OnlineMountRefiner> refiner;
  const std::size_t refine_row = report.rows.size();
  if (config.refinement.online) {
    refiner.emplace(config.refinement, body_T_camera, body_T_camera);
    report.rows.push_back({"refine (online)", {}, {}});
  }

  for (int k = 0; k < options.warmup_frames + measured; ++k) {
    const StereoFrame& frame = run.frames()[static_cast<std::size_t>(k)];
    const Timer read_timer;
    const StereoImages images = sequence.ReadImages(frame);
    const double read_wall = read_timer.WallMs(), read_cpu = read_timer.CpuMs();
    const std::int64_t t = frame.timestamp_ns;
    const Eigen::Isometry3d world_T_body = PoseOrLevelled(run, t);
    const Eigen::Vector3d up_camera = chain.UpInCamera(UpInBody(world_T_body));

    const Timer frame_timer;
    FrameResult result = run.pipeline().Process(images.left, images.right, up_camera);
    const double frame_wall = frame_timer.WallMs(), frame_cpu = frame_timer.CpuMs();
    result.timestamp_ns = t;

    double map_wall = 0, map_cpu = 0;
    std::size_t points_given = 0;
    if (options.with_map) {
      const Timer map_timer;
      const Eigen::Isometry3d world_T_rectified = chain.WorldTRectified(world_T_body);
      FuseFrame(result, world_T_rectified, config, run.geometry(), &points, &map);
      map_wall = map_timer.WallMs();
      map_cpu = map_timer.CpuMs();
      points_given = points.size();
    }
    double refine_wall = 0, refine_cpu = 0;
    if (refiner) {
      const Timer refine_timer;
      refiner->AddFrame(ExtractGroundEvidence(result, chain.camera_R_rectified(), UpInBody(world_T_body),
                                              config.refinement));
      refine_wall = refine_timer.WallMs();
      refine_cpu = refine_timer.CpuMs();
    }
    if (k < options.warmup_frames) continue;

    const StageTimings& s = result.timings;
    report.rows[kRead].wall_ms.push_back(read_wall);
    report.rows[kRead].cpu_ms.push_back(read_cpu);
    const double stages[] = {s.rectify_ms, s.match_ms, s.triangulate_ms, s.normals_ms, s.segment_ms, s.analyze_ms};
    for (int r = kRectify; r <= kAnalyze; ++r) report.rows[r].wall_ms.push_back(stages[r - kRectify]);
    report.rows[kFrame].wall_ms.push_back(frame_wall);
    report.rows[kFrame].cpu_ms.push_back(frame_cpu);
    if (options.with_map) {
      report.rows[kMap].wall_ms.push_back(map_wall);
      report.rows[kMap].cpu_ms.push_back(map_cpu);
      report.rows[kEndToEnd].wall_ms.push_back(read_wall + frame_wall + map_wall);
      report.rows[kEndToEnd].cpu_ms.push_back(read_cpu + frame_cpu + map_cpu);
    }
    if (refiner) {
      report.rows[refine_row].wall_ms.push_back(refine_wall);
      report.rows[refine_row].cpu_ms.push_back(refine_cpu);
    }
    report.series.push_back({k - options.warmup_frames, map_wall, points_given,
                             options.with_map ? map.NumNodes() : 0, CurrentResidentMib()});
  }
  report.peak_rss_mib = PeakResidentMib();
  AddWholeRun(sequence, config, options.warmup_frames, measured, &report);
  return report;
}

}  // namespace ssta
