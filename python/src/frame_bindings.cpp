// ssta.CameraCalibration, ssta.StereoCalibration, ssta.classify and ssta.FramePipeline: one
// rig and the per-frame chain over it.

#include <algorithm>
#include <memory>
#include <mutex>
#include <string>
#include <vector>

#include <pybind11/stl.h>

#include "bindings.h"
#include "ssta/analysis/label_rule.h"
#include "ssta/io/camera_calibration.h"
#include "ssta/pipeline/config.h"
#include "ssta/pipeline/frame_pipeline.h"

namespace ssta::python {
namespace {

Eigen::Isometry3d RigidArg(const py::handle& value, const char* name) {
  const auto a = MatrixArg(value, name, 4, 4);
  if (a.shape(0) != 4) throw py::value_error(std::string(name) + ": expected shape (4, 4)");
  Eigen::Matrix4d m;
  for (int r = 0; r < 4; ++r) {
    for (int c = 0; c < 4; ++c) m(r, c) = a.at(r, c);
  }
  std::string why;
  if (!IsRigidTransform(m, &why)) throw py::value_error(std::string(name) + ": " + why);
  Eigen::Isometry3d t;
  t.matrix() = m;
  return t;
}

CameraCalibration MakeCamera(int width, int height, const py::handle& k_arg, const std::vector<double>& distortion,
                             const py::object& body_T_camera) {
  const auto k = MatrixArg(k_arg, "K", 3, 3);
  if (k.shape(0) != 3) throw py::value_error("K: expected shape (3, 3)");
  if (k.at(0, 1) != 0.0 || k.at(1, 0) != 0.0 || k.at(2, 0) != 0.0 || k.at(2, 1) != 0.0 || k.at(2, 2) != 1.0) {
    throw py::value_error("K: expected [[fu, 0, cu], [0, fv, cv], [0, 0, 1]] (no skew)");
  }
  if (distortion.size() != 4) throw py::value_error("distortion: expected four numbers k1, k2, p1, p2");
  CameraCalibration c;
  c.width = width;
  c.height = height;
  c.fu = k.at(0, 0);
  c.fv = k.at(1, 1);
  c.cu = k.at(0, 2);
  c.cv = k.at(1, 2);
  std::copy(distortion.begin(), distortion.end(), c.distortion.begin());
  if (!body_T_camera.is_none()) c.body_T_camera = RigidArg(body_T_camera, "body_T_camera");
  std::string error;
  if (!c.IsValid(&error)) throw py::value_error(error);
  return c;
}

}  // namespace

void BindCalibration(py::module_& m) {
  py::class_<CameraCalibration>(m, "CameraCalibration", R"doc(
One camera (a `camN/sensor.yaml`): pinhole intrinsics [px] with radial-tangential distortion,
and the camera's pose in the body frame (camera x right, y down, z forward; body x forward,
z up).
)doc")
      .def(py::init(&MakeCamera), py::arg("width"), py::arg("height"), py::arg("K"),
           py::arg("distortion") = std::vector<double>{0, 0, 0, 0}, py::arg("body_T_camera") = py::none(),
           R"doc(
Args:
    width, height: image size [px].
    K: 3 x 3 camera matrix [[fu, 0, cu], [0, fv, cv], [0, 0, 1]] [px].
    distortion: k1, k2, p1, p2.
    body_T_camera: 4 x 4 rigid transform from camera to body coordinates; None: identity.
Raises ValueError naming the argument or key (as sensor.yaml's checks) for a bad value.
)doc")
      .def_static(
          "load",
          [](const py::object& path) {
            const std::string p = PathArg(path, "path");
            return ReportingMissingFiles({p}, [&] { return LoadCameraCalibration(p); });
          },
          py::arg("path"), "Reads a sensor.yaml; FileNotFoundError / ssta.Error naming the file and key.")
      .def_readonly("width", &CameraCalibration::width)
      .def_readonly("height", &CameraCalibration::height)
      .def_property_readonly("K",
                             [](const CameraCalibration& c) {
                               py::array_t<double> k({3, 3});
                               const double v[9] = {c.fu, 0, c.cu, 0, c.fv, c.cv, 0, 0, 1};
                               std::memcpy(k.mutable_data(), v, sizeof(v));
                               return k;
                             },
                             "3 x 3 camera matrix [px].")
      .def_property_readonly("distortion", [](const CameraCalibration& c) { return c.distortion; },
                             "k1, k2, p1, p2.")
      .def_property_readonly("body_T_camera", [](const CameraCalibration& c) { return Matrix4(c.body_T_camera); },
                             "4 x 4: camera coordinates into body coordinates [m].");

  py::class_<StereoCalibration>(m, "StereoCalibration", "The left (cam0) and right (cam1) cameras of a rig.")
      .def(py::init([](const CameraCalibration& left, const CameraCalibration& right) {
             StereoCalibration s{left, right};
             std::string error;
             if (!s.IsValid(&error)) throw py::value_error(error);
             return s;
           }),
           py::arg("left"), py::arg("right"),
           "Raises ValueError when the pair cannot be a rig (sizes differ, no baseline along x).")
      .def_static(
          "load",
          [](const py::object& cam0, const py::object& cam1) {
            const std::string p0 = PathArg(cam0, "cam0_yaml"), p1 = PathArg(cam1, "cam1_yaml");
            return ReportingMissingFiles({p0, p1}, [&] { return LoadStereoCalibration(p0, p1); });
          },
          py::arg("cam0_yaml"), py::arg("cam1_yaml"),
          "Reads the two sensor.yaml files (as `ssta classify --calib0 --calib1`); FileNotFoundError /\n"
          "ssta.Error naming the file and key.")
      .def_readonly("left", &StereoCalibration::left)
      .def_readonly("right", &StereoCalibration::right)
      .def_property_readonly("is_rectified", &StereoCalibration::IsRectified,
                             "Identical intrinsics, no distortion, baseline along camera x: used as is.");
}

struct SegmentRow {
  std::int32_t id, inliers;
  double centroid[3], normal[3], plane[4];
  double rms_m, slope_deg, step_m;
  bool has_plane, small, ground;
  std::uint8_t slope_class, step_class, cls;
};

// An 8-bit grey image from a uint8 H x W (grey) or H x W x 3 (RGB) array; ValueError naming
// `name` otherwise. Colour becomes grey as OpenCV's RGB2GRAY does (0.299 R + 0.587 G + 0.114 B
// in 14-bit fixed point), which is what `ssta classify` gets from a colour file.
namespace {

ImageU8 GreyArg(const py::handle& value, const char* name) {
  const py::array any = py::array::ensure(value);
  if (!any || any.dtype().kind() != 'u' || any.itemsize() != 1) {
    throw py::value_error(std::string(name) + ": expected a uint8 image, got " +
                          (any ? "dtype " + py::str(any.dtype()).cast<std::string>() : std::string("no array")));
  }
  const bool colour = any.ndim() == 3 && any.shape(2) == 3;
  if (!(any.ndim() == 2 || colour) || any.shape(0) < 1 || any.shape(1) < 1) {
    std::string shape;
    for (py::ssize_t i = 0; i < any.ndim(); ++i) shape += (i ? ", " : "") + std::to_string(any.shape(i));
    throw py::value_error(std::string(name) + ": expected shape (H, W) grey or (H, W, 3) RGB, got (" + shape + ")");
  }
  const auto a = py::array_t<std::uint8_t, py::array::c_style | py::array::forcecast>::ensure(any);
  const int h = static_cast<int>(a.shape(0)), w = static_cast<int>(a.shape(1));
  ImageU8 image(w, h);
  const std::uint8_t* src = a.data();
  if (!colour) {
    std::memcpy(image.data(), src, image.size());
  } else {
    for (std::size_t i = 0; i < image.size(); ++i) {
      const std::uint8_t* p = src + 3 * i;
      image[i] = static_cast<std::uint8_t>((p[0] * 4899 + p[1] * 9617 + p[2] * 1868 + (1 << 13)) >> 14);
    }
  }
  return image;
}

py::dict FrameDict(const FrameResult& r) {
  const auto image = [](const auto& im) {
    using T = std::decay_t<decltype(im[0])>;
    py::array_t<T> a({static_cast<py::ssize_t>(im.height()), static_cast<py::ssize_t>(im.width())});
    if (im.size() > 0) std::memcpy(a.mutable_data(), im.data(), im.size() * sizeof(T));
    return a;
  };
  const AnalysisResult& analysis = r.analysis;
  py::array_t<SegmentRow> segments(static_cast<py::ssize_t>(analysis.segments.size()));
  SegmentRow* rows = segments.mutable_data();
  py::list reasons;
  for (std::size_t i = 0; i < analysis.segments.size(); ++i) {
    const SegmentResult& s = analysis.segments[i];
    SegmentRow& row = rows[i];
    row.id = s.id;
    row.inliers = s.inliers;
    for (int k = 0; k < 3; ++k) row.centroid[k] = s.centroid[k], row.normal[k] = s.normal[k];
    for (int k = 0; k < 4; ++k) row.plane[k] = s.plane[k];
    row.rms_m = s.rms_m;
    row.slope_deg = s.slope_deg;
    row.step_m = s.step_m;
    row.has_plane = s.has_plane;
    row.small = s.small;
    row.ground = s.ground;
    row.slope_class = static_cast<std::uint8_t>(s.slope_class);
    row.step_class = static_cast<std::uint8_t>(s.step_class);
    row.cls = static_cast<std::uint8_t>(s.verdict);
    reasons.append(s.reason);
  }
  const GroundPlane& g = analysis.ground;
  py::dict ground;
  ground["found"] = g.found;
  ground["segment_id"] = g.segment_id;
  ground["plane"] = py::make_tuple(g.plane[0], g.plane[1], g.plane[2], g.plane[3]);
  ground["camera_height_m"] = g.camera_height_m;
  ground["surface_class"] = static_cast<int>(g.surface_class);
  ground["rms_m"] = g.rms_m;
  ground["share"] = g.share;
  py::dict quality;
  quality["passed"] = analysis.quality.passed;
  quality["judged"] = analysis.quality.judged;
  quality["reason"] = analysis.quality.reason;
  const StageTimings& t = r.timings;
  py::dict timings;
  timings["rectify"] = t.rectify_ms;
  timings["match"] = t.match_ms;
  timings["triangulate"] = t.triangulate_ms;
  timings["normals"] = t.normals_ms;
  timings["segment"] = t.segment_ms;
  timings["analyze"] = t.analyze_ms;
  timings["total"] = t.total_ms;

  py::dict out;
  out["labels"] = image(r.labels);
  out["rules"] = image(r.rules);
  out["disparity"] = image(r.disparity);
  out["segment_ids"] = image(r.segment_ids);
  out["segments"] = segments;
  out["segment_reasons"] = reasons;
  out["ground_plane"] = ground;
  out["quality"] = quality;
  out["up_rectified"] = py::make_tuple(r.up_rectified.x(), r.up_rectified.y(), r.up_rectified.z());
  out["timings_ms"] = timings;
  return out;
}

// A FramePipeline for Python: its buffers are reused between frames, so calls from several
// threads take turns (one pipeline per thread runs them in parallel).
class PythonPipeline {
 public:
  PythonPipeline(const StereoCalibration& calibration, const std::shared_ptr<Config>& config)
      : pipeline_(calibration, config ? *config : Config{}) {}

