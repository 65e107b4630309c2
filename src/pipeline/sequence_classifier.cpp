#include "ssta/pipeline/sequence_classifier.h"

#include <chrono>
#include <filesystem>
#include <iomanip>
#include <sstream>

#include "core/json_escape.h"
#include "ssta/io/file_util.h"
#include "ssta/io/ground_truth.h"
#include "ssta/io/image_io.h"
#include "ssta/sensors/gravity_provider.h"
#include "ssta/pipeline/frame_report.h"

namespace ssta {
namespace {


void Accumulate(const StageTimings& t, StageTimings* sum) {
  sum->rectify_ms += t.rectify_ms;
  sum->match_ms += t.match_ms;
  sum->triangulate_ms += t.triangulate_ms;
  sum->normals_ms += t.normals_ms;
  sum->segment_ms += t.segment_ms;
  sum->analyze_ms += t.analyze_ms;
  sum->total_ms += t.total_ms;
}

void Scale(double k, StageTimings* t) {
  for (double* x : {&t->rectify_ms, &t->match_ms, &t->triangulate_ms, &t->normals_ms, &t->segment_ms,
                    &t->analyze_ms, &t->total_ms}) {
    *x *= k;
  }
}

}  // namespace

void ApplyTrueLabels(const Sequence& sequence, std::int64_t timestamp_ns, const RectifiedGeometry& geometry,
                     ImageU8* labels) {
  const std::string path = TruthFramePath(sequence, "labels", timestamp_ns);
  const ImageU8 truth = ReadTrueLabels(sequence, timestamp_ns);
  if (truth.width() != geometry.full_width || truth.height() != geometry.full_height) {
    throw Error(path + ": the true labels are " + std::to_string(truth.width()) + "x" +
                std::to_string(truth.height()) + ", the frames are " + std::to_string(geometry.full_width) + "x" +
                std::to_string(geometry.full_height));
  }
  SSTA_CHECK(labels->width() == geometry.crop_width && labels->height() == geometry.crop_height,
             "ApplyTrueLabels: the labels are not of the common area's size");
  for (int v = 0; v < labels->height(); ++v) {
    const std::uint8_t* t = truth.row(v + geometry.crop_v0) + geometry.crop_u0;
    std::uint8_t* out = labels->row(v);
    for (int u = 0; u < labels->width(); ++u) {
      if (t[u] >= 1 && t[u] <= 3) out[u] = t[u];
    }
  }
}


bool ClassifyOptions::IsValid(std::string* error) const {
  if (out_dir.empty()) return Fail(error, "out: an output folder is required");
  if (max_frames < 0) return Fail(error, "max-frames: must not be negative");
  if (every < 1) return Fail(error, "every: must be at least 1");
  return true;
}

ClassifySummary ClassifySequence(const Sequence& sequence, const Config& config,
                                 const ClassifyOptions& options, const ProgressCallback& progress) {
  std::string error;
  if (!options.IsValid(&error)) throw Error(error);
  FramePipeline pipeline(sequence.calibration(), config);
  const GravityProvider gravity(sequence, config.gravity, config.attitude);
  // The frames of an earlier, longer run would stay beside this one's and be scored.
  const int stale_files_removed = RemoveFrameOutputs(options.out_dir);
  WriteRunConfig(config, options.out_dir);  // creates out_dir

  const std::vector<StereoFrame> todo = SelectFrames(sequence.frames(), options.every, options.max_frames);

  ClassifySummary summary;
  summary.stale_files_removed = stale_files_removed;
  summary.frames_total = static_cast<int>(sequence.frames().size() + sequence.skipped().size());
  summary.skipped = sequence.skipped();
  if (options.strict && !summary.skipped.empty()) {
    throw Error(sequence.root() + ": frame " + std::to_string(summary.skipped.front().timestamp_ns) + ": " +
                summary.skipped.front().reason + " (strict: no frame may be skipped)");
  }
  const auto start = std::chrono::steady_clock::now();
  int done = 0;
  for (const StereoFrame& frame : todo) {
    const std::string name = std::to_string(frame.timestamp_ns);
    try {
      const StereoImages images = ReadStereoImages(frame, sequence.calibration());
      const ImageU8& left = images.left;
      const ImageU8& right = images.right;
      const Eigen::Vector3d up = gravity.UpInCamera(frame.timestamp_ns);
      FrameResult result = options.oracle_disparity
                               ? pipeline.ProcessWithDisparity(left, right, ReadTrueDisparity(sequence, frame.timestamp_ns), up)
                               : pipeline.Process(left, right, up);
      result.timestamp_ns = frame.timestamp_ns;
      WriteFrameOutputs(result, options.out_dir, name, options.write_disparity);
      ++summary.frames_classified;
      Accumulate(result.timings, &summary.mean_timings);
      for (std::size_t i = 0; i < result.labels.size(); ++i) {
        if (result.labels[i] < 5) ++summary.class_pixels[result.labels[i]];
      }
      if (!result.analysis.quality.passed) {
        summary.quality_failed.push_back({frame.timestamp_ns, result.analysis.quality.reason});
      }
    } catch (const Error& e) {
      // A frame whose images cannot be read or have the wrong size is skipped, not fatal.
      if (options.strict) throw Error(std::string(e.what()) + " (strict: no frame may be skipped)");
      summary.skipped.push_back({frame.timestamp_ns, e.what()});
    }
    if (progress) progress(++done, static_cast<int>(todo.size()));
  }
  summary.wall_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  if (summary.frames_classified > 0) Scale(1.0 / summary.frames_classified, &summary.mean_timings);
  WriteTextAtomically(options.out_dir + "/summary.json", summary.Json());
  return summary;
}

std::string ClassifySummary::BriefReport() const {
  std::ostringstream r;
  r << std::fixed << std::setprecision(1);
  r << "frames: " << frames_classified << " classified, " << skipped.size() << " skipped, "
    << quality_failed.size() << " failed the quality check (of " << frames_total << " listed)\n";
  for (const auto& s : skipped) r << "  skipped " << s.timestamp_ns << ": " << s.reason << "\n";
  for (const auto& s : quality_failed) r << "  undecided " << s.timestamp_ns << ": " << s.reason << "\n";
  if (stale_files_removed > 0) r << "removed " << stale_files_removed << " frame files of an earlier run first\n";
  std::int64_t total = 0;
  for (auto n : class_pixels) total += n;
  if (total > 0) {
    r << "pixels:";
    for (int c = 0; c < 5; ++c) {
      r << " " << ClassName(static_cast<TravClass>(c)) << " " << 100.0 * class_pixels[c] / total << "%";
    }
    r << "\n";
  }
  const StageTimings& t = mean_timings;
  r << "mean ms/frame: rectify " << t.rectify_ms << ", match " << t.match_ms << ", triangulate "
    << t.triangulate_ms << ", normals " << t.normals_ms << ", segment " << t.segment_ms << ", analyze "
    << t.analyze_ms << ", total " << t.total_ms << " (wall " << wall_s << " s)\n";
  return r.str();
}

std::string ClassifySummary::Json() const {
  std::ostringstream j;
  j << "{\n  \"frames_total\": " << frames_total << ",\n  \"frames_classified\": " << frames_classified
    << ",\n  \"skipped\": [";
  for (std::size_t i = 0; i < skipped.size(); ++i) {
    j << (i ? ", " : "") << "{\"timestamp_ns\": " << skipped[i].timestamp_ns << ", \"reason\": \""
      << internal::JsonEscape(skipped[i].reason) << "\"}";
  }
  j << "],\n  \"quality_failed\": [";
  for (std::size_t i = 0; i < quality_failed.size(); ++i) {
    j << (i ? ", " : "") << "{\"timestamp_ns\": " << quality_failed[i].timestamp_ns << ", \"reason\": \""
      << internal::JsonEscape(quality_failed[i].reason) << "\"}";
  }
  j << "],\n  \"class_pixels\": {";
  for (int c = 0; c < 5; ++c) {
    j << (c ? ", " : "") << "\"" << ClassName(static_cast<TravClass>(c)) << "\": " << class_pixels[c];
  }
  const StageTimings& t = mean_timings;
  j << "},\n  \"mean_timings_ms\": {\"rectify\": " << t.rectify_ms << ", \"match\": " << t.match_ms
    << ", \"triangulate\": " << t.triangulate_ms << ", \"normals\": " << t.normals_ms << ", \"segment\": "
    << t.segment_ms << ", \"analyze\": " << t.analyze_ms << ", \"total\": " << t.total_ms << "},\n"
    << "  \"wall_s\": " << wall_s << "\n}\n";
  return j.str();
}

}  // namespace ssta
