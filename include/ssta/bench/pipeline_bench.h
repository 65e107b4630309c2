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

  /// Frames measured (the sample count of the first row; 0 without rows).
  int frames() const;

  /// A fixed-width text table, one line per row: median and p90 wall ms, median CPU ms (or
  /// "-"), and frames/s = 1000 / median wall ms; then peak memory, resident memory at the first
  /// and last frame and, with a map, its growth and update time in the first and second half.
  std::string Table() const;

  /// The same as JSON: per row the SampleStats of wall and CPU times and frames/s (from the
  /// median), peak memory, and the per-frame series (memory and map growth).
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

/// Runs the FramePipeline over the frames of `sequence` (images are read before the clock
/// starts), recording per frame each stage's wall time (StageTimings), the whole Process call's
/// wall and CPU time and, with `with_map`, the map update (MapPointsOfFrame at
/// config.map.pixel_stride + InsertFrame into a new map at config.map.fusion) and the map's size.
/// Rows: rectify, match, triangulate, normals, segment, analyze, frame (Process), and with the
/// map: map update, end to end (frame + map update: the latency of the sequential loop); with
/// config.refinement.online: refine (online), the ground evidence and window update with the
/// solves when due.
/// With the map, a second pass then runs the same frames as `ssta build-map` does by default
/// (BuildMapOptions::pipelined: the map update of frame k on a second thread while frame k+1 is
/// classified) into a fresh map, with the images of at most kMaxPipelinedFrames frames read
/// beforehand, and adds the rows "pipelined interval" (wall time between two frames' map
/// updates finishing; its frames/s is the pipeline's throughput) and "pipelined latency"
/// (from the start of a frame's Process to the end of its map update). Peak memory is taken
/// before that pass. Poses and gravity as `ssta build-map` takes them (a frame without a pose
/// is put at the origin, levelled by gravity).
/// Throws ssta::Error on invalid options or config, an unreadable image, or when the sequence
/// has fewer frames than the warm-up needs plus one.
BenchReport RunPipelineBench(const Sequence& sequence, const Config& config,
                             const PipelineBenchOptions& options);

/// Frames measured by RunPipelineBench's pipelined pass (their images are held in memory).
constexpr int kMaxPipelinedFrames = 100;

/// Peak resident set size of this process so far [MiB] (getrusage's ru_maxrss).
double PeakResidentMib();

/// Current resident set size of this process [MiB] (/proc/self/statm); NaN when unavailable.
double CurrentResidentMib();

}  // namespace ssta
