#pragma once

// Each sub-command of `ssta` lives in its own cmd_<name>.cpp and registers itself here.
// A command's callback throws ssta::Error for bad input; main() prints it as one line.

#include <CLI/CLI.hpp>

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

}  // namespace ssta::cli
