// ROS bags as sequences: ROS 1 bags written here with rosbag's own API, the real bags others
// recorded (tests/data/bags), topic choice, image encodings, raw-camera rectification and the
// transform tree.

#include <cstdio>
#include <filesystem>
#include <fstream>

#include <gtest/gtest.h>
#include <nav_msgs/Odometry.h>
#include <opencv2/imgproc.hpp>
#include <rosbag/bag.h>
#include <rosbag/view.h>
#include <sensor_msgs/CameraInfo.h>
#include <sensor_msgs/CompressedImage.h>
#include <sensor_msgs/Image.h>
#include <sensor_msgs/Imu.h>
#include <tf2_msgs/TFMessage.h>

#include "bags/bag_reader.h"
#include "bags/image_decoding.h"
#include "bags/ros_messages.h"
#include "bags/tf_tree.h"
#include "bags/support/bag_content.h"
#include "bags/support/ros_cdr_encoder.h"
#include "ssta/bags/bag_sequence.h"
#include "ssta/core/error.h"
#include "ssta/io/image_io.h"
#include "ssta/io/sequence.h"
#include "ssta/mapping/map_export.h"
#include "ssta/pipeline/map_builder.h"
#include "ssta/pipeline/sequence_classifier.h"
#include "ssta/stereo/rectifier.h"
#include "ssta/synth/sequence_synthesizer.h"
#include "ssta_test_paths.h"
#include "temp_dir.h"

