// The module `ssta._ssta` (re-exported by the package `ssta`): errors, Config, calibrations,
// the per-frame classifier and build_map; Map lives in map_bindings.cpp.

#include <Python.h>

#include <array>
#include <atomic>
#include <cerrno>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <mutex>
#include <optional>
#include <string>
#include <vector>

#include <pybind11/stl.h>

#include "bindings.h"
#include "ssta/analysis/label_rule.h"
#include "ssta/io/camera_calibration.h"
#include "ssta/files/file_util.h"
#include "ssta/io/sequence.h"
#include "ssta/pipeline/config.h"
#include "ssta/pipeline/frame_pipeline.h"
#include "ssta/pipeline/map_builder.h"

namespace ssta::python {
namespace {

// ---------------------------------------------------------------------------------------------
// Config: sections as attributes, each key read and written through its OptionField, so the
// values, kinds and checks are the YAML reader's own.

// Every section of a Config in file order, as config.cpp lists them (a test compares this list
// with the sections of ConfigToYaml, so a new section cannot be left out here).
template <class Visit>
void ForEachSection(Config& c, Visit&& visit) {
  visit("vehicle", c.vehicle);
  visit("rectification", c.rectification);
  visit("stereo", c.stereo);
  visit("triangulation", c.triangulation);
  visit("normals", c.normals);
  visit("segmentation", c.segmentation);
  visit("analysis", c.analysis);
  visit("gravity", c.gravity);
  visit("attitude", c.attitude);
  visit("map", c.map);
  visit("refinement", c.refinement);
}

std::vector<std::string> SectionNames() {
  Config c;
  std::vector<std::string> names;
  ForEachSection(c, [&](const char* name, auto&) { names.push_back(name); });
  return names;
}

py::object ToPython(const OptionValue& value, OptionKind kind) {
  if (const double* d = std::get_if<double>(&value)) {
    return kind == OptionKind::kInteger ? py::object(py::int_(static_cast<long long>(*d))) : py::object(py::float_(*d));
  }
  if (const bool* b = std::get_if<bool>(&value)) return py::bool_(*b);
  if (const std::string* s = std::get_if<std::string>(&value)) return py::str(*s);
  const Eigen::Vector3d& v = std::get<Eigen::Vector3d>(value);
  return py::make_tuple(v.x(), v.y(), v.z());
}

// `value` as the kind of field `key`; ValueError naming the key for a value of another type.
template <class O>
OptionValue FromPython(const OptionField<O>& f, const std::string& key, const py::handle& value) {
  const auto fail = [&](const std::string& what) {
    throw py::value_error(key + ": must be " + what + ", got " + py::repr(value).cast<std::string>());
  };
  const bool is_bool = py::isinstance<py::bool_>(value);
  switch (f.kind) {
    case OptionKind::kReal:
      if (is_bool || !(py::isinstance<py::int_>(value) || py::isinstance<py::float_>(value))) fail("a number");
      return value.cast<double>();
    case OptionKind::kInteger:
      if (is_bool || !py::isinstance<py::int_>(value)) fail("a whole number (int)");
      return static_cast<double>(value.cast<long long>());
    case OptionKind::kFlag:
      if (!is_bool) fail("True or False");
      return value.cast<bool>();
    case OptionKind::kChoice: {
      std::string names;
      for (const std::string& c : f.choices) names += (names.empty() ? "" : ", ") + c;
      if (!py::isinstance<py::str>(value)) fail("one of " + names);
      const std::string s = value.cast<std::string>();
      if (std::find(f.choices.begin(), f.choices.end(), s) == f.choices.end()) fail("one of " + names);
      return s;
    }
    case OptionKind::kVector3: {
      const auto a = py::array_t<double, py::array::forcecast>::ensure(value);
      if (!a || a.size() != 3) fail("three numbers [x, y, z]");
      return Eigen::Vector3d(a.data()[0], a.data()[1], a.data()[2]);
    }
  }
  fail("a value");
  return {};
}

// One section of a shared Config, e.g. `config.vehicle`.
struct Section {
  std::shared_ptr<Config> config;
  std::string name;

  // Calls visit(options) with this section's options struct.
  template <class Visit>
  void With(Visit&& visit) const {
    ForEachSection(*config, [&](const char* n, auto& options) {
      if (name == n) visit(options);
    });
  }

  template <class O>
  static const OptionField<O>* Find(const std::string& key) {
    for (const OptionField<O>& f : O::Fields()) {
      if (f.key == key) return &f;
    }
    return nullptr;
  }

