// Inputs of the stereo calibration that come from outside the images: file patterns and the
// body transform of cam0.

#include <glob.h>

#include <algorithm>
#include <cmath>
#include <filesystem>

#include "ssta/files/yaml_reader.h"
#include "ssta/calibration/stereo_calibrator.h"
#include "ssta/core/error.h"
#include "ssta/files/file_util.h"

namespace ssta {

std::vector<std::string> ExpandGlob(const std::string& pattern) {
  // An existing file is taken as it is, also when its name holds '[', '*' or '?'.
  if (std::filesystem::is_regular_file(pattern)) return {pattern};
  glob_t matches{};
  const int status = ::glob(pattern.c_str(), 0, nullptr, &matches);
  std::vector<std::string> paths;
  if (status == 0) {
    for (std::size_t i = 0; i < matches.gl_pathc; ++i) paths.emplace_back(matches.gl_pathv[i]);
  }
  ::globfree(&matches);
  // glob(3) sorts by the locale's collation; byte order makes the pairing independent of it.
  std::sort(paths.begin(), paths.end());
  return paths;
}

Eigen::Isometry3d BodyTransformFromRowMajor(const std::vector<double>& values,
                                            const std::string& what) {
  if (values.size() != 16) {
    throw Error(what + ": expected 16 numbers (a row-major 4x4 matrix), got " +
                std::to_string(values.size()));
  }
  Eigen::Matrix4d m;
  for (int i = 0; i < 16; ++i) m(i / 4, i % 4) = values[static_cast<std::size_t>(i)];
  if (!m.allFinite()) throw Error(what + ": contains NaN or infinite values");
  if (!m.row(3).isApprox(Eigen::RowVector4d(0, 0, 0, 1), 1e-9)) {
    throw Error(what + ": last row must be [0, 0, 0, 1]");
  }
  const Eigen::Matrix3d r = m.topLeftCorner<3, 3>();
  // The tolerance of the sensor.yaml reader: values typed with four decimals pass.
  if (!(r * r.transpose()).isApprox(Eigen::Matrix3d::Identity(), 1e-4) ||
      std::abs(r.determinant() - 1.0) > 1e-4) {
    throw Error(what + ": rotation part is not orthonormal with determinant +1");
  }
  // Snap to the nearest rotation so that cam1's T_BS, a product with it, stays exactly rigid.
  Eigen::Isometry3d t = Eigen::Isometry3d::Identity();
  t.linear() = Eigen::Quaterniond(r).normalized().toRotationMatrix();
  t.translation() = m.topRightCorner<3, 1>();
  return t;
}

Eigen::Isometry3d LoadBodyTransform(const std::string& path) {
  const YAML::Node root = internal::ParseYaml(ReadTextFile(path), path);
  internal::YamlSection yaml(root, path, "");
  const bool nested = yaml.Has("T_BS");
  internal::YamlSection section = nested ? yaml.Child("T_BS") : yaml;
  std::vector<double> values;
  section.ReadList("data", &values, 16);
  const std::string key = nested ? "T_BS.data" : "data";
  if (values.empty()) throw Error(path + ": " + key + ": missing key (16 numbers, row-major 4x4)");
  return BodyTransformFromRowMajor(values, path + ": " + key);
}

}  // namespace ssta
