// Fleet mapping on a rendered scene: a drive split into parts, each mapped on its own and the
// maps merged, against the same drive mapped in one run (docs/fleet.md holds the figures).

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <map>
#include <string>
#include <tuple>
#include <vector>

#include "ssta/eval/grid_evaluator.h"
#include "ssta/files/file_util.h"
#include "ssta/mapping/map_export.h"
#include "ssta/mapping/map_merge.h"
#include "ssta/pipeline/config.h"
#include "ssta/pipeline/map_builder.h"
#include "ssta/synth/sequence_synthesizer.h"
#include "temp_dir.h"

namespace ssta {
namespace {

namespace fs = std::filesystem;

/// A small, quick drive through the forest: 24 frames of 320x240 at 5 Hz (4.8 m), truth to 12 m.
synth::SynthOptions SmallForest() {
  synth::SynthOptions o;
  o.scene = "forest";
  o.frames = 24;
  o.seed = 1;
  o.rig.width = 320;
  o.rig.height = 240;
  o.rig.focal_px = 210.0;
  o.rig.rate_hz = 5.0;
  o.render.max_label_range_m = 12.0;
  o.render.threads = 2;
  return o;
}

/// A copy of the sequence `from` at `to` that lists only frames [first, first + count): a
/// recording of part of the drive (poses and IMU stay whole; frames select what is fused).
void CopyPart(const std::string& from, const std::string& to, int first, int count) {
  fs::copy(from, to, fs::copy_options::recursive);
  for (const char* cam : {"cam0", "cam1"}) {
    std::ifstream in(from + "/" + cam + "/data.csv");
    std::ofstream out(to + "/" + cam + "/data.csv");
    std::string line;
    std::getline(in, line);
    out << line << '\n';
    for (int i = 0; std::getline(in, line); ++i) {
      if (i >= first && i < first + count) out << line << '\n';
    }
  }
}

std::string Build(const std::string& seq, const std::string& map) {
  BuildMapOptions options;
  options.map_path = map;
  BuildMap(Sequence::Open(seq), fs::path(seq).filename().string(), Config{}, options);
  return map;
}

/// Grid accuracy of `map` against the truth of the whole drive.
double GridAccuracy(const TraversabilityMap& map, const std::string& truth_seq, const std::string& prefix) {
  ExportGrid(map, prefix);
  return EvaluateExportedGrid(prefix, truth_seq).matrix.Accuracy();
}

/// Occupied voxels whose class differs between `a` and `b`, or that only one holds, over the
/// occupied voxels of either.
double VoxelDisagreement(const TraversabilityMap& a, const TraversabilityMap& b) {
  std::map<std::tuple<long, long, long>, std::pair<int, int>> cells;
  auto key = [&](const CellInfo& c) {
    const double r = a.options().resolution_m;
    return std::make_tuple(std::lround(std::floor(c.center.x() / r)), std::lround(std::floor(c.center.y() / r)),
                           std::lround(std::floor(c.center.z() / r)));
  };
  for (const CellInfo& c : a.SurfaceCells()) cells[key(c)].first = static_cast<int>(c.cls) + 1;
  for (const CellInfo& c : b.SurfaceCells()) cells[key(c)].second = static_cast<int>(c.cls) + 1;
  int differ = 0;
  for (const auto& [k, classes] : cells) differ += classes.first != classes.second ? 1 : 0;
  return cells.empty() ? 0.0 : static_cast<double>(differ) / cells.size();
}

TEST(FleetMerge, HalvesMappedApartAndMergedMatchOneRunWithinAPoint) {
  // Measured (forest, 24 frames): one run 0.8126, halves merged 0.8087 (-0.4 points); the
  // quarters below 0.8033 to 0.8060 by merge order.
  const testing::TempDir dir;
  synth::WriteSyntheticSequence(SmallForest(), dir / "drive");
  CopyPart(dir / "drive", dir / "h0", 0, 12);
  CopyPart(dir / "drive", dir / "h1", 12, 12);

  const double one_run = GridAccuracy(TraversabilityMap::Load(Build(dir / "drive", dir / "drive.ot")),
                                      dir / "drive", dir / "g_one");
  const TraversabilityMap merged = MergeMaps({Build(dir / "h0", dir / "h0.ot"), Build(dir / "h1", dir / "h1.ot")});
  const double halves = GridAccuracy(merged, dir / "drive", dir / "g_halves");
  RecordProperty("one_run_accuracy", std::to_string(one_run));
  RecordProperty("halves_merged_accuracy", std::to_string(halves));
  EXPECT_GT(one_run, 0.75);  // the scene is mapped at all
  EXPECT_NEAR(halves, one_run, 0.01);

  // Four quarters merged in three orders: the clamps make the voxels differ a little.
  std::vector<std::string> quarters;
  for (int q = 0; q < 4; ++q) {
    const std::string name = "q" + std::to_string(q);
    CopyPart(dir / "drive", dir / name, 6 * q, 6);
    quarters.push_back(Build(dir / name, dir / (name + ".ot")));
  }
  const TraversabilityMap in_order = MergeMaps(quarters);
  MergeMaps({quarters[0], quarters[1]}).Save(dir / "q01.ot");
  MergeMaps({quarters[2], quarters[3]}).Save(dir / "q23.ot");
  const TraversabilityMap as_tree = MergeMaps({dir / "q01.ot", dir / "q23.ot"});
  const TraversabilityMap reversed = MergeMaps({quarters[3], quarters[2], quarters[1], quarters[0]});
  const double acc_order = GridAccuracy(in_order, dir / "drive", dir / "g_order");
  const double acc_tree = GridAccuracy(as_tree, dir / "drive", dir / "g_tree");
  const double acc_reversed = GridAccuracy(reversed, dir / "drive", dir / "g_reversed");
  const double tree_voxels = VoxelDisagreement(in_order, as_tree);
  const double reversed_voxels = VoxelDisagreement(in_order, reversed);
  RecordProperty("quarters_accuracy_in_order", std::to_string(acc_order));
  RecordProperty("quarters_accuracy_as_tree", std::to_string(acc_tree));
  RecordProperty("quarters_accuracy_reversed", std::to_string(acc_reversed));
  RecordProperty("voxels_differing_tree", std::to_string(tree_voxels));
  RecordProperty("voxels_differing_reversed", std::to_string(reversed_voxels));
  EXPECT_NEAR(acc_tree, acc_order, 0.01);
  EXPECT_NEAR(acc_reversed, acc_order, 0.01);
  EXPECT_LT(std::max(tree_voxels, reversed_voxels), 0.05);
  EXPECT_NEAR(acc_order, one_run, 0.015);
}

}  // namespace
}  // namespace ssta
