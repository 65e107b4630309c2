// The map and classify commands end to end through the built `ssta` binary: exit status, the
// one-line error naming the file or key, and the query CSV contract (docs/interfaces.md, section 5).

#include <gtest/gtest.h>
#include <opencv2/imgcodecs.hpp>

#include <filesystem>
#include <fstream>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <sstream>
#include <string>
#include <tuple>
#include <vector>

#include "cli_runner.h"
#include "ssta/core/units.h"
#include "ssta/files/file_util.h"
#include "ssta/io/image_io.h"
#include "ssta/mapping/column_explanation.h"
#include "ssta/mapping/traversability_map.h"
#include "ssta_test_paths.h"
#include "temp_dir.h"

namespace ssta {
namespace {

using testing::RunSsta;
namespace fs = std::filesystem;

const std::string kEuroc = std::string(SSTA_TEST_DATA_DIR) + "/euroc-v1-01-mini";
const std::string kEurocConfig = std::string(SSTA_CONFIG_DIR) + "/sensors/euroc.yaml";

// A rendered yard sequence of `frames` frames in dir/seq; returns its folder.
std::string SynthYard(const testing::TempDir& dir, int frames, const std::string& size_and_focal) {
  const std::string seq = (dir / "seq");
  const auto r = RunSsta("synth --scene yard --frames " + std::to_string(frames) + " " + size_and_focal +
                         " --out " + seq);
  EXPECT_EQ(r.exit_code, 0) << r.output;
  return seq;
}

std::vector<std::string> Lines(const std::string& text) {
  std::vector<std::string> out;
  std::stringstream s(text);
  std::string line;
  while (std::getline(s, line)) out.push_back(line);
  return out;
}

TEST(Cli, MapRoundTripBuildQueryExport) {
  testing::TempDir dir;
  const std::string map = dir / "m.ot";
  auto r = RunSsta("build-map --sequence " + kEuroc + " --static --config " + kEurocConfig + " --map " + map +
                   " --json " + (dir / "s.json") + " -q");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(ReadTextFile(dir / "s.json").find("\"frames_used\": 3"), std::string::npos);

  // Unobserved column: class 0, cost empty/NaN, zero observations.
  r = RunSsta("query --map " + map + " --at 500,500", false);
  ASSERT_EQ(r.exit_code, 0);
  auto lines = Lines(r.output);
  ASSERT_EQ(lines.size(), 2u) << r.output;
  EXPECT_EQ(lines[0], "x,y,z,class,cost,probability,slope_deg,step_m,observations,confidence,decided_by,frame_mean_slope_deg,frame_mean_step_m");
  EXPECT_EQ(lines[1].substr(0, lines[1].find(',')), "500.0000");
  EXPECT_NE(lines[1].find(",0,"), std::string::npos) << lines[1];

  // Points file with a header, X,Y and X,Y,Z rows.
  std::ofstream(dir / "p.csv") << "x,y,z\n500,500\n1,0,-0.9\n";
  r = RunSsta("query --map " + map + " --points " + (dir / "p.csv"), false);
  ASSERT_EQ(r.exit_code, 0);
  EXPECT_EQ(Lines(r.output).size(), 3u) << r.output;

  r = RunSsta("export --map " + map + " --format grid --out " + (dir / "g"));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  for (const char* f : {"g.png", "g_classes.png", "g.pgm", "g.yaml"}) {
    EXPECT_TRUE(fs::exists(dir.path() / f)) << f;
    EXPECT_NE(r.output.find(dir / f), std::string::npos) << "the report names each file: " << r.output;
  }
  const std::string yaml = ReadTextFile(dir / "g.yaml");
  for (const char* key : {"image:", "resolution:", "origin:", "negate:", "occupied_thresh:", "free_thresh:"}) {
    EXPECT_NE(yaml.find(key), std::string::npos) << key;
  }
  for (const char* format : {"octovis", "ply", "pcd", "csv"}) {
    r = RunSsta("export --map " + map + " --format " + format + " --out " + (dir / "x"));
    EXPECT_EQ(r.exit_code, 0) << format << ": " << r.output;
  }
  // The picture: one PNG, larger than the grid (legend, axes), named in the report.
  r = RunSsta("export --map " + map + " --format picture --out " + (dir / "pic"));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find(dir / "pic.png"), std::string::npos) << r.output;
  const cv::Mat picture = cv::imread(dir / "pic.png", cv::IMREAD_COLOR);
  const cv::Mat grid = cv::imread(dir / "g.png", cv::IMREAD_COLOR);
  EXPECT_GT(picture.cols, grid.cols + 150);
  EXPECT_GT(picture.rows, grid.rows);
  r = RunSsta("export --map " + map + " --format grid --flat --out " + (dir / "g2"));
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.output.find("--flat: only for --format picture"), std::string::npos) << r.output;
  // build-map draws it too when asked, and its report names it.
  r = RunSsta("build-map --sequence " + kEuroc + " --static --config " + kEurocConfig + " --map " + (dir / "m2.ot") +
              " --picture " + (dir / "m2.png"));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("picture: " + (dir / "m2.png")), std::string::npos) << r.output;
  EXPECT_EQ(cv::imread(dir / "m2.png", cv::IMREAD_COLOR).size(), picture.size());

  // query --as-exported answers every cell of the grid with the grid's class.
  double res = 0, x0 = 0, y0 = 0;
  ASSERT_EQ(std::sscanf(yaml.substr(yaml.find("resolution:")).c_str(), "resolution: %lf", &res), 1);
  ASSERT_EQ(std::sscanf(yaml.substr(yaml.find("origin:")).c_str(), "origin: [%lf, %lf", &x0, &y0), 2);
  const ImageU8 classes = ReadLabelImage(dir / "g_classes.png");
  {
    std::ofstream cells(dir / "cells.csv");
    for (int v = 0; v < classes.height(); ++v) {
      for (int u = 0; u < classes.width(); ++u) {
        cells << x0 + (u + 0.5) * res << ',' << y0 + (classes.height() - 1 - v + 0.5) * res << '\n';
      }
    }
  }
  r = RunSsta("query --map " + map + " --as-exported --points " + (dir / "cells.csv"), false);
  ASSERT_EQ(r.exit_code, 0) << r.output;
  lines = Lines(r.output);
  ASSERT_EQ(lines.size(), classes.size() + 1);
  int mismatches = 0, classified = 0;
  for (std::size_t i = 0; i < classes.size(); ++i) {
    std::stringstream row(lines[i + 1]);
    std::string field;
    for (int k = 0; k < 4; ++k) std::getline(row, field, ',');  // x, y, z, class
    mismatches += std::stoi(field) != classes[i];
    classified += classes[i] >= 1 && classes[i] <= 3;
  }
  EXPECT_EQ(mismatches, 0);
  EXPECT_GT(classified, 100);
  r = RunSsta("query --map " + map + " --as-exported --at 1,0,-0.9");  // the grid is 2D
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_EQ(Lines(r.output).size(), 1u) << r.output;
  EXPECT_NE(r.output.find("--as-exported answers X,Y points"), std::string::npos) << r.output;
  r = RunSsta("query --map " + map + " --at 1,0 --local-ground 2");  // only with --as-exported
  EXPECT_NE(r.exit_code, 0);
  EXPECT_NE(r.output.find("--local-ground requires --as-exported"), std::string::npos) << r.output;
}

