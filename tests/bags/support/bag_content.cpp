#include "bags/support/bag_content.h"

#include <limits>

#include <opencv2/calib3d.hpp>
#include <opencv2/core/eigen.hpp>

#include <rosbag/bag.h>
#include <nav_msgs/Odometry.h>
#include <sensor_msgs/CameraInfo.h>
#include <sensor_msgs/Image.h>
#include <sensor_msgs/Imu.h>
#include <tf2_msgs/TFMessage.h>

#include "bags/support/ros_cdr_encoder.h"

namespace ssta::testing {
namespace {

internal::RosTransform Transform(const std::string& parent, const std::string& child, std::int64_t stamp,
                                 const Eigen::Isometry3d& parent_T_child) {
  internal::RosTransform t;
  t.header.stamp_ns = stamp;
  t.header.frame_id = parent;
  t.child_frame_id = child;
  const Eigen::Vector3d p = parent_T_child.translation();
  const Eigen::Quaterniond q(parent_T_child.linear());
  t.translation = {p.x(), p.y(), p.z()};
  t.rotation_xyzw = {q.x(), q.y(), q.z(), q.w()};
  return t;
}

internal::RosImage Mono8(const ImageU8& image, const std::string& frame, std::int64_t stamp) {
  internal::RosImage m;
  m.header = {stamp, frame};
  m.width = static_cast<std::uint32_t>(image.width());
  m.height = static_cast<std::uint32_t>(image.height());
  m.encoding = "mono8";
  m.step = m.width;
  m.data.assign(image.data(), image.data() + static_cast<std::size_t>(image.width()) * image.height());
  return m;
}

ros::Time RosTime(std::int64_t ns) {
  ros::Time t;
  t.fromNSec(static_cast<std::uint64_t>(ns));
  return t;
}

std_msgs::Header RosHeader(const internal::RosHeader& h) {
  std_msgs::Header out;
  out.stamp = RosTime(h.stamp_ns);
  out.frame_id = h.frame_id;
  return out;
}

sensor_msgs::Image ToRos(const internal::RosImage& m) {
  sensor_msgs::Image out;
  out.header = RosHeader(m.header);
  out.height = m.height;
  out.width = m.width;
  out.encoding = m.encoding;
  out.is_bigendian = m.big_endian;
  out.step = m.step;
  out.data = m.data;
  return out;
}

sensor_msgs::CameraInfo ToRos(const internal::RosCameraInfo& m) {
  sensor_msgs::CameraInfo out;
  out.header = RosHeader(m.header);
  out.height = m.height;
  out.width = m.width;
  out.distortion_model = m.distortion_model;
  out.D = m.d;
  for (int i = 0; i < 9; ++i) out.K[i] = m.k[static_cast<std::size_t>(i)];
  for (int i = 0; i < 9; ++i) out.R[i] = m.r[static_cast<std::size_t>(i)];
  for (int i = 0; i < 12; ++i) out.P[i] = m.p[static_cast<std::size_t>(i)];
  return out;
}

sensor_msgs::Imu ToRos(const internal::RosImu& m) {
  sensor_msgs::Imu out;
  out.header = RosHeader(m.header);
  out.orientation.x = m.orientation_xyzw[0];
  out.orientation.y = m.orientation_xyzw[1];
  out.orientation.z = m.orientation_xyzw[2];
  out.orientation.w = m.orientation_xyzw[3];
  out.angular_velocity.x = m.angular_velocity[0];
  out.angular_velocity.y = m.angular_velocity[1];
  out.angular_velocity.z = m.angular_velocity[2];
  out.linear_acceleration.x = m.linear_acceleration[0];
  out.linear_acceleration.y = m.linear_acceleration[1];
  out.linear_acceleration.z = m.linear_acceleration[2];
  return out;
}

nav_msgs::Odometry ToRos(const internal::RosOdometry& m) {
  nav_msgs::Odometry out;
  out.header = RosHeader(m.header);
  out.child_frame_id = m.child_frame_id;
  out.pose.pose.position.x = m.position[0];
  out.pose.pose.position.y = m.position[1];
  out.pose.pose.position.z = m.position[2];
  out.pose.pose.orientation.x = m.orientation_xyzw[0];
  out.pose.pose.orientation.y = m.orientation_xyzw[1];
  out.pose.pose.orientation.z = m.orientation_xyzw[2];
  out.pose.pose.orientation.w = m.orientation_xyzw[3];
  return out;
}

tf2_msgs::TFMessage ToRos(const std::vector<internal::RosTransform>& transforms) {
  tf2_msgs::TFMessage out;
  for (const auto& t : transforms) {
    geometry_msgs::TransformStamped s;
    s.header = RosHeader(t.header);
    s.child_frame_id = t.child_frame_id;
    s.transform.translation.x = t.translation[0];
    s.transform.translation.y = t.translation[1];
    s.transform.translation.z = t.translation[2];
    s.transform.rotation.x = t.rotation_xyzw[0];
    s.transform.rotation.y = t.rotation_xyzw[1];
    s.transform.rotation.z = t.rotation_xyzw[2];
    s.transform.rotation.w = t.rotation_xyzw[3];
    out.transforms.push_back(s);
  }
  return out;
}

}  // namespace

internal::RosCameraInfo RectifiedInfo(const CameraCalibration& c, double tx, const std::string& frame, std::int64_t stamp) {
  internal::RosCameraInfo info;
  info.header = {stamp, frame};
  info.width = static_cast<std::uint32_t>(c.width);
  info.height = static_cast<std::uint32_t>(c.height);
  info.distortion_model = "plumb_bob";
  info.d = {0, 0, 0, 0, 0};
  info.k = {c.fu, 0, c.cu, 0, c.fv, c.cv, 0, 0, 1};
  info.r = {1, 0, 0, 0, 1, 0, 0, 0, 1};
  info.p = {c.fu, 0, c.cu, tx, 0, c.fv, c.cv, 0, 0, 0, 1, 0};
  return info;
}

std::array<internal::RosCameraInfo, 2> RawInfos(const StereoCalibration& c, std::int64_t stamp) {
  // R and P as ROS's camera_calibration computes them for a stereo pair: cv::stereoRectify with
  // zero disparity at infinity, alpha 0.
  const auto k = [](const CameraCalibration& cam) -> cv::Mat {
    return (cv::Mat_<double>(3, 3) << cam.fu, 0, cam.cu, 0, cam.fv, cam.cv, 0, 0, 1);
  };
  const auto d = [](const CameraCalibration& cam) -> cv::Mat {
    return (cv::Mat_<double>(1, 5) << cam.distortion[0], cam.distortion[1], cam.distortion[2], cam.distortion[3], 0.0);
  };
  const Eigen::Isometry3d right_T_left = c.LeftTRight().inverse();
  cv::Mat r, t, r1, r2, p1, p2, q;
  cv::eigen2cv(Eigen::Matrix3d(right_T_left.rotation()), r);
  cv::eigen2cv(Eigen::Vector3d(right_T_left.translation()), t);
  const cv::Size size(c.left.width, c.left.height);
  cv::stereoRectify(k(c.left), d(c.left), k(c.right), d(c.right), size, r, t, r1, r2, p1, p2, q,
                    cv::CALIB_ZERO_DISPARITY, 0.0, size);
  std::array<internal::RosCameraInfo, 2> out;
  const CameraCalibration* cams[2] = {&c.left, &c.right};
  const cv::Mat* rs[2] = {&r1, &r2};
  const cv::Mat* ps[2] = {&p1, &p2};
  for (int i = 0; i < 2; ++i) {
    internal::RosCameraInfo& info = out[static_cast<std::size_t>(i)];
    const CameraCalibration& cam = *cams[i];
    info.header = {stamp, i == 0 ? kLeftFrame : kRightFrame};
    info.width = static_cast<std::uint32_t>(cam.width);
    info.height = static_cast<std::uint32_t>(cam.height);
    info.distortion_model = "plumb_bob";
    info.d = {cam.distortion[0], cam.distortion[1], cam.distortion[2], cam.distortion[3], 0.0};
    info.k = {cam.fu, 0, cam.cu, 0, cam.fv, cam.cv, 0, 0, 1};
    for (int j = 0; j < 9; ++j) info.r[static_cast<std::size_t>(j)] = rs[i]->at<double>(j / 3, j % 3);
    for (int j = 0; j < 12; ++j) info.p[static_cast<std::size_t>(j)] = ps[i]->at<double>(j / 4, j % 4);
  }
  return out;
}

BagContent ContentFromSequence(const Sequence& asl) {
  BagContent out;
  const auto& calib = asl.calibration();
  const std::int64_t first = asl.frames().front().timestamp_ns;
  if (calib.IsRectified()) {
    const double baseline = calib.LeftTRight().translation().x();
    out.left_info = RectifiedInfo(calib.left, 0.0, kLeftFrame, first);
    out.right_info = RectifiedInfo(calib.right, -calib.right.fu * baseline, kRightFrame, first);
  } else {
    const auto infos = RawInfos(calib, first);
    out.left_info = infos[0];
    out.right_info = infos[1];
  }
  for (const StereoFrame& f : asl.frames()) {
    const StereoImages images = asl.ReadImages(f);
    out.left.push_back(Mono8(images.left, kLeftFrame, f.timestamp_ns));
    out.right.push_back(Mono8(images.right, kRightFrame, f.timestamp_ns));
  }
  for (const ImuSample& s : asl.imu()) {
    internal::RosImu m;
    m.header = {s.timestamp_ns, kImuFrame};
    m.angular_velocity = {s.angular_rate.x(), s.angular_rate.y(), s.angular_rate.z()};
    m.linear_acceleration = {s.specific_force.x(), s.specific_force.y(), s.specific_force.z()};
    out.imu.push_back(m);
  }
  for (const PoseSample& p : asl.poses()) {
    internal::RosOdometry m;
    m.header = {p.timestamp_ns, kWorldFrame};
    m.child_frame_id = kBodyFrame;
    m.position = {p.world_p_body.x(), p.world_p_body.y(), p.world_p_body.z()};
    m.orientation_xyzw = {p.world_q_body.x(), p.world_q_body.y(), p.world_q_body.z(), p.world_q_body.w()};
    out.odometry.push_back(m);
  }
  out.tf_static.push_back(Transform(kBodyFrame, kLeftFrame, first, calib.left.body_T_camera));
  out.tf_static.push_back(Transform(kBodyFrame, kImuFrame, first, asl.body_T_imu()));
  return out;
}

namespace {

/// Calls write(topic, time_ns, message) for every message of `content` in time order, as a
/// recorder interleaves them: the mounts first, then IMU and odometry up to each frame, each
/// frame's CameraInfo with its images.
template <typename Write>
void ForEachMessage(const BagContent& content, Write write) {
  if (!content.tf_static.empty()) write("/tf_static", content.tf_static.front().header.stamp_ns, content.tf_static);
  std::size_t imu = 0, odom = 0;
  const auto up_to = [&](std::int64_t t) {
    for (; imu < content.imu.size() && content.imu[imu].header.stamp_ns <= t; ++imu) {
      write(kImu, content.imu[imu].header.stamp_ns, content.imu[imu]);
    }
    for (; odom < content.odometry.size() && content.odometry[odom].header.stamp_ns <= t; ++odom) {
      write(kOdometry, content.odometry[odom].header.stamp_ns, content.odometry[odom]);
    }
  };
  for (std::size_t i = 0; i < content.left.size(); ++i) {
    const std::int64_t t = content.left[i].header.stamp_ns;
    up_to(t);
    internal::RosCameraInfo left_info = content.left_info, right_info = content.right_info;
    left_info.header.stamp_ns = right_info.header.stamp_ns = t;
    write(kLeftInfo, t, left_info);
    write(kRightInfo, t, right_info);
    write(kLeftImage, t, content.left[i]);
    if (i < content.right.size()) write(kRightImage, content.right[i].header.stamp_ns, content.right[i]);
  }
  up_to(std::numeric_limits<std::int64_t>::max());
}

}  // namespace

void WriteRos1Bag(const BagContent& content, const std::string& path, Ros1Compression compression) {
  rosbag::Bag bag(path, rosbag::bagmode::Write);
  bag.setCompression(compression == Ros1Compression::kBz2   ? rosbag::compression::BZ2
                     : compression == Ros1Compression::kLz4 ? rosbag::compression::LZ4
                                                            : rosbag::compression::Uncompressed);
  ForEachMessage(content, [&](const std::string& topic, std::int64_t t, const auto& message) {
    bag.write(topic, RosTime(t), ToRos(message));
  });
  bag.close();
}

std::vector<McapChunkSpan> WriteRos2Bag(const BagContent& content, const std::string& folder,
                                        const Ros2BagWriterOptions& options) {
  Ros2BagWriter writer(folder, options);
  // The topics the content has messages on, as a recorder that subscribed to what was published.
  if (!content.tf_static.empty()) writer.AddTopic("/tf_static", "tf2_msgs/msg/TFMessage");
  if (!content.imu.empty()) writer.AddTopic(kImu, "sensor_msgs/msg/Imu");
  if (!content.odometry.empty()) writer.AddTopic(kOdometry, "nav_msgs/msg/Odometry");
  writer.AddTopic(kLeftInfo, "sensor_msgs/msg/CameraInfo");
  writer.AddTopic(kRightInfo, "sensor_msgs/msg/CameraInfo");
  writer.AddTopic(kLeftImage, "sensor_msgs/msg/Image");
  writer.AddTopic(kRightImage, "sensor_msgs/msg/Image");
  ForEachMessage(content, [&](const std::string& topic, std::int64_t t, const auto& message) {
    writer.Write(topic, t, EncodeCdr(message));
  });
  writer.Close();
  return writer.chunks();
}

}  // namespace ssta::testing
