// The module `ssta._ssta` (re-exported by the package `ssta`): errors, Config
// (config_bindings.cpp), calibrations and the per-frame classifier (frame_bindings.cpp),
// build_map (build_map_bindings.cpp) and Map (map_bindings.cpp).

#include <string>

#include "bindings.h"
#include "ssta/analysis/label_rule.h"

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
  BindBuildMap(m);
}
