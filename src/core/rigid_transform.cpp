#include "ssta/core/rigid_transform.h"

#include <cmath>

#include <Eigen/Dense>

#include "ssta/core/error.h"

namespace ssta {

bool IsRigidTransform(const Eigen::Matrix4d& m, std::string* why) {
  if (!m.allFinite()) return Fail(why, "contains NaN or infinite values");
  if (!m.row(3).isApprox(Eigen::RowVector4d(0, 0, 0, 1), 1e-9)) {
    return Fail(why, "last row is not [0, 0, 0, 1]");
  }
  const Eigen::Matrix3d r = m.topLeftCorner<3, 3>();
  if (!(r * r.transpose()).isApprox(Eigen::Matrix3d::Identity(), 1e-4) ||
      std::abs(r.determinant() - 1.0) > 1e-4) {
    return Fail(why, "rotation part is not orthonormal with determinant +1");
  }
  return true;
}

}  // namespace ssta
