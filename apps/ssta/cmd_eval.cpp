#include "commands.h"

namespace ssta::cli {

// Placeholder until the eval command lands.
void RegisterEval(CLI::App& app) { (void)app; }

}  // namespace ssta::cli
