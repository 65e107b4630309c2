#include "commands.h"

namespace ssta::cli {

// Placeholder until the synth command lands.
void RegisterSynth(CLI::App& app) { (void)app; }

}  // namespace ssta::cli
