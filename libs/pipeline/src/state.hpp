#pragma once
// The lock file (the record of the last successful run of each instance) and staleness rules.
// Private to libs/pipeline.
#include <map>
#include <string>
#include <vector>

#include "tomodem/pipeline/pipeline.hpp"
#include "tomodem/pipeline/run.hpp"

namespace tomodem::pipeline::detail {

struct LockEntry {
  std::string command, version;
  std::map<std::string, std::string> params;
  std::map<std::string, std::string> deps, outs;  // path -> XXH3-128 hex
  std::string started, finished;
  double seconds = 0;
  // Provenance only, not in the signature: MPI ranks give the serial result to round-off.
  int ranks = 1;
  std::string launch;  // "mpirun -np 4" ("" for a serial step)
};

struct FailureRecord {
  int exit_code = 0;
  std::string finished, reason, log;
};

struct LockFile {
  std::map<std::string, LockEntry> steps;
  std::map<std::string, FailureRecord> failures;
};

/// Reads `path` (if it exists) into `lock` and `cache`, its entries replacing earlier ones.
/// A lock file that cannot be parsed is an InputError naming it.
void merge_lock(const std::string& path, LockFile& lock, HashCache& cache);
/// JSON text of the lock, with the stat cache (pruned to files that still exist).
std::string lock_json(const LockFile& lock, HashCache& cache);
/// The shard lock files (<stem>.lock.shard-K.json) next to the main one.
std::vector<std::string> shard_lock_files(const Pipeline& p);
std::string shard_lock_file(const Pipeline& p, int shard);
/// Main lock plus every shard lock.
void load_all_locks(const Pipeline& p, LockFile& lock, HashCache& cache);

struct Verdict {
  bool stale = false;
  std::vector<std::string> reasons;
  std::vector<std::string> notes;  // what differs without making the step stale (explain prints them)
};

/// Why `in` must run given its record `e` (nullptr: none). With `all`, every reason; otherwise
/// it stops at the first (and skips hashing when a cheaper rule already says "run"). A tool step
/// made by another build of the same release is up to date unless `rerun_on_rebuild`.
Verdict check(const Instance& in, const LockEntry* e, HashCache& cache, bool all, bool rerun_on_rebuild = false);

/// A tool's `--version` line without its build part: "tomodem 0.9.0 (git 1a2b3c)" -> "tomodem 0.9.0".
std::string release_of(const std::string& version);

/// A record of a successful run: hashes of the inputs and outputs as they are now.
LockEntry record(const Instance& in, HashCache& cache, const std::string& started, double seconds);

/// Log file of an instance.
std::string log_path(const Pipeline& p, const Instance& in);

}  // namespace tomodem::pipeline::detail