// A 3 x 3 m traversable floor map with a level 0.3 x 0.3 m patch at x, y in [0.5, 0.8) that the
// frames called non-traversable (a step against their plane): the export judges it floor.
void SaveFloorWithPatch(const std::string& path) {
  std::vector<ClassifiedPoint> points;
  for (int ix = 0; ix < 30; ++ix) {
    for (int iy = 0; iy < 30; ++iy) {
      ClassifiedPoint p;
      p.world_p = Eigen::Vector3f(0.05f + 0.1f * ix, 0.05f + 0.1f * iy, 0.05f);
      const bool patch = ix >= 5 && ix < 8 && iy >= 5 && iy < 8;
      p.cls = patch ? TravClass::kNonTraversable : TravClass::kTraversable;
      p.slope_deg = 2.0f;
      p.step_m = patch ? 0.3f : 0.0f;
      points.push_back(p);
    }
  }
  MapOptions options;
  options.occupied_threshold_prob = 0.5;  // one frame's hit makes a voxel occupied
  TraversabilityMap map(options);
  map.InsertFrame(points, {1.5, 1.5, 3.0}, 1);
  map.Save(path);
}

// Splits a CSV line at its commas (empty fields kept).
std::vector<std::string> Fields(const std::string& line) {
  std::vector<std::string> out;
  std::stringstream s(line);
  std::string field;
  while (std::getline(s, field, ',')) out.push_back(field);
  if (!line.empty() && line.back() == ',') out.emplace_back();
  return out;
}

TEST(Cli, QueryRowsGiveTheSlopeAndStepThatDecidedTheClassAndTheFramesMeans) {
  // A 30 deg ramp (steeper than the default vehicle's 25) whose points the frame calls
  // traversable at 5 deg, 0.01 m: the fused surface decides non-traversable by its slope.
  std::vector<ClassifiedPoint> points;
  for (int ix = 0; ix < 40; ++ix) {
    for (int iy = 0; iy < 40; ++iy) {
      ClassifiedPoint p;
      const double x = 0.05 + 0.1 * ix;
      p.world_p = Eigen::Vector3f(static_cast<float>(x), 0.05f + 0.1f * iy, static_cast<float>(std::tan(kPi / 6) * x));
      p.cls = TravClass::kTraversable;
      p.slope_deg = 5.0f;
      p.step_m = 0.01f;
      p.height_sigma_m = p.horizontal_sigma_m = 0.01f;
      points.push_back(p);
    }
  }
  MapOptions options;
  options.max_range_m = 30.0;
  options.occupied_threshold_prob = 0.5;  // one frame's hit makes a voxel occupied
  TraversabilityMap map(options);
  map.InsertFrame(points, {2.0, 2.0, 15.0}, 1);
  testing::TempDir dir;
  map.Save(dir / "ramp.ot");
  const CellInfo expected = TraversabilityMap::Load(dir / "ramp.ot").TopSurfaceAt(2.05, 2.05);

  const auto r = RunSsta("query --map " + (dir / "ramp.ot") + " --at 2.05,2.05", false);
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const auto lines = Lines(r.output);
  ASSERT_EQ(lines.size(), 2u) << r.output;
  const std::vector<std::string> header = Fields(lines[0]), row = Fields(lines[1]);
  ASSERT_EQ(header.size(), row.size()) << r.output;
  auto column = [&](const std::string& name) {
    const auto at = std::find(header.begin(), header.end(), name);
    EXPECT_NE(at, header.end()) << name << " in " << lines[0];
    return at == header.end() ? std::string() : row[static_cast<std::size_t>(at - header.begin())];
  };
  EXPECT_EQ(column("class"), "3");
  EXPECT_EQ(column("decided_by"), "surface");
  EXPECT_EQ(expected.decided_by, ClassJudge::kSurface);
  EXPECT_GT(std::stod(column("slope_deg")), 25.0);  // the surface's slope, which made it class 3
  EXPECT_NEAR(std::stod(column("slope_deg")), expected.slope_deg, 0.005);
  EXPECT_NEAR(std::stod(column("step_m")), expected.step_m, 0.0005);
  EXPECT_EQ(column("frame_mean_slope_deg"), "5.00");
  EXPECT_EQ(column("frame_mean_step_m"), "0.010");
}

TEST(Cli, ExplainNamesTheRuleAndTheEvidenceOfAColumn) {
  // SaveFloorWithPatch's patch: the frame called it non-traversable. Its points carry no height
  // sigma, so no height was fused and the frames decided alone.
  testing::TempDir dir;
  SaveFloorWithPatch(dir / "m.ot");
  const std::string explain = "explain --map " + (dir / "m.ot");
  auto r = RunSsta(explain + " --at 0.65,0.65", false);
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const ColumnExplanation why = TraversabilityMap::Load(dir / "m.ot").ExplainColumn(0.65, 0.65);
  EXPECT_EQ(why.rule, JudgeRule::kFramesAlone);
  EXPECT_EQ(why.cell.cls, TravClass::kNonTraversable);
  EXPECT_NE(r.output.find("column 0.6500, 0.6500"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("class: " + std::to_string(static_cast<int>(why.cell.cls)) + " ("), std::string::npos)
      << r.output;
  EXPECT_NE(r.output.find("rule: frames alone: "), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("frames: 1 gave a class"), std::string::npos) << r.output;
  // One clear vote for an obstacle (obstacle gain included) is one clear view.
  EXPECT_NEAR(why.evidence_views, 1.0, 1e-6);
  EXPECT_NE(r.output.find("evidence: 1.00 clear views (a verdict from 0.00)\n"), std::string::npos) << r.output;
  // The patch's points stand 0.3 m off their frame's ground plane: a step to the plane, which
  // the line names as such, not a jump seen beside the column.
  EXPECT_NE(r.output.find("frames' means: slope 2.00 deg, step to the ground plane 0.300 m (largest a frame saw "
                          "0.300 m)\n"),
            std::string::npos)
      << r.output;
  EXPECT_NE(r.output.find("surface: 0 columns within 0.25 m"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("; too few to judge"), std::string::npos) << r.output;
  r = RunSsta(explain + " --at 40,40", false);  // outside the floor
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("class: 0 (unknown)"), std::string::npos) << r.output;
  r = RunSsta(explain + " --at 1");
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.output.find("--at: give X,Y"), std::string::npos) << r.output;
}

