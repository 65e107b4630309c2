// StereoCalibrationSummary as text for a terminal and as JSON.

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <limits>
#include <sstream>

#include "ssta/core/json_writer.h"
#include "ssta/calibration/stereo_calibrator.h"
#include "ssta/core/units.h"

namespace ssta {
namespace {

/// Below this fraction of coverage-grid cells the report suggests more views near the edges.
constexpr double kLowCoverage = 0.5;

std::string FileName(const std::string& path) {
  return std::filesystem::path(path).filename().string();
}

std::string Fixed(double value, int decimals) {
  if (!std::isfinite(value)) return "-";
  char buffer[64];
  std::snprintf(buffer, sizeof(buffer), "%.*f", decimals, value);
  return buffer;
}

std::string Status(const CalibrationPairReport& p) {
  if (p.dropped) return "OUTLIER, dropped";
  if (!p.used()) return "skipped: " + p.skip_reason;
  return p.outlier ? "OUTLIER, kept" : "used";
}

double RotationDeg(const Eigen::Isometry3d& t) {
  return RadToDeg(Eigen::AngleAxisd(t.rotation()).angle());
}

void WriteCamera(const CameraCalibration& c, internal::JsonWriter* json) {
  json->BeginObject();
  json->Key("resolution");
  json->BeginInlineArray();
  json->Integer(c.width);
  json->Integer(c.height);
  json->EndArray();
  json->Key("intrinsics_px");
  json->BeginInlineArray();
  for (double v : {c.fu, c.fv, c.cu, c.cv}) json->Number(v);
  json->EndArray();
  json->Key("distortion_k1_k2_p1_p2");
  json->BeginInlineArray();
  for (double v : c.distortion) json->Number(v);
  json->EndArray();
  json->Key("T_BS");
  json->MatrixRows(c.body_T_camera.matrix());
  json->EndObject();
}

/// The chessboard: inner corners (columns, rows) and square size [m].
void WriteBoard(const StereoCalibratorOptions& options, internal::JsonWriter* json) {
  json->BeginObject();
  json->Key("inner_corners");
  json->BeginInlineArray();
  json->Integer(options.board_cols);
  json->Integer(options.board_rows);
  json->EndArray();
  json->Key("square_m");
  json->Number(options.square_m);
  json->EndObject();
}

/// RMS reprojection errors [px]: each camera alone, then the stereo solve.
void WriteRms(const StereoCalibrationSummary& s, internal::JsonWriter* json) {
  json->BeginObject();
  json->Key("left_mono");
  json->Number(s.left_mono_rms_px);
  json->Key("right_mono");
  json->Number(s.right_mono_rms_px);
  json->Key("stereo");
  json->Number(s.stereo_rms_px);
  json->EndObject();
}

/// The coverage grid (columns, rows) and the fraction of its cells with a corner, per camera.
void WriteCoverage(const StereoCalibrationSummary& s, internal::JsonWriter* json) {
  json->BeginObject();
  json->Key("grid");
  json->BeginInlineArray();
  json->Integer(s.options.coverage_cols);
  json->Integer(s.options.coverage_rows);
  json->EndArray();
  json->Key("left");
  json->Number(s.left_coverage);
  json->Key("right");
  json->Number(s.right_coverage);
  json->EndObject();
}

/// A pose as its 4x4 matrix, one inline array per row.
void WritePoseRows(const Eigen::Isometry3d& pose, internal::JsonWriter* json) {
  json->BeginArray();
  const Eigen::Matrix4d m = pose.matrix();
  for (int r = 0; r < 4; ++r) {
    json->BeginInlineArray();
    for (int k = 0; k < 4; ++k) json->Number(m(r, k));
    json->EndArray();
  }
  json->EndArray();
}

/// The epipolar check of the rectified pairs [px]; the errors are NaN when no pair was checked.
void WriteRectification(const RectificationCheck& c, internal::JsonWriter* json) {
  json->BeginObject();
  json->Key("pairs_checked");
  json->Integer(c.pairs_checked);
  json->Key("corners_checked");
  json->Integer(c.corners_checked);
  json->Key("mean_abs_dv_px");
  json->Number(c.pairs_checked > 0 ? c.mean_abs_dv_px : std::numeric_limits<double>::quiet_NaN());
  json->Key("max_abs_dv_px");
  json->Number(c.pairs_checked > 0 ? c.max_abs_dv_px : std::numeric_limits<double>::quiet_NaN());
  json->Key("rectified_f_px");
  json->Number(c.rectified_f_px);
  json->Key("common_area");
  json->BeginInlineArray();
  json->Integer(c.crop_width);
  json->Integer(c.crop_height);
  json->EndArray();
  json->Key("picture_pair");
  json->String(c.picture_pair);
  json->EndObject();
}

/// One input pair: its files, where the board was found, whether it was used, its RMS errors
/// [px] and its outlier status.
void WritePairReport(const CalibrationPairReport& p, internal::JsonWriter* json) {
  json->BeginObject();
  json->Key("left");
  json->String(p.left_path);
  json->Key("right");
  json->String(p.right_path);
  json->Key("board_in_left");
  json->Bool(p.board_in_left);
  json->Key("board_in_right");
  json->Bool(p.board_in_right);
  json->Key("used");
  json->Bool(p.used());
  json->Key("skip_reason");
  json->String(p.skip_reason);
  json->Key("left_mono_rms_px");
  json->Number(p.left_mono_rms_px);
  json->Key("right_mono_rms_px");
  json->Number(p.right_mono_rms_px);
  json->Key("left_stereo_rms_px");
  json->Number(p.left_stereo_rms_px);
  json->Key("right_stereo_rms_px");
  json->Number(p.right_stereo_rms_px);
  json->Key("outlier");
  json->Bool(p.outlier);
  json->Key("dropped");
  json->Bool(p.dropped);
  json->EndObject();
}

}  // namespace

std::string StereoCalibrationSummary::BriefReport() const {
  std::ostringstream out;
  char line[512];
  std::snprintf(line, sizeof(line), "%4s  %-22s %-22s %8s %8s %8s %8s  %s\n", "pair", "left",
                "right", "L mono", "R mono", "L stereo", "R stereo", "status");
  out << line;
  for (std::size_t i = 0; i < pairs.size(); ++i) {
    const CalibrationPairReport& p = pairs[i];
    std::snprintf(line, sizeof(line), "%4zu  %-22s %-22s %8s %8s %8s %8s  %s\n", i + 1,
                  FileName(p.left_path).c_str(), FileName(p.right_path).c_str(),
                  Fixed(p.left_mono_rms_px, 3).c_str(), Fixed(p.right_mono_rms_px, 3).c_str(),
                  Fixed(p.left_stereo_rms_px, 3).c_str(), Fixed(p.right_stereo_rms_px, 3).c_str(),
                  Status(p).c_str());
    out << line;
  }
  const CameraCalibration& l = calibration.left;
  const CameraCalibration& r = calibration.right;
  int outliers = 0, dropped = 0;
  for (const CalibrationPairReport& p : pairs) {
    outliers += p.outlier ? 1 : 0;
    dropped += p.dropped ? 1 : 0;
  }
  out << "per-pair RMS reprojection errors in px; outliers (worst pair out and solve again while "
         "a stereo error exceeds "
      << Fixed(options.outlier_px, 2) << " px): " << outliers;
  if (outliers > dropped) out << ", " << outliers - dropped << " kept (--drop-outliers removes them)";
  out << "\n";
  out << "pairs used: " << pairs_used << " of " << pairs.size() << ", images " << l.width << "x"
      << l.height << ", board " << options.board_cols << "x" << options.board_rows
      << " inner corners, square " << Fixed(options.square_m * 1000.0, 2) << " mm\n";
  out << "RMS reprojection error: left " << Fixed(left_mono_rms_px, 4) << " px, right "
      << Fixed(right_mono_rms_px, 4) << " px (each camera alone), stereo "
      << Fixed(stereo_rms_px, 4) << " px ("
      << (options.intrinsics == StereoIntrinsics::kFix ? "intrinsics fixed" : "intrinsics refined")
      << ")\n";
  if (stereo_rms_px > options.outlier_px) {
    out << "WARNING: the stereo RMS error is above the outlier threshold of "
        << Fixed(options.outlier_px, 2)
        << " px; this calibration is unlikely to be usable: check the flagged pairs, or run "
           "again with --drop-outliers\n";
  }
  out << "board coverage (" << options.coverage_cols << "x" << options.coverage_rows
      << " cells touched by corners): left " << Fixed(left_coverage * 100.0, 0) << " %, right "
      << Fixed(right_coverage * 100.0, 0) << " %\n";
  if (std::min(left_coverage, right_coverage) < kLowCoverage) {
    out << "note: the boards cover little of the image; distortion is only measured where "
           "corners were seen, so add views with the board near the edges and corners\n";
  }
  for (const auto* cam : {&l, &r}) {
    out << (cam == &l ? "cam0" : "cam1") << ": fu " << Fixed(cam->fu, 2) << ", fv "
        << Fixed(cam->fv, 2) << ", cu " << Fixed(cam->cu, 2) << ", cv " << Fixed(cam->cv, 2)
        << " px; k1 " << Fixed(cam->distortion[0], 4) << ", k2 " << Fixed(cam->distortion[1], 4)
        << ", p1 " << Fixed(cam->distortion[2], 5) << ", p2 " << Fixed(cam->distortion[3], 5)
        << "\n";
  }
  const Eigen::Vector3d t = cam0_T_cam1.translation();
  out << "baseline: " << Fixed(baseline_m, 4) << " m; cam1 in cam0 at [" << Fixed(t.x(), 4)
      << ", " << Fixed(t.y(), 4) << ", " << Fixed(t.z(), 4) << "] m, rotated "
      << Fixed(RotationDeg(cam0_T_cam1), 3) << " deg\n";
  const RectificationCheck& c = rectification;
  if (c.pairs_checked > 0) {
    out << "rectified (project Rectifier): f " << Fixed(c.rectified_f_px, 1) << " px, common area "
        << c.crop_width << "x" << c.crop_height << "; epipolar error |v_left - v_right| mean "
        << Fixed(c.mean_abs_dv_px, 3) << " px, max " << Fixed(c.max_abs_dv_px, 3) << " px over "
        << c.corners_checked << " corners in " << c.pairs_checked << " pairs\n";
  } else if (c.crop_width > 0) {
    out << "rectified (project Rectifier): the board was not found again in any rectified pair; "
           "no epipolar check\n";
  }
  return out.str();
}

std::string StereoCalibrationSummary::ToJson() const {
  internal::JsonWriter json;
  json.BeginObject();
  json.Key("board");
  WriteBoard(options, &json);
  json.Key("intrinsics_mode");
  json.String(options.intrinsics == StereoIntrinsics::kFix ? "fixed" : "refined");
  json.Key("outlier_px");
  json.Number(options.outlier_px);
  json.Key("drop_outliers");
  json.Bool(options.drop_outliers);
  json.Key("pairs_total");
  json.Integer(static_cast<std::int64_t>(pairs.size()));
  json.Key("pairs_used");
  json.Integer(pairs_used);
  json.Key("rms_px");
  WriteRms(*this, &json);
  json.Key("coverage");
  WriteCoverage(*this, &json);
  json.Key("baseline_m");
  json.Number(baseline_m);
  json.Key("cam0_T_cam1");
  WritePoseRows(cam0_T_cam1, &json);
  json.Key("cam0");
  WriteCamera(calibration.left, &json);
  json.Key("cam1");
  WriteCamera(calibration.right, &json);
  json.Key("rectification");
  WriteRectification(rectification, &json);
  json.Key("pairs");
  json.BeginArray();
  for (const CalibrationPairReport& p : pairs) WritePairReport(p, &json);
  json.EndArray();
  json.EndObject();
  return json.Take();
}

}  // namespace ssta
