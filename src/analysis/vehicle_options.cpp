#include "ssta/analysis/vehicle_options.h"

#include <algorithm>
#include <cmath>

namespace ssta {
namespace {
bool Fail(std::string* error, const std::string& message) {
  if (error) *error = message;
  return false;
}
}  // namespace

TravClass VehicleOptions::ClassifySlope(double slope_deg) const {
  if (!(slope_deg <= max_slope_deg)) return TravClass::kNonTraversable;  // NaN too
  if (slope_deg <= semi_slope_deg) return TravClass::kTraversable;
  return TravClass::kSemiTraversable;
}

TravClass VehicleOptions::ClassifyStep(double step_m) const {
  const double h = std::abs(step_m);
  if (!(h <= max_step_m)) return TravClass::kNonTraversable;
  if (h <= semi_step_m) return TravClass::kTraversable;
  return TravClass::kSemiTraversable;
}

const std::array<VehicleKey, 6>& VehicleKeys() {
  static const std::array<VehicleKey, 6> keys{{{"max_slope_deg", &VehicleOptions::max_slope_deg},
                                                {"semi_slope_deg", &VehicleOptions::semi_slope_deg},
                                                {"max_step_m", &VehicleOptions::max_step_m},
                                                {"semi_step_m", &VehicleOptions::semi_step_m},
                                                {"min_camera_height_m", &VehicleOptions::min_camera_height_m},
                                                {"max_camera_height_m", &VehicleOptions::max_camera_height_m}}};
  return keys;
}

bool SameVehicleValue(double a, double b) { return std::abs(a - b) <= 1e-9 * std::max(1.0, std::abs(b)); }

const VehicleKey* FirstDifferingKey(const VehicleOptions& a, const VehicleOptions& b) {
  for (const VehicleKey& k : VehicleKeys()) {
    if (!SameVehicleValue(a.*k.field, b.*k.field)) return &k;
  }
  return nullptr;
}

bool VehicleOptions::IsValid(std::string* error) const {
  if (!(max_slope_deg > 0 && max_slope_deg < 90)) return Fail(error, "max_slope_deg: must be in (0, 90) degrees");
  if (!(semi_slope_deg >= 0 && semi_slope_deg <= max_slope_deg)) {
    return Fail(error, "semi_slope_deg: must be in [0, max_slope_deg]");
  }
  if (!(max_step_m > 0 && max_step_m < 10)) return Fail(error, "max_step_m: must be in (0, 10) metres");
  if (!(semi_step_m >= 0 && semi_step_m <= max_step_m)) {
    return Fail(error, "semi_step_m: must be in [0, max_step_m]");
  }
  if (!(min_camera_height_m >= 0 && min_camera_height_m < 100)) {
    return Fail(error, "min_camera_height_m: must be in [0, 100) metres");
  }
  if (!(max_camera_height_m > min_camera_height_m && max_camera_height_m < 100)) {
    return Fail(error, "max_camera_height_m: must be above min_camera_height_m and below 100 m");
  }
  return true;
}

}  // namespace ssta
