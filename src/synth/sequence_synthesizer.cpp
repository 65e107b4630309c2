#include "ssta/synth/sequence_synthesizer.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <iomanip>
#include <numeric>
#include <sstream>
#include <utility>

#include "ssta/core/error.h"
#include "ssta/io/camera_calibration.h"
#include "ssta/files/file_util.h"
#include "ssta/io/image_io.h"
#include "ssta/synth/scene.h"
#include "ssta/synth/stereo_renderer.h"
#include "ssta/synth/vehicle_trajectory.h"
#include "ssta/core/units.h"
#include "synth/parallel.h"
#include "synth/random.h"

namespace ssta::synth {
namespace {

namespace fs = std::filesystem;

/// Time of the first IMU / pose sample; EuRoC-like magnitude to exercise int64 handling [ns].
constexpr std::int64_t kBaseNs = 1'600'000'000'000'000'000LL;
/// The first camera frame comes this long after the first IMU sample [s].
constexpr double kLeadInS = 0.1;
/// IMU and pose run on this long after the last camera frame [s].
constexpr double kLeadOutS = 0.1;

std::string Join(const std::string& a, const std::string& b) { return a + "/" + b; }

/// Body-frame rotation of the mount fault: pitch about body y, then roll about body x.
Eigen::Matrix3d MountError(const FaultOptions& f) {
  return (Eigen::AngleAxisd(DegToRad(f.mount_pitch_error_deg), Eigen::Vector3d::UnitY()) *
          Eigen::AngleAxisd(DegToRad(f.mount_roll_error_deg), Eigen::Vector3d::UnitX()))
      .toRotationMatrix();
}

/// The pose with its roll and pitch (ZYX Euler angles) offset by the given angles [rad].
Eigen::Isometry3d WithRollPitchOffset(const Eigen::Isometry3d& pose, double d_roll, double d_pitch) {
  const Eigen::Matrix3d& r = pose.linear();
  const double yaw = std::atan2(r(1, 0), r(0, 0));
  const double pitch = std::asin(std::clamp(-r(2, 0), -1.0, 1.0));
  const double roll = std::atan2(r(2, 1), r(2, 2));
  Eigen::Isometry3d out = pose;
  out.linear() = (Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ()) *
                  Eigen::AngleAxisd(pitch + d_pitch, Eigen::Vector3d::UnitY()) *
                  Eigen::AngleAxisd(roll + d_roll, Eigen::Vector3d::UnitX()))
                     .toRotationMatrix();
  return out;
}

std::string MatrixYaml(const Eigen::Matrix4d& m, const std::string& indent) {
  std::ostringstream out;
  out << std::setprecision(17);
  out << indent << "cols: 4\n" << indent << "rows: 4\n" << indent << "data: [";
  for (int i = 0; i < 16; ++i) out << m(i / 4, i % 4) << (i == 15 ? "]\n" : ", ");
  return out.str();
}

std::vector<int> DroppedFrames(const SynthOptions& o) {
  std::vector<int> dropped = o.faults.drop_frame_indices;
  if (dropped.empty() && o.faults.drop_frame_fraction > 0) {
    const int count = static_cast<int>(std::lround(o.faults.drop_frame_fraction * o.frames));
    std::vector<int> all(o.frames);
    std::iota(all.begin(), all.end(), 0);
    Rng rng(o.seed * 2654435761ULL + 17);
    for (int i = 0; i < count; ++i) {  // partial Fisher-Yates
      const int j = i + static_cast<int>(rng.Uniform(0, o.frames - i));
      std::swap(all[i], all[std::min(j, o.frames - 1)]);
    }
    dropped.assign(all.begin(), all.begin() + count);
  }
  std::sort(dropped.begin(), dropped.end());
  dropped.erase(std::unique(dropped.begin(), dropped.end()), dropped.end());
  return dropped;
}

/// The (x, y) of the surface points behind every 4th seen pixel of a frame, in the world: what
/// the cameras actually saw, so that the grid only scores that. Pixels in the don't-care band
/// of a class change count as seen: the grid takes its classes from the world, not from them.
void CollectSeenPoints(const StereoFrame& frame, const Eigen::Isometry3d& world_T_cam0, const RigOptions& rig,
                       std::vector<Eigen::Vector2d>* seen) {
  const double cu = (frame.depth.width() - 1) * 0.5, cv = (frame.depth.height() - 1) * 0.5;
  for (int v = 0; v < frame.depth.height(); v += 2) {
    for (int u = 0; u < frame.depth.width(); u += 2) {
      const float z = frame.depth(v, u);
      if (!(z > 0) || !frame.seen(v, u)) continue;
      const Eigen::Vector3d p = world_T_cam0 * Eigen::Vector3d((u - cu) * z / rig.focal_px, (v - cv) * z / rig.focal_px, z);
      seen->emplace_back(p.x(), p.y());
    }
  }
}

/// The world area the truth covers: every camera position, grown by the label range, out to
/// whole cells of the truth grid (`cell` [m]).
Eigen::AlignedBox2d TruthRegion(const std::vector<Eigen::Vector3d>& cams, double reach, double cell) {
  Eigen::AlignedBox2d box;
  for (const Eigen::Vector3d& c : cams) box.extend(c.head<2>());
  box.min() = ((box.min().array() - reach) / cell).floor() * cell;
  box.max() = ((box.max().array() + reach) / cell).ceil() * cell;
  return box;
}

/// World grid of classes over the area the cameras could label, map_server style: each cell
/// takes the worst true class of 3x3 samples of the top surface in it. Cells that no seen pixel
/// of any frame (StereoFrame::seen) fell in are 255 (don't care): a map cannot know them.
void WriteGrid(const TerrainTruth& truth, const SynthOptions& o, const Eigen::AlignedBox2d& region,
               const std::vector<Eigen::Vector2d>& seen, const std::string& gt_dir) {
  const double r = o.grid_resolution_m;
  const double x0 = region.min().x(), y0 = region.min().y();
  const int w = static_cast<int>(std::lround(region.sizes().x() / r));
  const int h = static_cast<int>(std::lround(region.sizes().y() / r));
  ImageU8 grid(w, h, 0);
  constexpr int kSub = 3;
  ParallelFor(h, o.render.threads, [&](int row) {
    for (int col = 0; col < w; ++col) {
      const double cx = x0 + col * r, cy = y0 + (h - 1 - row) * r;  // lower-left corner
      std::uint8_t worst = static_cast<std::uint8_t>(TravClass::kTraversable);
      for (int j = 0; j < kSub; ++j) {
        for (int i = 0; i < kSub; ++i) {
          const std::uint8_t c = truth.ClassAt(cx + (i + 0.5) * r / kSub, cy + (j + 0.5) * r / kSub);
          if (c == TerrainTruth::kDontCare) {
            worst = c;
          } else if (worst != TerrainTruth::kDontCare) {
            worst = static_cast<std::uint8_t>(Worse(static_cast<TravClass>(worst), static_cast<TravClass>(c)));
          }
        }
      }
      grid(row, col) = worst;
    }
  });
  ImageU8 seen_mask(w, h, 0);
  for (const Eigen::Vector2d& p : seen) {
    const int col = static_cast<int>(std::floor((p.x() - x0) / r));
    const int row = h - 1 - static_cast<int>(std::floor((p.y() - y0) / r));
    if (seen_mask.Contains(row, col)) seen_mask(row, col) = 1;
  }
  for (std::size_t i = 0; i < grid.size() && o.grid_seen_only; ++i) {
    if (!seen_mask[i]) grid[i] = kDontCare;
  }
  WriteImage(grid, Join(gt_dir, "grid_classes.png"));
  std::ostringstream yaml;
  yaml << std::setprecision(10);
  yaml << "# Ground-truth world grid of classes (ids of docs/interfaces.md, section 3); row 0 = largest y.\n"
       << "# A cell takes the worst true class of 3x3 samples of the top surface in it (the class of a\n"
       << "# point: docs/interfaces.md, section 3). Cells no camera saw are 255 (don't care): with\n"
       << "# seen both_cameras, a cell is seen when a pixel both cameras see within the label range\n"
       << "# lands in it.\n"
       << "image: grid_classes.png\n"
       << "seen: " << kTruthSeenBothCameras << "\n"
       << "resolution: " << r << "\n"
       << "origin: [" << x0 << ", " << y0 << ", 0.0]\n";
  WriteTextAtomically(Join(gt_dir, "grid.yaml"), yaml.str());
}

void WriteImuSensorYaml(const SynthOptions& o, const std::string& path) {
  std::ostringstream out;
  out << std::setprecision(10);
  const double sqrt_rate = std::sqrt(o.motion.imu_rate_hz);
  out << "%YAML:1.0\n"
      << "sensor_type: imu\n"
      << "comment: \"ssta synth: ideal IMU at the body origin (defines the body frame)\"\n"
      << "T_BS:\n"
      << MatrixYaml(Eigen::Matrix4d::Identity(), "  ")
      << "rate_hz: " << o.motion.imu_rate_hz << "\n"
      << "gyroscope_noise_density: " << o.faults.imu_gyro_noise / sqrt_rate << "\n"
      << "gyroscope_random_walk: 0.0\n"
      << "accelerometer_noise_density: " << o.faults.imu_accel_noise / sqrt_rate << "\n"
      << "accelerometer_random_walk: 0.0\n";
  WriteTextAtomically(path, out.str());
}

void WriteFaultsYaml(const SynthOptions& o, const Scene& scene, const Eigen::Isometry3d& true_cam0,
                     const Eigen::Isometry3d& written_cam0, const std::vector<int>& dropped,
                     const SynthSummary& s, const std::string& path) {
  const FaultOptions& f = o.faults;
  std::ostringstream out;
  out << std::setprecision(17);
  out << "# Faults injected by ssta synth; the images, IMU and gt/ always follow the truth.\n"
      << "mount_pitch_error_deg: " << f.mount_pitch_error_deg << "\n"
      << "mount_roll_error_deg: " << f.mount_roll_error_deg << "\n"
      << "# cam0/sensor.yaml and cam1/sensor.yaml carry T_BS_written = R_err * T_BS_true, rotated\n"
      << "# about cam0's optical centre; R_err = Ry(pitch) * Rx(roll) in the body frame.\n"
      << "true_cam0_T_BS:\n" << MatrixYaml(true_cam0.matrix(), "  ")
      << "written_cam0_T_BS:\n" << MatrixYaml(written_cam0.matrix(), "  ")
      << "pose_drift_roll_deg_per_s: " << f.pose_drift_roll_deg_per_s << "\n"
      << "pose_drift_pitch_deg_per_s: " << f.pose_drift_pitch_deg_per_s << "\n"
      << "# pose0 roll/pitch (ZYX Euler) = truth + drift * (t - t_first_pose)\n"
      << "imu_gyro_noise: " << f.imu_gyro_noise << "        # rad/s per sample, white\n"
      << "imu_accel_noise: " << f.imu_accel_noise << "       # m/s^2 per sample, white\n"
      << "imu_gyro_bias: " << f.imu_gyro_bias << "          # rad/s on every axis\n"
      << "imu_accel_bias: " << f.imu_accel_bias << "         # m/s^2 on every axis\n"
      << "drop_frames_fraction: " << f.drop_frame_fraction << "\n"
      << "# dropped frames are missing from cam1 only; cam0 and gt keep them\n"
      << "dropped_frames: [";
  for (std::size_t i = 0; i < s.dropped_timestamps_ns.size(); ++i) {
    out << (i ? ", " : "") << s.dropped_timestamps_ns[i];
  }
  out << "]\n"
      << "dropped_frame_indices: [";
  for (std::size_t i = 0; i < dropped.size(); ++i) out << (i ? ", " : "") << dropped[i];
  out << "]\n"
      << "textureless_patches: " << f.textureless_patches << "\n"
      << "# flat untextured discs on the ground: [x, y, radius] in world [m]\n"
      << "textureless_discs: [";
  for (std::size_t i = 0; i < scene.textureless.size(); ++i) {
    const TexturelessPatch& p = scene.textureless[i];
    out << (i ? ", " : "") << "[" << p.x << ", " << p.y << ", " << p.radius_m << "]";
  }
  out << "]\n";
  WriteTextAtomically(path, out.str());
}

std::string VehicleYaml(const VehicleOptions& v) {
  std::ostringstream out;
  out << std::setprecision(10);
  out << "# Vehicle thresholds used for this sequence's ground truth (docs/interfaces.md, section 4).\n"
      << "vehicle:\n"
      << "  max_slope_deg: " << v.max_slope_deg << "\n"
      << "  semi_slope_deg: " << v.semi_slope_deg << "\n"
      << "  max_step_m: " << v.max_step_m << "\n"
      << "  semi_step_m: " << v.semi_step_m << "\n"
      << "  step_radius_m: " << v.step_radius_m << "\n";
  return out.str();
}

/// synth writes into an empty or new folder, or over an earlier synth output (it has gt/): a
/// recorded sequence there would lose its images and its data.csv files.
void RequireSynthFolder(const std::string& out_dir) {
  std::error_code ec;
  const bool recorded = fs::exists(Join(out_dir, "cam0/data.csv"), ec) || fs::exists(Join(out_dir, "mav0"), ec);
  if (recorded && !fs::is_directory(Join(out_dir, "gt"), ec)) {
    throw Error(out_dir + ": holds a recorded sequence (cam0/data.csv or mav0/, and no gt/); synth writes only "
                "into a new or empty folder or over its own earlier output");
  }
}

/// The scene of the options: the named scene with the textureless patches and added boxes.
Scene BuildScene(const SynthOptions& o) {
  Scene scene = MakeScene(o.scene, o.seed, o.ramp_slope_deg);
  if (o.faults.textureless_patches > 0) AddTexturelessPatches(&scene, o.faults.textureless_patches, o.seed);
  for (const AddedBox& b : o.added_boxes) {
    AddBox(&scene, b.x, b.y, DegToRad(b.yaw_deg), b.length_m, b.width_m, b.height_m);
  }
  return scene;
}

/// Every camera frame's timestamp [ns] and true cam0 pose in the world.
struct FramePlan {
  std::vector<std::int64_t> stamps;
  std::vector<Eigen::Isometry3d> cam0_poses;     ///< world_T_cam0
  std::vector<Eigen::Vector3d> cam_positions;    ///< cam0's optical centre in world [m]
};

/// The frames at the rig rate, the first kLeadInS after the first IMU sample, with cam0 at
/// `body_T_cam0` on the vehicle.
FramePlan PlanFrames(const SynthOptions& o, const VehicleTrajectory& trajectory, const Eigen::Isometry3d& body_T_cam0) {
  FramePlan plan;
  for (int k = 0; k < o.frames; ++k) {
    const std::int64_t ns = kBaseNs + std::llround(kLeadInS * 1e9) + std::llround(k * 1e9 / o.rig.rate_hz);
    plan.stamps.push_back(ns);
    plan.cam0_poses.push_back(trajectory.WorldTBody(static_cast<double>(ns - kBaseNs) * 1e-9) * body_T_cam0);
    plan.cam_positions.push_back(plan.cam0_poses.back().translation());
  }
  return plan;
}

/// The mounts cam0/ and cam1/sensor.yaml carry (T_BS in the body frame).
struct WrittenMounts {
  Eigen::Isometry3d cam0, cam1;
};

/// The true mounts of cam0 (`body_T_cam0`) and cam1 turned by the mount fault about cam0's
/// optical centre.
WrittenMounts WrittenMountsOf(const SynthOptions& o, const Eigen::Isometry3d& body_T_cam0) {
  const Eigen::Isometry3d body_T_cam1 = body_T_cam0 * Eigen::Translation3d(o.rig.baseline_m, 0, 0);
  const Eigen::Matrix3d r_err = MountError(o.faults);
  WrittenMounts written{body_T_cam0, body_T_cam1};
  written.cam0.linear() = r_err * body_T_cam0.linear();
  written.cam1.linear() = r_err * body_T_cam1.linear();
  written.cam1.translation() =
      body_T_cam0.translation() + r_err * (body_T_cam1.translation() - body_T_cam0.translation());
  return written;
}

/// Makes the sequence's folders in `out_dir` (refused when it holds a recorded sequence) and
/// removes the frame files of an earlier run; returns how many were removed.
int PrepareFolder(const std::string& out_dir) {
  RequireSynthFolder(out_dir);
  for (const char* dir : {"cam0/data", "cam1/data", "imu0", "pose0", "gt/labels", "gt/disparity"}) {
    MakeDirectories(Join(out_dir, dir));
  }
  // The frames of an earlier, longer run would stay beside this one's and be scored.
  int removed = 0;
  for (const char* dir : {"cam0/data", "cam1/data", "gt/labels", "gt/disparity"}) {
    removed += RemoveFrameFiles(Join(out_dir, dir), ".png");
  }
  return removed;
}

/// cam0/ and cam1/sensor.yaml with the `written` mounts, gt/extrinsics.yaml with the true one
/// (`body_T_cam0`), imu0/sensor.yaml and vehicle.yaml.
void WriteCalibrationFiles(const SynthOptions& o, const CameraCalibration& intrinsics,
                           const Eigen::Isometry3d& body_T_cam0, const WrittenMounts& written,
                           const std::string& out_dir) {
  CameraCalibration cam = intrinsics;
  cam.body_T_camera = written.cam0;
  SaveCameraCalibration(cam, Join(out_dir, "cam0/sensor.yaml"), "ssta synth: cam0 (left)");
  cam.body_T_camera = written.cam1;
  SaveCameraCalibration(cam, Join(out_dir, "cam1/sensor.yaml"), "ssta synth: cam1 (right)");
  cam.body_T_camera = body_T_cam0;
  SaveCameraCalibration(cam, Join(out_dir, "gt/extrinsics.yaml"),
                        "ssta synth: the TRUE cam0 calibration and T_BS");
  WriteImuSensorYaml(o, Join(out_dir, "imu0/sensor.yaml"));
  WriteTextAtomically(Join(out_dir, "vehicle.yaml"), VehicleYaml(o.vehicle));
}

/// What rendering and writing the frames gave.
struct FrameOutputs {
  std::vector<Eigen::Vector2d> seen;  ///< world (x, y) of labelled surface points (CollectSeenPoints)
  std::vector<std::int64_t> dropped_timestamps_ns;  ///< frames left out of cam1
  int frames_written = 0;
  double max_disparity_px = 0;  ///< largest true disparity [px]
  double render_ms = 0;         ///< wall time of all renders [ms]
};

/// Renders every frame of `plan` and writes cam0/, cam1/ (without the `dropped` frame indices),
/// gt/labels/ and gt/disparity/ (16 bit, disparity * 256; 0 where the sky is seen) with the
/// data.csv files.
FrameOutputs WriteFrames(const SynthOptions& o, const StereoRenderer& renderer, const FramePlan& plan,
                         const std::vector<int>& dropped, const std::string& out_dir, const Progress& progress) {
  FrameOutputs out;
  std::ostringstream cam0_csv, cam1_csv;
  cam0_csv << "#timestamp [ns],filename\n";
  cam1_csv << "#timestamp [ns],filename\n";
  for (int k = 0; k < o.frames; ++k) {
    const std::int64_t ns = plan.stamps[static_cast<std::size_t>(k)];
    const Eigen::Isometry3d& world_T_cam0 = plan.cam0_poses[static_cast<std::size_t>(k)];
    const auto start = std::chrono::steady_clock::now();
    const StereoFrame frame = renderer.Render(world_T_cam0, k);
    out.render_ms += std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
    CollectSeenPoints(frame, world_T_cam0, o.rig, &out.seen);

    const std::string name = std::to_string(ns) + ".png";
    WriteImage(frame.left, Join(out_dir, "cam0/data/" + name));
    cam0_csv << ns << "," << name << "\n";
    if (std::binary_search(dropped.begin(), dropped.end(), k)) {
      out.dropped_timestamps_ns.push_back(ns);
    } else {
      WriteImage(frame.right, Join(out_dir, "cam1/data/" + name));
      cam1_csv << ns << "," << name << "\n";
    }
    ImageU16 disparity(frame.disparity.width(), frame.disparity.height(), 0);
    for (std::size_t i = 0; i < disparity.size(); ++i) {
      const float d = frame.disparity[i];
      if (d > 0) {
        disparity[i] = static_cast<std::uint16_t>(std::clamp(std::lround(d * 256.0), 1L, 65535L));
        out.max_disparity_px = std::max(out.max_disparity_px, static_cast<double>(d));
      }
    }
    WriteImage(frame.labels, Join(out_dir, "gt/labels/" + name));
    WriteImage(disparity, Join(out_dir, "gt/disparity/" + name));
    ++out.frames_written;
    if (progress) progress(k + 1, o.frames);
  }
  WriteTextAtomically(Join(out_dir, "cam0/data.csv"), cam0_csv.str());
  WriteTextAtomically(Join(out_dir, "cam1/data.csv"), cam1_csv.str());
  return out;
}

/// imu0/data.csv and pose0/data.csv at the IMU rate, from kLeadInS before the first frame to
/// kLeadOutS after the last, with the IMU and pose faults; returns the number of samples.
int WriteImuAndPoses(const SynthOptions& o, const VehicleTrajectory& trajectory, const std::string& out_dir) {
  const double t_end = kLeadInS + (o.frames - 1) / o.rig.rate_hz + kLeadOutS;
  const int samples = static_cast<int>(std::floor(t_end * o.motion.imu_rate_hz)) + 1;
  Rng imu_noise(o.seed * 6364136223846793005ULL + 23);
  std::ostringstream imu_csv, pose_csv;
  imu_csv << std::setprecision(12);
  pose_csv << std::setprecision(12);
  imu_csv << "#timestamp [ns],w_RS_S_x [rad s^-1],w_RS_S_y [rad s^-1],w_RS_S_z [rad s^-1],"
             "a_RS_S_x [m s^-2],a_RS_S_y [m s^-2],a_RS_S_z [m s^-2]\n";
  pose_csv << "#timestamp [ns],p_x [m],p_y [m],p_z [m],q_w [],q_x [],q_y [],q_z []\n";
  for (int i = 0; i < samples; ++i) {
    const std::int64_t ns = kBaseNs + std::llround(i * 1e9 / o.motion.imu_rate_hz);
    const double t = static_cast<double>(ns - kBaseNs) * 1e-9;
    const ImuSample imu = trajectory.Imu(t);
    Eigen::Vector3d gyro = imu.gyro_rad_s, accel = imu.accel_m_s2;
    for (int a = 0; a < 3; ++a) {
      gyro[a] += o.faults.imu_gyro_bias + o.faults.imu_gyro_noise * imu_noise.Gaussian();
      accel[a] += o.faults.imu_accel_bias + o.faults.imu_accel_noise * imu_noise.Gaussian();
    }
    imu_csv << ns << "," << gyro.x() << "," << gyro.y() << "," << gyro.z() << "," << accel.x()
            << "," << accel.y() << "," << accel.z() << "\n";
    const Eigen::Isometry3d pose = WithRollPitchOffset(
        trajectory.WorldTBody(t), DegToRad(o.faults.pose_drift_roll_deg_per_s) * t,
        DegToRad(o.faults.pose_drift_pitch_deg_per_s) * t);
    Eigen::Quaterniond q(pose.linear());
    q.normalize();
    if (q.w() < 0) q.coeffs() = -q.coeffs();
    const Eigen::Vector3d p = pose.translation();
    pose_csv << ns << "," << p.x() << "," << p.y() << "," << p.z() << "," << q.w() << "," << q.x()
             << "," << q.y() << "," << q.z() << "\n";
  }
  WriteTextAtomically(Join(out_dir, "imu0/data.csv"), imu_csv.str());
  WriteTextAtomically(Join(out_dir, "pose0/data.csv"), pose_csv.str());
  return samples;
}

/// A warning when the path runs past the distance the scene keeps clear; empty otherwise.
std::string ClearRunWarning(const SynthOptions& o, const Scene& scene) {
  const double run_m = o.motion.speed_mps * (o.frames - 1) / o.rig.rate_hz + kLeadInS * o.motion.speed_mps;
  if (!(run_m > scene.clear_run_m)) return "";
  std::ostringstream w;
  w << std::fixed << std::setprecision(1) << "the path runs " << run_m << " m, past the "
    << scene.clear_run_m << " m the " << o.scene
    << " scene keeps clear: the vehicle pose ignores obstacles and pits beyond";
  return w.str();
}

/// gt/rig.yaml: the rig and scene rendered, and the boxes added with --add-box.
void WriteRigYaml(const SynthOptions& o, const std::string& path) {
  std::ostringstream rig;
  rig << std::setprecision(10) << "# The rig and scene ssta synth rendered (for reports; the calibration is cam0/, cam1/).\n"
      << "scene: " << o.scene << "\nseed: " << o.seed << "\nwidth: " << o.rig.width << "\nheight: " << o.rig.height
      << "\nfocal_px: " << o.rig.focal_px << "\nbaseline_m: " << o.rig.baseline_m
      << "\ncamera_height_m: " << o.rig.camera_height_m << "\npitch_down_deg: " << o.rig.pitch_down_deg << "\n"
      << "# boxes added with --add-box: [x, y, length, width, height, yaw_deg] [m, deg]\nadded_boxes: [";
  for (std::size_t i = 0; i < o.added_boxes.size(); ++i) {
    const AddedBox& b = o.added_boxes[i];
    rig << (i ? ", " : "") << "[" << b.x << ", " << b.y << ", " << b.length_m << ", " << b.width_m << ", " << b.height_m
        << ", " << b.yaw_deg << "]";
  }
  rig << "]\n";
  WriteTextAtomically(path, rig.str());
}

}  // namespace

