// ssta calibrate-stereo: a stereo rig's sensor.yaml files from chessboard image pairs.

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <sstream>

#include "commands.h"
#include "ssta/calibration/stereo_calibrator.h"
#include "ssta/core/error.h"
#include "ssta/pipeline/config.h"

namespace ssta::cli {
namespace {

struct CalibrateStereoArgs {
  std::vector<std::string> left, right;
  std::string board = "9x6";
  std::string coverage_grid = "8x6";
  std::string body_T_cam0;
  std::string out;
  bool fix_intrinsics = false;
  bool quiet = false;
  std::vector<std::string> config;
  StereoCalibratorOptions options;
};

/// "9x6" -> (9, 6); throws naming the option.
void ParseGrid(const std::string& text, const std::string& option, int* cols, int* rows) {
  int c = 0, r = 0;
  char x = 0, extra = 0;
  if (std::sscanf(text.c_str(), "%d%c%d%c", &c, &x, &r, &extra) != 3 || (x != 'x' && x != 'X')) {
    throw Error(option + ": expected COLSxROWS such as 9x6, got '" + text + "'");
  }
  *cols = c;
  *rows = r;
}

/// Each argument is a glob pattern (quote it so that the program, not the shell, expands it)
/// or a file name; the matches of all of them, in byte order.
std::vector<std::string> ExpandAll(const std::vector<std::string>& patterns, const std::string& option) {
  std::vector<std::string> paths;
  for (const std::string& pattern : patterns) {
    const std::vector<std::string> matches = ExpandGlob(pattern);
    if (matches.empty()) throw Error(option + ": no file matches '" + pattern + "'");
    paths.insert(paths.end(), matches.begin(), matches.end());
  }
  std::sort(paths.begin(), paths.end());
  return paths;
}

/// A YAML file (T_BS block or top-level data:) or 16 comma-separated numbers, row-major.
Eigen::Isometry3d ParseBodyTransform(const std::string& text) {
  if (std::filesystem::exists(text)) return LoadBodyTransform(text);
  std::vector<double> values;
  std::stringstream in(text);
  std::string item;
  while (std::getline(in, item, ',')) {
    try {
      std::size_t used = 0;
      values.push_back(std::stod(item, &used));
      if (item.find_first_not_of(" \t", used) != std::string::npos) throw std::invalid_argument(item);
    } catch (const std::exception&) {
      throw Error("--body-T-cam0: '" + text + "' is neither an existing file nor 16 comma-separated numbers");
    }
  }
  return BodyTransformFromRowMajor(values, "--body-T-cam0");
}

void Run(CalibrateStereoArgs& a) {
  ParseGrid(a.board, "--board", &a.options.board_cols, &a.options.board_rows);
  ParseGrid(a.coverage_grid, "--coverage-grid", &a.options.coverage_cols, &a.options.coverage_rows);
  if (!a.body_T_cam0.empty()) a.options.body_T_cam0 = ParseBodyTransform(a.body_T_cam0);
  a.options.intrinsics = a.fix_intrinsics ? StereoIntrinsics::kFix : StereoIntrinsics::kRefine;
  a.options.rectification = LoadLayeredConfig(nullptr, a.config).rectification;  // names a bad file or key
  std::string error;
  if (!a.options.IsValid(&error)) throw Error("--" + error);

  const std::vector<std::string> left = ExpandAll(a.left, "--left");
  const std::vector<std::string> right = ExpandAll(a.right, "--right");
  const StereoCalibrationSummary summary = CalibrateStereoRig(a.options, left, right, a.out);
  if (!a.quiet) {
    std::cout << summary.BriefReport();
    std::cout << "outputs: " << a.out << "/cam0/sensor.yaml, " << a.out << "/cam1/sensor.yaml, "
              << a.out << "/calibration_report.json, " << a.out << "/rectified_pair.png\n";
  }
}

}  // namespace

void RegisterCalibrateStereo(CLI::App& app) {
  auto args = std::make_shared<CalibrateStereoArgs>();
  CLI::App* cmd = app.add_subcommand(
      "calibrate-stereo",
      "Calibrate a stereo rig from chessboard image pairs; writes cam0/ and cam1/sensor.yaml (ASL)");
  cmd->add_option("--left", args->left,
                  "left images: glob pattern(s) in quotes, e.g. 'L*.jpg', or file names; "
                  "sorted by name and paired with --right in that order")->required();
  cmd->add_option("--right", args->right, "right images, as --left")->required();
  cmd->add_option("--board", args->board, "inner corners of the chessboard, COLSxROWS")->capture_default_str();
  cmd->add_option("--square", args->options.square_m, "side of one chessboard square [m]")->required();
  cmd->add_option("--out", args->out, "output folder (cam0/, cam1/, report, picture)")->required()->check(OutputFolder());
  cmd->add_option("--body-T-cam0", args->body_T_cam0,
                  "pose of cam0 in the body frame: a YAML file (a T_BS block such as a sensor.yaml, "
                  "or data: [16 numbers]) or 16 comma-separated numbers, row-major 4x4; default identity");
  cmd->add_flag("--fix-intrinsics", args->fix_intrinsics,
                "keep each camera's own intrinsics in the stereo solve (default: refine them jointly)");
  cmd->add_option("--outlier-px", args->options.outlier_px,
                  "outliers: pairs taken out worst first, solving again each time, while a pair's "
                  "stereo RMS error (left or right view) exceeds this [px]")->capture_default_str();
  cmd->add_flag("--drop-outliers", args->options.drop_outliers, "leave the outliers out of the final solution (default: only flag them)");
  cmd->add_option("--min-pairs", args->options.min_pairs,
                  "fewest pairs with the board in both views")->capture_default_str();
  cmd->add_option("--coverage-grid", args->coverage_grid,
                  "image cells COLSxROWS for the board coverage figure")->capture_default_str();
  cmd->add_option("--config", args->config,
                  "YAML config (see config/default.yaml); repeatable, later files win. Its rectification "
                  "section (alpha, crop) is how the check rectifies the pairs, as classify and build-map will");
  cmd->add_flag("--quiet,-q", args->quiet, "no report on stdout");
  cmd->callback([args] { Run(*args); });
}

}  // namespace ssta::cli
