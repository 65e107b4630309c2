#pragma once

#include <array>
#include <string>

#include <Eigen/Geometry>

#include "ssta/core/rigid_transform.h"  // IsRigidTransform, which the calibration's checks use

namespace ssta {

/// One camera of an ASL sequence (`camN/sensor.yaml`, docs/interfaces.md, section 2): a pinhole model
/// with radial-tangential distortion and the camera's pose in the body frame.
struct CameraCalibration {
  int width = 0;   ///< image width [px]
  int height = 0;  ///< image height [px]
  double fu = 0.0, fv = 0.0;  ///< focal lengths [px]
  double cu = 0.0, cv = 0.0;  ///< principal point [px]
  std::array<double, 4> distortion{0.0, 0.0, 0.0, 0.0};  ///< k1, k2, p1, p2
  /// Maps camera coordinates (x right, y down, z forward) into the body frame (x fwd, z up).
  Eigen::Isometry3d body_T_camera = Eigen::Isometry3d::Identity();
  double rate_hz = 0.0;  ///< nominal frame rate, 0 when not given

  bool HasDistortion() const;
  /// Checks the values (positive focal lengths, principal point inside the image, rigid
  /// T_BS, finite numbers). On failure writes a message naming the key and returns false.
  bool IsValid(std::string* error) const;
};

/// Reads a `sensor.yaml` (also with OpenCV's `%YAML:1.0` first line).
/// Throws ssta::Error naming the file and key on a missing, malformed or invalid value.
CameraCalibration LoadCameraCalibration(const std::string& path);

/// Writes `calibration` in the same ASL format, atomically (temporary file + rename).
/// `comment` goes into the file's `comment:` key. Throws ssta::Error when it cannot write.
void SaveCameraCalibration(const CameraCalibration& calibration, const std::string& path,
                           const std::string& comment = "");

/// The left/right pair of a stereo rig.
struct StereoCalibration {
  CameraCalibration left;   ///< cam0
  CameraCalibration right;  ///< cam1

  /// Pose of the right camera in the left camera's frame (from the two T_BS).
  Eigen::Isometry3d LeftTRight() const;
  /// True when the pair is already rectified: identical intrinsics and size, zero distortion,
  /// no relative rotation, translation only along camera x (tolerances 1e-6 px / 1e-6 rad).
  bool IsRectified() const;
  /// Checks both cameras and the pair (same image size, a baseline along x that is not zero).
  bool IsValid(std::string* error) const;
};

/// Loads `dir/cam0/sensor.yaml` and `dir/cam1/sensor.yaml` (dir may be a sequence or its mav0).
StereoCalibration LoadStereoCalibration(const std::string& cam0_yaml, const std::string& cam1_yaml);


}  // namespace ssta