  [[noreturn]] void Unknown(const std::string& key) const {
    std::string keys;
    for (const std::string& k : Keys()) keys += (keys.empty() ? "" : ", ") + k;
    throw py::attribute_error(name + "." + key + ": unknown key (" + name + " has " + keys + ")");
  }

  std::vector<std::string> Keys() const {
    std::vector<std::string> keys;
    With([&](auto& options) {
      for (const auto& f : std::decay_t<decltype(options)>::Fields()) keys.push_back(f.key);
    });
    return keys;
  }

  py::object Get(const std::string& key) const {
    py::object out;
    With([&](auto& options) {
      using O = std::decay_t<decltype(options)>;
      if (const OptionField<O>* f = Find<O>(key)) out = ToPython(f->get(options), f->kind);
    });
    if (!out) Unknown(key);
    return out;
  }

  // Sets one key, checked as a config file's value is: its type, then its requirements (range,
  // and limits set by other keys of the section). A failed check leaves the section as it was.
  void Set(const std::string& key, const py::handle& value) const {
    bool found = false;
    With([&](auto& options) {
      using O = std::decay_t<decltype(options)>;
      const OptionField<O>* f = Find<O>(key);
      if (!f) return;
      found = true;
      const std::string full_key = name + "." + key;
      O changed = options;
      f->set(&changed, FromPython(*f, full_key, value));
      for (const auto& [ok, message] : f->requirements) {
        if (!ok(changed)) throw py::value_error(full_key + ": " + message(changed));
      }
      options = changed;
    });
    if (!found) Unknown(key);
  }

  py::dict Dict() const {
    py::dict out;
    for (const std::string& k : Keys()) out[k.c_str()] = Get(k);
    return out;
  }
};

std::shared_ptr<Config> LoadConfigFiles(const std::vector<std::string>& files, const Sequence* sequence) {
  auto config = std::make_shared<Config>();
  if (sequence && sequence->vehicle_config()) ApplyConfigFile(*sequence->vehicle_config(), config.get());
  for (const std::string& file : files) {
    ReportingMissingFiles({file}, [&] { ApplyConfigFile(file, config.get()); });
  }
  return config;
}

std::vector<std::string> PathsArg(const py::args& args, const char* name) {
  std::vector<std::string> paths;
  for (const py::handle& a : args) paths.push_back(PathArg(a, name));
  return paths;
}

void BindConfig(py::module_& m) {
  py::class_<Section>(m, "ConfigSection", R"doc(
One section of a Config (e.g. `config.vehicle`): its keys as attributes, with the units and
ranges of config/default.yaml. Setting a key checks it as a config file's value is checked (its
type, its range, limits set by other keys of the section); a failed check raises ValueError
naming the key and leaves the value as it was. An unknown key raises AttributeError.
)doc")
      .def("__getattr__", &Section::Get, py::arg("key"))
      .def("__setattr__", &Section::Set, py::arg("key"), py::arg("value"))
      .def("__dir__", &Section::Keys)
      .def("keys", &Section::Keys, "The section's keys in file order.")
      .def("to_dict", &Section::Dict, "The section as {key: value}.")
      .def("__repr__", [](const Section& s) { return "<ssta.ConfigSection " + s.name + ": " +
                                                     py::repr(s.Dict()).cast<std::string>() + ">"; });

