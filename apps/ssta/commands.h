#pragma once

// Each sub-command of `ssta` lives in its own cmd_<name>.cpp and registers itself here.
// A command's callback throws ssta::Error for bad input; main() prints it as one line.

#include <CLI/CLI.hpp>

#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include "ssta/mapping/map_export.h"
#include "ssta/mapping/traversability_map.h"

namespace ssta::cli {

void RegisterClassify(CLI::App& app);
void RegisterSynth(CLI::App& app);
void RegisterEval(CLI::App& app);
void RegisterBuildMap(CLI::App& app);
void RegisterQuery(CLI::App& app);
void RegisterExport(CLI::App& app);
void RegisterCalibrateStereo(CLI::App& app);
void RegisterBench(CLI::App& app);
void RegisterCalibrateMount(CLI::App& app);
void RegisterConfig(CLI::App& app);
void RegisterInspect(CLI::App& app);
void RegisterConvert(CLI::App& app);
void RegisterMergeMaps(CLI::App& app);
void RegisterExplain(CLI::App& app);
void RegisterDiffMaps(CLI::App& app);
/// `eval disparity` and `eval stereo` (cmd_eval_disparity.cpp), added to the `eval` command.
void AddDisparityEval(CLI::App* eval);

/// Validators for the paths a command writes, checked while the command line is parsed, so a
/// run fails before its work and not after it. A file needs an existing folder and must not be
/// a folder; a prefix (to which extensions are added) the same; a folder may be new (it is
/// created) but must not be a file. Their messages name the path and what is wrong with it.
CLI::Validator OutputFile();
CLI::Validator OutputPrefix();
CLI::Validator OutputFolder();

/// `v` as printf's `format` (one double) prints it, or "nan" when it is not finite: the
/// commands' text and CSV outputs agree on how a missing value reads.
inline std::string PrintNumber(double v, const char* format) {
  if (!std::isfinite(v)) return "nan";
  char buffer[64];
  std::snprintf(buffer, sizeof(buffer), format, v);
  return buffer;
}

/// The grid export's two steps as options (`--fill-holes N`, `--local-ground R`), shared by
/// `export` and `query --as-exported`; `scope` starts each help text ("grid: ").
void AddGridExportSteps(CLI::App* cmd, const std::string& scope, int* fill_min_neighbours,
                        double* local_ground_radius_m);

/// `--config FILE` (repeatable) for the commands that read a map (`query`, `export`, `eval
/// footprints`): every command takes one (docs/interfaces.md, section 4), and a script may pass the one
/// it built the map with. A map's classes were fused for the vehicle it was built for, so the
/// files, read over that vehicle, must leave it as it is (LoadMapForConfig checks); the other
/// sections do not apply to reading a map, though a bad value in them is still an error.
void AddMapConfig(CLI::App* cmd, std::vector<std::string>* config_files);

/// Reads `config_files` in turn over `expected` (a key they leave out matches) and throws
/// ssta::Error when a vehicle key ends up different (RequireSameVehicle): "<file>: gives
/// vehicle.<key> <value>, but <expected_for> <expected value> (<source>); <advice>", naming the
/// last file that set the key. A bad value in any section is an error naming its file and key.
void RequireVehicle(const VehicleOptions& expected, const std::vector<std::string>& config_files,
                    const std::string& expected_for, const std::string& source, const std::string& advice);

/// Loads the map at `map_path` and checks `config_files` against it (AddMapConfig): throws
/// ssta::Error naming the file and the vehicle key whose value differs from the map's.
TraversabilityMap LoadMapForConfig(const std::string& map_path, const std::vector<std::string>& config_files);

/// `--as-exported` (help text `help`) and the export's two steps, which need it: for commands
/// that read the map as the grid export shows it (`query`, `eval footprints`).
void AddAsExported(CLI::App* cmd, const std::string& help, bool* as_exported, GridExportOptions* exported);

}  // namespace ssta::cli
