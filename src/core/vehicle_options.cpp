#include "ssta/core/vehicle_options.h"

#include <algorithm>
#include <cmath>

#include "ssta/core/error.h"

namespace ssta {
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

void RequireSameVehicle(const VehicleOptions& a, const std::string& a_says, const VehicleOptions& b,
                        const std::string& b_says, const std::string& b_note, const std::string& advice) {
  const OptionField<VehicleOptions>* f = FirstDifferingField(a, b, VehicleOptions::Fields());
  if (f == nullptr) return;
  throw Error(a_says + " vehicle." + f->key + " " + FormatOptionValue(f->get(a), f->kind) + ", but " + b_says + " " +
              FormatOptionValue(f->get(b), f->kind) + b_note + "; " + advice);
}

const OptionFields<VehicleOptions>& VehicleOptions::Fields() {
  using O = VehicleOptions;
  static const OptionFields<O> fields = [] {
    OptionFields<O> f;
    f.push_back(Real<O>("max_slope_deg", &O::max_slope_deg, Open(0, 90), "deg",
                        "steeper than this: non-traversable"));
    f.push_back(Real<O>("semi_slope_deg", &O::semi_slope_deg, Closed(0, 90), "deg",
                        "steeper than this (up to max): semi-traversable")
                    .Require([](const O& o) { return o.semi_slope_deg <= o.max_slope_deg; },
                             [](const O& o) {
                               return "must not exceed max_slope_deg (semi_slope_deg " + ShortestDecimal(o.semi_slope_deg) +
                                      ", max_slope_deg " + ShortestDecimal(o.max_slope_deg) + ")";
                             }));
    f.push_back(Real<O>("max_step_m", &O::max_step_m, Open(0, 10), "m",
                        "a height jump above this within step_radius_m: non-traversable"));
    f.push_back(Real<O>("semi_step_m", &O::semi_step_m, Closed(0, 10), "m",
                        "a height jump above this (up to max): semi-traversable")
                    .Require([](const O& o) { return o.semi_step_m <= o.max_step_m; },
                             [](const O& o) {
                               return "must not exceed max_step_m (semi_step_m " + ShortestDecimal(o.semi_step_m) +
                                      ", max_step_m " + ShortestDecimal(o.max_step_m) + ")";
                             }));
    f.push_back(Real<O>("step_radius_m", &O::step_radius_m, OpenClosed(0, 5), "m",
                        "a point is judged by the height jumps within this horizontal distance of it: "
                        "level ground is traversable at any height, the band around a jump is not")
                    .AbsentMeans(0.2));
    f.push_back(Real<O>("min_camera_height_m", &O::min_camera_height_m, ClosedOpen(0, 100), "m",
                        "plausible camera height above the ground plane: a frame whose ground plane "
                        "lies outside [min, max] fails the quality check"));
    f.push_back(Real<O>("max_camera_height_m", &O::max_camera_height_m, Open(0, 100), "m",
                        "upper end of that band")
                    .Require([](const O& o) { return o.max_camera_height_m > o.min_camera_height_m; },
                             "must be above min_camera_height_m"));
    // Keys added after maps were first written: a map file leaves them out while they hold the
    // defaults, so the files of default vehicles stay byte for byte as they were.
    f.push_back(Real<O>("max_pitch_deg", &O::max_pitch_deg, Open(0, 90), "deg",
                        "heading costs: steepest climb (nose up) along the direction of travel, the pitch on the "
                        "plane fitted under the footprint")
                    .AbsentMeans(25.0));
    f.push_back(Real<O>("max_descent_deg", &O::max_descent_deg, Open(0, 90), "deg",
                        "heading costs: steepest descent (nose down) along the direction of travel")
                    .AbsentMeans(25.0));
    f.push_back(Real<O>("max_roll_deg", &O::max_roll_deg, Open(0, 90), "deg",
                        "heading costs: steepest cross-slope (roll on that plane, either side down)")
                    .AbsentMeans(25.0));
    return f;
  }();
  return fields;
}

bool VehicleOptions::IsValid(std::string* error) const { return CheckOptions(*this, Fields(), error); }

}  // namespace ssta
