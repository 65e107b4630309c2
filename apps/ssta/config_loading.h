#pragma once

#include <string>
#include <vector>

#include "ssta/io/sequence.h"
#include "ssta/pipeline/config.h"

namespace ssta::cli {

/// Defaults, then the sequence's own vehicle.yaml (if it ships one), then each --config FILE in
/// the order given (later files override earlier ones).
inline Config LoadLayeredConfig(const Sequence* sequence, const std::vector<std::string>& config_files) {
  Config config;
  if (sequence && sequence->vehicle_config()) ApplyConfigFile(*sequence->vehicle_config(), &config);
  for (const auto& file : config_files) ApplyConfigFile(file, &config);
  return config;
}

}  // namespace ssta::cli
