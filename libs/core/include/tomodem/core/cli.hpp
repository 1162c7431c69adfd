#pragma once
// Command-line pieces every tomodem tool shares (docs/architecture.md#conventions): --version, and a parse step
// that maps CLI11's outcomes onto the documented exit codes. CLI11 is header-only and every
// tool includes it anyway; the libraries never do.
#include <CLI/CLI.hpp>

#include <iostream>
#include <optional>
#include <string>

#include "tomodem/core/error.hpp"
#include "tomodem/core/tool.hpp"

namespace tomodem::cli {

/// --version prints "<tool> tomodem X (git H)" and exits with 0.
inline void add_version(CLI::App& app, const std::string& tool) {
  app.add_flag_callback(
      "--version",
      [tool] {
        std::cout << tool << " " << version_string() << "\n";
        throw CLI::Success();
      },
      "print the version and exit");
}

/// --threads N of the tools whose default is OpenMP's own (0: OMP_NUM_THREADS or all cores);
/// CLI11 refuses (exit 2, naming the option and the value) anything outside [0, 4096].
inline CLI::Option* add_threads(CLI::App& app, int& threads) {
  return app.add_option("--threads", threads, "threads (default 0: OMP_NUM_THREADS or all cores)")
      ->check(CLI::Range(0, 4096));
}

/// Parses the command line: the exit code to stop with (0 after --help or --version, 2 for bad
/// usage, after CLI11's message), or nothing when the tool should go on.
inline std::optional<int> parse(CLI::App& app, int argc, char** argv) {
  try {
    app.parse(argc, argv);
  } catch (const CLI::Success& e) {
    return app.exit(e);
  } catch (const CLI::ParseError& e) {
    app.exit(e);
    return exit_code::bad_input;
  }
  return std::nullopt;
}

}  // namespace tomodem::cli