  py::dict Classify(const py::object& left_arg, const py::object& right_arg, const py::object& up_arg) {
    const ImageU8 left = GreyArg(left_arg, "left"), right = GreyArg(right_arg, "right");
    Eigen::Vector3d up = pipeline_.UpInCamera(Eigen::Vector3d::UnitZ());
    if (!up_arg.is_none()) {
      const auto a = py::array_t<double, py::array::forcecast>::ensure(up_arg);
      if (!a || a.size() != 3) throw py::value_error("up: expected three numbers (x, y, z) in cam0");
      up = Eigen::Vector3d(a.data()[0], a.data()[1], a.data()[2]);
      if (!up.allFinite() || up.norm() < 1e-9) throw py::value_error("up: must be a finite, non-zero vector");
    }
    FrameResult result;
    {
      py::gil_scoped_release release;
      const std::lock_guard<std::mutex> lock(mutex_);
      result = pipeline_.Process(left, right, up.normalized());
    }
    return FrameDict(result);
  }

 private:
  std::mutex mutex_;
  FramePipeline pipeline_;
};

const char* kClassifyDoc = R"doc(
Classifies one raw stereo pair, as `ssta classify --left --right --calib0 --calib1`.

Args:
    left, right: uint8 images, H x W grey or H x W x 3 RGB (colour is made grey as OpenCV's
        RGB2GRAY; flip a BGR image with img[..., ::-1]), of the calibration's size.
    up: the up direction in cam0 (x right, y down, z forward); None: a level body through
        cam0's body_T_camera, as the command line without --up.

Returns a dict:
    labels: uint8 class ids at the rectified image size (0 outside the common area);
    rules: uint8 id of the rule that set each label, at the labels' size (ssta.LABEL_RULES
        names them; docs/interfaces.md);
    disparity: float32 [px] of the rectified common area, 0 invalid;
    segment_ids: int32 segment id per pixel of the common area, -1 none;
    segments: a structured array, one row per segment id: id, inliers [px], centroid,
        normal (3 each) and plane (A, B, C, D) in the rectified cam0 frame [m], rms_m,
        slope_deg, step_m (NaN without a ground plane), has_plane, small, ground,
        slope_class, step_class and class (the verdict its pixels get before the label
        refinements);
    segment_reasons: why each segment got its class (list of str);
    ground_plane: {found, segment_id, plane, camera_height_m, surface_class, rms_m, share};
    quality: {passed, judged, reason} of the point cloud quality check (judged: the frame got
        verdicts, as it does under the local rule when only the plane's share failed);
    up_rectified: up in the rectified cam0 frame; timings_ms: per stage.

Raises ValueError naming `left`, `right` or `up`, and ssta.Error for images of another size
than the calibration's.
)doc";

}  // namespace

