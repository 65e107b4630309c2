#include <gtest/gtest.h>

#include "ssta/core/vehicle_options.h"

namespace ssta {
namespace {

TEST(VehicleOptions, SlopeClassesFollowEquation3) {
  VehicleOptions v;  // semi 15, max 25
  EXPECT_EQ(v.ClassifySlope(0.0), TravClass::kTraversable);
  EXPECT_EQ(v.ClassifySlope(15.0), TravClass::kTraversable);
  EXPECT_EQ(v.ClassifySlope(15.01), TravClass::kSemiTraversable);
  EXPECT_EQ(v.ClassifySlope(25.0), TravClass::kSemiTraversable);
  EXPECT_EQ(v.ClassifySlope(25.01), TravClass::kNonTraversable);
  EXPECT_EQ(v.ClassifySlope(std::nan("")), TravClass::kNonTraversable);
}

TEST(VehicleOptions, StepClassesUseAbsoluteHeight) {
  VehicleOptions v;  // semi 0.10, max 0.20
  EXPECT_EQ(v.ClassifyStep(0.05), TravClass::kTraversable);
  EXPECT_EQ(v.ClassifyStep(-0.15), TravClass::kSemiTraversable);
  EXPECT_EQ(v.ClassifyStep(0.21), TravClass::kNonTraversable);
  EXPECT_EQ(v.ClassifyStep(-0.5), TravClass::kNonTraversable);
}

TEST(VehicleOptions, ValidationNamesTheKey) {
  VehicleOptions v;
  std::string error;
  EXPECT_TRUE(v.IsValid(&error));
  v.semi_slope_deg = 30;
  EXPECT_FALSE(v.IsValid(&error));
  EXPECT_EQ(error.rfind("semi_slope_deg:", 0), 0u) << error;
  v = VehicleOptions{};
  v.max_step_m = -1;
  EXPECT_FALSE(v.IsValid(&error));
  EXPECT_EQ(error.rfind("max_step_m:", 0), 0u) << error;
}

}  // namespace
}  // namespace ssta
