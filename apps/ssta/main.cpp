// ssta: stereo traversability analysis on the command line. Thin: parses arguments and hands
// them to the library; every sub-command is in cmd_<name>.cpp.

#include <cstdlib>
#include <exception>
#include <iostream>

#include <opencv2/core/utility.hpp>

#include "commands.h"
#include "ssta/core/error.h"

int main(int argc, char** argv) {
  // OpenCV reads OPENCV_FOR_THREADS_NUM only when asked for its default: with it set, the default
  // thread count (no --threads) is that number, as OpenCV documents; without it, every core.
  cv::setNumThreads(-1);
  CLI::App app{"ssta: stereo superpixel surface traversability analysis (SSTA) and maps"};
  app.name("ssta");
  app.set_version_flag("--version", std::string("ssta ") + SSTA_VERSION);
  app.require_subcommand(1);
  // Every parallel loop (the matcher, the normals' bands, the analysis's concurrent steps) runs
  // on OpenCV's threads, so one setting caps them all; it applies before the command runs.
  app.fallthrough();  // accepted after the command's name too
  app.add_option("--threads", "threads for matching and the per-frame geometry (0: all cores)")
      ->check(CLI::Range(0, 256))
      ->each([](const std::string& value) {
        const int threads = std::stoi(value);
        cv::setNumThreads(threads > 0 ? threads : -1);  // -1: OpenCV's default, all cores
      });
  ssta::cli::RegisterClassify(app);
  ssta::cli::RegisterSynth(app);
  ssta::cli::RegisterBuildMap(app);
  ssta::cli::RegisterQuery(app);
  ssta::cli::RegisterExplain(app);
  ssta::cli::RegisterExport(app);
  ssta::cli::RegisterMergeMaps(app);
  ssta::cli::RegisterDiffMaps(app);
  ssta::cli::RegisterEval(app);
  ssta::cli::RegisterCalibrateStereo(app);
  ssta::cli::RegisterCalibrateMount(app);
  ssta::cli::RegisterBench(app);
  ssta::cli::RegisterConfig(app);
  ssta::cli::RegisterInspect(app);
  ssta::cli::RegisterConvert(app);
  if (argc == 1) {  // nothing asked: the usage, as a failed run (nothing ran)
    std::cerr << app.help();
    return 2;
  }
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    // --help and --version end here with status 0 (CLI11 prints them); a bad command line is bad
    // input like any other: one line naming the option, status 2.
    if (e.get_exit_code() == static_cast<int>(CLI::ExitCodes::Success)) return app.exit(e);
    const std::vector<std::string> unparsed = app.remaining();
    if (app.get_subcommands().empty() && !unparsed.empty() && unparsed.front().rfind('-', 0) != 0) {
      std::string names;
      for (const CLI::App* sub : app.get_subcommands({})) names += (names.empty() ? "" : ", ") + sub->get_name();
      std::cerr << "ssta: error: unknown command '" << unparsed.front() << "' (commands: " << names << ")\n";
      return 2;
    }
    // A value a validator refused (an output path that cannot be written, a format not among
    // the choices, a number out of range) is named with the option; other mistakes point at --help.
    const bool path_check = dynamic_cast<const CLI::ValidationError*>(&e) != nullptr;
    std::cerr << "ssta: error: " << e.what() << (path_check ? "" : " (--help lists the options)") << "\n";
    return 2;
  } catch (const ssta::Error& e) {
    std::cerr << "ssta: error: " << e.what() << "\n";
    return 2;
  } catch (const std::exception& e) {
    std::cerr << "ssta: internal error: " << e.what() << "\n";
    return 3;
  }
  return 0;
}