TEST(Cli, QueryFootprintAndPathAsObservedAndAsExported) {
  // A 3 x 3 m traversable floor with a level 0.3 x 0.3 m patch at x, y in [0.5, 0.8) that the
  // frames called non-traversable (a step against their plane): the export judges it floor.
  testing::TempDir dir;
  SaveFloorWithPatch(dir / "m.ot");
  const std::string query = "query --map " + (dir / "m.ot");
  auto r = RunSsta(query + " --footprint 0.65,0.65,0,0.3,0.3", false);
  ASSERT_EQ(r.exit_code, 0) << r.output;
  // The floor is level: the vehicle stands flat on it (attitude 1, traversable).
  EXPECT_EQ(r.output,
            "worst,mean_cost,max_cost,fraction_observed,cells,observed_cells,pitch_deg,roll_deg,attitude,"
            "attitude_heights,drivable_confidence\n3,1.0000,1.0000,1.0000,9,9,0.00,0.00,1,9,nan\n");
  r = RunSsta(query + " --footprint 0.65,0.65,90,0.3,0.3 --as-exported --local-ground 1", false);
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_EQ(Lines(r.output).back(), "1,0.0000,0.0000,1.0000,9,9,0.00,0.00,1,9,nan");  // the export made it floor

  std::ofstream(dir / "path.csv") << "x,y\n0.05,0.65\n1.55,0.65\n";
  r = RunSsta(query + " --path " + (dir / "path.csv"));  // with the verdict from stderr
  ASSERT_EQ(r.exit_code, 0) << r.output;
  auto lines = Lines(r.output);
  EXPECT_EQ(lines.size(), 1u + 31u + 1u) << r.output;  // header, a sample every 0.05 m, verdict
  EXPECT_EQ(lines[0], "distance_m,x,y,class,cost,fraction_observed,drivable_confidence");
  // Floor seen once: traversable, confidence 0.742 (one view and the open-ground prior), so
  // cost 0.25 * 1.5 * (1 - 0.742).
  EXPECT_EQ(lines[1], "0.0000,0.0500,0.6500,1,0.0967,1.0000,0.7421");
  EXPECT_NE(r.output.find("blocked at 0.50 m"), std::string::npos) << r.output;  // x = 0.55 (0.5 rounds below)
  // A planner that needs 0.75 is told the once-seen floor is undecided, with no cost; the patch
  // still blocks the path where it did.
  r = RunSsta(query + " --path " + (dir / "path.csv") + " --min-confidence 0.75");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_EQ(Lines(r.output)[1], "0.0000,0.0500,0.6500,4,nan,1.0000,nan");
  EXPECT_NE(r.output.find("worst class 3, blocked at 0.50 m"), std::string::npos) << r.output;
  r = RunSsta(query + " --at 0.05,0.65 --min-confidence 0.74", false);  // just under the floor's 0.7421
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_EQ(Lines(r.output).back().substr(0, 25), "0.0500,0.6500,0.0500,1,0.");
  r = RunSsta(query + " --at 0.05,0.65 --min-confidence 0.75", false);
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_EQ(Lines(r.output).back().substr(0, 31), "0.0500,0.6500,0.0500,4,nan,nan,");
  r = RunSsta(query + " --at 0.05,0.65 --min-confidence 1.5");
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.output.find("--min-confidence: must be a probability in [0, 1]"), std::string::npos) << r.output;
  r = RunSsta(query + " --path " + (dir / "path.csv") + " --width 0.4 --as-exported --local-ground 1");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("path 1.50 m, 31 samples, worst class 1, not blocked, 100 % observed"), std::string::npos)
      << r.output;

  r = RunSsta(query + " --path " + (dir / "path.csv") + " --width -1");
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.output.find("--width: must be >= 0"), std::string::npos) << r.output;
  r = RunSsta(query + " --footprint 0.65,0.65,0,-1,0.3");
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.output.find("--footprint: LENGTH and WIDTH must be >= 0"), std::string::npos) << r.output;
  std::ofstream(dir / "xyz.csv") << "1,2,3\n";
  r = RunSsta(query + " --path " + (dir / "xyz.csv"));
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.output.find("xyz.csv:1: expected x,y, got 3 values"), std::string::npos) << r.output;
  // Queries too large for the map name the option that asked them, with its values.
  r = RunSsta(query + " --footprint 0.65,0.65,0,1e9,0.3");
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.output.find("--footprint 0.65,0.65,0,1e+09,0.3: the rectangle reaches beyond the map's addressable"),
            std::string::npos)
      << r.output;
  r = RunSsta(query + " --path " + (dir / "path.csv") + " --width 1e9");
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.output.find("path.csv --width 1e+09: the path and its width span more than"), std::string::npos)
      << r.output;
  r = RunSsta(query + " --path " + (dir / "path.csv") + " --width 1e9 --as-exported");  // the projection refuses
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.output.find("path.csv --width 1e+09: grid projection: more than"), std::string::npos) << r.output;
}

