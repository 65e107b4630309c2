#pragma once

// The options of the commands that read a map (query, export, explain, eval footprints, ...):
// apart from commands.h so that the others do not compile the map's headers.

#include <string>
#include <vector>

#include "commands.h"
#include "ssta/core/vehicle_options.h"
#include "ssta/mapping/map_export.h"
#include "ssta/mapping/traversability_map.h"

namespace ssta::cli {

/// The grid export's two steps as options (`--fill-holes N`, `--local-ground R`), shared by
/// `export` and `query --as-exported`; `scope` starts each help text ("grid: ").
void AddGridExportSteps(CLI::App* cmd, const std::string& scope, int* fill_min_neighbours,
                        double* local_ground_radius_m);

/// Throws ssta::Error "<flag>: must be a probability in [0, 1]" unless 0 <= value <= 1 (NaN
/// included): a bar such as `--min-confidence`.
void RequireProbability(const std::string& flag, double value);

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
