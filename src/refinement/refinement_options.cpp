#include "ssta/refinement/refinement_options.h"

#include <cmath>

#include "ssta/core/error.h"

namespace ssta {
namespace {

bool Fail(std::string* error, const std::string& message) {
  if (error) *error = message;
  return false;
}

bool Positive(double v) { return std::isfinite(v) && v > 0.0; }

}  // namespace

GroundReference ParseGroundReference(const std::string& name) {
  if (name == "body") return GroundReference::kBody;
  if (name == "gravity") return GroundReference::kGravity;
  throw Error("refinement.ground_reference: '" + name + "' is not one of body, gravity");
}

std::string GroundReferenceName(GroundReference reference) {
  return reference == GroundReference::kBody ? "body" : "gravity";
}

RobustLoss ParseRobustLoss(const std::string& name) {
  if (name == "huber") return RobustLoss::kHuber;
  if (name == "cauchy") return RobustLoss::kCauchy;
  throw Error("refinement.robust_loss: '" + name + "' is not one of huber, cauchy");
}

std::string RobustLossName(RobustLoss loss) { return loss == RobustLoss::kHuber ? "huber" : "cauchy"; }

bool RefinementOptions::IsValid(std::string* error) const {
  if (points_per_frame < 3) return Fail(error, "points_per_frame: must be at least 3");
  if (min_points_per_frame < 3 || min_points_per_frame > points_per_frame) {
    return Fail(error, "min_points_per_frame: must be in [3, points_per_frame]");
  }
  if (!Positive(max_range_m)) return Fail(error, "max_range_m: must be positive");
  if (min_frames < 1) return Fail(error, "min_frames: must be at least 1");
  if (!Positive(point_sigma_m)) return Fail(error, "point_sigma_m: must be positive");
  if (!Positive(point_sigma_range_m)) return Fail(error, "point_sigma_range_m: must be positive");
  if (!Positive(loss_scale)) return Fail(error, "loss_scale: must be positive");
  if (!Positive(terrain_tilt_sigma_deg) || terrain_tilt_sigma_deg > 45.0) {
    return Fail(error, "terrain_tilt_sigma_deg: must be in (0, 45] degrees");
  }
  if (!Positive(prior_sigma_deg) || prior_sigma_deg > 45.0) {
    return Fail(error, "prior_sigma_deg: must be in (0, 45] degrees");
  }
  if (!(max_sigma_ratio > 0.0 && max_sigma_ratio < 1.0)) return Fail(error, "max_sigma_ratio: must be in (0, 1)");
  if (!std::isfinite(body_height_m) || body_height_m > 10.0) {
    return Fail(error, "body_height_m: must be a finite height up to 10 m (negative: unknown)");
  }
  if (!Positive(terrain_height_sigma_m)) return Fail(error, "terrain_height_sigma_m: must be positive");
  if (estimate_height && body_height_m < 0.0) {
    return Fail(error, "estimate_height: needs body_height_m (the camera height is otherwise unobservable)");
  }
  if (!Positive(height_prior_sigma_m)) return Fail(error, "height_prior_sigma_m: must be positive");
  if (max_iterations < 1) return Fail(error, "max_iterations: must be at least 1");
  if (window_frames < min_frames) return Fail(error, "window_frames: must be at least min_frames");
  if (solve_every_frames < 1) return Fail(error, "solve_every_frames: must be at least 1");
  return true;
}

}  // namespace ssta
