#include "ssta/pipeline/frame_report.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <iomanip>
#include <sstream>

#include <opencv2/imgproc.hpp>

#include "core/json_escape.h"
#include "ssta/analysis/label_rule.h"
#include "ssta/files/file_util.h"
#include "ssta/io/image_io.h"

namespace ssta {
namespace {


// Finite numbers as they are, NaN/inf as null (JSON has no NaN).
std::string Num(double x) {
  if (!std::isfinite(x)) return "null";
  std::ostringstream s;
  s << std::setprecision(6) << x;
  return s.str();
}

template <typename Vec>
std::string Array(const Vec& v) {
  std::string out = "[";
  for (int i = 0; i < v.size(); ++i) out += (i ? ", " : "") + Num(v[i]);
  return out + "]";
}

ImageRgb FalseColourDisparity(const ImageF& disparity) {
  float max_d = 1.0f;
  for (std::size_t i = 0; i < disparity.size(); ++i) max_d = std::max(max_d, disparity[i]);
  cv::Mat grey(disparity.height(), disparity.width(), CV_8UC1);
  for (int v = 0; v < disparity.height(); ++v) {
    for (int u = 0; u < disparity.width(); ++u) {
      grey.at<std::uint8_t>(v, u) = static_cast<std::uint8_t>(std::lround(255.0f * disparity(v, u) / max_d));
    }
  }
  cv::Mat colour;
  cv::applyColorMap(grey, colour, cv::COLORMAP_TURBO);
  ImageRgb out(disparity.width(), disparity.height());
  for (int v = 0; v < disparity.height(); ++v) {
    for (int u = 0; u < disparity.width(); ++u) {
      const auto bgr = colour.at<cv::Vec3b>(v, u);
      out(v, u) = disparity(v, u) > 0 ? Rgb8{bgr[2], bgr[1], bgr[0]} : Rgb8{0, 0, 0};
    }
  }
  return out;
}

/// Pixels per rule and class over the frame's full-size labels and rules.
std::array<std::array<long, kNumClasses>, kNumLabelRules> PixelsByRule(const FrameResult& f) {
  std::array<std::array<long, kNumClasses>, kNumLabelRules> counts{};
  if (f.rules.width() != f.labels.width() || f.rules.height() != f.labels.height()) return counts;
  for (std::size_t i = 0; i < f.labels.size(); ++i) {
    const int rule = f.rules[i], c = f.labels[i];
    if (rule < kNumLabelRules && c < kNumClasses) ++counts[rule][c];
  }
  return counts;
}

/// The rule image in colour over the left image, with a legend of the rules present: a swatch,
/// the name and the pixel count per line, in the top left corner.
ImageRgb ExplainPicture(const ImageU8& grey, const ImageU8& rules) {
  cv::Mat picture(rules.height(), rules.width(), CV_8UC3);
  std::array<long, kNumLabelRules> count{};
  for (int v = 0; v < rules.height(); ++v) {
    for (int u = 0; u < rules.width(); ++u) {
      const int rule = std::min<int>(rules(v, u), kNumLabelRules - 1);
      ++count[rule];
      const Rgb8 c = LabelRules()[rule].colour;
      const int g = grey.width() == rules.width() && grey.height() == rules.height() ? grey(v, u) : 128;
      auto mix = [&](int channel) { return static_cast<std::uint8_t>((2 * channel + g) / 3); };
      picture.at<cv::Vec3b>(v, u) = cv::Vec3b(mix(c.r), mix(c.g), mix(c.b));  // RGB order in the Mat
    }
  }
  const double scale = 0.4;
  const int line = 14;
  int y = 4;
  for (const LabelRuleInfo& info : LabelRules()) {
    const long n = count[static_cast<int>(info.rule)];
    if (n == 0) continue;
    const std::string text = std::string(info.name) + " " + std::to_string(n);
    cv::rectangle(picture, cv::Rect(2, y, 150, line), cv::Scalar(0, 0, 0), cv::FILLED);
    cv::rectangle(picture, cv::Rect(4, y + 2, 10, line - 4), cv::Scalar(info.colour.r, info.colour.g, info.colour.b),
                  cv::FILLED);
    cv::putText(picture, text, cv::Point(18, y + line - 3), cv::FONT_HERSHEY_SIMPLEX, scale,
                cv::Scalar(255, 255, 255), 1, cv::LINE_AA);
    y += line;
  }
  ImageRgb out(rules.width(), rules.height());
  for (int v = 0; v < rules.height(); ++v) {
    for (int u = 0; u < rules.width(); ++u) {
      const auto px = picture.at<cv::Vec3b>(v, u);
      out(v, u) = Rgb8{px[0], px[1], px[2]};
    }
  }
  return out;
}

}  // namespace

std::string FrameReportJson(const FrameResult& f, const std::string& name) {
  const AnalysisResult& a = f.analysis;
  std::ostringstream j;
  j << "{\n  \"frame\": \"" << internal::JsonEscape(name) << "\",\n  \"timestamp_ns\": " << f.timestamp_ns << ",\n";
  j << "  \"up_camera\": " << Array(f.up_rectified) << ",\n";
  j << "  \"depth_pixels\": " << a.depth_pixels << ",\n  \"inliers_min\": " << a.inliers_min << ",\n";
  j << "  \"labels_min_texture\": " << Num(f.labels_min_texture) << ",\n";
  j << "  \"quality\": {\"passed\": " << (a.quality.passed ? "true" : "false")
    << ", \"judged\": " << (a.quality.judged ? "true" : "false") << ", \"reason\": \""
    << internal::JsonEscape(a.quality.reason) << "\"},\n";
  j << "  \"ground_plane\": ";
  if (a.ground.found) {
    j << "{\"segment\": " << a.ground.segment_id << ", \"plane\": " << Array(a.ground.plane)
      << ", \"camera_height_m\": " << Num(a.ground.camera_height_m) << ", \"rms_m\": " << Num(a.ground.rms_m)
      << ", \"share\": " << Num(a.ground.share) << "},\n";
  } else {
    j << "null,\n";
  }
  const StageTimings& t = f.timings;
  j << "  \"timings_ms\": {\"rectify\": " << Num(t.rectify_ms) << ", \"match\": " << Num(t.match_ms)
    << ", \"triangulate\": " << Num(t.triangulate_ms) << ", \"normals\": " << Num(t.normals_ms)
    << ", \"segment\": " << Num(t.segment_ms) << ", \"analyze\": " << Num(t.analyze_ms)
    << ", \"total\": " << Num(t.total_ms) << "},\n";
  // Segments of fewer than min_plane_points points are fragments of noisy surfaces: listing
  // each (tens of thousands on real stereo) would make the report huge, so they are summed up.
  std::array<long, kNumClasses> fragment_pixels{};
  long fragments = 0;
  for (const SegmentResult& s : a.segments) {
    if (s.inliers > 0 && s.inliers < a.min_plane_points) {
      ++fragments;
      fragment_pixels[static_cast<int>(s.verdict)] += s.inliers;
    }
  }
  j << "  \"fragments\": {\"segments\": " << fragments << ", \"pixels_by_class\": {";
  for (int c = 0; c < kNumClasses; ++c) {
    j << (c ? ", " : "") << "\"" << ClassName(static_cast<TravClass>(c)) << "\": " << fragment_pixels[c];
  }
  j << "}},\n";
  // Which rule set how many pixels of each class (LabelRule; the rules' pixels add up to the
  // labels' per class).
  const auto by_rule = PixelsByRule(f);
  j << "  \"pixels_by_rule\": {";
  for (const LabelRuleInfo& info : LabelRules()) {
    const auto& counts = by_rule[static_cast<int>(info.rule)];
    j << (info.rule == LabelRule::kNoDepth ? "\n" : ",\n") << "    \"" << info.name << "\": {";
    for (int c = 0; c < kNumClasses; ++c) {
      j << (c ? ", " : "") << "\"" << ClassName(static_cast<TravClass>(c)) << "\": " << counts[c];
    }
    j << "}";
  }
  j << "\n  },\n";
  j << "  \"segments\": [";
  bool first = true;
  for (const SegmentResult& s : a.segments) {
    if (s.inliers == 0 || s.inliers < a.min_plane_points) continue;
    j << (first ? "\n" : ",\n") << "    {\"id\": " << s.id << ", \"inliers\": " << s.inliers;
    first = false;
    if (s.has_plane) {
      j << ", \"centroid\": " << Array(s.centroid) << ", \"normal\": " << Array(s.normal)
        << ", \"plane\": " << Array(s.plane) << ", \"rms_m\": " << Num(s.rms_m)
        << ", \"slope_deg\": " << Num(s.slope_deg) << ", \"slope_sigma_deg\": " << Num(s.slope_sigma_deg)
        << ", \"rise_m\": " << Num(s.rise_m) << ", \"step_m\": " << Num(s.step_m);
    }
    j << ", \"class\": " << static_cast<int>(s.verdict) << ", \"class_name\": \"" << ClassName(s.verdict)
      << "\", \"ground\": " << (s.ground ? "true" : "false") << ", \"reason\": \"" << internal::JsonEscape(s.reason) << "\"}";
  }
  j << "\n  ]\n}\n";
  return j.str();
}

int RemoveFrameOutputs(const std::string& out_dir) {
  int removed = 0;
  for (const char* dir : {"labels", "overlay", "disparity", "disparity_colour", "explain", "explain_colour"}) {
    removed += RemoveFrameFiles(out_dir + "/" + dir, ".png");
  }
  return removed + RemoveFrameFiles(out_dir + "/frames", ".json");
}

void WriteRunConfig(const Config& config, const std::string& out_dir) {
  MakeDirectories(out_dir);
  WriteTextAtomically(out_dir + "/config.yaml",
                      "# ssta classify: the configuration of this run (defaults, the sequence's vehicle.yaml, "
                      "--config files)\n" + ConfigToYaml(config));
}

void WriteFrameOutputs(const FrameResult& frame, const std::string& out_dir, const std::string& name,
                       const FrameOutputExtras& extras) {
  const bool disparity = extras.disparity;
  for (const char* sub : {"labels", "overlay", "frames"}) MakeDirectories(out_dir + "/" + sub);
  WriteImage(frame.labels, out_dir + "/labels/" + name + ".png");
  WriteImage(MakeOverlay(frame.left_rectified, frame.labels), out_dir + "/overlay/" + name + ".png");
  WriteTextAtomically(out_dir + "/frames/" + name + ".json", FrameReportJson(frame, name));
  if (disparity) {
    // KITTI's convention (as gt/disparity): 16 bit, disparity * 256, 0 = none; and a picture.
    MakeDirectories(out_dir + "/disparity");
    MakeDirectories(out_dir + "/disparity_colour");
    ImageU16 fixed(frame.disparity.width(), frame.disparity.height());
    for (std::size_t i = 0; i < fixed.size(); ++i) {
      const float d = frame.disparity[i];
      fixed[i] = d > 0.0f ? static_cast<std::uint16_t>(std::min(65535L, std::lround(d * 256.0f))) : std::uint16_t{0};
    }
    WriteImage(fixed, out_dir + "/disparity/" + name + ".png");
    WriteImage(FalseColourDisparity(frame.disparity), out_dir + "/disparity_colour/" + name + ".png");
  }
  if (extras.explain) {
    MakeDirectories(out_dir + "/explain");
    MakeDirectories(out_dir + "/explain_colour");
    WriteImage(frame.rules, out_dir + "/explain/" + name + ".png");
    WriteImage(ExplainPicture(frame.left_rectified, frame.rules), out_dir + "/explain_colour/" + name + ".png");
  }
}

}  // namespace ssta
