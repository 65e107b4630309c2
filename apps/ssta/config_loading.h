#pragma once

#include <string>

#include "ssta/io/asl_sequence.h"
#include "ssta/pipeline/config.h"

namespace ssta::cli {

/// Defaults, then the sequence's own vehicle.yaml (if it ships one), then --config FILE.
inline Config LoadLayeredConfig(const AslSequence* sequence, const std::string& config_file) {
  Config config;
  if (sequence && sequence->vehicle_config()) ApplyConfigFile(*sequence->vehicle_config(), &config);
  if (!config_file.empty()) ApplyConfigFile(config_file, &config);
  return config;
}

}  // namespace ssta::cli
