// Writes a sequence in the ASL layout (docs/interfaces.md, section 2): what `ssta convert` makes
// of a bag, for tools that want folders.

#include <filesystem>
#include <iomanip>
#include <sstream>

#include "ssta/core/error.h"
#include "ssta/files/file_util.h"
#include "ssta/io/image_io.h"
#include "ssta/io/sequence.h"

namespace fs = std::filesystem;

namespace ssta {
namespace {

std::string MatrixYaml(const Eigen::Matrix4d& m) {
  std::ostringstream out;
  out << std::setprecision(17) << "T_BS:\n  cols: 4\n  rows: 4\n  data: [";
  for (int i = 0; i < 16; ++i) out << (i ? ", " : "") << m(i / 4, i % 4);
  out << "]\n";
  return out.str();
}

/// `text` inside a double-quoted YAML scalar.
std::string YamlEscaped(const std::string& text) {
  std::string out;
  for (const char c : text) {
    if (c == '"' || c == '\\') out += '\\';
    out += c;
  }
  return out;
}

}  // namespace

void WriteAslSequence(const Sequence& sequence, const std::string& out, const std::function<void(int, int)>& progress) {
  if (fs::exists(fs::path(out) / "cam0" / "data.csv")) {
    throw Error(out + ": already holds a sequence (cam0/data.csv); choose a new folder");
  }
  const std::string cam[2] = {out + "/cam0", out + "/cam1"};
  for (const auto& dir : cam) MakeDirectories(dir + "/data");
  const std::string comment = "written by ssta convert from " + sequence.root();
  SaveCameraCalibration(sequence.calibration().left, cam[0] + "/sensor.yaml", comment);
  SaveCameraCalibration(sequence.calibration().right, cam[1] + "/sensor.yaml", comment);

  std::ostringstream list;
  list << "#timestamp [ns],filename\n";
  const int total = static_cast<int>(sequence.frames().size());
  int done = 0;
  for (const StereoFrame& frame : sequence.frames()) {
    const StereoImages images = sequence.ReadImages(frame);
    const std::string name = std::to_string(frame.timestamp_ns) + ".png";
    WriteImage(images.left, cam[0] + "/data/" + name);
    WriteImage(images.right, cam[1] + "/data/" + name);
    list << frame.timestamp_ns << "," << name << "\n";
    if (progress) progress(++done, total);
  }
  if (!sequence.imu().empty()) {
    MakeDirectories(out + "/imu0");
    std::ostringstream csv;
    csv << std::setprecision(17)
        << "#timestamp [ns],w_RS_S_x [rad s^-1],w_RS_S_y [rad s^-1],w_RS_S_z [rad s^-1],a_RS_S_x [m s^-2],"
           "a_RS_S_y [m s^-2],a_RS_S_z [m s^-2]\n";
    for (const ImuSample& s : sequence.imu()) {
      csv << s.timestamp_ns << "," << s.angular_rate.x() << "," << s.angular_rate.y() << "," << s.angular_rate.z() << ","
          << s.specific_force.x() << "," << s.specific_force.y() << "," << s.specific_force.z() << "\n";
    }
    WriteTextAtomically(out + "/imu0/data.csv", csv.str());
    WriteTextAtomically(out + "/imu0/sensor.yaml", "sensor_type: imu\ncomment: \"" + YamlEscaped(comment) + "\"\n" +
                                                        MatrixYaml(sequence.body_T_imu().matrix()));
  }
  if (!sequence.poses().empty()) {
    MakeDirectories(out + "/pose0");
    std::ostringstream csv;
    csv << std::setprecision(17) << "#timestamp [ns],p_x [m],p_y [m],p_z [m],q_w [],q_x [],q_y [],q_z []\n";
    for (const PoseSample& p : sequence.poses()) {
      csv << p.timestamp_ns << "," << p.world_p_body.x() << "," << p.world_p_body.y() << "," << p.world_p_body.z() << ","
          << p.world_q_body.w() << "," << p.world_q_body.x() << "," << p.world_q_body.y() << "," << p.world_q_body.z()
          << "\n";
    }
    WriteTextAtomically(out + "/pose0/data.csv", csv.str());
  }
  // The camera lists go last: a folder whose conversion stopped half-way has no data.csv to be
  // read as a (shorter, or IMU-less) sequence.
  WriteTextAtomically(cam[0] + "/data.csv", list.str());
  WriteTextAtomically(cam[1] + "/data.csv", list.str());

}

}  // namespace ssta
