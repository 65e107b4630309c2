#include "ssta/mapping/map_options.h"

#include <cmath>

namespace ssta {
namespace {

bool Fail(std::string* error, const std::string& message) {
  if (error) *error = message;
  return false;
}

bool InOpen(double v, double lo, double hi) { return v > lo && v < hi; }

}  // namespace

bool MapOptions::IsValid(std::string* error) const {
  if (!(resolution_m > 0.005 && resolution_m <= 10.0)) {
    return Fail(error, "resolution_m: must be in (0.005, 10] metres");
  }
  if (!(max_range_m > 0.0 && max_range_m <= 1000.0)) {
    return Fail(error, "max_range_m: must be in (0, 1000] metres");
  }
  if (!InOpen(occupancy_hit_prob, 0.5, 1.0)) return Fail(error, "occupancy_hit_prob: must be in (0.5, 1)");
  if (!InOpen(occupancy_miss_prob, 0.0, 0.5)) return Fail(error, "occupancy_miss_prob: must be in (0, 0.5)");
  if (!InOpen(occupancy_clamp_min_prob, 0.0, 0.5)) {
    return Fail(error, "occupancy_clamp_min_prob: must be in (0, 0.5)");
  }
  if (!InOpen(occupancy_clamp_max_prob, 0.5, 1.0)) {
    return Fail(error, "occupancy_clamp_max_prob: must be in (0.5, 1)");
  }
  if (!InOpen(occupied_threshold_prob, occupancy_clamp_min_prob, occupancy_clamp_max_prob)) {
    return Fail(error,
                "occupied_threshold_prob: must lie strictly between occupancy_clamp_min_prob and "
                "occupancy_clamp_max_prob");
  }
  if (!(class_hit_log_odds > 0.0 && std::isfinite(class_hit_log_odds))) {
    return Fail(error, "class_hit_log_odds: must be a positive number");
  }
  if (!(class_miss_log_odds <= 0.0 && std::isfinite(class_miss_log_odds))) {
    return Fail(error, "class_miss_log_odds: must be zero or negative");
  }
  if (!(class_free_decay_log_odds >= 0.0 && std::isfinite(class_free_decay_log_odds))) {
    return Fail(error, "class_free_decay_log_odds: must be zero or positive");
  }
  if (!(class_clamp_min < 0.0 && class_clamp_min > -50.0)) {
    return Fail(error, "class_clamp_min: must be in (-50, 0)");
  }
  if (!(free_space_clearance_m >= 0.0 && free_space_clearance_m <= 5.0)) {
    return Fail(error, "free_space_clearance_m: must be in [0, 5] m");
  }
  if (!(std::isfinite(free_space_obstacle_shortening_per_m2) && free_space_obstacle_shortening_per_m2 <= 1.0)) {
    return Fail(error, "free_space_obstacle_shortening_per_m2: must be at most 1 per m (negative: off)");
  }
  if (!(free_space_ray_cell == 1 || free_space_ray_cell == 2 || free_space_ray_cell == 4 ||
        free_space_ray_cell == 8)) {
    return Fail(error, "free_space_ray_cell: must be 1, 2, 4 or 8 voxels");
  }
  if (!(class_clamp_max > 0.0 && class_clamp_max < 50.0)) {
    return Fail(error, "class_clamp_max: must be in (0, 50)");
  }
  return true;
}


bool MappingOptions::IsValid(std::string* error) const {
  if (!fusion.IsValid(error)) return false;
  if (pixel_stride < 1 || pixel_stride > 64) return Fail(error, "pixel_stride: must be in [1, 64]");
  if (!(min_texture >= 0 && min_texture < 128)) return Fail(error, "min_texture: must be in [0, 128) grey levels");
  if (subpixel_window_px < 0 || subpixel_window_px > 31 || (subpixel_window_px > 0 && subpixel_window_px % 2 == 0)) {
    return Fail(error, "subpixel_window_px: must be 0 (off) or odd in [1, 31] px");
  }
  if (checkpoint_every_frames < 0) return Fail(error, "checkpoint_every_frames: must be >= 0 (0: never)");
  return true;
}

}  // namespace ssta
