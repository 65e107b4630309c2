// The heading costs on a rendered hillside: the verdicts (straight up allowed under a
// 25 deg pitch limit, across refused under a 15 deg roll limit) hold within the stereo noise.

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>

#include "ssta/core/units.h"
#include "ssta/io/sequence.h"
#include "ssta/mapping/traversability_map.h"
#include "ssta/pipeline/config.h"
#include "ssta/pipeline/map_builder.h"
#include "ssta/synth/sequence_synthesizer.h"
#include "temp_dir.h"

namespace ssta {
namespace {

TEST(HeadingCosts, RenderedTwentyDegreeHillsideAllowsClimbingAndRefusesTraversing) {
  // The `ramp` scene is the plane z = tan(20 deg) x; three stereo frames (SGBM, 320 x 240) from
  // the foot of it. A 1 x 0.6 m footprint 2 and 3 m ahead covers ~60 columns whose fused
  // heights carry the stereo noise (depth sigma ~0.1 m at 3 m with f 210 px, b 0.12 m, 0.25 px,
  // averaged over the footprint and the frames): the fitted angles come within ~1 deg of the
  // truth there, so 2 deg is the tolerance, well inside the 5 deg between 20 deg and either limit.
  testing::TempDir dir;
  synth::SynthOptions o;
  o.scene = "ramp";
  o.ramp_slope_deg = 20.0;
  o.frames = 3;
  o.rig.width = 320;
  o.rig.height = 240;
  o.rig.focal_px = 210.0;
  const std::filesystem::path seq = dir / "seq";
  synth::WriteSyntheticSequence(o, seq);

  Config config;
  config.vehicle.max_pitch_deg = 25.0;
  config.vehicle.max_descent_deg = 25.0;
  config.vehicle.max_roll_deg = 15.0;
  BuildMapOptions options;
  options.map_path = dir / "m.ot";
  BuildMap(Sequence::Open(seq), "ramp", config, options);
  const TraversabilityMap map = TraversabilityMap::Load(options.map_path);

  for (const double x : {2.0, 3.0}) {
    const FootprintResult up = map.QueryFootprint({x, 0.0, 0.0, 1.0, 0.6});
    ASSERT_GE(up.fraction_observed, 0.75) << x;
    ASSERT_GE(up.attitude_heights, 30) << x;
    EXPECT_NEAR(up.pitch_deg, 20.0, 2.0) << x;
    EXPECT_NEAR(up.roll_deg, 0.0, 2.0) << x;
    EXPECT_TRUE(up.attitude == TravClass::kTraversable || up.attitude == TravClass::kSemiTraversable) << x;

    const FootprintResult across = map.QueryFootprint({x, 0.0, DegToRad(90.0), 1.0, 0.6});
    EXPECT_NEAR(across.pitch_deg, 0.0, 2.0) << x;
    EXPECT_NEAR(across.roll_deg, -20.0, 2.0) << x;  // facing +y, the lower side (-x) is on the left
    EXPECT_EQ(across.attitude, TravClass::kNonTraversable) << x;
    std::printf("rendered 20 deg hillside, footprint at x = %.0f m: up pitch %.2f roll %.2f; across pitch %.2f roll %.2f\n",
                x, up.pitch_deg, up.roll_deg, across.pitch_deg, across.roll_deg);
  }
}

}  // namespace
}  // namespace ssta
