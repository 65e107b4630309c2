// The config file parser (ApplyConfigFile / LoadConfig), every section and key.

#include "fuzz_util.h"
#include "pipeline/config_text.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string text = ssta::fuzz::AsText(data, size);
  ssta::fuzz::ExpectParsedOrError([&] {
    ssta::Config config;
    ssta::internal::ApplyConfigText(text, "config.yaml", &config);
    // What parsed must be valid and survive its own YAML round trip.
    std::string error;
    if (!config.IsValid(&error)) __builtin_trap();
    ssta::Config again;
    ssta::internal::ApplyConfigText(ssta::ConfigToYaml(config), "round-trip.yaml", &again);
  });
  return 0;
}
