#include <gtest/gtest.h>

#include <fstream>
#include <iterator>

#include "ssta/core/error.h"
#include "ssta/pipeline/config.h"
#include "ssta_test_paths.h"
#include "temp_dir.h"

namespace ssta {
namespace {

std::string ErrorOf(const std::string& yaml) {
  testing::TempDir dir;
  std::ofstream(dir / "c.yaml") << yaml;
  try {
    LoadConfig(dir / "c.yaml");
  } catch (const Error& e) {
    return e.what();
  }
  return "";
}

TEST(Config, ShippedDefaultYamlEqualsTheBuiltInDefaults) {
  // config/default.yaml documents every key; it must say what the code does, in the words of
  // the code's field descriptions (regenerate it with `ssta config --out config/default.yaml`).
  const std::string path = std::string(SSTA_CONFIG_DIR) + "/default.yaml";
  std::ifstream in(path);
  const std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  EXPECT_EQ(text, ConfigToCommentedYaml(Config{})) << "regenerate " << path << " with `ssta config --out`";
  EXPECT_EQ(ConfigToYaml(LoadConfig(path)), ConfigToYaml(Config{}));
}

TEST(Config, VehicleProfilesLoadAndDiffer) {
  const Config small = LoadConfig(std::string(SSTA_CONFIG_DIR) + "/vehicles/small_ugv.yaml");
  const Config large = LoadConfig(std::string(SSTA_CONFIG_DIR) + "/vehicles/large_ugv.yaml");
  EXPECT_LT(small.vehicle.max_step_m, large.vehicle.max_step_m);
  EXPECT_LT(small.vehicle.max_slope_deg, large.vehicle.max_slope_deg);
  // The profiles change the vehicle section only.
  Config small_elsewhere = small;
  small_elsewhere.vehicle = Config{}.vehicle;
  EXPECT_EQ(ConfigToYaml(small_elsewhere), ConfigToYaml(Config{}));
}

TEST(Config, PaperProfileRestoresThePaperExactly) {
  const Config paper = LoadConfig(std::string(SSTA_CONFIG_DIR) + "/paper.yaml");
  EXPECT_EQ(paper.analysis.small_segments, SmallSegmentPolicy::kPaper);
  EXPECT_EQ(paper.segmentation.max_segment_angle_deg, 0.0);
  EXPECT_EQ(paper.segmentation.max_disparity_jump_px, 0.0);
  EXPECT_DOUBLE_EQ(paper.analysis.inliers_min_ratio, 0.02);
}

TEST(Config, PartialFileKeepsTheOtherDefaults) {
  testing::TempDir dir;
  std::ofstream(dir / "v.yaml") << "vehicle:\n  max_step_m: 0.35\n";
  const Config c = LoadConfig(dir / "v.yaml");
  EXPECT_DOUBLE_EQ(c.vehicle.max_step_m, 0.35);
  EXPECT_DOUBLE_EQ(c.vehicle.semi_step_m, Config{}.vehicle.semi_step_m);
  EXPECT_EQ(c.stereo.num_disparities, Config{}.stereo.num_disparities);
}

TEST(Config, LaterFilesOverrideEarlierOnes) {
  testing::TempDir dir;
  std::ofstream(dir / "a.yaml") << "vehicle:\n  max_step_m: 0.35\n  semi_step_m: 0.2\n";
  std::ofstream(dir / "b.yaml") << "vehicle:\n  max_step_m: 0.25\n";
  Config c;
  ApplyConfigFile(dir / "a.yaml", &c);
  ApplyConfigFile(dir / "b.yaml", &c);
  EXPECT_DOUBLE_EQ(c.vehicle.max_step_m, 0.25);
  EXPECT_DOUBLE_EQ(c.vehicle.semi_step_m, 0.2);
}

TEST(Config, ErrorsNameTheKey) {
  EXPECT_NE(ErrorOf("vehicle:\n  max_slop_deg: 3\n").find("vehicle.max_slop_deg: unknown key"), std::string::npos);
  EXPECT_NE(ErrorOf("vehicles:\n  max_slope_deg: 3\n").find("vehicles: unknown key"), std::string::npos);
  EXPECT_NE(ErrorOf("vehicle:\n  max_slope_deg: steep\n").find("vehicle.max_slope_deg: wrong type"), std::string::npos);
  EXPECT_NE(ErrorOf("vehicle:\n  semi_slope_deg: 40\n").find("vehicle.semi_slope_deg"), std::string::npos);
  EXPECT_NE(ErrorOf("stereo:\n  num_disparities: 50\n").find("stereo.num_disparities"), std::string::npos);
  EXPECT_NE(ErrorOf("stereo:\n  algorithm: magic\n").find("stereo.algorithm"), std::string::npos);
  EXPECT_NE(ErrorOf("normals:\n  method: guess\n").find("normals.method"), std::string::npos);
  EXPECT_NE(ErrorOf("normals:\n  subsample: 4\n").find("normals.subsample"), std::string::npos);
  EXPECT_NE(ErrorOf("segmentation:\n  roughness_deg: -1\n").find("segmentation.roughness_deg"), std::string::npos);
  EXPECT_NE(ErrorOf("analysis:\n  inliers_min_ratio: 2\n").find("analysis.inliers_min_ratio"), std::string::npos);
  EXPECT_NE(ErrorOf("gravity:\n  source: moon\n").find("gravity.source"), std::string::npos);
  EXPECT_NE(ErrorOf("map:\n  subpixel_window_px: 4\n").find("map.subpixel_window_px: must be 0 (off) or odd"),
            std::string::npos);
  EXPECT_NE(ErrorOf("attitude:\n  max_rest_gravity_error_mps2: 0\n").find("attitude.max_rest_gravity_error_mps2"),
            std::string::npos);
  EXPECT_NE(ErrorOf("? [a, b]\n: 1\n").find("keys must be plain names"), std::string::npos);
  EXPECT_NE(ErrorOf("vehicle: [1, 2]\n").find("expected a mapping"), std::string::npos);
  EXPECT_NE(ErrorOf("vehicle:\n  max_slope_deg: [\n").find("YAML syntax error"), std::string::npos);
  // A quote left open on the last line: yaml-cpp reads "20 " and would convert it.
  EXPECT_NE(ErrorOf("vehicle:\n  max_slope_deg: \"20\n").find("vehicle.max_slope_deg: wrong type"), std::string::npos);
  EXPECT_NE(ErrorOf("vehicle:\n  max_slope_deg: '20\n").find("is a quote left open?"), std::string::npos);
  // A cross-key limit names both keys and their values: either may be the one at fault.
  EXPECT_NE(ErrorOf("triangulation:\n  min_range_m: 30\n").find("(max_range_m 25, min_range_m 30)"),
            std::string::npos);
}

TEST(Config, YamlDumpReadsBackToTheSameConfig) {
  Config c;
  c.vehicle.max_slope_deg = 31;
  c.stereo.algorithm = MatcherType::kPclAdaptiveCost;
  c.gravity.source = GravitySource::kLevel;
  testing::TempDir dir;
  std::ofstream(dir / "dump.yaml") << ConfigToYaml(c);
  EXPECT_EQ(ConfigToYaml(LoadConfig(dir / "dump.yaml")), ConfigToYaml(c));
}

}  // namespace
}  // namespace ssta
