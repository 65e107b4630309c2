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

namespace {

/// How many frames the first pass measures after the warm-up. Throws ssta::Error on invalid
/// options or config, or when the sequence has fewer frames than the warm-up needs plus one.
int MeasuredFrames(const Sequence& sequence, const Config& config, const PipelineBenchOptions& options) {
  std::string error;
  if (!options.IsValid(&error)) throw Error(error);
  if (!config.IsValid(&error)) throw Error("config: " + error);
  const int available = static_cast<int>(sequence.frames().size());
  if (available < options.warmup_frames + 1) {
    throw Error(sequence.root() + ": " + std::to_string(available) + " frames, the bench needs at least " +
                std::to_string(options.warmup_frames + 1) + " (warm-up + 1)");
  }
  return options.max_frames > 0 ? std::min(options.max_frames, available - options.warmup_frames)
                                : available - options.warmup_frames;
}

/// The rows of the first pass, by index (MakeReportRows).
enum StageRow { kRead, kRectify, kMatch, kTriangulate, kNormals, kSegment, kAnalyze, kFrame, kMap, kEndToEnd };

/// The first pass's rows, empty, in StageRow order: the stages of a frame, with `with_map` the
/// map update and end to end, with refinement.online the refiner's row last (ground evidence +
/// window update + the solves when due, every solve_every_frames frames: the median is a frame
/// without a solve, the mean amortizes them).
std::vector<BenchRow> MakeReportRows(const Config& config, const PipelineBenchOptions& options) {
  std::vector<BenchRow> rows;
  for (const char* name :
       {"read images", "rectify", "match", "triangulate", "normals", "segment", "analyze", "frame (Process)"}) {
    rows.push_back({name, {}, {}});
  }
  if (options.with_map) {
    rows.push_back({"map update", {}, {}});
    rows.push_back({"end to end", {}, {}});
  }
  if (config.refinement.online) rows.push_back({"refine (online)", {}, {}});
  return rows;
}

/// The report before the first frame: what is run, on what machine, and its empty rows.
BenchReport NewReport(const Sequence& sequence, const Config& config, const PipelineBenchOptions& options) {
  BenchReport report;
  report.source = sequence.root();
  report.width = sequence.calibration().left.width;
  report.height = sequence.calibration().left.height;
  report.matcher = MatcherTypeName(config.stereo.algorithm);
  report.warmup_frames = options.warmup_frames;
  report.threads = static_cast<int>(std::thread::hardware_concurrency());
  report.with_map = options.with_map;
  report.rows = MakeReportRows(config, options);
  return report;
}

/// A map at config.map for the run's rig and the config's vehicle, with nothing fused yet.
TraversabilityMap EmptyMap(const Config& config, const SequenceRun& run) {
  MapMetadata metadata;
  metadata.vehicle = config.vehicle;
  return TraversabilityMap(
      config.map.FusionFor(run.geometry().f * run.geometry().baseline_m, config.stereo.disparity_sigma_px), metadata);
}

/// What the frames of the first pass work on: the run, its rig chain, the map they are fused
/// into with the frame's map points (reused as build-map does) and, with refinement.online,
/// the mount refiner. The bench keeps the configured mount; it measures the refiner's cost only.
struct StagePass {
  StagePass(const Sequence& sequence, const Config& config, int frames)
      : run(sequence, config, {1, frames, false}),
        chain(sequence.calibration().left.body_T_camera, run.geometry()),
        map(EmptyMap(config, run)) {
    const Eigen::Isometry3d& body_T_camera = sequence.calibration().left.body_T_camera;
    if (config.refinement.online) refiner.emplace(config.refinement, body_T_camera, body_T_camera);
  }

