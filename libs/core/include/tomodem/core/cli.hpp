#pragma once
// Command-line pieces every tomodem tool shares (docs/architecture.md#conventions): --version, and a parse step
// that maps CLI11's outcomes onto the documented exit codes. CLI11 is header-only and every
// tool includes it anyway; the libraries never do.
#include <CLI/CLI.hpp>

#include <iostream>
#include <optional>
#include <string>
#include <vector>

#include "tomodem/core/cli_docs.hpp"
#include "tomodem/core/error.hpp"
#include "tomodem/core/output.hpp"
#include "tomodem/core/tool.hpp"
#include "tomodem/core/units.hpp"

namespace tomodem::cli {

/// --version prints "<tool> tomodem X (git H)", then "features: ..." (build_features()), and exits with 0.
inline void add_version(CLI::App& app, const std::string& tool) {
  app.add_flag_callback(
      "--version",
      [tool] {
        if (writes_outputs()) std::cout << tool << " " << version_string() << "\nfeatures: " << build_features(tool) << "\n";
        throw CLI::Success();
      },
      "print the version and exit");
}

/// --threads N: N threads; 0 (the default) is OMP_NUM_THREADS or every core (all_threads()).
/// CLI11 refuses (exit 2, naming the option and the value) anything outside [0, 4096].
/// `default_text` replaces the default's description where an input file may name a count.
inline CLI::Option* add_threads(CLI::App& app, int& threads,
                                const std::string& default_text = "default 0: OMP_NUM_THREADS or all cores") {
  return app.add_option("--threads", threads, "threads; 0: OMP_NUM_THREADS or all cores (" + default_text + ")")
      ->check(CLI::Range(0, 4096));
}

/// --json FILE: the summary goes to FILE (written atomically) and not to stdout; "-" or no
/// --json: to stdout. One meaning in every tool (docs/cli.md).
inline CLI::Option* add_json(CLI::App& app, std::string& path) {
  return app.add_option("--json", path, "write the JSON summary to FILE (atomically) instead of stdout; '-': stdout");
}

/// -q/--quiet: no progress on stderr (warnings and errors stay); set as soon as it is parsed.
inline CLI::Option* add_quiet(CLI::App& app, bool& quiet_flag) {
  return app.add_flag_function(
      "-q,--quiet",
      [&quiet_flag](std::int64_t) {
        quiet_flag = true;
        set_quiet(true);
      },
      "no progress messages on stderr (warnings and errors stay)");
}

/// The options every tool has, with one meaning each (docs/cli.md).
struct Common {
  std::string json;  ///< --json FILE; "" or "-": stdout
  bool quiet = false;
  int threads = 0;   ///< --threads; 0: all_threads()
};

/// --json, -q/--quiet, --version and (when `threads`) --threads.
inline void add_common(CLI::App& app, const std::string& tool, Common& c, bool threads = true) {
  add_json(app, c.json);
  add_quiet(app, c.quiet);
  if (threads) add_threads(app, c.threads);
  add_version(app, tool);
}

/// "--grip" from "-g,--grip": how messages name an option.
inline std::string long_name(const std::string& names) {
  std::string first;
  for (const auto& n : CLI::detail::split_names(names)) {
    if (n.rfind("--", 0) == 0) return n;
    if (first.empty()) first = n;
  }
  return first;
}

/// A length option (docs/cli.md "Lengths"): "60.7um", "0.05mm", "2nm", "1e-3" (metres). A bad
/// unit is an InputError naming the option (exit 2). `metres` keeps its default when not given.
inline CLI::Option* add_length(CLI::App& app, const std::string& names, double& metres, const std::string& help) {
  const std::string option = long_name(names);
  return app.add_option_function<std::string>(
      names, [&metres, option](const std::string& text) { metres = parse_length(option, text); },
      help + " (length: m, mm, um, nm; bare number: m)");
}

/// A random seed (parse_seed): a whole number in [0, 2^64 − 1]; a negative or larger one is an
/// InputError naming the option (exit 2), never wrapped or clamped. `seed` keeps its default when not given.
inline CLI::Option* add_seed(CLI::App& app, const std::string& names, uint64_t& seed, const std::string& help) {
  const std::string option = long_name(names);
  return app.add_option_function<std::string>(
      names, [&seed, option](const std::string& text) { seed = parse_seed("", option, text); },
      help + " (a whole number in [0, 2^64 - 1])");
}

/// Several lengths, comma separated (--offset 1mm,0,-2um); `count` of them.
inline CLI::Option* add_lengths(CLI::App& app, const std::string& names, std::vector<double>& metres, int count,
                                const std::string& help) {
  const std::string option = long_name(names);
  return app
      .add_option_function<std::vector<std::string>>(
          names,
          [&metres, option](const std::vector<std::string>& texts) {
            metres.clear();
            for (const auto& t : texts) metres.push_back(parse_length(option, t));
          },
          help + " (lengths: m, mm, um, nm; bare numbers: m)")
      ->delimiter(',')
      ->expected(count);
}

/// Tools that write several files into a folder (dem, sinter) take --output-dir; -o names a file
/// in every other tool, so here it is refused with a pointer instead of meaning a folder.
inline void refuse_o_as_folder(CLI::App& app, std::string& o_value) {
  app.add_option("-o,--output", o_value, "")->group("");  // hidden: only to say what to use instead
}
inline void check_o_as_folder(const std::string& o_value, const std::string& tool) {
  if (!o_value.empty())
    throw InputError("", "-o", o_value,
                     "-o names an output file in every tomodem tool; " + tool +
                         " writes the files its scene names into a folder: give it with --output-dir");
}

/// Refuses every option given whose help text starts with `scope` and a colon ("explicit: bond
/// dashpot ratio", "sla pcg: relative residual" for scope "sla") when that scope is not in use:
/// the help text's prefix says where an option applies, and an option that would be ignored is
/// refused, never ignored. `in_use` says what runs instead ("--method implicit").
inline void refuse_unused_scope(const CLI::App& app, const std::string& scope, const std::string& in_use) {
  for (const CLI::Option* o : app.get_options()) {
    const std::string& d = o->get_description();
    const auto colon = d.find(':');
    if (o->count() == 0 || colon == std::string::npos || d.compare(0, scope.size(), scope) != 0 ||
        (d.size() > scope.size() && d[scope.size()] != ':' && d[scope.size()] != ' '))
      continue;
    const auto given = o->results();
    throw InputError("", o->get_name(), given.empty() ? "(given)" : given.front(),
                     "applies to " + d.substr(0, colon) + " only, and " + in_use + " does not run it");
  }
}

/// Integer options are read in decimal and never clamped or wrapped (docs/cli.md "whole numbers").
/// CLI11 2.1 reads them with strtoll/strtoull in base 0: `--size 010` was octal 8, `0x10` hex 16,
/// 2^64 clamped to 2^63 - 1 and -1 wrapped to 2^64 - 1 in an unsigned option. This transform, put
/// first on every option whose type is INT or UINT (parse() does it for every tool), rewrites
/// decimal digits (a sign allowed; leading zeros dropped: `010` is 10) and refuses, naming the
/// option and the value (exit 2), a number outside the 64-bit range (the option's own type then
/// checks its narrower range), a negative one for an unsigned option, and a number in another base
/// (`0x10`, `0b1`). Other text (`2.5`, `1e3`, a word) is left to the option's checks and CLI11.
inline std::string decimal_integer(std::string& text, bool is_unsigned) {
  const auto d = read_decimal_digits(text);
  if (!d) {
    // 0x10 (and 0b1 where the C library reads it) would be taken in another base: refused. Other
    // forms (2.5, 1e3, a word) are left to the option's own check, then to CLI11, which refuses them.
    const std::size_t k = !text.empty() && (text[0] == '+' || text[0] == '-') ? 1 : 0;
    if (k + 1 < text.size() && text[k] == '0' && std::string("xXbB").find(text[k + 1]) != std::string::npos)
      return "'" + text + "' is not a whole number in decimal digits";
    return "";
  }
  const std::string range = is_unsigned ? "[0, 18446744073709551615]" : "[-9223372036854775808, 9223372036854775807]";
  if (is_unsigned && d->negative && d->magnitude != 0)
    return "'" + text + "' is negative: expected a whole number in " + range + " (never wrapped)";
  const uint64_t limit = is_unsigned ? UINT64_MAX : d->negative ? uint64_t(1) << 63 : uint64_t(INT64_MAX);
  if (d->too_large || d->magnitude > limit)
    return "'" + text + "' is out of range: expected a whole number in " + range + " (never clamped)";
  text = (d->negative && d->magnitude != 0 ? "-" : "") + std::to_string(d->magnitude);
  return "";
}

/// Puts decimal_integer first on every INT or UINT option of `app` and its subcommands.
inline void read_integers_as_decimal(CLI::App& app) {
  for (CLI::Option* o : app.get_options()) {
    if (o->get_type_size() == 0) continue;  // flags
    const std::string t = o->get_type_name();
    const bool is_signed = t == "INT" || t.rfind("INT:", 0) == 0;
    const bool is_unsigned = t == "UINT" || t.rfind("UINT:", 0) == 0;
    if (!is_signed && !is_unsigned) continue;
    o->transform(CLI::Validator([is_unsigned](std::string& text) { return decimal_integer(text, is_unsigned); }, "", ""));
  }
  for (CLI::App* sub : app.get_subcommands([](CLI::App*) { return true; })) read_integers_as_decimal(*sub);
}

/// Parses the command line: the exit code to stop with (0 after --help or --version, 2 for bad
/// usage, after CLI11's message), or nothing when the tool should go on.
/// `TOOL --help-man` prints the manual page and `TOOL --help-completion` the bash completion,
/// both generated from `app` (cli_docs.hpp; used by the install step, hidden from --help).
inline std::optional<int> parse(CLI::App& app, int argc, char** argv) {
  set_command_line(argc, argv);
  if (argc == 2 && (std::string(argv[1]) == "--help-man" || std::string(argv[1]) == "--help-completion")) {
    std::string tool = argv[0];
    tool = tool.substr(tool.find_last_of('/') + 1);
    std::cout << (std::string(argv[1]) == "--help-man" ? man_page(app, tool, version_string()) : bash_completion(app, tool));
    return exit_code::ok;
  }
  read_integers_as_decimal(app);
  try {
    app.parse(argc, argv);
  } catch (const CLI::Success& e) {  // --help; on several ranks rank 0 alone prints (output.hpp)
    return writes_outputs() ? app.exit(e) : exit_code::ok;
  } catch (const CLI::ParseError& e) {
    if (writes_outputs()) app.exit(e);
    return exit_code::bad_input;
  }
  return std::nullopt;
}

}  // namespace tomodem::cli
