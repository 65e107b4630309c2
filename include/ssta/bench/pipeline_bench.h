#pragma once

#include <cstddef>
#include <limits>
#include <string>
#include <vector>

#include "ssta/io/sequence.h"
#include "ssta/pipeline/config.h"

namespace ssta {

/// Order statistics of per-frame samples (times in ms, in practice). NaN when there are none.
struct SampleStats {
  int count = 0;
  double median = std::numeric_limits<double>::quiet_NaN();
  double p90 = std::numeric_limits<double>::quiet_NaN();
  double mean = std::numeric_limits<double>::quiet_NaN();
  double min = std::numeric_limits<double>::quiet_NaN();
  double max = std::numeric_limits<double>::quiet_NaN();
};

/// The q-quantile of `samples` (q in [0, 1]) with linear interpolation between the two nearest
/// ranks: the sorted value at rank q * (n - 1) (numpy's default, Hyndman-Fan type 7), so the
/// median of an even count is the mean of the two middle values. NaN for no samples.
/// Precondition (ssta::InternalError): 0 <= q <= 1.
double Quantile(std::vector<double> samples, double q);

/// Count, median, 90th percentile (Quantile), mean, min and max of `samples`.
SampleStats Summarize(const std::vector<double>& samples);

/// One line of a benchmark table: a stage (or a group of stages) measured once per frame.
struct BenchRow {
  std::string name;
  std::vector<double> wall_ms;  ///< wall time per frame [ms]
  /// Process CPU time per frame [ms] (std::clock: all threads together, so CPU > wall means
  /// the stage ran on more than one core); empty when the row has no CPU measurement.
  std::vector<double> cpu_ms;
};

/// The process after one measured frame: its memory and, with a map, the map's size.
struct FrameSample {
  int frame = 0;             ///< 0-based index of the measured frame
  double update_ms = 0.0;    ///< wall time of MapPointsOfFrame + InsertFrame [ms]; 0 without map
  std::size_t points = 0;    ///< points given to InsertFrame; 0 without map
  std::size_t nodes = 0;     ///< octree nodes after the update (TraversabilityMap::NumNodes); 0 without map
  double rss_mib = 0.0;      ///< resident memory of the process after the frame [MiB]
};

/// What a pipeline benchmark measured, and how it prints.
struct BenchReport {
  std::string source;      ///< what was run, e.g. the sequence folder or "synthetic yard"
  int width = 0, height = 0;  ///< input image size [px]
  std::string matcher;     ///< stereo.algorithm
  int warmup_frames = 0;   ///< frames run before measuring (not in the rows)
  int threads = 0;         ///< hardware threads of the machine
  std::vector<BenchRow> rows;         ///< in pipeline order; frames = rows' sample count
  bool with_map = false;              ///< the frames were fused into a map
  std::vector<FrameSample> series;    ///< one per measured frame
  double peak_rss_mib = 0.0;  ///< peak resident memory of the process at the end [MiB]
  /// The whole run (RunPipelineBench): frames measured, and their wall and process CPU time
  /// from the first one's image read to the last one's map update [ms]; 0 frames: not run.
  int whole_run_frames = 0;
  double whole_run_wall_ms = std::numeric_limits<double>::quiet_NaN();
  double whole_run_cpu_ms = std::numeric_limits<double>::quiet_NaN();

  /// Frames per second of the whole run: whole_run_frames / whole_run_wall_ms; NaN when not run.
  double WholeRunFramesPerSecond() const;

  /// Frames measured (the sample count of the first row; 0 without rows).
  int frames() const;

  /// A fixed-width text table, one line per row: median and p90 wall ms, median CPU ms (or
  /// "-"), and frames/s = 1000 / median wall ms; then the whole run (frames, wall and CPU ms,
  /// frames/s, wall ms per frame), peak memory, resident memory at the first and last frame
  /// and, with a map, its growth and update time in the first and second half.
  std::string Table() const;

  /// The same as JSON: per row the SampleStats of wall and CPU times and frames/s (from the
  /// median), the whole run ("whole_run": frames, wall_ms, cpu_ms, frames_per_s), peak memory,
  /// and the per-frame series (memory and map growth).
  std::string Json() const;
};

/// Options of RunPipelineBench (`ssta bench`).
struct PipelineBenchOptions {
  int max_frames = 0;      ///< measure at most this many frames after the warm-up (0: all)
  int warmup_frames = 1;   ///< frames processed first and left out of the statistics
  /// Also fuse each frame into a TraversabilityMap (config.map) and time that update.
  bool with_map = false;
  /// On failure writes a message that starts with the key name and returns false.
  bool IsValid(std::string* error) const;
};

/// Runs the FramePipeline over the frames of `sequence` in two passes.
///
/// The first pass times each stage of each frame: rows read images (Sequence::ReadImages: the
/// files read and decoded), rectify, match, triangulate, normals, segment, analyze
/// (StageTimings), frame (Process, wall and CPU) and, with `with_map`, map update (FuseFrame,
/// as build-map fuses a frame: MapPointsOfFrame + InsertFrame into a new map at config.map) and
/// end to end (read + frame + map update: the latency of the sequential loop), with the map's
/// size per frame; with config.refinement.online, refine (online): the ground evidence and
/// window update with the solves when due (the configured mount is kept). Peak memory is taken
/// after this pass.
///
/// The second pass, the whole run, runs the same frames the way `ssta build-map` does by default
/// into a fresh map: each frame's images read, classified (SequenceRun::Classify), and fused
/// (FuseFrame) on a second thread while the next frame is read and classified
/// (BuildMapOptions::pipelined), with the online refinement fed when configured. Its clock
/// starts at the first measured frame (the warm-up frames' fusion done) and stops when the last
/// frame's map update ends; the map is not saved. It adds the rows "pipelined interval" (wall
/// time between two frames' map updates ending) and "pipelined latency" (from the start of a
/// frame's image read to the end of its map update), and the whole_run_* figures.
///
/// Poses and gravity as `ssta build-map` takes them (a frame without a pose is put at the
/// origin, levelled by gravity). Throws ssta::Error on invalid options or config, an unreadable
/// image, or when the sequence has fewer frames than the warm-up needs plus one.
BenchReport RunPipelineBench(const Sequence& sequence, const Config& config,
                             const PipelineBenchOptions& options);

/// Peak resident set size of this process so far [MiB] (getrusage's ru_maxrss).
double PeakResidentMib();

/// Current resident set size of this process [MiB] (/proc/self/statm); NaN when unavailable.
double CurrentResidentMib();

}  // namespace ssta