  SequenceRun run;
  RigChain chain;
  TraversabilityMap map;
  std::vector<ClassifiedPoint> points;
  std::optional<OnlineMountRefiner> refiner;
};

/// Wall and process CPU time of one step [ms].
struct StepTime {
  double wall_ms = 0.0;
  double cpu_ms = 0.0;
};

/// What one frame of the first pass took: its image read, Process (with the stages' own
/// times), the map update (with `with_map`) and the refiner's update (with a refiner), and the
/// points the map was given (0 without map).
struct FrameTimings {
  StepTime read;
  StageTimings stages;
  StepTime frame;
  std::optional<StepTime> map;
  std::optional<StepTime> refine;
  std::size_t points_given = 0;
};

/// Reads `frame`'s images, processes them, fuses the result into the pass's map with
/// `with_map` and feeds the pass's refiner when it has one, timing each step.
FrameTimings TimeFrame(const Sequence& sequence, const Config& config, const PipelineBenchOptions& options,
                       const StereoFrame& frame, StagePass* pass) {
  FrameTimings out;
  const Timer read_timer;
  const StereoImages images = sequence.ReadImages(frame);
  out.read = {read_timer.WallMs(), read_timer.CpuMs()};
  const std::int64_t t = frame.timestamp_ns;
  const Eigen::Isometry3d world_T_body = PoseOrLevelled(pass->run, t);
  const Eigen::Vector3d up_camera = pass->chain.UpInCamera(UpInBody(world_T_body));

  const Timer frame_timer;
  FrameResult result = pass->run.pipeline().Process(images.left, images.right, up_camera);
  out.frame = {frame_timer.WallMs(), frame_timer.CpuMs()};
  result.timestamp_ns = t;
  out.stages = result.timings;

  if (options.with_map) {
    const Timer map_timer;
    const Eigen::Isometry3d world_T_rectified = pass->chain.WorldTRectified(world_T_body);
    FuseFrame(result, world_T_rectified, config, pass->run.geometry(), &pass->points, &pass->map);
    out.map = StepTime{map_timer.WallMs(), map_timer.CpuMs()};
    out.points_given = pass->points.size();
  }
  if (pass->refiner) {
    const Timer refine_timer;
    pass->refiner->AddFrame(ExtractGroundEvidence(result, pass->chain.camera_R_rectified(), UpInBody(world_T_body),
                                                  config.refinement));
    out.refine = StepTime{refine_timer.WallMs(), refine_timer.CpuMs()};
  }
  return out;
}

/// Appends one measured frame's times to the report's rows (MakeReportRows).
void RecordTimings(const FrameTimings& t, BenchReport* report) {
  std::vector<BenchRow>& rows = report->rows;
  rows[kRead].wall_ms.push_back(t.read.wall_ms);
  rows[kRead].cpu_ms.push_back(t.read.cpu_ms);
  const StageTimings& s = t.stages;
  const double stages[] = {s.rectify_ms, s.match_ms, s.triangulate_ms, s.normals_ms, s.segment_ms, s.analyze_ms};
  for (int r = kRectify; r <= kAnalyze; ++r) rows[r].wall_ms.push_back(stages[r - kRectify]);
  rows[kFrame].wall_ms.push_back(t.frame.wall_ms);
  rows[kFrame].cpu_ms.push_back(t.frame.cpu_ms);
  if (t.map) {
    rows[kMap].wall_ms.push_back(t.map->wall_ms);
    rows[kMap].cpu_ms.push_back(t.map->cpu_ms);
    rows[kEndToEnd].wall_ms.push_back(t.read.wall_ms + t.frame.wall_ms + t.map->wall_ms);
    rows[kEndToEnd].cpu_ms.push_back(t.read.cpu_ms + t.frame.cpu_ms + t.map->cpu_ms);
  }
  if (t.refine) {  // the refiner's row is the last
    rows.back().wall_ms.push_back(t.refine->wall_ms);
    rows.back().cpu_ms.push_back(t.refine->cpu_ms);
  }
}

}  // namespace

BenchReport RunPipelineBench(const Sequence& sequence, const Config& config, const PipelineBenchOptions& options) {
  const int measured = MeasuredFrames(sequence, config, options);
  StagePass pass(sequence, config, options.warmup_frames + measured);
  BenchReport report = NewReport(sequence, config, options);
  for (int k = 0; k < options.warmup_frames + measured; ++k) {
    const StereoFrame& frame = pass.run.frames()[static_cast<std::size_t>(k)];
    const FrameTimings timings = TimeFrame(sequence, config, options, frame, &pass);
    if (k < options.warmup_frames) continue;
    RecordTimings(timings, &report);
    report.series.push_back({k - options.warmup_frames, timings.map ? timings.map->wall_ms : 0.0,
                             timings.points_given, options.with_map ? pass.map.NumNodes() : 0, CurrentResidentMib()});
  }
  report.peak_rss_mib = PeakResidentMib();
  AddWholeRun(sequence, config, options.warmup_frames, measured, &report);
  return report;
}

}  // namespace ssta
