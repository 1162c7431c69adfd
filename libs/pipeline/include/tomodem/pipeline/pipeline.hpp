#pragma once
// Pipeline files: loading, expansion of sweeps into step instances, and the build graph.
// The file format is described in docs/pipelines.md. yaml-cpp stays inside the .cpp files.
#include <map>
#include <string>
#include <utility>
#include <vector>

namespace tomodem::pipeline {

/// Where something was declared: "file:line".
struct Location {
  std::string file;
  int line = 0;
  std::string str() const { return line > 0 ? file + ":" + std::to_string(line) : file; }
};

/// A named path (the name is the map key in the file, or the list index "0", "1", ...).
using NamedPaths = std::vector<std::pair<std::string, std::string>>;

/// One runnable unit: a step, or one cell of a step's sweep.
struct Instance {
  std::string id;                            // "pack" or "pack[d0.5_r1]"
  std::string step;                          // "pack"
  std::string cell;                          // "" for a step without a sweep
  std::map<std::string, std::string> matrix; // cell values, e.g. density -> 0.5
  std::string tool;                          // "" for a `cmd:` step
  std::vector<std::string> argv;             // what is executed (tool path + args, or sh -c cmd)
  std::string command;                       // the command line as recorded in the lock file
  std::string version;                       // tool --version output, or the step's `version:`
  NamedPaths deps;                           // inputs, relative to the pipeline folder
  NamedPaths outs;                           // outputs, relative to the pipeline folder
  std::map<std::string, std::string> params; // flattened "a.b" -> scalar text
  int threads = 1;                           // per rank
  int ranks = 1;                             // MPI ranks (`ranks:`); > 1 starts it through a launcher
  int replica = -1;                          // ${replica}, or -1 for a step without `replicas:`
  std::vector<std::size_t> upstream;         // indices of instances whose outputs this one reads
  Location where;                            // the step's declaration
};

struct LoadOptions {
  /// --set KEY=VALUE: "name" or "vars.name" sets a variable; "steps.S.params.K" a step param.
  std::vector<std::string> overrides;
  /// Folder searched first for tomodem-<tool> executables ("" = beside this executable).
  std::string tool_dir;
  /// Check that inputs no step produces exist (off for `dot` and `export`, which run nothing).
  bool check_inputs = true;
  /// Adaptive replicas: how many replicas each group (ReplicaGroup::id) has now. Without
  /// `use_counts`, the counts of the last run's record (<stem>.replicas.json), else `min`; such a
  /// load also expands every adaptive step to `max` first, so bad input is found before any round.
  std::map<std::string, int> replica_counts;
  bool use_counts = false;
};

/// `replicas: {until: {KEY: target, ...}, min: M, max: X, batch: B}` of one step: replicas are
/// added until the relative 95 % half-width of the mean of every KEY (read from the step's JSON
/// outputs) is at most its target, or X replicas ran; B per group and round (`projected`: half
/// of what the current spread says is missing).
struct Adaptive {
  std::string step;
  std::vector<std::pair<std::string, double>> until;
  std::vector<Location> until_where;
  int min = 0, max = 0;
  int batch = 1;  ///< replicas added per group and round; 0: `projected`
  Location where;
};

/// The replicas of one cell of an adaptive step (its cell without the replica).
struct ReplicaGroup {
  std::string id;                            // "draw[level=a]"; the step name when it has no sweep
  std::size_t adaptive = 0;                  // index into Pipeline::adaptive
  std::map<std::string, std::string> matrix; // the cell's values, without the replica
  std::vector<std::size_t> instances;        // by replica: 0 .. count-1
};

struct Pipeline {
  std::string file;       // the pipeline file as given
  std::string dir;        // its folder: commands run there, paths are relative to it
  std::string lock_file;  // <stem>.lock.json next to the pipeline file
  std::string logs_dir;   // <stem>.logs/ next to the pipeline file (or `logs:` in the file)
  std::string replicas_file;  // <stem>.replicas.json: the runner's record of adaptive replicas
  std::vector<std::string> steps;   // step names in declaration order
  std::vector<Instance> instances;  // in a topological order (upstream first)
  std::vector<Adaptive> adaptive;   // steps with adaptive replicas
  std::vector<ReplicaGroup> groups; // their cells, with the replicas expanded now
  std::vector<std::string> warnings;  // what loads but is likely a mistake (tomodem-run prints them)
  LoadOptions options;              // as loaded, so the runner can expand it again
};

/// Reads, expands and validates a pipeline. Throws tomodem::InputError (exit 2) naming the
/// file, line and name for: unknown keys, unknown step/output/variable references, cycles, two
/// instances writing one output, missing input files, unknown tools.
Pipeline load(const std::string& file, const LoadOptions& options = {});

/// Indices of the instances selected by a name: a step name (all its cells) or an instance id.
/// Throws InputError when nothing matches.
std::vector<std::size_t> select(const Pipeline& p, const std::string& name);

}  // namespace tomodem::pipeline
