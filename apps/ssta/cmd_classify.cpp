#include "commands.h"

namespace ssta::cli {

// Placeholder until the classify command lands.
void RegisterClassify(CLI::App& app) { (void)app; }

}  // namespace ssta::cli