std::string SynthSummary::BriefReport() const {
  std::ostringstream out;
  out << std::fixed << std::setprecision(1) << "synth: " << frames_written << " frames ("
      << frames_dropped << " dropped from cam1), " << imu_samples << " IMU samples, largest disparity "
      << max_disparity_px << " px, " << render_ms_per_frame << " ms per stereo frame";
  if (stale_files_removed > 0) out << "; removed " << stale_files_removed << " frame files of an earlier run";
  return out.str();
}

Eigen::Isometry3d TrueBodyTCam0(const RigOptions& rig, const MotionOptions& motion) {
  const double p = DegToRad(rig.pitch_down_deg);
  Eigen::Matrix3d r;
  r.col(0) = Eigen::Vector3d(0, -1, 0);                         // camera x: body right
  r.col(2) = Eigen::Vector3d(std::cos(p), 0, -std::sin(p));     // camera z: forward, pitched down
  r.col(1) = r.col(2).cross(r.col(0));                          // camera y: down
  Eigen::Isometry3d t = Eigen::Isometry3d::Identity();
  t.linear() = r;
  t.translation() = Eigen::Vector3d(rig.camera_forward_m, 0.5 * rig.baseline_m,
                                    rig.camera_height_m - motion.body_height_m);
  return t;
}