TEST(Cli, ExportWithHeadingsWritesACostLayerPerHeading) {
  // A 20 deg hillside rising along +x (fused heights on the plane) for a vehicle that climbs
  // 25 deg and rolls 15 deg: climbing keeps the class cost, traversing is refused (cost 1).
  testing::TempDir dir;
  std::vector<ClassifiedPoint> points;
  const double gradient = std::tan(DegToRad(20.0));
  for (int ix = 0; ix < 30; ++ix) {
    for (int iy = 0; iy < 30; ++iy) {
      ClassifiedPoint p;
      p.world_p = Eigen::Vector3f(0.05f + 0.1f * ix, 0.05f + 0.1f * iy, static_cast<float>(gradient * (0.05 + 0.1 * ix)));
      p.cls = TravClass::kSemiTraversable;
      p.slope_deg = 20.0f;
      p.height_sigma_m = p.horizontal_sigma_m = 0.01f;
      points.push_back(p);
    }
  }
  MapOptions options;
  options.occupied_threshold_prob = 0.5;
  MapMetadata metadata;
  metadata.vehicle.max_roll_deg = 15.0;
  TraversabilityMap map(options, metadata);
  map.InsertFrame(points, {1.5, 1.5, 10.0}, 1);
  map.Save(dir / "m.ot");

  const std::string prefix = dir / "g";
  auto r = RunSsta("export --map " + (dir / "m.ot") + " --format grid --headings 8 --out " + prefix, false);
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const ImageU8 classes = ReadLabelImage(prefix + "_classes.png");
  std::string listed;
  for (const char* deg : {"0", "45", "90", "135", "180", "225", "270", "315"}) {
    const std::string png = prefix + "_cost_heading_" + deg + ".png";
    ASSERT_TRUE(fs::exists(png)) << png;
    const ImageU8 layer = ReadGreyImage(png);
    ASSERT_EQ(layer.width(), classes.width());
    ASSERT_EQ(layer.height(), classes.height());
    listed += std::string(listed.empty() ? "" : ", ") + "g_cost_heading_" + deg + ".png";
  }
  std::ifstream yaml(prefix + ".yaml");
  const std::string text((std::istreambuf_iterator<char>(yaml)), std::istreambuf_iterator<char>());
  EXPECT_NE(text.find("heading_cost_images: [" + listed + "]"), std::string::npos) << text;
  EXPECT_NE(text.find("heading_cost_footprint_m: [1, 0.6]"), std::string::npos) << text;
  // The middle of the hillside: across (90, 270) cost 1 (254); up and down the class cost of a
  // 20 deg slope, 0.25 + 0.5 (20 - 15) / (25 - 15) = 0.5 (127).
  const int v = classes.height() / 2, u = classes.width() / 2;
  EXPECT_EQ(ReadGreyImage(prefix + "_cost_heading_90.png")(v, u), 254);
  EXPECT_EQ(ReadGreyImage(prefix + "_cost_heading_270.png")(v, u), 254);
  EXPECT_NEAR(ReadGreyImage(prefix + "_cost_heading_0.png")(v, u), 127, 1);
  EXPECT_NEAR(ReadGreyImage(prefix + "_cost_heading_180.png")(v, u), 127, 1);

  r = RunSsta("query --map " + (dir / "m.ot") + " --footprint 1.5,1.5,90,1,0.6", false);
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const std::vector<std::string> row = Fields(Lines(r.output).back());  // ...,pitch,roll,attitude,heights,confidence
  ASSERT_EQ(row.size(), 11u) << r.output;
  EXPECT_NEAR(std::stod(row[6]), 0.0, 0.05);
  EXPECT_NEAR(std::stod(row[7]), -20.0, 0.05);  // facing +y, the left (-x) side is the lower one
  EXPECT_EQ(row[8], "3");                        // beyond the 15 deg roll limit

  r = RunSsta("export --map " + (dir / "m.ot") + " --format csv --headings 8 --out " + prefix);
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.output.find("--headings: only for --format grid or mcap"), std::string::npos) << r.output;
  r = RunSsta("export --map " + (dir / "m.ot") + " --format grid --headings 8 --heading-footprint 0,1 --out " + prefix);
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.output.find("--heading-footprint: must be in (0, 100] m"), std::string::npos) << r.output;
}

TEST(Cli, MapReadingCommandsTakeTheConfigTheMapWasBuiltWith) {
  // The floor map was built for the default vehicle (max slope 25 deg, max step 0.2 m).
  testing::TempDir dir;
  SaveFloorWithPatch(dir / "m.ot");
  const std::string query = "query --map " + (dir / "m.ot") + " --at 1.05,1.05";
  const auto plain = RunSsta(query, false);
  ASSERT_EQ(plain.exit_code, 0) << plain.output;
  // The defaults, or a file without a vehicle section: the same answer.
  for (const std::string file : {"/default.yaml", "/realtime.yaml"}) {
    const auto r = RunSsta(query + " --config " + SSTA_CONFIG_DIR + file, false);
    EXPECT_EQ(r.exit_code, 0) << file << ": " << r.output;
    EXPECT_EQ(r.output, plain.output) << file;
  }
  // Another vehicle: one line naming the file and the key, for each map-reading command.
  const std::string large = std::string(SSTA_CONFIG_DIR) + "/vehicles/large_ugv.yaml";
  fs::create_directories(dir / "seq/gt");
  WriteImage(ImageU8(30, 30, 1), dir / "seq/gt/grid_classes.png");
  std::ofstream(dir / "seq/gt/grid.yaml") << "image: grid_classes.png\nresolution: 0.1\norigin: [0, 0, 0]\nseen: both_cameras\n";
  for (const std::string& command : std::vector<std::string>{
           query, "export --map " + (dir / "m.ot") + " --format csv --out " + (dir / "x"),
           "eval footprints --map " + (dir / "m.ot") + " --gt " + (dir / "seq")}) {
    const auto r = RunSsta(command + " --config " + large);
    EXPECT_EQ(r.exit_code, 2) << command;
    EXPECT_EQ(Lines(r.output).size(), 1u) << r.output;
    EXPECT_NE(r.output.find("large_ugv.yaml: gives vehicle.max_slope_deg 30, but"), std::string::npos) << r.output;
    EXPECT_NE(r.output.find("was built for 25"), std::string::npos) << r.output;
  }
  EXPECT_FALSE(fs::exists(dir / "x.csv"));
  // Later files win: a file that sets the map's values back makes the pair match; the key that
  // still differs is named with the file that set it.
  std::ofstream(dir / "back.yaml") << "vehicle:\n  max_slope_deg: 25\n  semi_slope_deg: 15\n  max_step_m: 0.2\n"
                                      "  semi_step_m: 0.1\n  min_camera_height_m: 0.2\n  max_camera_height_m: 3\n"
                                      "  max_pitch_deg: 25\n  max_descent_deg: 25\n  max_roll_deg: 25\n";
  auto r = RunSsta(query + " --config " + large + " --config " + (dir / "back.yaml"), false);
  EXPECT_EQ(r.exit_code, 0) << r.output;
  EXPECT_EQ(r.output, plain.output);
  std::ofstream(dir / "step.yaml") << "vehicle:\n  max_step_m: 0.25\n";
  r = RunSsta(query + " --config " + (dir / "step.yaml") + " --config " + (dir / "back.yaml") + " --config " +
              (dir / "step.yaml"));
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.output.find("step.yaml: gives vehicle.max_step_m 0.25, but"), std::string::npos) << r.output;
  // A bad value in any section is still an error.
  std::ofstream(dir / "bad.yaml") << "map:\n  resolution_m: -1\n";
  r = RunSsta(query + " --config " + (dir / "bad.yaml"));
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.output.find("bad.yaml"), std::string::npos) << r.output;
}

