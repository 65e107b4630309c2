#include "ssta/pipeline/sequence_classifier.h"

#include <chrono>
#include <filesystem>
#include <iomanip>
#include <sstream>

#include "core/json_escape.h"
#include "ssta/files/file_util.h"
#include "ssta/io/ground_truth.h"
#include "ssta/io/image_io.h"
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

bool ClassifyOptions::IsValid(std::string* error) const {
  if (out_dir.empty()) return Fail(error, "out: an output folder is required");
  return frames.IsValid(error);
}

ClassifySummary ClassifySequence(const Sequence& sequence, const Config& config, const ClassifyOptions& options,
                                 const Progress& progress) {
  std::string error;
  if (!options.IsValid(&error)) throw Error(error);
  SequenceRun run(sequence, config, options.frames, Oracles{options.oracle_disparity, false});
  ClassifySummary summary;
  // The frames of an earlier, longer run would stay beside this one's and be scored.
  summary.stale_files_removed = RemoveFrameOutputs(options.out_dir);
  WriteRunConfig(config, options.out_dir);  // creates out_dir
  summary.frames_total = run.frames_listed();
  summary.skipped = run.sequence_skips();
  const auto start = std::chrono::steady_clock::now();
  int done = 0;
  for (const StereoFrame& frame : run.frames()) {
    try {
      const FrameResult result = run.Classify(frame, run.gravity().UpInCamera(frame.timestamp_ns));
      FrameOutputExtras extras;
      extras.disparity = options.write_disparity;
      extras.explain = options.write_explain;
      WriteFrameOutputs(result, options.out_dir, std::to_string(frame.timestamp_ns), extras);
      summary.Add(result);
    } catch (const StrictStop&) {
      throw;
    } catch (const Error& e) {
      // A frame whose images cannot be read or have the wrong size is skipped, not fatal.
      run.RequireNotStrict(frame.timestamp_ns, e.what());
      summary.skipped.push_back({frame.timestamp_ns, e.what()});
    }
    if (progress) progress(++done, static_cast<int>(run.frames().size()));
  }
  summary.wall_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  if (summary.frames_classified > 0) Scale(1.0 / summary.frames_classified, &summary.mean_timings);
  WriteTextAtomically(options.out_dir + "/summary.json", summary.Json());
  return summary;
}

void ClassifySummary::Add(const FrameResult& frame) {
  ++frames_classified;
  Accumulate(frame.timings, &mean_timings);
  for (std::size_t i = 0; i < frame.labels.size(); ++i) {
    if (frame.labels[i] < 5) ++class_pixels[frame.labels[i]];
  }
  if (!frame.analysis.quality.judged) quality_failed.push_back({frame.timestamp_ns, frame.analysis.quality.reason});
}

std::string ClassifySummary::BriefReport() const {
  std::ostringstream r;
  r << std::fixed << std::setprecision(1);
  r << "frames: " << frames_classified << " classified, " << skipped.size() << " skipped, "
    << quality_failed.size() << " left undecided by the quality check (of " << frames_total << " listed)\n";
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