  py::class_<Config, std::shared_ptr<Config>> config(m, "Config", R"doc(
Every setting of SSTA (config/default.yaml): one section per pipeline stage, readable and
editable as attributes (`config.vehicle.max_slope_deg = 20.0`, degrees and metres as the key
names say), written back as YAML by to_yaml() and save().

A Config() holds the defaults; Config.load(*files) reads config files over them as `--config`
does on the command line, with the same checks and messages.
)doc");
  config.def(py::init<>(), "The defaults (config/default.yaml).")
      .def_static(
          "load",
          [](const py::args& files) { return LoadConfigFiles(PathsArg(files, "files"), nullptr); },
          R"doc(
The defaults with each YAML file applied in turn (later files win), as `--config A --config B`.

Raises FileNotFoundError naming a missing file, and ssta.Error naming the file and key for an
unknown section or key, a wrong type or a value out of range (the command line's message).
)doc")
      .def("to_yaml", [](const Config& c) { return ConfigToYaml(c); },
           "Every key as YAML text, which Config.load reads back exactly.")
      .def(
          "save",
          [](const Config& c, const py::object& path) {
            const std::string p = PathArg(path, "path");
            py::gil_scoped_release release;
            WriteTextAtomically(p, ConfigToYaml(c));
          },
          py::arg("path"), "Writes to_yaml() to `path` atomically; ssta.Error naming it when it cannot.")
      .def("to_dict",
           [](const std::shared_ptr<Config>& c) {
             py::dict out;
             for (const std::string& name : SectionNames()) out[name.c_str()] = Section{c, name}.Dict();
             return out;
           },
           "Every section as {section: {key: value}}.")
      .def("sections", [](const Config&) { return SectionNames(); }, "The section names in file order.")
      .def("copy", [](const Config& c) { return std::make_shared<Config>(c); }, "An independent copy.")
      .def("__repr__", [](const Config&) { return std::string("<ssta.Config; to_yaml() prints it>"); });
  for (const std::string& name : SectionNames()) {
    config.def_property_readonly(
        name.c_str(), [name](const std::shared_ptr<Config>& c) { return Section{c, name}; },
        ("The `" + name + "` section (a ConfigSection).").c_str());
  }
}

// ---------------------------------------------------------------------------------------------
// Calibration

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

py::array_t<double> Matrix4(const Eigen::Isometry3d& t) {
  py::array_t<double> a({4, 4});
  for (int r = 0; r < 4; ++r) {
    for (int c = 0; c < 4; ++c) a.mutable_at(r, c) = t.matrix()(r, c);
  }
  return a;
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

// ---------------------------------------------------------------------------------------------
// Frames

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
    quality: {passed, reason} of the point cloud quality check;
    up_rectified: up in the rectified cam0 frame; timings_ms: per stage.

Raises ValueError naming `left`, `right` or `up`, and ssta.Error for images of another size
than the calibration's.
)doc";

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

// ---------------------------------------------------------------------------------------------
// build_map

py::dict BuildMapPython(const py::object& sequence_arg, const py::object& map_arg, const py::object& config_arg,
                        const py::object& progress, bool resume, bool static_platform, int max_frames, int every,
                        bool strict, bool sequential, bool refine, bool oracle_disparity, bool oracle_labels,
                        bool allow_overlap) {
  const std::string sequence_path = PathArg(sequence_arg, "sequence");
  const std::string map_path = PathArg(map_arg, "map_path");
  BuildMapOptions options;
  options.map_path = map_path;
  options.resume = resume;
  options.allow_overlap = allow_overlap;
  options.static_platform = static_platform;
  options.frames.max_frames = max_frames;
  options.frames.every = every;
  options.frames.strict = strict;
  options.pipelined = !sequential;
  options.oracles.disparity = oracle_disparity;
  options.oracles.labels = oracle_labels;
  std::string error;
  if (!options.IsValid(&error)) throw py::value_error(error);
  // The checks `build-map --map` makes while parsing: before any work.
  std::error_code ec;
  if (std::filesystem::is_directory(map_path, ec)) throw py::value_error("map_path: " + map_path + " is a folder");
  if (const std::string problem = ParentFolderProblem(map_path); !problem.empty()) {
    const std::string folder = std::filesystem::path(map_path).parent_path().string();
    if (!std::filesystem::exists(folder, ec)) throw MissingFile(map_path + ": " + problem, folder);
    throw py::value_error("map_path: " + map_path + ": " + problem);
  }
  if (!progress.is_none() && !PyCallable_Check(progress.ptr())) {
    throw py::value_error("progress: expected a callable progress(done, total) or None");
  }

  const Sequence sequence = ReportingMissingFiles({sequence_path}, [&] {
    py::gil_scoped_release release;
    return Sequence::Open(sequence_path);
  });
  // As the command line layers them: defaults, the sequence's vehicle.yaml, the files given. A
  // Config object is taken as it is.
  std::shared_ptr<Config> config;
  if (config_arg.is_none()) {
    config = LoadConfigFiles({}, &sequence);
  } else if (py::isinstance<Config>(config_arg)) {
    config = std::make_shared<Config>(config_arg.cast<const Config&>());
  } else if (py::isinstance<py::str>(config_arg) || py::hasattr(config_arg, "__fspath__")) {
    config = LoadConfigFiles({PathArg(config_arg, "config")}, &sequence);
  } else if (py::isinstance<py::list>(config_arg) || py::isinstance<py::tuple>(config_arg)) {
    std::vector<std::string> files;
    for (const py::handle& f : config_arg) files.push_back(PathArg(f, "config"));
    config = LoadConfigFiles(files, &sequence);
  } else {
    throw py::value_error("config: expected None, an ssta.Config, a config file path or a list of them");
  }
  if (refine) config->refinement.online = true;

  const bool map_existed = std::filesystem::exists(map_path, ec);
  const std::string name = std::filesystem::path(sequence_path).lexically_normal().filename().string();

  // Ctrl-C: Python's handler only notes the signal; the progress callback, run on this thread
  // after every frame, lets Python raise KeyboardInterrupt and asks the build to stop after the
  // current frame. The map is then saved, and the KeyboardInterrupt raised once BuildMap returns,
  // as `ssta build-map` stops on SIGINT. An exception from `progress` stops it the same way.
  std::atomic<bool> stop{false};
  std::optional<py::error_already_set> raised;
  const Progress on_frame = [&](int done, int total) {
    py::gil_scoped_acquire acquire;
    if (raised) return;
    try {
      if (!progress.is_none()) progress(done, total);
      if (PyErr_CheckSignals() != 0) throw py::error_already_set();
    } catch (py::error_already_set& e) {
      raised.emplace(std::move(e));
      stop = true;
    }
  };
  BuildMapSummary summary;
  {
    py::gil_scoped_release release;
    summary = BuildMap(sequence, name.empty() ? sequence_path : name, *config, options, on_frame, &stop);
  }
  if (raised) {
    raised->restore();
    throw py::error_already_set();
  }
  const bool fused = summary.frames_used > 0 || summary.frames_already_in_map > 0;
  if (!fused) {
    throw Error(sequence_path + ": no frame could be fused; " + map_path +
                (map_existed ? " was left as it was" : " was not written"));
  }
  py::dict out = py::module_::import("json").attr("loads")(summary.Json());
  out["map_path"] = map_path;
  return out;
}

const char* kBuildMapDoc = R"doc(
Classifies every usable frame of a sequence and fuses it into the map at `map_path`, as
`ssta build-map --sequence SEQ --map MAP`; returns the run's summary as a dict (the fields of
`build-map --json`: frames listed, used, skipped with their reasons, map size, wall time, ...).

Args:
    sequence: an ASL / EuRoC sequence folder, a KITTI raw drive, or a ROS 1 / ROS 2 bag (topics
        found automatically, docs/bags.md).
    map_path: the .ot file to write (its folder must exist). Written atomically and
        checkpointed (config map.checkpoint_every_frames).
    config: None (the defaults and the sequence's vehicle.yaml, as the command line without
        --config), a config file path or a list of them (over the same, as --config), or a
        Config (taken as it is: load the sequence's vehicle.yaml into it yourself).
    progress: None or progress(done, total), called after every frame on the calling thread.
    resume, static_platform, max_frames, every, strict, sequential, refine, oracle_disparity,
        oracle_labels, allow_overlap: the options --resume, --static, --max-frames, --every,
        --strict, --sequential, --refine, --oracle-disparity, --oracle-labels and
        --allow-overlap.

Ctrl-C (KeyboardInterrupt) stops the run after the current frame: the map is saved with the
frames fused so far (continue with resume=True) and KeyboardInterrupt is raised. An exception
raised by `progress` stops it the same way and is raised. The GIL is released while it runs.

Raises FileNotFoundError naming a missing sequence, config file or map folder; ValueError
naming a bad argument; ssta.Error with the command line's message for bad input, when no
frame could be fused, when another process (or thread) is writing the same map ("MAP: another
process is writing this map (pid N: COMMAND) ..."; one writer per map: the lock is held for the
whole call), and with resume=True when the map already holds frames of the sequence (same time
and image; allow_overlap=True fuses them anyway).
)doc";

}  // namespace

}  // namespace ssta::python

PYBIND11_MODULE(_ssta, m) {
  namespace py = pybind11;
  using namespace ssta::python;
  m.doc() = "SSTA: stereo traversability maps for ground robots (the C++ library's Python binding).";
  m.attr("__version__") = SSTA_VERSION;
  {
    py::list names;  // index = the rule id of classify's "rules"
    for (const ssta::LabelRuleInfo& info : ssta::LabelRules()) names.append(std::string(info.name));
    m.attr("LABEL_RULES") = py::tuple(names);
  }

  RegisterErrors(m);
  m.attr("MAP_ONLY") = false;

  BindConfig(m);
  BindCalibration(m);
  BindFrames(m);
  BindMap(m);
  m.def("build_map", &BuildMapPython, py::arg("sequence"), py::arg("map_path"), py::arg("config") = py::none(),
        py::arg("progress") = py::none(), py::kw_only(), py::arg("resume") = false,
        py::arg("static_platform") = false, py::arg("max_frames") = 0, py::arg("every") = 1,
        py::arg("strict") = false, py::arg("sequential") = false, py::arg("refine") = false,
        py::arg("oracle_disparity") = false, py::arg("oracle_labels") = false, py::arg("allow_overlap") = false,
        kBuildMapDoc);
}