TEST(Cli, EvalFootprintsCountsUnsafeAndFalselyBlockedFootprints) {
  // The map: SaveFloorWithPatch's floor, its patch at cells 5..7. The truth: all traversable
  // except a non-traversable block at cells 20..22 that the map calls floor.
  testing::TempDir dir;
  SaveFloorWithPatch(dir / "m.ot");
  {
    ImageU8 truth(30, 30, 1);
    for (int c = 20; c <= 22; ++c) {
      for (int b = 20; b <= 22; ++b) truth(29 - b, c) = 3;
    }
    fs::create_directories(dir / "seq/gt");
    WriteImage(truth, dir / "seq/gt/grid_classes.png");
    std::ofstream(dir / "seq/gt/grid.yaml") << "image: grid_classes.png\nresolution: 0.1\norigin: [0, 0, 0]\nseen: both_cameras\n";
  }
  // 0.3 m squares on every cell: 900 poses, the 116 on the border reach outside the truth.
  // Unsafe: the 5 x 5 centres whose square touches the block; falsely blocked as observed: the
  // 5 x 5 around the patch, which the export judges floor.
  const std::string eval = "eval footprints --map " + (dir / "m.ot") + " --gt " + (dir / "seq") +
                           " --width 0.3 --step 0.1";
  auto r = RunSsta(eval + " --length 0.3 --yaws 0 --json " + (dir / "f.json") + " --misses " + (dir / "m.csv"));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("misses: " + (dir / "m.csv") + " (25 unsafe, 25 falsely blocked)"), std::string::npos)
      << r.output;
  const std::string misses = ReadTextFile(dir / "m.csv");
  EXPECT_EQ(std::count(misses.begin(), misses.end(), '\n'), 1 + 25 + 25) << misses;
  EXPECT_EQ(misses.find("unsafe,"), misses.find('\n') + 1) << misses;  // the unsafe ones first
  // Each names the cell that misleads, the truth and the map there, and the map's rule: the
  // unsafe ones a cell of the block the map calls floor, the falsely blocked ones the patch.
  std::istringstream lines(misses);
  std::string line;
  std::getline(lines, line);
  EXPECT_EQ(line, "kind,x_m,y_m,yaw_deg,truth,answer,fraction_known,distance_from_path_m,cell_x_m,cell_y_m,cell_truth,"
                  "cell_class,cell_rule");
  while (std::getline(lines, line)) {
    const bool unsafe = line.rfind("unsafe,", 0) == 0;
    EXPECT_NE(line.find(unsafe ? ",3,1,frames alone" : ",1,3,"), std::string::npos) << line;
    EXPECT_NE(line.back(), ',') << line;  // a rule is named
  }
  EXPECT_NE(r.output.find("poses: 900, partly unseen in the truth (unscored): 116"), std::string::npos) << r.output;
  // Shares of the truly blocked and of the truly free footprints.
  EXPECT_NE(r.output.find("answered traversable or semi): 25 of 25 (1.0000)"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("answered non-traversable): 25 of 759 (0.0329)"), std::string::npos) << r.output;
  const std::string json = ReadTextFile(dir / "f.json");
  EXPECT_NE(json.find("\"unsafe\": 25"), std::string::npos) << json;
  EXPECT_NE(json.find("\"accuracy\": " + std::to_string(734.0 / 784.0).substr(0, 6)), std::string::npos) << json;
  r = RunSsta(eval + " --length 0.3 --yaws 0,90 --as-exported --local-ground 1");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("poses: 1800, partly unseen in the truth (unscored): 232"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("answered traversable or semi): 50 of 50 (1.0000)"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("answered non-traversable): 0 of 1518 (0.0000)"), std::string::npos) << r.output;

  // Padded by 0.1 m, the map is asked about 0.5 m squares: 7 x 7 centres around the patch are
  // blocked; the truth, and so which footprints count as blocked or free, stays the 0.3 m square.
  r = RunSsta(eval + " --length 0.3 --yaws 0 --padding 0.1");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("the map asked with 0.10 m of padding"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("answered traversable or semi): 25 of 25 (1.0000)"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("answered non-traversable): 49 of 759 (0.0646)"), std::string::npos) << r.output;
  // The report lists what a planner with a confidence bar is told; with the bar at 1 no drivable
  // answer is sure enough, so none is unsafe and the block's footprints are undecided.
  EXPECT_NE(r.output.find("driving only on answers at least this confident (unsafe / free answered drivable): 0.40:"),
            std::string::npos)
      << r.output;
  r = RunSsta(eval + " --length 0.3 --yaws 0 --min-confidence 1");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("answered traversable or semi): 0 of 25 (0.0000)"), std::string::npos) << r.output;
  r = RunSsta(eval + " --min-confidence 1.5");
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.output.find("--min-confidence: must be a probability in [0, 1]"), std::string::npos) << r.output;
  r = RunSsta(eval + " --padding -0.1");
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.output.find("--padding: must be a number of metres >= 0"), std::string::npos) << r.output;

  r = RunSsta(eval + " --length 0");
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.output.find("--length: must be a positive number"), std::string::npos) << r.output;
  r = RunSsta(eval + " --yaws 0,nan");
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.output.find("--yaws: headings must be finite"), std::string::npos) << r.output;
  r = RunSsta(eval + " --local-ground 2");  // only with --as-exported
  EXPECT_NE(r.exit_code, 0);
  EXPECT_NE(r.output.find("--local-ground requires --as-exported"), std::string::npos) << r.output;
  // Truth classed for another vehicle than the map's (the map: the default vehicle): refused.
  std::ofstream(dir / "seq/vehicle.yaml") << "vehicle:\n  max_step_m: 0.3\n";
  r = RunSsta(eval);
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.output.find((dir / "m.ot") + ": the map was built for vehicle.max_step_m 0.2, but the truth in " +
                          (dir / "seq/gt") + " was classed for 0.3 (" + (dir / "seq/vehicle.yaml") + ")"),
            std::string::npos)
      << r.output;
  std::ofstream(dir / "seq/vehicle.yaml") << "vehicle:\n  max_step_m: 0.2\n";  // the map's: scored
  r = RunSsta(eval);
  EXPECT_EQ(r.exit_code, 0) << r.output;
}

