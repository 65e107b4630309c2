#pragma once

// Private: the config parser from text already read (the fuzz target calls it directly).

#include <string>

#include "ssta/pipeline/config.h"

namespace ssta::internal {

/// ApplyConfigFile on the text of `path` (`path` only names the file in messages).
void ApplyConfigText(const std::string& text, const std::string& path, Config* config);

}  // namespace ssta::internal
