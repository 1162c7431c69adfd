#pragma once
// Shared main() behaviour of the tomodem executables: exit codes, error messages, --version.
#include <functional>
#include <string>

namespace tomodem {

/// "tomodem 0.1.0 (git abc123)".
std::string version_string();

/// Whether a tool shares one run among the ranks it is started on (declared in its run_tool call).
enum class RankUse {
  one_rank,  ///< the default: started on several ranks it refuses (exit 2) instead of running N copies
  shared     ///< one job across the ranks (young, fracture, conduct: PETSc rows; dem: domain decomposition)
};

/// What this build (and `tool`, when named) can do, for the second line of every tool's --version:
/// "openmp"; with -DTOMODEM_MPI=ON "openmp mpi petsc", where `mpi` is said by a tool only when it
/// is the running tool and declared RankUse::shared in its run_tool call. tomodem-run reads it
/// before it starts a step on several ranks.
std::string build_features(const std::string& tool = "");

/// Ranks this process was started on by a launcher (mpirun, srun; 1 without one), and its rank,
/// from the launcher's environment (no MPI call).
int launched_ranks();
int launched_rank();

/// Runs `body` and maps exceptions onto the documented exit codes, printing one clear line:
///   InputError -> 2 ("tomodem-dem: error: scene.yaml: field 'x': value 'y': why")
///   NumericalError -> 3, anything else -> 1.
/// A build without MPI started on several ranks (mpirun, srun) exits 2 at once, rank 0 saying why;
/// so does a tool that does not declare RankUse::shared. A shared tool started on several ranks
/// in the MPI build gets MPI initialised before `body` (finalised at exit); an InputError (the
/// same on every rank: bad input is found before the ranks part) is printed by rank 0 only, any
/// other failure by the rank that failed, which then aborts the job with the exit code, so no
/// rank waits forever in a collective the failed one never reaches.
/// A tool's outputs appear together when `body` returns (whatever code it returns): their renames
/// wait until then (core/output.hpp), and a body that throws leaves none of them. A tool that
/// keeps records as it goes (tomodem-run: its lock file after each step) asks for as_written.
enum class OutputCommit { together, as_written };
int run_tool(const std::string& tool_name, const std::function<int()>& body, RankUse ranks = RankUse::one_rank,
             OutputCommit commit = OutputCommit::together);

/// Messages on stderr; info is silenced by set_quiet(true).
void set_quiet(bool quiet);
bool quiet();
void info(const std::string& message);
void warn(const std::string& message);
/// The name messages start with ("tomodem-dem"; set by run_tool).
const std::string& tool_name();

/// The command line as typed, for provenance (recorded by cli::parse; words with spaces or
/// shell characters in single quotes).
void set_command_line(int argc, char** argv);
const std::string& command_line();

/// What --threads 0 means (docs/cli.md): OMP_NUM_THREADS when set (its first number), else every
/// core of the machine, shared out among the MPI ranks running on it.
int all_threads();

}  // namespace tomodem
