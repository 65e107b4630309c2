#pragma once

#include <string>

#include <Eigen/Core>

namespace ssta {

/// True when `m` is a finite rigid transform (last row 0 0 0 1, rotation orthonormal within 1e-4
/// with determinant +1); else false, with the reason in *why when why is not null.
bool IsRigidTransform(const Eigen::Matrix4d& m, std::string* why);

}  // namespace ssta