SynthSummary WriteSyntheticSequence(const SynthOptions& o, const std::string& out_dir,
                                    const Progress& progress) {
  std::string error;
  if (!o.IsValid(&error)) throw Error(error);

  const Scene scene = BuildScene(o);
  const VehicleTrajectory trajectory(scene, o.motion);
  const Eigen::Isometry3d body_T_cam0 = TrueBodyTCam0(o.rig, o.motion);
  const FramePlan plan = PlanFrames(o, trajectory, body_T_cam0);
  const Eigen::AlignedBox2d region = TruthRegion(plan.cam_positions, o.render.max_label_range_m, o.grid_resolution_m);
  const TerrainTruth truth(scene, o.vehicle, region, o.render.threads);
  const StereoRenderer renderer(scene, o.rig, o.render, &truth, o.seed);

  SynthSummary summary;
  summary.body_T_cam0 = body_T_cam0;
  const WrittenMounts written = WrittenMountsOf(o, body_T_cam0);
  summary.stale_files_removed = PrepareFolder(out_dir);
  WriteCalibrationFiles(o, renderer.Intrinsics(), body_T_cam0, written, out_dir);

  const std::vector<int> dropped = DroppedFrames(o);
  FrameOutputs frames = WriteFrames(o, renderer, plan, dropped, out_dir, progress);
  summary.frames_written = frames.frames_written;
  summary.dropped_timestamps_ns = std::move(frames.dropped_timestamps_ns);
  summary.frames_dropped = static_cast<int>(summary.dropped_timestamps_ns.size());
  summary.max_disparity_px = frames.max_disparity_px;
  summary.render_ms_per_frame = frames.render_ms / o.frames;
  summary.imu_samples = WriteImuAndPoses(o, trajectory, out_dir);

  summary.warning = ClearRunWarning(o, scene);
  WriteGrid(truth, o, region, frames.seen, Join(out_dir, "gt"));
  WriteRigYaml(o, Join(out_dir, "gt/rig.yaml"));
  WriteFaultsYaml(o, scene, body_T_cam0, written.cam0, dropped, summary, Join(out_dir, "gt/faults.yaml"));
  return summary;
}

}  // namespace ssta::synth
