// Shards, the Slurm export and the summaries.
#include <algorithm>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <sstream>

#include "tomodem/core/error.hpp"
#include "tomodem/core/summary.hpp"
#include "tomodem/core/tool.hpp"
#include "template.hpp"
#include "tomodem/pipeline/run.hpp"

namespace tomodem::pipeline {

namespace fs = std::filesystem;

namespace {
// Cells of swept steps with no swept step downstream: the units the shards divide.
std::vector<std::size_t> sweep_leaves(const Pipeline& p) {
  const std::size_t count = p.instances.size();
  std::vector<char> swept(count), swept_below(count);
  for (std::size_t i = 0; i < count; ++i) swept[i] = !p.instances[i].cell.empty();
  // Instances come upstream first, so walking backwards sees every dependant before its inputs.
  for (std::size_t i = count; i-- > 0;)
    if (swept[i] || swept_below[i])
      for (const auto u : p.instances[i].upstream) swept_below[u] = 1;
  std::vector<std::size_t> leaves;
  for (std::size_t i = 0; i < count; ++i)
    if (swept[i] && !swept_below[i]) leaves.push_back(i);
  return leaves;
}
}  // namespace

std::vector<int> shard_owners(const Pipeline& p, int n) {
  const std::size_t count = p.instances.size();
  const std::vector<std::size_t> leaves = sweep_leaves(p);
  // Contiguous blocks keep neighbouring cells (which often share an upstream cell) together.
  std::vector<int> owner(count, -1);
  for (std::size_t q = 0; q < leaves.size(); ++q)
    owner[leaves[q]] = 1 + static_cast<int>(q * static_cast<std::size_t>(n) / leaves.size());
  const auto merge = [](int a, int b) { return a < 0 ? b : b < 0 || a == b ? a : 0; };
  for (std::size_t i = count; i-- > 0;)
    if (owner[i] >= 0)
      for (const auto u : p.instances[i].upstream) owner[u] = merge(owner[u], owner[i]);
  return owner;
}

std::pair<int, int> parse_shard(const std::string& text) {
  const auto slash = text.find('/');
  try {
    std::size_t a = 0, b = 0;
    if (slash == std::string::npos) throw std::invalid_argument("no slash");
    const int k = std::stoi(text.substr(0, slash), &a);
    const int n = std::stoi(text.substr(slash + 1), &b);
    if (a != slash || b != text.size() - slash - 1 || n < 1 || k < 0 || k > n) throw std::invalid_argument("range");
    return {k, n};
  } catch (const std::exception&) {
    throw InputError("", "--shard", text, "expected K/N with 1 <= K <= N (or 0/N for the shared upstream steps)");
  }
}

namespace {
using detail::shell_quote;

// A value on an `#SBATCH` line: sbatch is not a shell there, but it splits at blanks and takes
// double quotes; a newline would start a line of script. So: quoted when it has blanks, refused
// when it has a double quote or a control character.
std::string sbatch_value(const std::string& v, const std::string& option) {
  for (const char c : v)
    if (c == '"' || static_cast<unsigned char>(c) < 0x20 || c == 0x7f)
      throw InputError("", option, v, "a value written into an #SBATCH line cannot hold '\"' or control characters");
  return v.find_first_of(" \t") == std::string::npos && !v.empty() ? v : "\"" + v + "\"";
}

void require_chars(const std::string& v, const std::string& option, const std::string& allowed, const std::string& what) {
  if (v.empty() || v.find_first_not_of(allowed) != std::string::npos)
    throw InputError("", option, v, "expected " + what);
}
}  // namespace

SlurmFiles slurm_scripts(const Pipeline& p, const SlurmOptions& o) {
  if (!p.adaptive.empty())  // the shards could not share the decisions of adaptive replicas
    throw InputError(p.adaptive[0].where.str(), "steps." + p.adaptive[0].step + ".replicas", "until",
                     "adaptive replicas are decided as replicas finish: run the pipeline without shards");
  const int leaves = static_cast<int>(sweep_leaves(p).size());
  if (leaves == 0)
    throw InputError(p.file, "matrix", "", "nothing to shard: the pipeline has no matrix:, cases: or replicas:");
  int shards = o.shards > 0 ? o.shards : std::min(leaves, 1000);
  int cpus = o.cpus;
  for (const auto& in : p.instances) cpus = o.cpus > 0 ? cpus : std::max(cpus, in.threads);
  // MPI steps run under srun inside the job (the runner picks srun where SLURM_JOB_ID is set),
  // so each job asks for the largest rank count as tasks, each with `cpus` cores.
  int ranks = 1;
  for (const auto& in : p.instances) ranks = std::max(ranks, in.ranks);
  const std::string ntasks = ranks > 1 ? "--ntasks=" + std::to_string(ranks) : "";
  const fs::path file = fs::absolute(p.file).lexically_normal();
  const std::string stem = file.stem().string();
  const std::string logs = fs::absolute(p.logs_dir).lexically_normal().string();
  // Every value is data: shell-quoted in the scripts' commands, checked on #SBATCH lines.
  require_chars(o.time, "--time", "0123456789:-", "a Slurm time such as 04:00:00 or 1-12:00:00");
  if (!o.partition.empty())
    require_chars(o.partition, "--partition", "abcdefghijklmnopqrstuvwxyzABCDEFGHIJKLMNOPQRSTUVWXYZ0123456789_.,-",
                  "partition names (letters, digits, '_', '.', '-', commas between several)");
  const std::string job = sbatch_value(stem, "pipeline file name");
  const std::string run = o.runner + " " + shell_quote(file.string());
  const std::string part = o.partition.empty() ? "" : "#SBATCH --partition=" + o.partition + "\n";
  SlurmFiles f;
  f.array_path = (file.parent_path() / (stem + ".array.sbatch")).string();
  f.submit_path = (file.parent_path() / (stem + ".submit.sh")).string();
  std::ostringstream a;
  // The comment lines hold only names without control characters (a newline would end them).
  a << "#!/bin/bash\n"
    << "# Generated by `tomodem-run export slurm` from " << job << ".\n"
    << "# One array task per shard of the sweep; at most " << o.limit << " run at once.\n"
    << "# Submit with the .submit.sh beside it (shared upstream steps, then this array, then the gather).\n"
    << "#SBATCH --job-name=" << job << "\n"
    << "#SBATCH --array=1-" << shards << "%" << o.limit << "\n"
    << (ntasks.empty() ? "" : "#SBATCH " + ntasks + "\n") << "#SBATCH --cpus-per-task=" << cpus << "\n"
    << "#SBATCH --time=" << o.time << "\n"
    << part << "#SBATCH --output=" << sbatch_value(logs + "/slurm-%A_%a.out", "logs") << "\n"
    << "set -euo pipefail\n"
    << "exec " << run << " --shard \"${SLURM_ARRAY_TASK_ID}/" << shards << "\" --jobs \"${SLURM_CPUS_PER_TASK:-" << cpus
    << "}\" --quiet\n";
  f.array_script = a.str();
  const std::string common = (ntasks.empty() ? "" : " " + ntasks) + " --cpus-per-task=" + std::to_string(cpus) + " --time=" + o.time +
                             (o.partition.empty() ? "" : " --partition=" + o.partition);
  std::ostringstream s;
  s << "#!/bin/bash\n"
    << "# Generated by `tomodem-run export slurm`: submits the shared upstream steps (--shard 0/" << shards
    << "),\n# then the job array (" << shards << " shards), then the gather run that collects the results.\n"
    << "set -euo pipefail\n"
    << "mkdir -p " << shell_quote(logs) << "\n"
    << "shared=$(sbatch --parsable " << shell_quote("--job-name=" + stem + "-shared") << common
    << " --output=" << shell_quote(logs + "/slurm-shared-%j.out")
    << " --wrap=" << shell_quote(run + " --shard 0/" + std::to_string(shards) + " --jobs " + std::to_string(cpus) + " --quiet")
    << ")\n"
    << "array=$(sbatch --parsable --dependency=afterok:${shared} " << shell_quote(f.array_path) << ")\n"
    << "gather=$(sbatch --parsable --dependency=afterok:${array} " << shell_quote("--job-name=" + stem + "-gather") << common
    << " --output=" << shell_quote(logs + "/slurm-gather-%j.out") << " --wrap=" << shell_quote(run + " --jobs " + std::to_string(cpus))
    << ")\n"
    << "echo \"submitted: shared ${shared}, array ${array} (" << shards << " tasks), gather ${gather}\"\n";
  f.submit_script = s.str();
  return f;
}

std::string summary_json(const Pipeline& p, const RunSummary& s) {
  Summary j("tomodem-run");  // the common keys (docs/cli.md "Summary")
  j.input(p.file);
  j.output("lock_file", p.lock_file);
  j["pipeline"] = p.file;
  j["lock_file"] = p.lock_file;
  j["wall_s"] = s.wall_s;
  j["ran"] = s.ran;
  j["up_to_date"] = s.up_to_date;
  j["would_run"] = s.would_run;
  j["failed"] = s.failed;
  j["skipped"] = s.skipped;
  j["interrupted"] = s.interrupted;
  j["files_hashed"] = s.files_hashed;
  j["steps"] = nlohmann::json::array();
  for (std::size_t i = 0; i < s.steps.size(); ++i) {
    const auto& r = s.steps[i];
    nlohmann::json outs = nlohmann::json::array();
    for (const auto& o : p.instances[i].outs) outs.push_back(o.second);
    j["steps"].push_back({{"id", r.id}, {"state", r.state}, {"reason", r.reason}, {"seconds", r.seconds},
                          {"exit_code", r.exit_code}, {"log", r.log}, {"outs", outs}});
  }
  return j.text();
}

std::string summary_text(const RunSummary& s) {
  std::ostringstream o;
  o.precision(3);
  if (s.would_run || (!s.ran && !s.failed && !s.skipped && !s.would_run))
    o << s.would_run << " would run, " << s.up_to_date << " up to date\n";
  else
    o << s.ran << " ran, " << s.up_to_date << " up to date, " << s.failed << " failed, " << s.skipped
      << " skipped in " << s.wall_s << " s" << (s.interrupted ? " (interrupted)" : "") << "\n";
  for (const auto& r : s.steps)
    if (r.state == "failed") o << "  failed  " << r.id << ": " << r.reason << " (log: " << r.log << ")\n";
  for (const auto& r : s.steps)
    if (r.state == "skipped") o << "  skipped " << r.id << ": " << r.reason << "\n";
  return o.str();
}

}  // namespace tomodem::pipeline
