// `ssta config`: every setting with its unit, range and meaning, after the given files.

#include <iostream>
#include <string>
#include <vector>

#include "commands.h"
#include "ssta/files/file_util.h"
#include "ssta/pipeline/config.h"

namespace ssta::cli {

void RegisterConfig(CLI::App& app) {
  struct Args {
    std::vector<std::string> config;
    std::string out;
    bool plain = false;
  };
  auto args = std::make_shared<Args>();
  CLI::App* cmd = app.add_subcommand(
      "config", "Print every setting with its unit and meaning: the defaults, or what --config files make of them");
  cmd->add_option("--config", args->config, "YAML config files over the defaults; repeatable, later files win")
      ->check(CLI::ExistingFile);
  cmd->add_option("--out", args->out, "write to this file (atomically) instead of stdout")->check(OutputFile());
  cmd->add_flag("--plain", args->plain, "keys and values only, without the comments");
  cmd->callback([args] {
    const Config config = LoadLayeredConfig(nullptr, args->config);
    const std::string text = args->plain ? ConfigToYaml(config) : ConfigToCommentedYaml(config);
    if (args->out.empty()) {
      std::cout << text;
    } else {
      WriteTextAtomically(args->out, text);
    }
  });
}

}  // namespace ssta::cli
