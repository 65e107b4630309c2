#pragma once

// Each sub-command of `ssta` lives in its own cmd_<name>.cpp and registers itself here.
// A command's callback throws ssta::Error for bad input; main() prints it as one line.

#include <CLI/CLI.hpp>

#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

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

}  // namespace ssta::cli
