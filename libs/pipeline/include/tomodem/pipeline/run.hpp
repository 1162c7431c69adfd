#pragma once
// Staleness, execution, sharding and reports over a loaded Pipeline.
#include <cstdint>
#include <iosfwd>
#include <map>
#include <string>
#include <vector>

#include "tomodem/pipeline/pipeline.hpp"

namespace tomodem::pipeline {

// ---- content hashes with a stat cache -------------------------------------------------------

/// XXH3-128 hashes of files (and folders: hash over the sorted file names and hashes), cached by
/// (size, mtime in ns, inode) so an unchanged file is not read again.
class HashCache {
 public:
  struct Entry {
    std::string hash;
    std::int64_t size = 0, mtime_ns = 0;
    std::uint64_t inode = 0;
    // Status-change time, as git keeps it: `touch -r` can put an old mtime back, not an old ctime.
    // 0 (a lock file written before ctime was kept) never matches, so the file is read again.
    std::int64_t ctime_ns = 0;
  };
  /// "" when the path does not exist. Relative paths are taken from `root`, and are the keys.
  std::string hash(const std::string& path);
  std::string root = ".";
  /// How many files were actually read (for tests and the summary).
  int files_hashed() const { return hashed_; }
  std::map<std::string, Entry> entries;

 private:
  int hashed_ = 0;
};

// ---- shards ---------------------------------------------------------------------------------

/// Owner of each instance for `--shard K/N`: K in 1..N for the slice that alone needs it,
/// 0 for upstream instances that several slices share (run by `--shard 0/N` first), and -1 for
/// instances downstream of the sweep (the gather: run by the plain run afterwards).
/// The sweep's leaves (cells with no sweep cell downstream) are cut into N contiguous blocks.
std::vector<int> shard_owners(const Pipeline& p, int n);

/// "K/N" -> {K, N}; throws InputError unless 0 <= K <= N, N >= 1.
std::pair<int, int> parse_shard(const std::string& text);

// ---- running --------------------------------------------------------------------------------

struct RunOptions {
  int jobs = 1;                     // slots; a step takes min(threads, jobs) of them
  std::vector<std::string> force;   // steps or instance ids to run even when up to date
  bool force_all = false;
  bool dry_run = false;             // say what would run and why; run nothing
  bool keep_going = false;          // after a failure, go on with steps that do not depend on it
  int shard = -1, shards = 0;       // --shard K/N (shard < 0: everything)
  bool quiet = false;
  bool rerun_on_rebuild = false;    // a tool built from another commit of the same release is stale too
};

struct StepResult {
  std::string id;
  std::string state;   // "ran", "up-to-date", "would-run", "failed", "skipped", "not-in-shard"
  std::string reason;  // why it ran / failed / was skipped
  double seconds = 0;
  int exit_code = 0;
  std::string log;     // log file of this run
};

struct RunSummary {
  std::vector<StepResult> steps;  // in the pipeline's instance order
  int ran = 0, up_to_date = 0, failed = 0, skipped = 0, would_run = 0;
  int files_hashed = 0;
  double wall_s = 0;
  bool interrupted = false;
  int exit_code() const { return interrupted || failed || skipped ? 1 : 0; }
};

/// Brings the pipeline up to date. Progress lines go to `progress` ("[k/N] ..."). The lock
/// file is rewritten after every finished step, so a killed run resumes where it stopped.
RunSummary run(const Pipeline& p, const RunOptions& options, std::ostream& progress);

/// What `run` would do, without running anything (state "would-run" or "up-to-date").
RunSummary status(const Pipeline& p, const RunOptions& options);

/// Every reason each instance of `name` is stale (changed input, param old -> new, command,
/// version, missing/modified output), with its command and files; notes on what differs without
/// making it stale (a tool of another build).
std::string explain(const Pipeline& p, const std::string& name, const RunOptions& options = {});

/// Graphviz DOT of the instances; stale ones are filled.
std::string dot(const Pipeline& p);

/// The JSON summary (`--json FILE`).
std::string summary_json(const Pipeline& p, const RunSummary& s);

/// A few lines for the terminal: counts, then each failed or skipped step and why.
std::string summary_text(const RunSummary& s);

// ---- MPI steps (`ranks: N`) ---------------------------------------------------------------

/// How a step with `ranks: N > 1` is started (docs/pipelines.md, "MPI steps"): the launcher's
/// words, then the rank count in its own flags, then the step's command.
struct Launcher {
  std::vector<std::string> words;  // {"mpirun"}, {"srun"}, or TOMODEM_MPIRUN split at blanks
  bool srun = false;               // the first word is srun: `-n N -c T`, else `-np N`
};

/// TOMODEM_MPIRUN when set and not blank (e.g. "mpirun --oversubscribe"); else `srun` inside a
/// Slurm job (SLURM_JOB_ID set: the Slurm export's jobs); else `mpirun`. Null means unset.
Launcher make_launcher(const char* tomodem_mpirun, const char* slurm_job_id);
/// The same, from this process's environment.
Launcher launcher_from_env();

/// What is executed for `in`: in.argv itself when in.ranks <= 1, else the launcher's words, the
/// rank count (and for srun the threads per rank) and in.argv.
std::vector<std::string> launch_argv(const Instance& in, const Launcher& launcher);

// ---- Slurm ----------------------------------------------------------------------------------

struct SlurmOptions {
  int shards = 0;          // 0: one per sweep leaf, at most 1000
  int limit = 8;           // array concurrency (`%` in --array)
  int cpus = 0;            // --cpus-per-task (0: the largest `threads` of a step)
                           // --ntasks: the largest `ranks` of a step (when > 1)
  std::string time = "04:00:00";
  std::string partition;   // "" = the cluster's default
  std::string runner = "tomodem-run";
};

struct SlurmFiles {
  std::string array_path, array_script;    // sbatch job array: one task per shard
  std::string submit_path, submit_script;  // submits shared -> array -> gather with dependencies
};

/// The scripts for `export slurm` (paths next to the pipeline file; nothing is written).
SlurmFiles slurm_scripts(const Pipeline& p, const SlurmOptions& o);

}  // namespace tomodem::pipeline
