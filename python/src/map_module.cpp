// The Python module of a map-only build (cmake -DSSTA_MAP_ONLY=ON): ssta.Map and ssta.Error
// over ssta::map, with none of the frames, configs and builds that the full module binds.

#include "bindings.h"

PYBIND11_MODULE(_ssta, m) {
  using namespace ssta::python;
  m.doc() = "SSTA: stereo traversability maps for ground robots (the C++ library's Python binding, maps only).";
  m.attr("__version__") = SSTA_VERSION;
  m.attr("MAP_ONLY") = true;
  RegisterErrors(m);
  BindMap(m);
}
