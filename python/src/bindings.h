#pragma once

// Shared by the translation units of the Python module: argument checks, the exceptions they
// raise, and each unit's Bind function. Conventions (docs/python.md): a bad argument raises ValueError naming it; a
// missing input file FileNotFoundError naming the file; the library's ssta::Error becomes
// ssta.Error (a ValueError) with the message the command line prints.

#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>

#include <cerrno>
#include <cmath>
#include <exception>
#include <filesystem>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

#include <Eigen/Geometry>

#include "ssta/core/error.h"

namespace ssta::python {

namespace py = pybind11;

/// Raised as Python's FileNotFoundError with `filename` set (RegisterErrors translates it).
class MissingFile : public std::runtime_error {
 public:
  MissingFile(const std::string& message, std::string path)
      : std::runtime_error(message), path_(std::move(path)) {}
  const std::string& path() const { return path_; }

 private:
  std::string path_;
};

/// Runs `call` (which reads the input files `paths`); when it throws ssta::Error and one of
/// `paths` does not exist, throws MissingFile with the library's message instead, so Python
/// gets FileNotFoundError with the text the command line prints.
template <class Call>
auto ReportingMissingFiles(const std::vector<std::string>& paths, Call&& call) {
  try {
    return call();
  } catch (const Error& e) {
    for (const std::string& path : paths) {
      std::error_code ec;
      if (!std::filesystem::exists(path, ec)) throw MissingFile(e.what(), path);
    }
    throw;
  }
}

/// A str or os.PathLike as a path; ValueError naming `name` otherwise.
inline std::string PathArg(const py::handle& value, const char* name) {
  if (py::isinstance<py::str>(value) || py::hasattr(value, "__fspath__")) {
    const py::object path = py::module_::import("os").attr("fspath")(value);
    if (py::isinstance<py::str>(path)) return path.cast<std::string>();
  }
  throw py::value_error(std::string(name) + ": expected a path (str or os.PathLike), got " +
                        py::str(py::type::of(value).attr("__name__")).cast<std::string>());
}

/// `value` as a C-contiguous float64 array of shape (N, c) with c in [min_cols, max_cols] and
/// N >= 1; any real numeric dtype is converted. ValueError naming `name` for another shape or
/// dtype (finiteness is checked by the caller, without the GIL: RequireFinite).
inline py::array_t<double, py::array::c_style> MatrixArg(const py::handle& value, const char* name, int min_cols,
                                                         int max_cols) {
  const std::string cols = min_cols == max_cols ? std::to_string(min_cols)
                                                : std::to_string(min_cols) + " or " + std::to_string(max_cols);
  const py::array any = py::array::ensure(value);
  if (!any) throw py::value_error(std::string(name) + ": expected an array of shape (N, " + cols + ")");
  const char kind = any.dtype().kind();
  if (kind != 'f' && kind != 'i' && kind != 'u') {
    throw py::value_error(std::string(name) + ": expected real numbers (float64), got dtype " +
                          py::str(any.dtype()).cast<std::string>());
  }
  std::string shape = "(";
  for (py::ssize_t i = 0; i < any.ndim(); ++i) shape += (i ? ", " : "") + std::to_string(any.shape(i));
  shape += any.ndim() == 1 ? ",)" : ")";
  if (any.ndim() != 2 || any.shape(1) < min_cols || any.shape(1) > max_cols || any.shape(0) < 1) {
    throw py::value_error(std::string(name) + ": expected shape (N, " + cols + ") with N >= 1, got " + shape);
  }
  return py::array_t<double, py::array::c_style | py::array::forcecast>::ensure(any);
}

/// Throws ValueError naming `name` and the first row that holds NaN or infinity. Needs no GIL.
inline void RequireFinite(const double* data, py::ssize_t rows, py::ssize_t cols, const char* name) {
  for (py::ssize_t i = 0; i < rows * cols; ++i) {
    if (!std::isfinite(data[i])) {
      throw py::value_error(std::string(name) + ": row " + std::to_string(i / cols) + " holds NaN or infinity");
    }
  }
}

/// A finite float >= 0 named `name`; ValueError otherwise.
inline double NonNegativeArg(double value, const char* name) {
  if (!(std::isfinite(value) && value >= 0.0)) {
    throw py::value_error(std::string(name) + ": must be a finite number >= 0, got " + std::to_string(value));
  }
  return value;
}

/// ssta.Error (the library's ssta::Error, a ValueError) and the translation of MissingFile into
/// FileNotFoundError, on module `m`.
inline void RegisterErrors(py::module_& m) {
  py::register_exception<Error>(m, "Error", PyExc_ValueError);
  m.attr("Error").attr("__doc__") =
      "Bad input to SSTA (a corrupt file, a bad config value, a calibration that cannot be right): the\n"
      "library's ssta::Error, with the message the command line prints. A subclass of ValueError.";
  py::register_exception_translator([](std::exception_ptr p) {
    try {
      if (p) std::rethrow_exception(p);
    } catch (const MissingFile& e) {
      // FileNotFoundError(errno, strerror, filename), as open() raises it: str() reads
      // "[Errno 2] <the library's reason>: '<file>'", and `filename` names the file.
      std::string reason = e.what();
      if (reason.rfind(e.path() + ": ", 0) == 0) reason.erase(0, e.path().size() + 2);
      const py::object error =
          py::reinterpret_borrow<py::object>(PyExc_FileNotFoundError)(ENOENT, reason, e.path());
      PyErr_SetObject(PyExc_FileNotFoundError, error.ptr());
    }
  });
}

/// `t` as a 4x4 float64 array.
inline py::array_t<double> Matrix4(const Eigen::Isometry3d& t) {
  py::array_t<double> a({4, 4});
  const Eigen::Matrix4d m = t.matrix();
  for (int r = 0; r < 4; ++r) {
    for (int c = 0; c < 4; ++c) a.mutable_at(r, c) = m(r, c);
  }
  return a;
}

void BindMap(py::module_& m);  // map_bindings.cpp

#if !SSTA_PYTHON_MAP_ONLY
}  // namespace ssta::python
namespace ssta {
struct Config;
class Sequence;
}  // namespace ssta
namespace ssta::python {

void BindConfig(py::module_& m);  // config_bindings.cpp
void BindCalibration(py::module_& m);  // frame_bindings.cpp
void BindFrames(py::module_& m);  // frame_bindings.cpp
void BindBuildMap(py::module_& m);  // build_map_bindings.cpp

/// The config LoadLayeredConfig gives, with FileNotFoundError for a missing file
/// (config_bindings.cpp).
std::shared_ptr<Config> LoadConfigFiles(const std::vector<std::string>& files, const Sequence* sequence);
#endif

}  // namespace ssta::python
