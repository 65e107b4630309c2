#pragma once

// Each sub-command of `ssta` lives in its own cmd_<name>.cpp and registers itself here.
// A command's callback throws ssta::Error for bad input; main() prints it as one line.

#include <CLI/CLI.hpp>

#include "ssta/mapping/map_export.h"

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

/// The grid export's two steps as options (`--fill-holes N`, `--local-ground R`), shared by
/// `export` and `query --as-exported`; `scope` starts each help text ("grid: ").
void AddGridExportSteps(CLI::App* cmd, const std::string& scope, int* fill_min_neighbours,
                        double* local_ground_radius_m);

/// `--as-exported` (help text `help`) and the export's two steps, which need it: for commands
/// that read the map as the grid export shows it (`query`, `eval footprints`).
void AddAsExported(CLI::App* cmd, const std::string& help, bool* as_exported, GridExportOptions* exported);

}  // namespace ssta::cli