void BindFrames(py::module_& m) {
  PYBIND11_NUMPY_DTYPE_EX(SegmentRow, id, "id", inliers, "inliers", centroid, "centroid", normal, "normal", plane,
                          "plane", rms_m, "rms_m", slope_deg, "slope_deg", step_m, "step_m", has_plane, "has_plane",
                          small, "small", ground, "ground", slope_class, "slope_class", step_class, "step_class", cls,
                          "class");
  py::class_<PythonPipeline>(m, "FramePipeline", R"doc(
The per-frame chain (rectify, match, triangulate, normals, segments, SSTA) for one rig and
config, built once and reused frame after frame: faster than ssta.classify for a stream of
frames. Calls on one pipeline from several threads take turns; use one per thread to run them
in parallel.
)doc")
      .def(py::init([](const StereoCalibration& calibration, const std::shared_ptr<Config>& config) {
             return std::make_unique<PythonPipeline>(calibration, config);
           }),
           py::arg("calibration"), py::arg("config") = py::none(),
           "Raises ssta.Error naming the key of an invalid config or calibration.")
      .def("classify", &PythonPipeline::Classify, py::arg("left"), py::arg("right"), py::kw_only(),
           py::arg("up") = py::none(), kClassifyDoc);
  m.def(
      "classify",
      [](const py::object& left, const py::object& right, const StereoCalibration& calibration,
         const std::shared_ptr<Config>& config, const py::object& up) {
        PythonPipeline pipeline(calibration, config);
        return pipeline.Classify(left, right, up);
      },
      py::arg("left"), py::arg("right"), py::arg("calibration"), py::arg("config") = py::none(), py::kw_only(),
      py::arg("up") = py::none(),
      (std::string(kClassifyDoc) + "\nconfig: a Config; None: the defaults. Builds a FramePipeline per call.").c_str());
}

}  // namespace ssta::python
