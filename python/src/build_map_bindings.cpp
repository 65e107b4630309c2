// ssta.build_map: `ssta build-map` from Python, with its progress, Ctrl-C and errors.

#include <Python.h>

#include <atomic>
#include <filesystem>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include <pybind11/stl.h>

#include "bindings.h"
#include "ssta/files/file_util.h"
#include "ssta/io/sequence.h"
#include "ssta/pipeline/config.h"
#include "ssta/pipeline/map_builder.h"

namespace ssta::python {
namespace {

// The check `build-map --map` makes while parsing, before any work: FileNotFoundError for a
// missing folder, ValueError for a path that cannot be written.
void CheckMapPath(const std::string& map_path) {
  const std::string problem = OutputFileProblem(map_path);
  if (problem.empty()) return;
  const std::string folder = std::filesystem::path(map_path).parent_path().string();
  std::error_code ec;
  if (!folder.empty() && !std::filesystem::exists(folder, ec)) throw MissingFile(map_path + ": " + problem, folder);
  throw py::value_error("map_path: " + map_path + ": " + problem);
}

// The config of build_map's `config` argument, layered as the command line layers it:
// defaults, the sequence's vehicle.yaml, the files given. A Config object is taken as it is.
std::shared_ptr<Config> ConfigArg(const py::object& config_arg, const Sequence& sequence) {
  if (config_arg.is_none()) return LoadConfigFiles({}, &sequence);
  if (py::isinstance<Config>(config_arg)) return std::make_shared<Config>(config_arg.cast<const Config&>());
  if (py::isinstance<py::str>(config_arg) || py::hasattr(config_arg, "__fspath__")) {
    return LoadConfigFiles({PathArg(config_arg, "config")}, &sequence);
  }
  if (py::isinstance<py::list>(config_arg) || py::isinstance<py::tuple>(config_arg)) {
    std::vector<std::string> files;
    for (const py::handle& f : config_arg) files.push_back(PathArg(f, "config"));
    return LoadConfigFiles(files, &sequence);
  }
  throw py::value_error("config: expected None, an ssta.Config, a config file path or a list of them");
}

// BuildMap with the GIL released, stopped by Ctrl-C or by an exception from `progress`.
// Python's handler only notes the signal; the progress callback, run on this thread after every
// frame, lets Python raise KeyboardInterrupt and asks the build to stop after the current frame.
// The map is then saved, and the KeyboardInterrupt raised once BuildMap returns, as `ssta
// build-map` stops on SIGINT. An exception from `progress` stops it the same way.
BuildMapSummary RunInterruptibly(const Sequence& sequence, const std::string& sequence_path, const Config& config,
                                 const BuildMapOptions& options, const py::object& progress) {
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
    summary = BuildMap(sequence, SequenceNameOf(sequence_path), config, options, on_frame, &stop);
  }
  if (raised) {
    raised->restore();
    throw py::error_already_set();
  }
  return summary;
}

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
  CheckMapPath(map_path);
  if (!progress.is_none() && !PyCallable_Check(progress.ptr())) {
    throw py::value_error("progress: expected a callable progress(done, total) or None");
  }

  const Sequence sequence = ReportingMissingFiles({sequence_path}, [&] {
    py::gil_scoped_release release;
    return Sequence::Open(sequence_path);
  });
  const std::shared_ptr<Config> config = ConfigArg(config_arg, sequence);
  if (refine) config->refinement.online = true;
  const BuildMapSummary summary = RunInterruptibly(sequence, sequence_path, *config, options, progress);
  RequireFused(summary, sequence_path, map_path);
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

void BindBuildMap(py::module_& m) {
  m.def("build_map", &BuildMapPython, py::arg("sequence"), py::arg("map_path"), py::arg("config") = py::none(),
        py::arg("progress") = py::none(), py::kw_only(), py::arg("resume") = false,
        py::arg("static_platform") = false, py::arg("max_frames") = 0, py::arg("every") = 1,
        py::arg("strict") = false, py::arg("sequential") = false, py::arg("refine") = false,
        py::arg("oracle_disparity") = false, py::arg("oracle_labels") = false, py::arg("allow_overlap") = false,
        kBuildMapDoc);
}

}  // namespace ssta::python