namespace ssta {
namespace {

using internal::RosEncoding;
namespace fs = std::filesystem;

const std::string kBags = std::string(SSTA_TEST_DATA_DIR) + "/bags/";

/// A short rendered yard, small enough for the sanitizer build: 6 frames of 320x240.
std::string RenderYard(const testing::TempDir& dir) {
  synth::SynthOptions o;
  o.scene = "yard";
  o.frames = 6;
  o.seed = 3;
  o.rig.width = 320;
  o.rig.height = 240;
  o.rig.focal_px = 210.0;
  o.render.max_label_range_m = 12.0;
  const std::string seq = dir / "asl";
  synth::WriteSyntheticSequence(o, seq);
  return seq;
}

std::string FileBytes(const std::string& path) {
  std::ifstream f(path, std::ios::binary);
  return std::string((std::istreambuf_iterator<char>(f)), {});
}

void ExpectSameSequence(const Sequence& a, const Sequence& b) {
  ASSERT_EQ(a.frames().size(), b.frames().size());
  for (std::size_t i = 0; i < a.frames().size(); ++i) EXPECT_EQ(a.frames()[i].timestamp_ns, b.frames()[i].timestamp_ns);
  const auto& ca = a.calibration();
  const auto& cb = b.calibration();
  EXPECT_EQ(ca.left.width, cb.left.width);
  EXPECT_DOUBLE_EQ(ca.left.fu, cb.left.fu);
  EXPECT_DOUBLE_EQ(ca.left.cv, cb.left.cv);
  EXPECT_DOUBLE_EQ(ca.right.cu, cb.right.cu);
  EXPECT_EQ(ca.left.distortion, cb.left.distortion);
  EXPECT_EQ(ca.right.distortion, cb.right.distortion);
  EXPECT_TRUE(ca.left.body_T_camera.isApprox(cb.left.body_T_camera, 1e-12));
  EXPECT_TRUE(ca.right.body_T_camera.isApprox(cb.right.body_T_camera, 1e-12));
  EXPECT_EQ(ca.IsRectified(), cb.IsRectified());
  ASSERT_EQ(a.imu().size(), b.imu().size());
  ASSERT_FALSE(a.imu().empty());
  EXPECT_EQ(a.imu().back().timestamp_ns, b.imu().back().timestamp_ns);
  EXPECT_EQ(a.imu().back().specific_force, b.imu().back().specific_force);
  EXPECT_TRUE(a.body_T_imu().isApprox(b.body_T_imu(), 1e-12));
  ASSERT_EQ(a.poses().size(), b.poses().size());
  if (!a.poses().empty()) {
    EXPECT_TRUE(a.poses().back().world_p_body.isApprox(b.poses().back().world_p_body, 1e-12));
  }
  const std::size_t last = a.frames().size() - 1;
  const StereoImages ia = a.ReadImages(a.frames()[std::min<std::size_t>(2, last)]);
  const StereoImages ib = b.ReadImages(b.frames()[std::min<std::size_t>(2, last)]);
  EXPECT_TRUE(std::equal(ia.right.data(), ia.right.data() + ia.right.width() * ia.right.height(), ib.right.data()));
}

/// Writes `asl` as a ROS 1 bag (bz2 chunks), an MCAP rosbag2 folder (zstd chunks) and, with
/// `sqlite`, an sqlite3 one; classifies and maps each and the folder with the same config, and
/// expects the same sequence, the same label PNGs and the same map CSV, byte for byte.
void ExpectSameLabelsAndMapInEveryContainer(const testing::TempDir& dir, const Sequence& asl, bool sqlite) {
  const testing::BagContent content = testing::ContentFromSequence(asl);
  testing::WriteRos1Bag(content, dir / "seq.bag", testing::Ros1Compression::kBz2);
  testing::Ros2BagWriterOptions mcap;
  mcap.compression = testing::McapCompression::kZstd;
  mcap.chunk_bytes = 256 * 1024;
  testing::WriteRos2Bag(content, dir / "seq_mcap", mcap);
  std::vector<std::pair<std::string, std::string>> bags = {{"seq.bag", "ros1"}, {"seq_mcap", "ros2 mcap"}};
  if (sqlite) {
    testing::Ros2BagWriterOptions db3;
    db3.storage = testing::Ros2Storage::kSqlite3;
    testing::WriteRos2Bag(content, dir / "seq_db3", db3);
    bags.emplace_back("seq_db3", "ros2 sqlite3");
  }

  Config config;
  if (asl.vehicle_config()) ApplyConfigFile(*asl.vehicle_config(), &config);
  const auto run = [&](const Sequence& sequence, const std::string& name) {
    ClassifyOptions classify;
    classify.out_dir = dir / ("labels-" + name);
    ClassifySequence(sequence, config, classify);
    BuildMapOptions map;
    map.map_path = dir / (name + ".ot");
    map.static_platform = sequence.poses().empty();  // EuRoC's excerpt: 3 frames, no poses
    BuildMap(sequence, "seq", config, map);
    ExportCsv(TraversabilityMap::Load(map.map_path), dir / (name + ".csv"));
  };
  run(asl, "asl");
  const std::string map_asl = FileBytes(dir / "asl.csv");
  EXPECT_GT(map_asl.size(), 10000u);
  const TraversabilityMap asl_map = TraversabilityMap::Load(dir / "asl.ot");
  for (const auto& [name, format] : bags) {
    SCOPED_TRACE(name);
    const Sequence bag = Sequence::Open(dir / name);
    EXPECT_EQ(bag.format(), format);
    // Nothing assumed (but that there are no poses, when the folder has none either).
    EXPECT_EQ(bag.notes().size(), asl.poses().empty() ? 1u : 0u) << bag.notes().front();
    ExpectSameSequence(asl, bag);
    run(bag, name);
    int compared = 0;
    for (const StereoFrame& f : asl.frames()) {
      const std::string file = "/labels/" + std::to_string(f.timestamp_ns) + ".png";
      const std::string a = FileBytes(dir / ("labels-asl" + file));
      ASSERT_FALSE(a.empty()) << file;
      EXPECT_EQ(a, FileBytes(dir / ("labels-" + name + file))) << file;
      ++compared;
    }
    EXPECT_EQ(compared, static_cast<int>(asl.frames().size()));
    // The rectification, its crop and focal length included, is the folder's.
    EXPECT_EQ(TraversabilityMap::Load(dir / (name + ".ot")).metadata().calibration_summary,
              asl_map.metadata().calibration_summary);
    EXPECT_EQ(map_asl, FileBytes(dir / (name + ".csv")));
  }
}

// The same rendered sequence as an ASL folder, as a ROS 1 bag (bz2 chunks) and as ROS 2 bags
// (MCAP with zstd chunks, sqlite3) is the same sequence: frames, calibration, mounts, IMU, poses,
// and so the same labels and the same map, byte for byte.
TEST(Bags, GiveTheSameLabelsAndMapAsTheAslSequence) {
  testing::TempDir dir;
  ExpectSameLabelsAndMapInEveryContainer(dir, Sequence::Open(RenderYard(dir)), true);
}

// A raw recording (EuRoC's distorted 752x480 cameras): its bags carry K, D, R and P as ROS's
// camera_calibration writes them, and the pipeline rectifies them with the folder's Rectifier,
// cropped to the common area (645x348, f 313 px): the same labels and map as the folder.
TEST(Bags, OfARawRecordingGiveTheFoldersRectificationLabelsAndMap) {
  testing::TempDir dir;
  const Sequence asl = Sequence::Open(std::string(SSTA_TEST_DATA_DIR) + "/euroc-v1-01-mini");
  ASSERT_FALSE(asl.calibration().IsRectified());
  ExpectSameLabelsAndMapInEveryContainer(dir, asl, false);
  const Sequence bag = Sequence::Open(dir / "seq.bag");
  const Rectifier rectifier(bag.calibration(), RectifierOptions{});
  EXPECT_EQ(rectifier.geometry().crop_width, 645);
  EXPECT_EQ(rectifier.geometry().crop_height, 348);
  EXPECT_NEAR(rectifier.geometry().f, 313.0, 1.0);
}

// convert writes the ASL layout; reading it back gives the bag's sequence.
TEST(Ros1Bag, ConvertsToAnAslSequence) {
  testing::TempDir dir;
  const Sequence asl = Sequence::Open(RenderYard(dir));
  const std::string bag_path = dir / "yard.bag";
  testing::WriteRos1Bag(testing::ContentFromSequence(asl), bag_path, testing::Ros1Compression::kLz4);
  const Sequence bag = Sequence::Open(bag_path);
  int calls = 0;
  WriteAslSequence(bag, dir / "converted", [&](int done, int total) {
    ++calls;
    EXPECT_EQ(total, 6);
    EXPECT_EQ(done, calls);
  });
  EXPECT_EQ(calls, 6);
  ExpectSameSequence(bag, Sequence::Open(dir / "converted"));
  EXPECT_THROW(WriteAslSequence(bag, dir / "converted"), Error);  // never over an existing sequence
}

// Pairing as for ASL: a right image missing is a skipped frame with its reason.
TEST(Ros1Bag, PairsFramesByHeaderStampAndReportsTheUnpaired) {
  testing::TempDir dir;
  const Sequence asl = Sequence::Open(RenderYard(dir));
  testing::BagContent content = testing::ContentFromSequence(asl);
  content.right.erase(content.right.begin() + 3);
  content.right[3].header.stamp_ns += 400'000;  // 0.4 ms late: still pairs
  const std::string bag_path = dir / "gap.bag";
  testing::WriteRos1Bag(content, bag_path);
  const Sequence bag = Sequence::Open(bag_path);
  ASSERT_EQ(bag.frames().size(), 5u);
  ASSERT_EQ(bag.skipped().size(), 1u);
  EXPECT_EQ(bag.skipped()[0].timestamp_ns, asl.frames()[3].timestamp_ns);
  EXPECT_NE(bag.skipped()[0].reason.find("no /stereo/right/image_raw image within 1 ms"), std::string::npos);
  EXPECT_EQ(bag.frames()[3].timestamp_ns, asl.frames()[4].timestamp_ns);
}

/// A bag with two cameras' image topics, CameraInfo, and nothing else.
testing::BagContent TinyContent() {
  testing::BagContent c;
  CameraCalibration cam;
  cam.width = 8;
  cam.height = 6;
  cam.fu = cam.fv = 10;
  cam.cu = 4;
  cam.cv = 3;
  c.left_info = testing::RectifiedInfo(cam, 0.0, testing::kLeftFrame, 1'000'000'000);
  c.right_info = testing::RectifiedInfo(cam, -10 * 0.1, testing::kRightFrame, 1'000'000'000);
  for (int i = 0; i < 2; ++i) {
    internal::RosImage m;
    m.header = {1'000'000'000 + i * 100'000'000, testing::kLeftFrame};
    m.width = 8;
    m.height = 6;
    m.encoding = "mono8";
    m.step = 8;
    m.data.assign(48, static_cast<std::uint8_t>(10 * i));
    c.left.push_back(m);
    m.header.frame_id = testing::kRightFrame;
    c.right.push_back(m);
  }
  return c;
}

TEST(BagTopics, WithoutMountsAndPosesTheAssumptionsAreNoted) {
  testing::TempDir dir;
  testing::WriteRos1Bag(TinyContent(), dir / "tiny.bag");
  const Sequence s = Sequence::Open(dir / "tiny.bag");
  ASSERT_EQ(s.frames().size(), 2u);
  EXPECT_TRUE(s.imu().empty());
  EXPECT_TRUE(s.poses().empty());
  ASSERT_EQ(s.notes().size(), 2u);
  EXPECT_NE(s.notes()[0].find("looking along body x"), std::string::npos);
  // Optical z (forward) is body x, optical x (right) is body -y.
  EXPECT_TRUE((s.calibration().left.body_T_camera.linear() * Eigen::Vector3d::UnitZ()).isApprox(Eigen::Vector3d::UnitX()));
  EXPECT_TRUE((s.calibration().left.body_T_camera.linear() * Eigen::Vector3d::UnitX()).isApprox(-Eigen::Vector3d::UnitY()));
  EXPECT_NEAR(s.calibration().LeftTRight().translation().x(), 0.1, 1e-12);
  const StereoImages images = s.ReadImages(s.frames()[1]);
  EXPECT_EQ(images.left(5, 7), 10);
}

// A camera with its own IMU and no robot around it (a RealSense D435i's bag): no body frame in
// /tf, so the body is made up around the camera, and the IMU's mount is read relative to the
// camera and carried through that assumed mount: at rest the IMU must read gravity as up.
TEST(BagTopics, AnImuOnTheCameraWithoutABodyFrameIsMountedThroughTheAssumedMount) {
  testing::TempDir dir;
  testing::BagContent c = TinyContent();
  // The IMU in the camera's optical axes (x right, y down, z forward): at rest, specific force
  // points up, which is optical -y.
  for (int i = 0; i < 5; ++i) {
    internal::RosImu imu;
    imu.header = {900'000'000 + i * 100'000'000, testing::kLeftFrame};
    imu.linear_acceleration = {0.0, -9.81, 0.0};
    c.imu.push_back(imu);
  }
  testing::WriteRos1Bag(c, dir / "d435i.bag");
  const Sequence s = Sequence::Open(dir / "d435i.bag");
  ASSERT_EQ(s.imu().size(), 5u);
  const Eigen::Vector3d up_in_body = s.body_T_imu().linear() * s.imu().front().specific_force;
  EXPECT_TRUE(up_in_body.isApprox(Eigen::Vector3d(0, 0, 9.81), 1e-9)) << up_in_body.transpose();
  // Without poses or a mount: the two assumptions are noted, the IMU's is not.
  EXPECT_EQ(s.notes().size(), 2u);
}

// A recording whose poses live only on /tf (a SLAM node's odom -> base_link, no Odometry topic)
// is mapped with them by default; a /tf that only holds fixed mounts gives no poses.
TEST(BagTopics, TfMovingTheBodyIsThePoseByDefault) {
  testing::TempDir dir;
  const std::string path = dir / "tf_only.bag";
  testing::WriteRos1Bag(TinyContent(), path);
  const auto add_tf = [&](const char* topic, double x0, double x1) {
    rosbag::Bag bag(path, rosbag::bagmode::Append);
    for (const auto& [t, x] : {std::pair<double, double>{0.9, x0}, {1.3, x1}}) {
      geometry_msgs::TransformStamped link;
      link.header.stamp.fromSec(t);
      link.header.frame_id = "odom";
      link.child_frame_id = "base_link";
      link.transform.translation.x = x;
      link.transform.rotation.w = 1.0;
      tf2_msgs::TFMessage m;
      m.transforms.push_back(link);
      bag.write(topic, ros::Time(t), m);
    }
  };
  add_tf("/tf_static", 0.0, 0.0);
  EXPECT_TRUE(Sequence::Open(path).poses().empty());
  add_tf("/tf", 0.0, 4.0);
  const Sequence s = Sequence::Open(path);
  ASSERT_EQ(s.poses().size(), 2u);
  EXPECT_NEAR(s.WorldTBodyAt(1'100'000'000)->translation().x(), 2.0, 1e-9);
}

// A misconfigured static_transform_publisher (a zero quaternion) on a link SSTA does not use
// leaves the bag readable, as tf2 leaves it out; it is noted.
TEST(BagTopics, ABrokenTransformIsLeftOutWithANote) {
  testing::TempDir dir;
  const std::string path = dir / "bad_tf.bag";
  testing::WriteRos1Bag(TinyContent(), path);
  {
    rosbag::Bag bag(path, rosbag::bagmode::Append);
    geometry_msgs::TransformStamped bad;
    bad.header.frame_id = "base_link";
    bad.child_frame_id = "laser";  // rotation left 0 0 0 0
    tf2_msgs::TFMessage m;
    m.transforms.push_back(bad);
    bag.write("/tf_static", ros::Time(1.0), m);
  }
  const Sequence s = Sequence::Open(path);
  EXPECT_EQ(s.frames().size(), 2u);
  ASSERT_FALSE(s.notes().empty());
  EXPECT_NE(s.notes().front().find("/tf_static base_link -> laser: quaternion norm 0"), std::string::npos)
      << s.notes().front();
}

TEST(BagTopics, TopicOptionsOnAFolderAreAnError) {
  BagTopics topics;
  topics.imu = "/imu";
  const std::string euroc = std::string(SSTA_TEST_DATA_DIR) + "/euroc-v1-01-mini";
  try {
    Sequence::Open(euroc, topics);
    FAIL();
  } catch (const Error& e) {
    EXPECT_EQ(std::string(e.what()), euroc + ": --imu-topic applies to ROS bags; this is not one (a .bag, .mcap, "
                                             ".db3 or rosbag2 folder)");
  }
}

TEST(BagTopics, ChoiceErrorsNameTheBagAndTheWayOut) {
  testing::TempDir dir;
  const std::string path = dir / "tiny.bag";
  testing::WriteRos1Bag(TinyContent(), path);
  const auto message = [&](const BagTopics& topics) {
    try {
      Sequence::Open(path, topics);
    } catch (const Error& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  BagTopics t;
  t.left = "/nope";
  t.right = "/stereo/right/image_raw";
  EXPECT_EQ(message(t), path + ": --left-topic /nope: no such topic in the bag (image topics: /stereo/left/image_raw, "
                               "/stereo/right/image_raw)");
  t.left = "/stereo/left/camera_info";
  EXPECT_EQ(message(t), path +
                            ": --left-topic /stereo/left/camera_info is sensor_msgs/CameraInfo, expected "
                            "sensor_msgs/Image, sensor_msgs/CompressedImage");
  BagTopics imu;
  imu.imu = "/imu";
  EXPECT_EQ(message(imu), path + ": --imu-topic /imu: no such topic in the bag");
  BagTopics tf;
  tf.pose = "/tf";
  EXPECT_EQ(message(tf), path + ": --pose-topic /tf: the bag has no /tf topic");
  // Only the left topic given: the right one is its mirror.
  BagTopics left_only;
  left_only.left = "/stereo/left/image_raw";
  EXPECT_EQ(Sequence::Open(path, left_only).frames().size(), 2u);
}

TEST(BagTopics, TwoStereoPairsAreAskedFor) {
  testing::TempDir dir;
  const std::string path = dir / "two.bag";
  {
    rosbag::Bag bag(path, rosbag::bagmode::Write);
    sensor_msgs::Image image;
    image.header.stamp.fromSec(1.0);
    for (const char* topic : {"/a/left/image", "/a/right/image", "/b/left/image", "/b/right/image"}) {
      bag.write(topic, ros::Time(1.0), image);
    }
  }
  try {
    Sequence::Open(path);
    FAIL() << "two pairs must not be guessed between";
  } catch (const Error& e) {
    EXPECT_EQ(std::string(e.what()), path +
                                         ": 2 stereo pairs of image topics (/a/left/image + /a/right/image, "
                                         "/b/left/image + /b/right/image): choose one with --left-topic and "
                                         "--right-topic");
  }
}

TEST(BagTopics, AStereoPairWithoutStereoCalibrationIsRefused) {
  testing::TempDir dir;
  testing::BagContent c = TinyContent();
  c.right_info.p[3] = 0.0;  // two monocular calibrations
  testing::WriteRos1Bag(c, dir / "mono.bag");
  try {
    Sequence::Open(dir / "mono.bag");
    FAIL();
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("/stereo/right/camera_info: P[3] is 0: not a stereo calibration"),
              std::string::npos)
        << e.what();
  }
}

// A mount and poses from /tf: base_link moves in odom (dynamic), the camera sits on it
// (static). The body pose is read through the chain, interpolated between samples.
TEST(BagTopics, PosesAndMountFromTf) {
  testing::TempDir dir;
  const std::string path = dir / "tf.bag";
  testing::BagContent content = TinyContent();
  testing::WriteRos1Bag(content, path);
  {
    rosbag::Bag bag(path, rosbag::bagmode::Append);
    const auto transform = [](const char* parent, const char* child, double t, double x, double yaw) {
      geometry_msgs::TransformStamped s;
      s.header.stamp.fromSec(t);
      s.header.frame_id = parent;
      s.child_frame_id = child;
      s.transform.translation.x = x;
      s.transform.rotation.z = std::sin(yaw / 2);
      s.transform.rotation.w = std::cos(yaw / 2);
      tf2_msgs::TFMessage m;
      m.transforms.push_back(s);
      return m;
    };
    geometry_msgs::TransformStamped mount;
    mount.header.frame_id = "base_link";
    mount.child_frame_id = testing::kLeftFrame;
    mount.transform.translation.z = 0.5;
    // optical -> body: z forward = x, x right = -y, y down = -z (quaternion of that rotation)
    mount.transform.rotation.x = -0.5;
    mount.transform.rotation.y = 0.5;
    mount.transform.rotation.z = -0.5;
    mount.transform.rotation.w = 0.5;
    tf2_msgs::TFMessage statics;
    statics.transforms.push_back(mount);
    bag.write("/tf_static", ros::Time(1.0), statics);
    bag.write("/tf", ros::Time(0.9), transform("odom", "base_link", 0.9, 0.0, 0.0));
    bag.write("/tf", ros::Time(1.3), transform("odom", "base_link", 1.3, 4.0, 0.4));
  }
  BagTopics topics;
  topics.pose = "/tf";
  const Sequence s = Sequence::Open(path, topics);
  EXPECT_TRUE(s.notes().empty());
  EXPECT_TRUE(s.calibration().left.body_T_camera.translation().isApprox(Eigen::Vector3d(0, 0, 0.5)));
  EXPECT_TRUE((s.calibration().left.body_T_camera.linear() * Eigen::Vector3d::UnitZ()).isApprox(Eigen::Vector3d::UnitX()));
  const auto pose = s.WorldTBodyAt(1'100'000'000);  // half-way between the two samples
  ASSERT_TRUE(pose);
  EXPECT_NEAR(pose->translation().x(), 2.0, 1e-9);
  EXPECT_NEAR(Eigen::AngleAxisd(pose->linear()).angle(), 0.2, 1e-9);
  EXPECT_NE(s.pose_path().find("odom -> base_link"), std::string::npos) << s.pose_path();
}

TEST(TfTree, LooksUpThroughTheCommonAncestorAndLimitsExtrapolation) {
  internal::TfTree tf;
  Eigen::Isometry3d a = Eigen::Isometry3d::Identity();
  a.translation() = Eigen::Vector3d(1, 0, 0);
  Eigen::Isometry3d b = Eigen::Isometry3d::Identity();
  b.translation() = Eigen::Vector3d(0, 2, 0);
  tf.Add("base", "cam", 0, a, true);
  tf.Add("base", "imu", 0, b, true);
  tf.Add("odom", "base", 1'000'000'000, Eigen::Isometry3d::Identity(), false);
  tf.Add("odom", "base", 2'000'000'000, Eigen::Isometry3d(Eigen::Translation3d(10, 0, 0)), false);
  const auto cam_T_imu = tf.Lookup("cam", "imu", 0);
  ASSERT_TRUE(cam_T_imu);
  EXPECT_TRUE(cam_T_imu->translation().isApprox(Eigen::Vector3d(-1, 2, 0)));
  EXPECT_EQ(tf.RootOf("cam"), "odom");
  const auto at = [&](std::int64_t t) { return tf.Lookup("odom", "cam", t); };
  ASSERT_TRUE(at(1'250'000'000));
  EXPECT_NEAR(at(1'250'000'000)->translation().x(), 3.5, 1e-12);
  ASSERT_TRUE(at(2'400'000'000));  // 0.4 s past the last sample: held
  EXPECT_NEAR(at(2'400'000'000)->translation().x(), 11.0, 1e-12);
  EXPECT_FALSE(at(2'600'000'000));  // 0.6 s past it: unknown
  EXPECT_FALSE(tf.Lookup("cam", "elsewhere", 0));
  EXPECT_EQ(tf.ChangeTimes("odom", "cam"), (std::vector<std::int64_t>{1'000'000'000, 2'000'000'000}));
}

internal::RosImage Image(const std::string& encoding, int channels_bytes, std::uint32_t step_padding = 0) {
  internal::RosImage m;
  m.width = 4;
  m.height = 2;
  m.encoding = encoding;
  m.step = 4 * static_cast<std::uint32_t>(channels_bytes) + step_padding;
  m.data.assign(static_cast<std::size_t>(m.step) * 2, 0);
  return m;
}

TEST(BagImages, EncodingsBecomeGrey) {
  // mono8 with row padding: the padding is dropped.
  internal::RosImage mono = Image("mono8", 1, 3);
  mono.data[7 + 2] = 200;  // row 1, column 2
  EXPECT_EQ(internal::GreyImage(mono, "m")(1, 2), 200);
  EXPECT_EQ(internal::GreyImage(mono, "m")(0, 2), 0);
  // mono16, both byte orders: 0x8000 -> 128.
  internal::RosImage deep = Image("mono16", 2);
  deep.data[2 * 1 + 1] = 0x80;  // little endian, column 1
  EXPECT_EQ(internal::GreyImage(deep, "d")(0, 1), 128);
  deep.big_endian = true;
  EXPECT_EQ(internal::GreyImage(deep, "d")(0, 1), 0);  // now 0x0080 -> 0
  // Colour: pure red is 0.299 * 255 = 76 in rgb8, the same bytes are blue (29) in bgr8.
  internal::RosImage rgb = Image("rgb8", 3);
  for (std::size_t p = 0; p < rgb.data.size(); p += 3) rgb.data[p] = 255;
  EXPECT_EQ(internal::GreyImage(rgb, "c")(0, 0), 76);
  rgb.encoding = "bgr8";
  EXPECT_EQ(internal::GreyImage(rgb, "c")(0, 0), 29);
  internal::RosImage bgra = Image("bgra8", 4);
  for (std::size_t p = 1; p < bgra.data.size(); p += 4) bgra.data[p] = 255;  // green
  EXPECT_EQ(internal::GreyImage(bgra, "c")(1, 3), 150);
  // A Bayer mosaic of a uniform grey scene demosaics to that grey.
  // A Bayer mosaic of a uniform colour (R 200, G 100, B 50) demosaics to that colour's grey,
  // 0.299 R + 0.587 G + 0.114 B = 124; reading BGGR as RGGB would give 96.
  internal::RosImage bayer = Image("bayer_bggr8", 1);
  bayer.width = bayer.height = bayer.step = 8;
  bayer.data.resize(64);
  for (int v = 0; v < 8; ++v) {
    for (int u = 0; u < 8; ++u) {
      const bool even_row = v % 2 == 0, even_col = u % 2 == 0;  // B G / G R
      bayer.data[static_cast<std::size_t>(8 * v + u)] = even_row && even_col ? 50 : !even_row && !even_col ? 200 : 100;
    }
  }
  EXPECT_NEAR(internal::GreyImage(bayer, "b")(4, 4), 124, 1);
  bayer.encoding = "bayer_rggb8";
  EXPECT_NEAR(internal::GreyImage(bayer, "b")(4, 4), 96, 1);
  // Wrong: an unknown encoding, data shorter than height * step.
  try {
    internal::GreyImage(Image("yuv422", 2), "cam.bag:/left@5");
    FAIL();
  } catch (const Error& e) {
    EXPECT_EQ(std::string(e.what()).rfind("cam.bag:/left@5: image encoding 'yuv422' is not read", 0), 0u) << e.what();
  }
  internal::RosImage short_data = Image("mono8", 1);
  short_data.data.resize(5);
  EXPECT_THROW(internal::GreyImage(short_data, "s"), Error);
}

TEST(BagImages, CompressedPngIsDecodedLosslessly) {
  testing::TempDir dir;
  ImageU8 image(5, 3);
  for (int v = 0; v < 3; ++v) {
    for (int u = 0; u < 5; ++u) image(v, u) = static_cast<std::uint8_t>(17 * u + 50 * v);
  }
  WriteImage(image, dir / "i.png");
  const std::string bytes = FileBytes(dir / "i.png");
  internal::RosCompressedImage m;
  m.format = "mono8; png compressed ";
  m.data.assign(bytes.begin(), bytes.end());
  const ImageU8 back = internal::GreyImage(m, "p");
  ASSERT_EQ(back.width(), 5);
  EXPECT_EQ(back(2, 4), 17 * 4 + 100);
  m.data.resize(20);
  EXPECT_THROW(internal::GreyImage(m, "p"), Error);
}

// A stereo pair recorded compressed (image_transport's `.../compressed` topics, PNG here, so
// lossless): the CameraInfo is found one namespace up and the frames decode to the images.
TEST(BagImages, ACompressedStereoPairIsASequence) {
  testing::TempDir dir;
  const testing::BagContent c = TinyContent();
  testing::Ros2BagWriter writer(dir / "compressed");
  writer.AddTopic(testing::kLeftInfo, "sensor_msgs/msg/CameraInfo");
  writer.AddTopic(testing::kRightInfo, "sensor_msgs/msg/CameraInfo");
  const std::string left = std::string(testing::kLeftImage) + "/compressed";
  const std::string right = std::string(testing::kRightImage) + "/compressed";
  writer.AddTopic(left, "sensor_msgs/msg/CompressedImage");
  writer.AddTopic(right, "sensor_msgs/msg/CompressedImage");
  writer.Write(testing::kLeftInfo, 1, testing::EncodeCdr(c.left_info));
  writer.Write(testing::kRightInfo, 1, testing::EncodeCdr(c.right_info));
  for (std::size_t i = 0; i < c.left.size(); ++i) {
    for (const auto& [topic, raw] : {std::pair<std::string, const internal::RosImage*>{left, &c.left[i]}, {right, &c.right[i]}}) {
      ImageU8 image(static_cast<int>(raw->width), static_cast<int>(raw->height));
      std::copy(raw->data.begin(), raw->data.end(), image.data());
      image(2, 3) = static_cast<std::uint8_t>(200 + i);  // one pixel that tells the frames apart
      WriteImage(image, dir / "frame.png");
      const std::string bytes = FileBytes(dir / "frame.png");
      internal::RosCompressedImage m;
      m.header = raw->header;
      m.format = "mono8; png compressed ";
      m.data.assign(bytes.begin(), bytes.end());
      writer.Write(topic, raw->header.stamp_ns, testing::EncodeCdr(m));
    }
  }
  writer.Close();
  const Sequence s = Sequence::Open(dir / "compressed");
  EXPECT_EQ(s.format(), "ros2 mcap");
  ASSERT_EQ(s.frames().size(), 2u);
  EXPECT_NE(s.frames()[1].left_path.find(left + "@1100000000"), std::string::npos) << s.frames()[1].left_path;
  const StereoImages images = s.ReadImages(s.frames()[1]);
  EXPECT_EQ(images.left(2, 3), 201);
  EXPECT_EQ(images.right(5, 7), 10);
}

/// A 64x48 pair of raw cameras (K 50 px) whose left CameraInfo rotates it by R (0.05 rad about
/// its y axis), 0.1 m apart; every image row is 0, 3, 6, ... (3 u).
testing::BagContent RotatedRawContent(const Eigen::Matrix3d& r) {
  testing::BagContent c = TinyContent();
  const int w = 64, h = 48;
  for (auto* info : {&c.left_info, &c.right_info}) {
    info->width = w;
    info->height = h;
    info->k = {50, 0, 32, 0, 50, 24, 0, 0, 1};
    info->p[0] = info->p[5] = 50;
    info->p[2] = 32;
    info->p[6] = 24;
  }
  c.right_info.p[3] = -50 * 0.1;
  for (int i = 0; i < 9; ++i) c.left_info.r[static_cast<std::size_t>(i)] = r(i / 3, i % 3);
  for (auto* images : {&c.left, &c.right}) {
    for (auto& m : *images) {
      m.width = w;
      m.height = h;
      m.step = w;
      m.data.resize(static_cast<std::size_t>(w * h));
      for (int v = 0; v < h; ++v) {
        for (int u = 0; u < w; ++u) m.data[static_cast<std::size_t>(v * w + u)] = static_cast<std::uint8_t>(3 * u);
      }
    }
  }
  return c;
}

// A raw pair the Rectifier describes (plumb_bob) reaches the pipeline raw: the calibration is K
// and D, the right camera where R and P put it (turned by R_left^T R_right, at R_left^T
// (baseline, 0, 0)), and the images as recorded; the Rectifier then rectifies it as a folder's.
TEST(BagImages, ARawPairReachesTheRectifierWithItsCameraInfo) {
  testing::TempDir dir;
  const double angle = 0.05;  // about the left camera's y axis
  const Eigen::Matrix3d r = Eigen::AngleAxisd(angle, Eigen::Vector3d::UnitY()).toRotationMatrix();
  testing::WriteRos1Bag(RotatedRawContent(r), dir / "raw.bag");
  const Sequence s = Sequence::Open(dir / "raw.bag");
  for (const std::string& note : s.notes()) EXPECT_EQ(note.find("image_proc"), std::string::npos) << note;
  const StereoCalibration& c = s.calibration();
  EXPECT_FALSE(c.IsRectified());
  EXPECT_DOUBLE_EQ(c.left.fu, 50.0);
  EXPECT_DOUBLE_EQ(c.left.cu, 32.0);
  const Eigen::Isometry3d left_T_right = c.LeftTRight();
  EXPECT_NEAR(Eigen::AngleAxisd(left_T_right.linear()).angle(), angle, 1e-12);
  EXPECT_TRUE(left_T_right.translation().isApprox(r.transpose() * Eigen::Vector3d(0.1, 0, 0), 1e-12));
  const StereoImages images = s.ReadImages(s.frames()[0]);
  for (const auto& [u, v] : {std::pair<int, int>{32, 24}, {20, 10}, {40, 30}}) {
    EXPECT_EQ(images.left(v, u), 3 * u);
    EXPECT_EQ(images.right(v, u), 3 * u);
  }
  // The Rectifier's rectified x axis is the baseline, as the CameraInfo's R makes it.
  const Rectifier rectifier(c, RectifierOptions{});
  const Eigen::Vector3d baseline = rectifier.geometry().rectified_R_camera * left_T_right.translation();
  EXPECT_NEAR(baseline.normalized().x(), 1.0, 1e-12);
  EXPECT_NEAR(rectifier.geometry().baseline_m, 0.1, 1e-12);
}

// A distortion model the Rectifier does not take (rational_polynomial with k5 != 0) is
// rectified on read as image_proc does, with a note: the rectified pixel (u, v) shows the raw
// pixel K R^T K^-1 (u, v, 1).
TEST(BagImages, OtherDistortionModelsAreRectifiedWithTheirCameraInfo) {
  testing::TempDir dir;
  const double angle = 0.05;
  const Eigen::Matrix3d r = Eigen::AngleAxisd(angle, Eigen::Vector3d::UnitY()).toRotationMatrix();
  testing::BagContent c = RotatedRawContent(r);
  for (auto* info : {&c.left_info, &c.right_info}) {
    info->distortion_model = "rational_polynomial";
    info->d = {0, 0, 0, 0, 0, 1e-12, 0, 0};
  }
  testing::WriteRos1Bag(c, dir / "raw.bag");
  const Sequence s = Sequence::Open(dir / "raw.bag");
  EXPECT_TRUE(s.calibration().IsRectified());
  EXPECT_DOUBLE_EQ(s.calibration().left.fu, 50.0);
  ASSERT_EQ(s.notes().size(), 3u);  // the assumed mount, this, no poses
  EXPECT_EQ(s.notes()[1], "the 'rational_polynomial' / 'rational_polynomial' distortion is rectified with "
                          "CameraInfo's P as image_proc does, not by SSTA's rectification: "
                          "rectification.crop_to_common_area does not apply");
  const StereoImages images = s.ReadImages(s.frames()[0]);
  const Eigen::Matrix3d k = (Eigen::Matrix3d() << 50, 0, 32, 0, 50, 24, 0, 0, 1).finished();
  for (const auto& [u, v] : {std::pair<int, int>{32, 24}, {20, 10}, {40, 30}}) {
    const Eigen::Vector3d raw = k * r.transpose() * k.inverse() * Eigen::Vector3d(u, v, 1);
    EXPECT_NEAR(images.left(v, u), 3 * raw.x() / raw.z(), 1.5) << u << "," << v;
    EXPECT_EQ(images.right(v, u), 3 * u);  // the right camera's R is identity: unchanged
  }
  // The rectified left camera is the raw one turned by R^T: its optical axis in the body.
  const Eigen::Vector3d axis = s.calibration().left.body_T_camera.linear() * Eigen::Vector3d::UnitZ();
  const Eigen::Vector3d raw_axis = s.calibration().left.body_T_camera.linear() * r * Eigen::Vector3d::UnitZ();
  EXPECT_NEAR(std::acos(axis.dot(raw_axis)), angle, 1e-9);
}

TEST(BagMessages, TruncatedMessagesAreErrorsNamingThem) {
  internal::RosImu imu;
  imu.header = {5, "imu"};
  std::vector<std::uint8_t> bytes(20, 0);
  try {
    internal::DecodeImu(bytes, RosEncoding::kRos1, "x.bag: /imu");
    FAIL();
  } catch (const Error& e) {
    EXPECT_EQ(std::string(e.what()).rfind("x.bag: /imu: message ends early", 0), 0u) << e.what();
  }
  // A string length past the end.
  std::vector<std::uint8_t> header = {0, 0, 0, 0, 1, 0, 0, 0, 0, 0, 0, 0, 0xff, 0xff, 0xff, 0x7f};
  EXPECT_THROW(internal::DecodeHeader(header, RosEncoding::kRos1, "h"), Error);
  // CDR: big-endian encapsulation is refused by name.
  std::vector<std::uint8_t> big = {0, 0, 0, 0, 1, 0, 0, 0};
  try {
    internal::DecodeHeader(big, RosEncoding::kCdr, "h");
    FAIL();
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("is not read (plain little-endian CDR is 00 01"), std::string::npos) << e.what();
  }
}

// A ROS 1 bag cut short has lost the index rosbag reads: the error says it is truncated and how
// rosbag recovers it, with or without allow_truncated (rosbag cannot read it unindexed).
TEST(Ros1Bag, ATruncatedOrMissingBagIsAnErrorNamingIt) {
  testing::TempDir dir;
  EXPECT_THROW(Sequence::Open(dir / "none.bag"), Error);
  testing::WriteRos1Bag(TinyContent(), dir / "whole.bag");
  const std::string bytes = FileBytes(dir / "whole.bag");
  const std::string cut = dir / "cut.bag";
  std::ofstream(cut, std::ios::binary).write(bytes.data(), static_cast<std::streamsize>(bytes.size() / 2));
  for (const bool allow : {false, true}) {
    BagTopics topics;
    topics.allow_truncated = allow;
    try {
      Sequence::Open(cut, topics);
      FAIL();
    } catch (const Error& e) {
      const std::string what = e.what();
      EXPECT_EQ(what.rfind(cut + ": truncated: the file ends at byte " + std::to_string(bytes.size() / 2) +
                               ", before the end of its index (which starts at byte ",
                           0),
                0u)
          << what;
      const std::string tail = "; `rosbag reindex " + cut + "` recovers its complete messages (keeping the original as .orig.bag)";
      EXPECT_EQ(what.substr(what.size() - std::min(what.size(), tail.size())), tail) << what;
    }
  }
}

/// "S.NNNNNNNNN" of a time in ns.
std::string Seconds(std::int64_t ns) {
  char text[32];
  std::snprintf(text, sizeof(text), "%lld.%09lld", static_cast<long long>(ns / 1000000000),
                static_cast<long long>(ns % 1000000000));
  return text;
}

// An MCAP cut mid-chunk (a crash, an interrupted copy), with or without its summary: refused,
// naming the file, where it ends, the last complete message's time and the way to read it
// anyway; allow_truncated reads the frames of its complete chunks, with a warning.
TEST(TruncatedBags, AnMcapCutMidChunkIsRefusedUnlessAllowed) {
  testing::TempDir dir;
  const Sequence asl = Sequence::Open(RenderYard(dir));
  const testing::BagContent content = testing::ContentFromSequence(asl);
  for (const bool summary : {true, false}) {
    SCOPED_TRACE(summary ? "with a chunk index" : "without a summary");
    testing::Ros2BagWriterOptions options;
    options.summary = summary;
    options.chunk_bytes = 50 * 1024;  // a chunk closes after each 320x240 image
    const std::string folder = dir / (summary ? "indexed" : "plain");
    const std::vector<testing::McapChunkSpan> chunks = testing::WriteRos2Bag(content, folder, options);
    ASSERT_GE(chunks.size(), 8u);
    const testing::McapChunkSpan& cut = chunks[7];
    std::filesystem::resize_file(cut.file, cut.offset + cut.length / 2);
    const std::string expected = cut.file + ": truncated: the file ends inside a Chunk record at offset " +
                                 std::to_string(cut.offset) +
                                 ", before the Data End record, the summary and the footer (the recording did not "
                                 "finish); the last complete message was logged at " +
                                 Seconds(chunks[6].last_log_time_ns) + " s";
    for (const std::string& path : {cut.file, folder}) {
      try {
        Sequence::Open(path);
        ADD_FAILURE() << path << " opened";
      } catch (const Error& e) {
        EXPECT_EQ(std::string(e.what()), expected + "; --allow-truncated reads the complete messages");
      }
    }
    BagTopics topics;
    topics.allow_truncated = true;
    const Sequence read = Sequence::Open(cut.file, topics);
    ASSERT_EQ(read.warnings().size(), 1u);
    EXPECT_EQ(read.warnings()[0], expected + ": only the complete messages were read (--allow-truncated)");
    // The frames whose both images lie in the complete chunks, read as the folder's.
    std::size_t complete = 0;
    for (const StereoFrame& f : asl.frames()) complete += f.timestamp_ns < chunks[6].last_log_time_ns ? 1 : 0;
    ASSERT_GE(complete, 2u);
    ASSERT_GE(read.frames().size(), complete);
    ASSERT_LE(read.frames().size(), complete + 1);
    for (std::size_t i = 0; i < read.frames().size(); ++i) {
      EXPECT_EQ(read.frames()[i].timestamp_ns, asl.frames()[i].timestamp_ns);
      EXPECT_EQ(read.ReadImages(read.frames()[i]).right.data()[1000], asl.ReadImages(asl.frames()[i]).right.data()[1000]);
    }
  }
}

// A rosbag2 folder whose files hold fewer messages than its metadata.yaml lists (a split file
// lost, a database's last transactions lost) is truncated too.
TEST(TruncatedBags, ARosbag2FolderHoldingFewerMessagesThanItsMetadataListsIsRefused) {
  testing::TempDir dir;
  const testing::BagContent content = TinyContent();
  const std::string folder = dir / "bag";
  const std::vector<testing::McapChunkSpan> chunks = testing::WriteRos2Bag(content, folder);
  std::size_t held = 0;
  std::int64_t last = 0;
  for (const auto& c : chunks) {
    held += c.messages;
    last = std::max(last, c.last_log_time_ns);
  }
  const std::string yaml_path = folder + "/metadata.yaml";
  std::string yaml = FileBytes(yaml_path);
  const std::string count = "\n  message_count: " + std::to_string(held) + "\n";
  ASSERT_NE(yaml.find(count), std::string::npos) << yaml;
  yaml.replace(yaml.find(count), count.size(), "\n  message_count: " + std::to_string(held + 7) + "\n");
  std::ofstream(yaml_path) << yaml;
  try {
    Sequence::Open(folder);
    FAIL();
  } catch (const Error& e) {
    EXPECT_EQ(std::string(e.what()), folder + ": truncated: metadata.yaml lists " + std::to_string(held + 7) +
                                         " messages, its files hold " + std::to_string(held) +
                                         "; the last complete message was logged at " + Seconds(last) +
                                         " s; --allow-truncated reads the complete messages");
  }
  BagTopics topics;
  topics.allow_truncated = true;
  const Sequence read = Sequence::Open(folder, topics);
  EXPECT_EQ(read.frames().size(), 2u);
  EXPECT_EQ(read.warnings().size(), 1u);
}

// ---------------------------------------------------------------------------------------------
// Real bags recorded by others (tests/data/bags/README.md): topics and counts as recorded, and
// every message of the types SSTA reads decoded by our decoders as ROS's own message classes
// decode it.

struct RealBag {
  const char* file;
  std::map<std::string, std::size_t> counts;  ///< some topics and their message counts
};

std::map<std::string, std::size_t> Counts(const internal::BagReader& bag) {
  std::map<std::string, std::size_t> out;
  for (std::size_t i = 0; i < bag.connections().size(); ++i) out[bag.connections()[i].topic] = bag.List({static_cast<int>(i)}).size();
  return out;
}

/// Decodes every message of the types SSTA reads both ways and compares; returns how many.
int CompareWithRosDecoding(const std::string& path) {
  rosbag::Bag ros(path, rosbag::bagmode::Read);
  rosbag::View view(ros);
  int compared = 0;
  const auto bytes_of = [](const rosbag::MessageInstance& m) {
    std::vector<std::uint8_t> b(m.size());
    ros::serialization::OStream s(b.data(), static_cast<std::uint32_t>(b.size()));
    m.write(s);
    return b;
  };
  for (const rosbag::MessageInstance& m : view) {
    const auto bytes = bytes_of(m);
    const std::string where = path + ": " + m.getTopic();
    if (auto image = m.instantiate<sensor_msgs::Image>()) {
      const internal::RosImage ours = internal::DecodeImage(bytes, RosEncoding::kRos1, where);
      EXPECT_EQ(ours.header.stamp_ns, static_cast<std::int64_t>(image->header.stamp.toNSec()));
      EXPECT_EQ(ours.header.frame_id, image->header.frame_id);
      EXPECT_EQ(ours.width, image->width);
      EXPECT_EQ(ours.encoding, image->encoding);
      EXPECT_EQ(ours.step, image->step);
      EXPECT_EQ(ours.data, image->data);
    } else if (auto info = m.instantiate<sensor_msgs::CameraInfo>()) {
      const internal::RosCameraInfo ours = internal::DecodeCameraInfo(bytes, RosEncoding::kRos1, where);
      EXPECT_EQ(ours.distortion_model, info->distortion_model);
      EXPECT_EQ(ours.d, info->D);
      for (int i = 0; i < 12; ++i) EXPECT_EQ(ours.p[static_cast<std::size_t>(i)], info->P[i]);
      for (int i = 0; i < 9; ++i) EXPECT_EQ(ours.k[static_cast<std::size_t>(i)], info->K[i]);
    } else if (auto compressed = m.instantiate<sensor_msgs::CompressedImage>()) {
      const internal::RosCompressedImage ours = internal::DecodeCompressedImage(bytes, RosEncoding::kRos1, where);
      EXPECT_EQ(ours.format, compressed->format);
      EXPECT_EQ(ours.data, compressed->data);
    } else if (auto imu = m.instantiate<sensor_msgs::Imu>()) {
      const internal::RosImu ours = internal::DecodeImu(bytes, RosEncoding::kRos1, where);
      EXPECT_EQ(ours.linear_acceleration[2], imu->linear_acceleration.z);
      EXPECT_EQ(ours.angular_velocity[0], imu->angular_velocity.x);
      EXPECT_EQ(ours.orientation_xyzw[3], imu->orientation.w);
    } else if (auto odom = m.instantiate<nav_msgs::Odometry>()) {
      const internal::RosOdometry ours = internal::DecodeOdometry(bytes, RosEncoding::kRos1, where);
      EXPECT_EQ(ours.child_frame_id, odom->child_frame_id);
      EXPECT_EQ(ours.position[0], odom->pose.pose.position.x);
      EXPECT_EQ(ours.orientation_xyzw[2], odom->pose.pose.orientation.z);
    } else {
      continue;
    }
    ++compared;
  }
  return compared;
}

TEST(RealBags, TopicsCountsAndEveryMessageDecodeAsRosDecodesThem) {
  const std::vector<RealBag> bags = {
      {"jsk_demos/test-button-light.bag", {{"/wide_stereo/left/image_raw", 19}, {"/wide_stereo/left/camera_info", 292}}},
      {"jsk_pr2eus/pr1040_camera_info.bag",
       {{"/narrow_stereo/left/camera_info", 29}, {"/wide_stereo/right/camera_info", 28}, {"/prosilica/camera_info", 43}}},
      {"librealsense/single_depth_color_640x480.bag",
       {{"/device_0/sensor_0/Depth_0/image/data", 2}, {"/device_0/sensor_1/Color_0/image/data", 1}}},
      {"fiducials/aruco_images.bag", {{"/raspicam_node/image/compressed", 1}, {"/raspicam_node/camera_info", 15}}},
      {"robot_localization/test1.bag", {{"/imu/data", 11865}, {"/husky_velocity_controller/odom", 3952}, {"/fix", 989}}},
  };
  const std::map<std::string, int> decoded = {{"jsk_demos/test-button-light.bag", 19 + 292},
                                              {"jsk_pr2eus/pr1040_camera_info.bag", 295 + 295 + 30 + 29 + 29 + 43 + 29 + 28 + 28},
                                              {"librealsense/single_depth_color_640x480.bag", 2 + 1 + 1 + 1},
                                              {"fiducials/aruco_images.bag", 1 + 15},
                                              {"robot_localization/test1.bag", 11865 + 3952}};
  for (const RealBag& real : bags) {
    const std::string path = kBags + real.file;
    ASSERT_TRUE(IsBagPath(path)) << path;
    const auto bag = internal::OpenBag(path);
    EXPECT_EQ(bag->format(), "ros1");
    const auto counts = Counts(*bag);
    for (const auto& [topic, n] : real.counts) EXPECT_EQ(counts.at(topic), n) << real.file << " " << topic;
    EXPECT_EQ(CompareWithRosDecoding(path), decoded.at(real.file)) << real.file;
  }
}

/// The first message on `topic` of a real bag, as our reader reads it.
std::vector<std::uint8_t> FirstBytes(const internal::BagReader& bag, const std::string& topic) {
  for (std::size_t i = 0; i < bag.connections().size(); ++i) {
    if (bag.connections()[i].topic == topic) return bag.Read(bag.List({static_cast<int>(i)}).front());
  }
  ADD_FAILURE() << topic;
  return {};
}

TEST(RealBags, FirstImagesAndSamples) {
  {  // PR2 wide stereo left camera, Bayer BGGR: demosaiced to grey.
    const auto bag = internal::OpenBag(kBags + "jsk_demos/test-button-light.bag");
    const internal::RosImage m = internal::DecodeImage(FirstBytes(*bag, "/wide_stereo/left/image_raw"), RosEncoding::kRos1, "jsk");
    EXPECT_EQ(m.encoding, "bayer_bggr8");
    const ImageU8 grey = internal::GreyImage(m, "jsk");
    EXPECT_EQ(grey.width(), 640);
    EXPECT_EQ(grey.height(), 480);
    cv::Mat raw(480, 640, CV_8UC1, const_cast<std::uint8_t*>(m.data.data())), expected;
    cv::cvtColor(raw, expected, cv::COLOR_BayerRG2GRAY);  // ROS's BGGR is OpenCV's RG
    EXPECT_EQ(grey(240, 320), expected.at<std::uint8_t>(240, 320));
    EXPECT_EQ(grey(240, 320), 43);
  }
  {  // RealSense: 16-bit depth and an rgb8 colour image (lz4 chunks).
    const auto bag = internal::OpenBag(kBags + "librealsense/single_depth_color_640x480.bag");
    const internal::RosImage depth =
        internal::DecodeImage(FirstBytes(*bag, "/device_0/sensor_0/Depth_0/image/data"), RosEncoding::kRos1, "rs");
    EXPECT_EQ(depth.encoding, "mono16");
    EXPECT_EQ(depth.width, 640u);
    const internal::RosImage colour =
        internal::DecodeImage(FirstBytes(*bag, "/device_0/sensor_1/Color_0/image/data"), RosEncoding::kRos1, "rs");
    EXPECT_EQ(colour.encoding, "rgb8");
    const ImageU8 grey = internal::GreyImage(colour, "rs");
    EXPECT_EQ(grey.height(), 480);
    const std::size_t at = 3 * (240 * 640 + 320);
    EXPECT_NEAR(grey(240, 320), 0.299 * colour.data[at] + 0.587 * colour.data[at + 1] + 0.114 * colour.data[at + 2], 1.0);
  }
  {  // Raspberry Pi camera, JPEG.
    const auto bag = internal::OpenBag(kBags + "fiducials/aruco_images.bag");
    const internal::RosCompressedImage m =
        internal::DecodeCompressedImage(FirstBytes(*bag, "/raspicam_node/image/compressed"), RosEncoding::kRos1, "pi");
    EXPECT_EQ(m.format, "jpg");
    const ImageU8 grey = internal::GreyImage(m, "pi");
    EXPECT_EQ(grey.width(), 1280);
    EXPECT_EQ(grey.height(), 960);
  }
  {  // PR2's stereo calibration: the right camera's P[3] = -fx * baseline.
    const auto bag = internal::OpenBag(kBags + "jsk_pr2eus/pr1040_camera_info.bag");
    const internal::RosCameraInfo right =
        internal::DecodeCameraInfo(FirstBytes(*bag, "/wide_stereo/right/camera_info"), RosEncoding::kRos1, "pr2");
    EXPECT_EQ(right.distortion_model, "plumb_bob");
    EXPECT_NEAR(right.p[3], -34.531, 1e-3);
    EXPECT_NEAR(-right.p[3] / right.p[0], 0.09, 0.01);  // the PR2's wide stereo baseline, about 9 cm
  }
  {  // Clearpath Husky: the first IMU sample at rest reads about +9.8 m/s^2 along its z.
    const auto bag = internal::OpenBag(kBags + "robot_localization/test1.bag");
    const internal::RosImu imu = internal::DecodeImu(FirstBytes(*bag, "/imu/data"), RosEncoding::kRos1, "husky");
    EXPECT_EQ(imu.header.frame_id, "imu_link");
    EXPECT_NEAR(std::hypot(imu.linear_acceleration[0], imu.linear_acceleration[1], imu.linear_acceleration[2]), 9.8, 0.3);
  }
}

TEST(RealBags, BagsWithoutAStereoPairSayWhy) {
  const std::string path = kBags + "robot_localization/test1.bag";
  const BagDescription d = DescribeBag(path);
  EXPECT_NE(d.text.find("/imu/data"), std::string::npos);
  EXPECT_NE(d.text.find("11865"), std::string::npos);
  EXPECT_EQ(d.problem, path + ": the bag has no image topics (sensor_msgs/Image or CompressedImage): it holds no "
                              "camera recording");
  EXPECT_NE(d.text.find("not usable as a stereo sequence: " + d.problem), std::string::npos) << d.text;
}

}  // namespace
}  // namespace ssta