TEST(Cli, BadInputGivesOneLineNamingTheFileOrKey) {
  testing::TempDir dir;
  auto r = RunSsta("query --map " + (dir / "missing.ot") + " --at 1,2");
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_EQ(Lines(r.output).size(), 1u) << r.output;
  EXPECT_NE(r.output.find("missing.ot"), std::string::npos) << r.output;

  std::ofstream(dir / "bad.yaml") << "stereo:\n  num_disparity: 64\n";
  r = RunSsta("classify --sequence " + kEuroc + " --config " + (dir / "bad.yaml") + " --out " + (dir / "o"));
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.output.find("stereo.num_disparity: unknown key"), std::string::npos) << r.output;

  std::ofstream(dir / "bad.csv") << "x,y\n1,abc\n";
  std::ofstream(dir / "not_a_map.ot") << "# just text\n";
  r = RunSsta("query --map " + (dir / "not_a_map.ot") + " --points " + (dir / "bad.csv"));
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.output.find("not_a_map.ot"), std::string::npos) << r.output;

  r = RunSsta("build-map --sequence " + (dir / "nope") + " --map " + (dir / "m.ot"));
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.output.find("nope"), std::string::npos) << r.output;
  EXPECT_FALSE(fs::exists(dir.path() / "m.ot"));

  // A malformed command line is bad input too: one line naming the option, status 2.
  for (const std::string& args : {std::string("query --map m.ot --at abc,1"), std::string("classify --sequence s"),
                                  std::string("export --map m.ot --format Grid --out g")}) {
    r = RunSsta(args);
    EXPECT_EQ(r.exit_code, 2) << args;
    EXPECT_EQ(Lines(r.output).size(), 1u) << r.output;
    EXPECT_EQ(r.output.rfind("ssta: error: ", 0), 0u) << r.output;
  }
  EXPECT_NE(r.output.find("--format"), std::string::npos) << r.output;
  // A point file whose only line is not comma-separated numbers is not taken for a header.
  TraversabilityMap().Save(dir / "empty.ot");
  std::ofstream(dir / "semicolon.csv") << "2;0\n";
  r = RunSsta("query --map " + (dir / "empty.ot") + " --points " + (dir / "semicolon.csv"));
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.output.find("semicolon.csv:1: expected x,y or x,y,z numbers"), std::string::npos) << r.output;
  // A first line is a header only when every cell starts with a letter: "4,1e999" is a number
  // out of range, "4,a" a bad row, each named with its line; a path's vertex is x,y, by line.
  for (const auto& [file, text, expected] : std::vector<std::tuple<std::string, std::string, std::string>>{
           {"huge.csv", "4,1e999\n", "huge.csv:1: '1e999' is out of the range of a double"},
           {"letter.csv", "4,a\n", "letter.csv:1: expected x,y or x,y,z numbers, comma-separated, got '4,a'"},
           {"header.csv", "x,y\n", "header.csv: no points after its header"},
           {"four.csv", "x,y\n1,2,3,4\n", "four.csv:2: expected x,y or x,y,z, got 4 values"}}) {
    std::ofstream(dir / file) << text;
    r = RunSsta("query --map " + (dir / "empty.ot") + " --points " + (dir / file));
    EXPECT_EQ(r.exit_code, 2) << file;
    EXPECT_NE(r.output.find(expected), std::string::npos) << r.output;
  }
  std::ofstream(dir / "path.csv") << "0,0\n2,0,0\n";
  r = RunSsta("query --map " + (dir / "empty.ot") + " --path " + (dir / "path.csv"));
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.output.find("path.csv:2: expected x,y, got 3 values"), std::string::npos) << r.output;
  r = RunSsta("query --map " + (dir / "empty.ot") + " --at 1");
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.output.find("--at: expected X,Y or X,Y,Z"), std::string::npos) << r.output;
}

TEST(Cli, PathsAnOptionWritesAreCheckedBeforeTheWork) {
  testing::TempDir dir;
  std::ofstream(dir / "afile") << "x";
  fs::create_directory(dir.path() / "adir");
  struct Case {
    std::string args, expected;
  };
  const std::string map = dir / "m.ot";
  const Case cases[] = {
      // The map would be built and written, then the summary refused.
      {"build-map --sequence " + kEuroc + " --static --map " + map + " --json " + (dir / "nodir/s.json"),
       "--json: " + (dir / "nodir/s.json") + ": the folder " + (dir / "nodir") + " does not exist"},
      {"build-map --sequence " + kEuroc + " --static --map " + map + " --json " + (dir / "afile/s.json"),
       "--json: " + (dir / "afile/s.json") + ": " + (dir / "afile") + " is a file, not a folder"},
      {"build-map --sequence " + kEuroc + " --static --map " + (dir / "adir"), "--map: " + (dir / "adir") + ": is a folder"},
      {"export --map " + map + " --format grid --out " + (dir / "adir") + "/",
       "--out: " + (dir / "adir") + "/: is a folder; give a prefix such as"},
      {"eval grid --pred " + (dir / "g") + " --gt " + kEuroc + " --picture " + (dir / "nodir/e.png"),
       "--picture: " + (dir / "nodir/e.png") + ": the folder"},
      {"classify --sequence " + kEuroc + " --out " + (dir / "afile"), "--out: " + (dir / "afile") + ": is a file, not a folder"},
      {"frobnicate --map " + map, "unknown command 'frobnicate' (commands: classify, synth, build-map"},
  };
  for (const Case& c : cases) {
    const auto r = RunSsta(c.args);
    EXPECT_EQ(r.exit_code, 2) << c.args;
    EXPECT_EQ(Lines(r.output).size(), 1u) << r.output;
    EXPECT_NE(r.output.find("ssta: error: " + c.expected), std::string::npos) << r.output;
    EXPECT_FALSE(fs::exists(map)) << c.args << ": the work ran";
  }
}

TEST(Cli, ExportAtAConfidenceBarWritesTheUnsureFloorUnknown) {
  // The floor was seen once (confidence 0.7421): a bar of 0.75 exports every floor cell
  // undecided, which the navigation PGM shows unknown; the patch stays an obstacle.
  testing::TempDir dir;
  SaveFloorWithPatch(dir / "m.ot");
  const std::string common = "export --map " + (dir / "m.ot");
  auto r = RunSsta(common + " --format grid --out " + (dir / "g") + " --fill-holes 0 --min-confidence 0.75");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("0 holes filled, 891 drivable cells below the confidence bar)"), std::string::npos)
      << r.output;
  const cv::Mat pgm = cv::imread(dir / "g.pgm", cv::IMREAD_UNCHANGED);
  ASSERT_FALSE(pgm.empty());
  EXPECT_EQ(cv::countNonZero(pgm == 254), 0);  // no cell exported free
  EXPECT_EQ(cv::countNonZero(pgm == 0), 9);    // the 0.3 x 0.3 m patch
  r = RunSsta(common + " --format ply --out " + (dir / "p") + " --min-confidence 0.5");
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.output.find("--min-confidence: only for --format grid, picture or mcap"), std::string::npos) << r.output;
  r = RunSsta(common + " --format grid --out " + (dir / "g") + " --min-confidence -0.1");
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.output.find("--min-confidence: must be a probability in [0, 1]"), std::string::npos) << r.output;
}

