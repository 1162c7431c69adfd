// tomodem-run (also `tomodem run`): brings a pipeline file up to date, Make-style.
// The work is in libs/pipeline; this file parses the command line and reports.
#include <CLI/CLI.hpp>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <thread>

#include "tomodem/core/cli.hpp"
#include "tomodem/core/error.hpp"
#include "tomodem/core/output.hpp"
#include "tomodem/core/tool.hpp"
#include "tomodem/pipeline/results.hpp"
#include "tomodem/pipeline/run.hpp"

namespace {
// --jobs default: the Slurm allocation, else every core.
int default_jobs() {
  if (const char* s = std::getenv("SLURM_CPUS_PER_TASK"); s && std::atoi(s) > 0) return std::atoi(s);
  return std::max(1u, std::thread::hardware_concurrency());
}
}  // namespace

int main(int argc, char** argv) {
  namespace tp = tomodem::pipeline;
  CLI::App app{"tomodem-run: run a pipeline file, re-running only the steps whose inputs, params, command or\n"
               "tool version changed (see docs/pipelines.md). Without a subcommand it runs the pipeline."};
  app.set_version_flag("--version", tomodem::version_string() + "\nfeatures: " + tomodem::build_features());
  std::string file, json_file, step, shard;
  bool quiet = false;
  tp::LoadOptions lo;
  tp::RunOptions ro;
  tp::SlurmOptions so;
  ro.jobs = default_jobs();
  app.add_option("pipeline", file, "pipeline file (YAML)");
  app.add_option("-j,--jobs", ro.jobs, "parallel slots; a step takes `threads` of them (default: all cores)")
      ->check(CLI::Validator(
          [](std::string& v) {  // CLI::PositiveNumber's message named a range from 0 to 1.8e308
            char* end = nullptr;
            const long n = std::strtol(v.c_str(), &end, 10);
            return !v.empty() && *end == '\0' && n >= 1 && n <= 1000000 ? std::string()
                                                                       : "value '" + v + "': expected a number of slots from 1 to 1000000";
          },
          "N>=1"));
  app.add_option("--force", ro.force, "run STEP (or STEP[cell]) even if it is up to date")->allow_extra_args(false);
  app.add_flag("-B,--force-all", ro.force_all, "run every step");
  app.add_flag("-n,--dry-run", ro.dry_run, "say what would run and why; run nothing");
  app.add_flag("-k,--keep-going", ro.keep_going, "after a failure, run the steps that do not depend on it");
  app.add_flag("--rerun-on-rebuild", ro.rerun_on_rebuild,
               "re-run tool steps made by another build (git commit) of the same release");
  app.add_option("--shard", shard, "run slice K of N of the sweep (0/N: the shared upstream steps)");
  app.add_option("--set", lo.overrides, "override a variable (NAME=VALUE) or steps.S.params.K=VALUE")
      ->allow_extra_args(false);
  app.add_option("--json", json_file, "write the JSON summary to FILE ('-' for stdout)");
  app.add_flag("-q,--quiet", quiet, "no progress lines");
  CLI::App* st = app.add_subcommand("status", "list each step as up to date or would run, and why");
  CLI::App* ex = app.add_subcommand("explain", "every reason a step (or STEP[cell]) would run, with its files");
  CLI::App* dt = app.add_subcommand("dot", "print the graph of step instances (Graphviz DOT; stale ones orange)");
  CLI::App* exp = app.add_subcommand("export", "write scripts for a cluster");
  CLI::App* sl = exp->add_subcommand("slurm", "write <stem>.array.sbatch and <stem>.submit.sh next to the pipeline");
  for (CLI::App* sub : {st, ex, dt, sl}) {
    sub->add_option("pipeline", file, "pipeline file (YAML)")->required();
    sub->fallthrough();
  }
  exp->fallthrough();
  exp->require_subcommand(1);
  ex->add_option("step", step, "step name or instance id")->required();
  sl->add_option("--shards", so.shards, "array size (default: one per sweep leaf)");
  sl->add_option("--limit", so.limit, "array tasks running at once (the % in --array)")->capture_default_str();
  sl->add_option("--cpus", so.cpus, "cpus per task (default: the largest step `threads`)");
  sl->add_option("--time", so.time, "time limit per task")->capture_default_str();
  sl->add_option("--partition", so.partition, "Slurm partition");
  sl->add_option("--runner", so.runner, "command that runs tomodem-run on the nodes")->capture_default_str();
  // Results: one row per cell from its steps' JSON summaries, then the table, plots and report.
  std::string row_out, report_dir;
  std::vector<std::string> row_values, row_summaries, report_rows;
  tp::ReportOptions rep;
  CLI::App* rw = app.add_subcommand("row", "write one results row (JSON) from values and step summaries");
  rw->add_option("-o,--output", row_out, "row file (.json)")->required();
  rw->add_option("--value", row_values, "a column KEY=VALUE (numbers stay numbers); repeatable")->allow_extra_args(false);
  rw->add_option("--summary", row_summaries, "NAME=FILE.json: the summary's scalars as columns NAME.key; repeatable")
      ->allow_extra_args(false);
  CLI::App* rp = app.add_subcommand("report", "rows -> DIR/table.csv, plots (PNG, SVG; gnuplot) and DIR/index.html");
  rp->add_option("-o,--output", report_dir, "report folder (replaced as a whole)")->required();
  rp->add_option("rows", report_rows, "row files (from `tomodem run row`), one table row each")->required();
  rp->add_option("--title", rep.title, "title of the report")->capture_default_str();
  rp->add_option("--command", rep.command, "the command that makes the report, shown in it");
  // Every list option takes one value per occurrence (repeat it, or join the list with commas
  // where the help says so): a multi-value option would swallow the row files that follow it.
  rp->add_option("--columns", rep.columns, "A,B,...: the table's columns, in order (default: all); repeatable")
      ->delimiter(',')
      ->allow_extra_args(false);
  rp->add_option("--ratio", rep.ratios, "NAME=A/B: a column A/B (columns or numbers); repeatable")->allow_extra_args(false);
  rp->add_option("--plot", rep.plots,
                 "name=N;x=COL;y=COL[,COL];by=COL;logx;logy;title=T;xlabel=L;ylabel=L (repeatable)")
      ->allow_extra_args(false);
  rp->add_option("--group", rep.group,
                 "A,B: columns whose values make a cell; its rows are replicas (default: plots' by, x); repeatable")
      ->delimiter(',')
      ->allow_extra_args(false);
  rp->add_option("--stats", rep.stats, "A,B,...: properties to summarise (default: every number column); repeatable")
      ->delimiter(',')
      ->allow_extra_args(false);
  rp->add_option("--bound", rep.bounds, "NAME=LO:HI: the physical range of a column (numbers or columns; a side may be empty); repeatable")
      ->allow_extra_args(false);
  rp->add_option("--replicas", rep.replicas, "the runner's adaptive-replica record (${run.replicas}): stopped_because");
  app.require_subcommand(0, 1);
  if (const auto code = tomodem::cli::parse(app, argc, argv)) return *code;
  return tomodem::run_tool("tomodem-run", [&] {
    tomodem::set_quiet(quiet);
    ro.quiet = quiet;
    if (rw->parsed()) {
      std::vector<std::string> inputs;
      for (const auto& sm : row_summaries) inputs.push_back(sm.substr(sm.find('=') + 1));
      tomodem::check_outputs(inputs, {{"-o", row_out}});
      tomodem::write_text_atomic(row_out, tp::make_row(row_values, row_summaries));
      return 0;
    }
    if (rp->parsed()) {
      const tp::ReportFiles f = tp::write_report(report_dir, report_rows, rep);
      for (const auto& o : f.outside_bounds) tomodem::warn(o);
      for (const auto& w : f.warnings) tomodem::warn(w);
      for (const auto& n : f.not_ranked) tomodem::info(n);
      tomodem::info("wrote " + f.table + " (" + std::to_string(f.rows) + " rows, " + std::to_string(f.columns) +
                    " columns), " + std::to_string(f.plots.size()) + " plots, " + f.summary + " (" +
                    std::to_string(f.cells) + " cells, " + std::to_string(f.rankings) + " rankings) and " + f.html);
      return 0;
    }
    if (file.empty()) throw tomodem::InputError("", "pipeline", "", "no pipeline file given (see --help)");
    if (!shard.empty()) std::tie(ro.shard, ro.shards) = tp::parse_shard(shard);
    lo.check_inputs = !(dt->parsed() || sl->parsed());  // nothing runs, so inputs may come later
    const tp::Pipeline p = tp::load(file, lo);
    for (const auto& w : p.warnings) tomodem::warn(w);
    tomodem::check_outputs({file, p.lock_file}, {{"--json", json_file}});
    if (sl->parsed()) {
      const tp::SlurmFiles f = tp::slurm_scripts(p, so);
      tomodem::write_text_atomic(f.array_path, f.array_script);
      tomodem::write_text_atomic(f.submit_path, f.submit_script);
      std::filesystem::permissions(f.submit_path, std::filesystem::perms::owner_exec | std::filesystem::perms::group_exec,
                                   std::filesystem::perm_options::add);
      tomodem::info("wrote " + f.array_path + " and " + f.submit_path + " (run the latter to submit)");
      return 0;
    }
    if (dt->parsed()) {
      std::cout << tp::dot(p);
      return 0;
    }
    if (ex->parsed()) {
      std::cout << tp::explain(p, step, ro);
      return 0;
    }
    const tp::RunSummary s = st->parsed() ? tp::status(p, ro) : tp::run(p, ro, std::cerr);
    if (st->parsed())
      for (const auto& r : s.steps)
        std::cout << (r.state == "would-run" ? "would run   " : r.state == "up-to-date" ? "up to date  " : "other shard ")
                  << r.id << (r.reason.empty() ? "" : ": " + r.reason) << '\n';
    if (json_file == "-")
      std::cout << tp::summary_json(p, s);
    else if (!json_file.empty())
      tomodem::write_text_atomic(json_file, tp::summary_json(p, s));
    if (!quiet || s.exit_code()) std::cerr << "tomodem-run: " << tp::summary_text(s);
    return s.exit_code();
  }, tomodem::RankUse::one_rank, tomodem::OutputCommit::as_written);  // the lock file records each step as it ends
}
