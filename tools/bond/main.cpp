// tomodem-bond: a packing -> a bonded-particle network (docs/bond.md).
#include <CLI/CLI.hpp>
#include <omp.h>

#include "tomodem/core/cli.hpp"
#include "tomodem/core/cli_choice.hpp"
#include "tomodem/core/error.hpp"
#include "tomodem/core/summary.hpp"
#include "tomodem/core/tool.hpp"
#include "tomodem/mechanics/tools.hpp"

int main(int argc, char** argv) {
  return tomodem::run_tool("tomodem-bond", [&]() -> int {
    tomodem::mechanics::BondConfig c;
    CLI::App app{"Bond a packing: necks between touching (or nearly touching) particles (docs/bond.md)", "tomodem-bond"};
    app.add_option("input", c.input, "packing (.h5, shared data model)")->required();
    app.add_option("-o,--output", c.output, "bonded packing (.h5 + .xdmf), with /bonds and /bonds/image")->required();
    tomodem::cli::add_choice(app, "--rule", c.rule, tomodem::mechanics::kNeckRuleNames,
                             "neck radius: ratio | overlap | density | sinter");
    app.add_option("--sinter-config", c.sinter_config, "rule sinter: sintering settings YAML (docs/sintering.md)");
    app.add_option("--neck-ratio", c.neck_ratio, "rule ratio: a_b/R, R = 2R_iR_j/(R_i+R_j)")->capture_default_str();
    app.add_option("--min-neck-ratio", c.min_neck_ratio, "rules overlap/density: smallest a_b/R")->capture_default_str();
    app.add_option("--target-density", c.target_density, "rules density, sinter: relative density to reach");
    app.add_option("--gap-tolerance", c.gap_tolerance, "bond when the gap is at most tol * 2RiRj/(Ri+Rj) (-)")->capture_default_str();
    app.add_option("--exclude", c.exclude, "no bonds between these phases: A:B (names or indices), repeatable");
    app.add_option("--pair-ratio", c.pair_ratio, "rule ratio per phase pair: A:B=RATIO, repeatable");
    bool require = false;
    app.add_flag("--require-spanning", require, "exit 2 when no bonded cluster spans the periodic cell");
    tomodem::cli::Common common;
    tomodem::cli::add_common(app, "tomodem-bond", common);
    if (const auto code = tomodem::cli::parse(app, argc, argv)) return *code;
    // An option of another rule would be ignored (the default rule is overlap): refuse it.
    using tomodem::mechanics::NeckRule;
    const auto only = [&](const char* option, std::initializer_list<NeckRule> rules, const char* which) {
      if (app.count(option) == 0) return;
      for (const NeckRule r : rules)
        if (c.rule == r) return;
      throw tomodem::InputError("", option, app.get_option(option)->results().front(),
                                std::string("applies to ") + which + " only; --rule " +
                                    tomodem::mechanics::to_string(c.rule) + " does not use it");
    };
    only("--target-density", {NeckRule::density, NeckRule::sinter}, "--rule density and --rule sinter");
    only("--neck-ratio", {NeckRule::ratio}, "--rule ratio");
    only("--pair-ratio", {NeckRule::ratio}, "--rule ratio");
    only("--sinter-config", {NeckRule::sinter}, "--rule sinter");
    only("--min-neck-ratio", {NeckRule::overlap, NeckRule::density}, "--rule overlap and --rule density");
    c.allow_disconnected = !require;
    c.json = common.json;
    c.threads = common.threads;
    if (common.threads > 0) omp_set_num_threads(common.threads);
    tomodem::info("reading " + c.input);
    tomodem::emit_summary(tomodem::mechanics::run_bond(c), c.json);
    return tomodem::exit_code::ok;
  });
}