TEST(Cli, ExportRefusesToWriteOverTheMapItReads) {
  testing::TempDir dir;
  TraversabilityMap().Save(dir / "m.ot");  // empty: the octovis export of it crashed in OctoMap
  const std::string before = ReadTextFile(dir / "m.ot");
  auto r = RunSsta("export --map " + (dir / "m.ot") + " --format octovis --out " + (dir / "m"));
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.output.find("over the map it reads"), std::string::npos) << r.output;
  EXPECT_EQ(ReadTextFile(dir / "m.ot"), before);
  r = RunSsta("export --map " + (dir / "m.ot") + " --format octovis --out " + (dir / "m_octovis"));
  EXPECT_EQ(r.exit_code, 0) << r.output;
  r = RunSsta("export --map " + (dir / "m.ot") + " --format ply --out " + (dir / "p") + " --resolution 0.2");
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.output.find("--resolution: only for --format grid"), std::string::npos) << r.output;
}

TEST(Cli, StrictMakesASkippedFrameFatal) {
  testing::TempDir dir;
  const fs::path seq = dir.path() / "seq";
  fs::copy(kEuroc, seq, fs::copy_options::recursive);
  // Remove the second cam1 image: that frame cannot be used.
  std::vector<fs::path> images;
  for (const auto& e : fs::directory_iterator(seq / "mav0" / "cam1" / "data")) images.push_back(e.path());
  std::sort(images.begin(), images.end());
  fs::remove(images[1]);
  const std::string common = "classify --sequence " + seq.string() + " --config " + kEurocConfig + " --out " + (dir / "o");
  auto r = RunSsta(common + " -q");
  EXPECT_EQ(r.exit_code, 0) << r.output;
  r = RunSsta(common + " --strict");
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_NE(r.output.find(images[1].filename().string()), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("strict"), std::string::npos) << r.output;
  r = RunSsta("build-map --sequence " + seq.string() + " --static --strict --config " + kEurocConfig + " --map " +
              (dir / "m.ot"));
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_NE(r.output.find("cam1 image missing"), std::string::npos) << r.output;
}

TEST(Cli, ClassifyWritesTheInterfaceOutputs) {
  testing::TempDir dir;
  const auto r = RunSsta("classify --sequence " + kEuroc + " --config " + kEurocConfig + " --out " + (dir / "o") + " -q");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  std::size_t labels = 0;
  for (const auto& e : fs::directory_iterator(dir.path() / "o" / "labels")) labels += e.path().extension() == ".png";
  EXPECT_EQ(labels, 3u);
  EXPECT_TRUE(fs::exists(dir.path() / "o" / "summary.json"));
  EXPECT_TRUE(fs::exists(dir.path() / "o" / "overlay"));
  // config.yaml holds the run's configuration: given alone, it repeats the run label for label,
  // while the defaults alone do not (euroc.yaml changes the stereo ranges).
  const std::string config = dir / "o/config.yaml";
  ASSERT_TRUE(fs::exists(config));
  const auto again = RunSsta("classify --sequence " + kEuroc + " --config " + config + " --out " + (dir / "again") + " -q");
  ASSERT_EQ(again.exit_code, 0) << again.output;
  const auto plain = RunSsta("classify --sequence " + kEuroc + " --out " + (dir / "plain") + " -q");
  ASSERT_EQ(plain.exit_code, 0) << plain.output;
  int differ = 0;
  for (const auto& e : fs::directory_iterator(dir.path() / "o" / "labels")) {
    const std::string name = e.path().filename().string();
    const std::string labels_png = ReadTextFile(e.path().string());
    EXPECT_EQ(labels_png, ReadTextFile(dir / ("again/labels/" + name))) << name;
    differ += labels_png != ReadTextFile(dir / ("plain/labels/" + name));
  }
  EXPECT_GT(differ, 0) << "euroc.yaml should change some labels, or the repeat proves nothing";
  EXPECT_EQ(ReadTextFile(dir / "again/config.yaml"), ReadTextFile(config));
  // A shorter run into the same folder leaves none of the longer run's frames behind (eval
  // would score them), and nothing that is not a frame file of its own is touched.
  std::ofstream(dir.path() / "o" / "labels" / "notes.txt") << "mine";
  const auto shorter = RunSsta("classify --sequence " + kEuroc + " --config " + config + " --max-frames 1 --out " +
                               (dir / "o"));
  ASSERT_EQ(shorter.exit_code, 0) << shorter.output;
  EXPECT_NE(shorter.output.find("removed 9 frame files of an earlier run first"), std::string::npos) << shorter.output;
  for (const char* sub : {"labels", "overlay", "frames"}) {
    std::size_t frame_files = 0;
    for (const auto& e : fs::directory_iterator(dir.path() / "o" / sub)) frame_files += e.path().stem() != "notes";
    EXPECT_EQ(frame_files, 1u) << sub;
  }
  EXPECT_EQ(ReadTextFile(dir / "o/labels/notes.txt"), "mine");
}

