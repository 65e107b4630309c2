#include "ssta/io/camera_calibration.h"

#include <cmath>
#include <iomanip>
#include <sstream>

#include "ssta/core/error.h"
#include "ssta/files/file_util.h"
#include "text_parsers.h"
#include "ssta/files/yaml_reader.h"

namespace ssta {
bool CameraCalibration::HasDistortion() const {
  for (double d : distortion) {
    if (d != 0.0) return true;
  }
  return false;
}

bool CameraCalibration::IsValid(std::string* error) const {
  if (width <= 0 || height <= 0) return Fail(error, "resolution: must be positive");
  if (!(std::isfinite(fu) && std::isfinite(fv) && fu > 0 && fv > 0)) {
    return Fail(error, "intrinsics: focal lengths fu, fv must be positive and finite");
  }
  if (!(std::isfinite(cu) && std::isfinite(cv) && cu >= 0 && cv >= 0 && cu < width &&
        cv < height)) {
    return Fail(error, "intrinsics: principal point cu, cv must lie inside the image");
  }
  for (double d : distortion) {
    if (!std::isfinite(d)) return Fail(error, "distortion_coefficients: NaN or infinite value");
  }
  std::string why;
  if (!IsRigidTransform(body_T_camera.matrix(), &why)) return Fail(error, "T_BS: not a rigid transform: " + why);
  return true;
}

CameraCalibration LoadCameraCalibration(const std::string& path) {
  return internal::ParseCameraCalibration(ReadTextFile(path), path);
}

namespace internal {

CameraCalibration ParseCameraCalibration(const std::string& text, const std::string& path) {
  const YAML::Node root = internal::ParseYaml(text, path);
  internal::YamlSection yaml(root, path, "");
  CameraCalibration c;

  internal::YamlSection t_bs = yaml.Child("T_BS");
  if (!yaml.Has("T_BS")) throw Error(yaml.Name("T_BS") + ": missing key");
  std::vector<double> m;
  t_bs.ReadList("data", &m, 16);
  if (m.empty()) throw Error(t_bs.Name("data") + ": missing key");
  t_bs.Ignore("rows");
  t_bs.Ignore("cols");
  Eigen::Matrix4d mat;
  for (int i = 0; i < 16; ++i) mat(i / 4, i % 4) = m[i];
  std::string why;
  if (!IsRigidTransform(mat, &why)) throw Error(yaml.Name("T_BS") + ": not a rigid transform: " + why);
  c.body_T_camera.matrix() = mat;

  std::vector<double> resolution;
  yaml.ReadList("resolution", &resolution, 2);
  if (resolution.empty()) throw Error(yaml.Name("resolution") + ": missing key");
  if (resolution[0] != std::floor(resolution[0]) || resolution[1] != std::floor(resolution[1]) ||
      resolution[0] <= 0 || resolution[1] <= 0 || resolution[0] > 100000 || resolution[1] > 100000) {
    throw Error(yaml.Name("resolution") + ": must be two positive whole numbers");
  }
  c.width = static_cast<int>(resolution[0]);
  c.height = static_cast<int>(resolution[1]);

  const auto model = yaml.Has("camera_model") ? yaml.Require<std::string>("camera_model") : "pinhole";
  if (model != "pinhole") throw Error(yaml.Name("camera_model") + ": only 'pinhole' is supported, got '" + model + "'");
  std::vector<double> k;
  yaml.ReadList("intrinsics", &k, 4);
  if (k.empty()) throw Error(yaml.Name("intrinsics") + ": missing key");
  c.fu = k[0];
  c.fv = k[1];
  c.cu = k[2];
  c.cv = k[3];

  const auto dmodel = yaml.Has("distortion_model") ? yaml.Require<std::string>("distortion_model")
                                                   : "radial-tangential";
  if (dmodel != "radial-tangential") {
    throw Error(yaml.Name("distortion_model") + ": only 'radial-tangential' is supported, got '" + dmodel + "'");
  }
  std::vector<double> d;
  yaml.ReadList("distortion_coefficients", &d, 4);
  if (!d.empty()) std::copy(d.begin(), d.end(), c.distortion.begin());
  yaml.Read("rate_hz", &c.rate_hz);
  // Descriptive keys that ASL files carry; they do not change the model.
  for (const char* key : {"sensor_type", "comment"}) yaml.Ignore(key);
  yaml.RejectUnknownKeys();

  std::string error;
  if (!c.IsValid(&error)) throw Error(path + ": " + error);
  return c;
}

}  // namespace internal

void SaveCameraCalibration(const CameraCalibration& c, const std::string& path,
                           const std::string& comment) {
  std::ostringstream out;
  out << std::setprecision(17);
  out << "%YAML:1.0\n";
  out << "sensor_type: camera\n";
  out << "comment: \"" << (comment.empty() ? std::string("written by ssta") : comment) << "\"\n";
  out << "T_BS:\n  cols: 4\n  rows: 4\n  data: [";
  const Eigen::Matrix4d m = c.body_T_camera.matrix();
  for (int i = 0; i < 16; ++i) {
    out << m(i / 4, i % 4) << (i == 15 ? "]\n" : (i % 4 == 3 ? ",\n         " : ", "));
  }
  if (c.rate_hz > 0) out << "rate_hz: " << c.rate_hz << "\n";
  out << "resolution: [" << c.width << ", " << c.height << "]\n";
  out << "camera_model: pinhole\n";
  out << "intrinsics: [" << c.fu << ", " << c.fv << ", " << c.cu << ", " << c.cv << "]\n";
  out << "distortion_model: radial-tangential\n";
  out << "distortion_coefficients: [" << c.distortion[0] << ", " << c.distortion[1] << ", "
      << c.distortion[2] << ", " << c.distortion[3] << "]\n";
  WriteTextAtomically(path, out.str());
}

Eigen::Isometry3d StereoCalibration::LeftTRight() const {
  return left.body_T_camera.inverse() * right.body_T_camera;
}

bool StereoCalibration::IsRectified() const {
  const Eigen::Isometry3d lr = LeftTRight();
  const double angle = Eigen::AngleAxisd(lr.rotation()).angle();
  const Eigen::Vector3d t = lr.translation();
  return !left.HasDistortion() && !right.HasDistortion() && left.width == right.width &&
         left.height == right.height && std::abs(left.fu - right.fu) < 1e-6 &&
         std::abs(left.fv - right.fv) < 1e-6 && std::abs(left.cu - right.cu) < 1e-6 &&
         std::abs(left.cv - right.cv) < 1e-6 && std::abs(left.fu - left.fv) < 1e-6 &&
         angle < 1e-6 && std::abs(t.y()) < 1e-6 * t.norm() && std::abs(t.z()) < 1e-6 * t.norm();
}

bool StereoCalibration::IsValid(std::string* error) const {
  std::string e;
  if (!left.IsValid(&e)) return Fail(error, "cam0: " + e);
  if (!right.IsValid(&e)) return Fail(error, "cam1: " + e);
  if (left.width != right.width || left.height != right.height) {
    return Fail(error, "cam0 and cam1 resolutions differ");
  }
  const Eigen::Vector3d t = LeftTRight().translation();
  if (t.norm() < 1e-4) return Fail(error, "T_BS: the baseline between cam0 and cam1 is zero");
  if (t.x() <= 0 || std::abs(t.x()) < 0.5 * t.norm()) {
    return Fail(error, "T_BS: cam1 must lie to the right of cam0 (baseline along +x of cam0)");
  }
  return true;
}

StereoCalibration LoadStereoCalibration(const std::string& cam0_yaml, const std::string& cam1_yaml) {
  StereoCalibration s{LoadCameraCalibration(cam0_yaml), LoadCameraCalibration(cam1_yaml)};
  std::string error;
  if (!s.IsValid(&error)) throw Error(cam0_yaml + ", " + cam1_yaml + ": " + error);
  return s;
}

}  // namespace ssta
