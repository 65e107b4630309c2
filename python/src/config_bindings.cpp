// ssta.Config and ssta.ConfigSection: every setting, section by section, each key read and
// written through its OptionField, so the values, kinds and checks are the YAML reader's own.

#include <algorithm>
#include <memory>
#include <string>
#include <vector>

#include <pybind11/stl.h>

#include "bindings.h"
#include "ssta/files/file_util.h"
#include "ssta/io/sequence.h"
#include "ssta/pipeline/config.h"

namespace ssta::python {
namespace {

std::vector<std::string> SectionNames() {
  Config c;
  std::vector<std::string> names;
  ForEachConfigSection(c, [&](const char* name, const char*, auto&) { names.push_back(name); });
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
    ForEachConfigSection(*config, [&](const char* n, const char*, auto& options) {
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

std::vector<std::string> PathsArg(const py::args& args, const char* name) {
  std::vector<std::string> paths;
  for (const py::handle& a : args) paths.push_back(PathArg(a, name));
  return paths;
}

}  // namespace

std::shared_ptr<Config> LoadConfigFiles(const std::vector<std::string>& files, const Sequence* sequence) {
  return ReportingMissingFiles(files, [&] { return std::make_shared<Config>(LoadLayeredConfig(sequence, files)); });
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

}  // namespace ssta::python