TEST(Cli, ClassifyOnePairWritesItsLabelsAndConfig) {
  testing::TempDir dir;
  const std::string kitti = std::string(SSTA_TEST_DATA_DIR) + "/kitti-street-pair";
  const std::string config = " --config " + std::string(SSTA_CONFIG_DIR) + "/sensors/kitti.yaml";
  const std::string pair = " --left " + kitti + "/cam0/data/1000000000.png --right " + kitti +
                           "/cam1/data/1000000000.png --calib0 " + kitti + "/cam0/sensor.yaml --calib1 " + kitti +
                           "/cam1/sensor.yaml" + config;
  auto r = RunSsta("classify" + pair + " --out " + (dir / "o"));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  // The pair is the one-frame sequence's frame (no IMU: a level body in both modes).
  r = RunSsta("classify --sequence " + kitti + config + " -q --out " + (dir / "s"));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const ImageU8 labels = ReadLabelImage(dir / "o/labels/1000000000.png");
  std::size_t decided = 0;
  for (std::size_t i = 0; i < labels.size(); ++i) decided += labels[i] >= 1 && labels[i] <= 3;
  EXPECT_GT(decided, labels.size() / 2);
  EXPECT_EQ(ReadTextFile(dir / "o/labels/1000000000.png"), ReadTextFile(dir / "s/labels/1000000000.png"));
  // The config.yaml a sequence run writes, for --config and eval's vehicle check.
  EXPECT_EQ(ReadTextFile(dir / "o/config.yaml").substr(ReadTextFile(dir / "o/config.yaml").find("vehicle:")),
            ReadTextFile(dir / "s/config.yaml").substr(ReadTextFile(dir / "s/config.yaml").find("vehicle:")));
  // Options of the other mode would be ignored: refused instead.
  r = RunSsta("classify --sequence " + kitti + pair + " --out " + (dir / "p"));
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.output.find("--sequence excludes --left"), std::string::npos) << r.output;
  r = RunSsta("classify" + pair + " --every 2 --out " + (dir / "p"));
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.output.find("--every: only with --sequence"), std::string::npos) << r.output;
  EXPECT_FALSE(fs::exists(dir.path() / "p"));
}

TEST(Cli, ThreadsCapTheWorkButNeverChangeTheLabels) {
  // --threads (before or after the command's name) caps OpenCV's pool, which runs the matcher,
  // the normals' bands and the analysis's concurrent steps; every label must be the same.
  testing::TempDir dir;
  const std::string seq = SynthYard(dir, 2, "--width 320 --height 240 --focal 210");
  ASSERT_FALSE(::testing::Test::HasFailure());
  auto r = RunSsta("--threads 1 classify --sequence " + seq + " -q --out " + (dir / "one"));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  r = RunSsta("classify --sequence " + seq + " -q --threads 0 --out " + (dir / "all"));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  std::size_t files = 0, decided = 0;
  for (const auto& e : fs::directory_iterator(dir.path() / "one" / "labels")) {
    const ImageU8 one = ReadLabelImage(e.path().string());
    const ImageU8 all = ReadLabelImage((dir.path() / "all" / "labels" / e.path().filename()).string());
    ASSERT_EQ(one.size(), all.size());
    std::size_t differ = 0;
    for (std::size_t i = 0; i < one.size(); ++i) {
      differ += one[i] != all[i];
      decided += one[i] >= 1 && one[i] <= 3;
    }
    EXPECT_EQ(differ, 0u) << e.path().filename();
    ++files;
  }
  EXPECT_EQ(files, 2u);
  EXPECT_GT(decided, 320u * 240u / 2);  // a comparison of real labels, not of empty images
  r = RunSsta("--threads 300 classify --sequence " + seq + " -q --out " + (dir / "bad"));
  EXPECT_NE(r.exit_code, 0);
  EXPECT_NE(r.output.find("--threads"), std::string::npos) << r.output;
}

TEST(Cli, ClassifyWritesDisparitiesInTheGroundTruthConvention) {
  // With the true disparity as input, disparity/ must give back gt/disparity value for value:
  // 16 bit, disparity * 256, 0 where there is none.
  testing::TempDir dir;
  const std::string seq = SynthYard(dir, 1, "--width 160 --height 120 --focal 105");
  ASSERT_FALSE(::testing::Test::HasFailure());
  auto r = RunSsta("classify --sequence " + seq + " --oracle-disparity --disparity -q --out " + (dir / "o"));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  std::size_t files = 0;
  for (const auto& e : fs::directory_iterator(fs::path(seq) / "gt" / "disparity")) {
    const ImageU16 truth = ReadImageU16(e.path().string());
    const ImageU16 written = ReadImageU16((dir.path() / "o" / "disparity" / e.path().filename()).string());
    ASSERT_EQ(written.width(), truth.width());
    ASSERT_EQ(written.height(), truth.height());
    std::size_t nonzero = 0, differ = 0;
    for (std::size_t i = 0; i < truth.size(); ++i) {
      nonzero += truth[i] != 0;
      differ += written[i] != truth[i];
    }
    EXPECT_GT(nonzero, truth.size() / 2);
    EXPECT_EQ(differ, 0u);
    EXPECT_TRUE(fs::exists(dir.path() / "o" / "disparity_colour" / e.path().filename()));
    ++files;
  }
  EXPECT_EQ(files, 1u);
}

TEST(Cli, StrictStopsOnceWhenTheMapRejectsAFrame) {
  // Poses 5 km away lie outside the map's addressable cube (+-3.3 km at 0.1 m): the map rejects
  // the frames. Strict mode stops at the first with one error naming it once, in both the
  // pipelined and the sequential build (the per-frame handlers once wrapped it a second time).
  testing::TempDir dir;
  const fs::path seq = dir.path() / "seq";
  auto r = RunSsta("synth --scene yard --frames 2 --width 160 --height 120 --focal 105 --out " + seq.string());
  ASSERT_EQ(r.exit_code, 0) << r.output;
  std::string text = ReadTextFile((seq / "pose0" / "data.csv").string());
  std::stringstream in(text), out;
  std::string line;
  while (std::getline(in, line)) {
    if (!line.empty() && line[0] != '#') {
      const std::size_t a = line.find(','), b = line.find(',', a + 1);
      line = line.substr(0, a + 1) + std::to_string(5000.0 + std::stod(line.substr(a + 1, b - a - 1))) + line.substr(b);
    }
    out << line << "\n";
  }
  WriteTextAtomically((seq / "pose0" / "data.csv").string(), out.str());
  const auto count = [](const std::string& text, const std::string& what) {
    std::size_t n = 0;
    for (std::size_t at = text.find(what); at != std::string::npos; at = text.find(what, at + 1)) ++n;
    return n;
  };
  for (const std::string mode : {"", " --sequential"}) {
    r = RunSsta("build-map --strict -q --sequence " + seq.string() + " --map " + (dir / "m.ot") + mode);
    EXPECT_EQ(r.exit_code, 2) << r.output;
    EXPECT_EQ(count(r.output, "ssta: error:"), 1u) << r.output;
    EXPECT_EQ(count(r.output, "map rejected the frame"), 1u) << r.output;
    EXPECT_EQ(count(r.output, "strict: no frame may be skipped"), 1u) << r.output;
  }
  r = RunSsta("build-map --sequence " + seq.string() + " --map " + (dir / "m.ot"));
  EXPECT_EQ(count(r.output, "map rejected the frame"), 2u) << r.output;  // both skipped, named
}

}  // namespace
}  // namespace ssta
