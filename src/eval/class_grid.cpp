#include "ssta/eval/class_grid.h"

#include <cmath>
#include <filesystem>
#include <vector>

#include "ssta/files/yaml_reader.h"
#include "ssta/core/classes.h"
#include "ssta/core/error.h"
#include "ssta/files/file_util.h"
#include "ssta/io/image_io.h"
#include "ssta/synth/sequence_synthesizer.h"

namespace ssta {
namespace {

// Index of the half-open unit interval holding `f`. Values within a rounding error of an
// integer are snapped to it, so a point computed to lie on an edge lands in the same cell on
// every platform.
long CellIndex(double f) {
  const double nearest = std::round(f);
  const double snapped = std::abs(f - nearest) < 1e-9 ? nearest : std::floor(f);
  return static_cast<long>(snapped);
}

}  // namespace

std::optional<GridCell> ClassGrid::CellAt(const Eigen::Vector2d& p_world) const {
  if (!p_world.allFinite() || resolution_m <= 0.0) return std::nullopt;
  const double fx = (p_world.x() - origin_m.x()) / resolution_m;
  const double fy = (p_world.y() - origin_m.y()) / resolution_m;
  // Guard the conversion to long against absurd coordinates.
  if (std::abs(fx) > 1e12 || std::abs(fy) > 1e12) return std::nullopt;
  const long col = CellIndex(fx);
  const long row_from_bottom = CellIndex(fy);
  if (col < 0 || col >= classes.width() || row_from_bottom < 0 ||
      row_from_bottom >= classes.height()) {
    return std::nullopt;
  }
  return GridCell{classes.height() - 1 - static_cast<int>(row_from_bottom), static_cast<int>(col)};
}

Eigen::Vector2d ClassGrid::CellCentre(const GridCell& cell) const {
  const int row_from_bottom = classes.height() - 1 - cell.row;
  return origin_m + resolution_m * Eigen::Vector2d(cell.col + 0.5, row_from_bottom + 0.5);
}

std::uint8_t ClassGrid::ClassAt(const Eigen::Vector2d& p_world) const {
  const auto cell = CellAt(p_world);
  if (!cell) return static_cast<std::uint8_t>(TravClass::kUnknown);
  return classes(cell->row, cell->col);
}

ClassGrid ReadClassGrid(const std::string& yaml_path, const std::string& classes_png) {
  if (!std::filesystem::exists(yaml_path)) throw Error(yaml_path + ": grid YAML file not found");
  internal::YamlSection yaml(internal::ParseYaml(ReadTextFile(yaml_path), yaml_path), yaml_path,
                             "");
  ClassGrid grid;
  grid.resolution_m = yaml.Require<double>("resolution");
  if (!std::isfinite(grid.resolution_m) || grid.resolution_m <= 0.0) {
    throw Error(yaml.Name("resolution") + ": must be a positive number of metres per cell");
  }
  const auto origin = yaml.Require<std::vector<double>>("origin");
  if (origin.size() != 2 && origin.size() != 3) {
    throw Error(yaml.Name("origin") + ": expected [x, y] or [x, y, yaw]");
  }
  for (const double value : origin) {
    if (!std::isfinite(value)) throw Error(yaml.Name("origin") + ": values must be finite");
  }
  if (origin.size() == 3 && origin[2] != 0.0) {
    throw Error(yaml.Name("origin") + ": a rotated grid (yaw " + std::to_string(origin[2]) +
                ") is not supported; yaw must be 0");
  }
  grid.origin_m = Eigen::Vector2d(origin[0], origin[1]);
  yaml.Read("seen", &grid.seen);
  grid.classes = ReadLabelImage(classes_png);
  grid.source = classes_png;
  return grid;
}

std::string FindGroundTruthDir(const std::string& sequence) {
  namespace fs = std::filesystem;
  for (const fs::path& candidate : {fs::path(sequence) / "gt", fs::path(sequence) / "mav0" / "gt"}) {
    if (fs::is_directory(candidate)) return candidate.string();
  }
  // Also accept the gt folder itself.
  fs::path normal = fs::path(sequence).lexically_normal();
  if (normal.filename().empty()) normal = normal.parent_path();  // trailing slash
  if (normal.filename() == "gt" && fs::is_directory(normal)) return normal.string();
  throw Error(sequence + ": no ground truth (looked for " + (fs::path(sequence) / "gt").string() +
              " and " + (fs::path(sequence) / "mav0" / "gt").string() + ")");
}

ClassGrid ReadGroundTruthGrid(const std::string& sequence) {
  const std::filesystem::path gt = FindGroundTruthDir(sequence);
  return ReadClassGrid((gt / "grid.yaml").string(), (gt / "grid_classes.png").string());
}

std::string StaleTruthGridWarning(const ClassGrid& truth) {
  if (truth.seen == synth::kTruthSeenBothCameras) return "";
  const std::string yaml = (std::filesystem::path(truth.source).parent_path() / "grid.yaml").string();
  return "warning: " + yaml + ": no 'seen: " + synth::kTruthSeenBothCameras +
         "': an older ssta synth rendered this truth, and its grid leaves the cells along class boundaries "
         "(beside every obstacle and lip) unscored; render the sequence again (ssta synth) to score them";
}

}  // namespace ssta
