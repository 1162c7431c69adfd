#include "tomodem/core/tool.hpp"

#include <unistd.h>

#include <cstdlib>
#include <fstream>
#include <iostream>
#include <iterator>
#include <thread>
#include <algorithm>
#include <optional>
#include <vector>

#include "tomodem/core/error.hpp"
#include "tomodem/core/output.hpp"
#include "git_hash.hpp"

#ifdef TOMODEM_HAVE_MPI
// The C API only: core links MPI::MPI_C (the C++ bindings would need MPI::MPI_CXX).
#define OMPI_SKIP_MPICXX 1
#define MPICH_SKIP_MPICXX 1
#include <mpi.h>
#endif

namespace tomodem {

namespace {
bool g_quiet = false;
std::string g_tool = "tomodem";
}  // namespace

std::string version_string() {
  return std::string("tomodem ") + TOMODEM_VERSION + " (git " + git_hash() + ")";
}

void set_quiet(bool q) { g_quiet = q; }
// A silent rank (output.hpp, writes_outputs) says nothing: rank 0 says it once.
bool quiet() { return g_quiet || !writes_outputs(); }
void info(const std::string& m) {
  if (!quiet()) std::cerr << g_tool << ": " << m << '\n';
}
void warn(const std::string& m) {
  if (writes_outputs()) std::cerr << g_tool << ": warning: " << m << '\n';
}
const std::string& tool_name() { return g_tool; }

namespace {
std::string g_command_line;
}  // namespace

namespace {
// One word of a command line, quoted where the shell would need it.
std::string shell_word(const std::string& word) {
  const bool plain = !word.empty() && word.find_first_not_of(
      "abcdefghijklmnopqrstuvwxyzABCDEFGHIJKLMNOPQRSTUVWXYZ0123456789-_./=,:+@%") == std::string::npos;
  if (plain) return word;
  std::string q = "'";
  for (char c : word) q += c == '\'' ? std::string("'\\''") : std::string(1, c);
  return q + "'";
}
}  // namespace

void set_command_line(int argc, char** argv) {
  std::string s;
  for (int k = 0; k < argc; ++k) s += (k ? " " : "") + shell_word(argv[k]);
  g_command_line = s;
}

const std::string& command_line() {
  // Not recorded (a library call outside a tool's main): this process's own, from /proc.
  if (g_command_line.empty()) {
    std::ifstream in("/proc/self/cmdline", std::ios::binary);
    const std::string all((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    for (std::size_t b = 0, e; b < all.size(); b = e + 1) {
      e = all.find('\0', b);
      if (e == std::string::npos) e = all.size();
      g_command_line += (b ? " " : "") + shell_word(all.substr(b, e - b));
    }
  }
  return g_command_line;
}

int all_threads() {
  if (const char* s = std::getenv("OMP_NUM_THREADS")) {
    const int n = std::atoi(s);  // "4,2": the first level's count
    if (n > 0) return n;
  }
  // Several ranks on one node share its cores: each takes its part (OpenMPI and MPICH say how many
  // ranks run on this node), so an MPI + OpenMP run does not start ranks x cores threads.
  int ranks_here = 1;
  for (const char* name : {"OMPI_COMM_WORLD_LOCAL_SIZE", "MPI_LOCALNRANKS"})
    if (const char* s = std::getenv(name)) ranks_here = std::max(ranks_here, std::atoi(s));
  return std::max(1, int(std::thread::hardware_concurrency()) / ranks_here);
}

namespace {
// How long an idle OpenMP thread spins before it sleeps. libgomp's default (300 000 spins) and
// OMP_WAIT_POLICY=ACTIVE take the cores from the other threads when two runs share a machine;
// PASSIVE (no spin) makes every DEM step pay a futex wake-up. Measured on the 2-core machine,
// scene A 8000 spheres, 2 threads (docs/benchmarks.md, "Waiting threads"): 1000 spins costs 10 %
// alone and is 1.5 to 5 times faster than the default with two runs at once. libgomp reads the
// setting once, when it is loaded, so a tool started without one sets it and starts itself again
// with the same arguments (/proc/self/cmdline). A setting the user made is kept.
void spin_briefly_unless_told() {
  if (std::getenv("OMP_WAIT_POLICY") || std::getenv("GOMP_SPINCOUNT")) return;
  std::ifstream in("/proc/self/cmdline", std::ios::binary);
  const std::string all((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  if (all.empty()) return;
  std::vector<std::string> words;
  for (std::size_t b = 0, e; b < all.size(); b = e + 1) {
    e = all.find('\0', b);
    if (e == std::string::npos) e = all.size();
    words.push_back(all.substr(b, e - b));
  }
  std::vector<char*> argv;
  for (auto& w : words) argv.push_back(w.data());
  argv.push_back(nullptr);
  ::setenv("GOMP_SPINCOUNT", "1000", 1);
  std::cout.flush();
  std::cerr.flush();
  ::execv("/proc/self/exe", argv.data());
  // exec failed (no /proc): go on with the runtime's default.
}
}  // namespace

namespace {
int env_int(const char* name, int fallback) {
  const char* s = std::getenv(name);
  return s && *s ? std::atoi(s) : fallback;
}

// What the running tool declared in its run_tool call (docs/scaling.md lists which tools do).
RankUse g_ranks = RankUse::one_rank;
}  // namespace

// OpenMPI's mpirun (OMPI_COMM_WORLD_SIZE), MPICH's Hydra and srun --mpi=pmi2 (PMI_SIZE), srun
// itself (SLURM_STEP_NUM_TASKS; not SLURM_NTASKS, which a batch script with --ntasks also has,
// and from which tomodem-run starts serial steps).
int launched_ranks() {
  return std::max({env_int("OMPI_COMM_WORLD_SIZE", 1), env_int("PMI_SIZE", 1), env_int("SLURM_STEP_NUM_TASKS", 1)});
}
// A launcher's rank counts only where its job has more than one (a serial step inside one task of
// a Slurm job keeps rank 0).
int launched_rank() {
  int rank = 0;
  if (env_int("OMPI_COMM_WORLD_SIZE", 1) > 1) rank = std::max(rank, env_int("OMPI_COMM_WORLD_RANK", 0));
  if (env_int("PMI_SIZE", 1) > 1) rank = std::max(rank, env_int("PMI_RANK", 0));
  if (env_int("SLURM_STEP_NUM_TASKS", 1) > 1) rank = std::max(rank, env_int("SLURM_PROCID", 0));
  return rank;
}

std::string build_features(const std::string& tool) {
#ifdef TOMODEM_HAVE_MPI
  if (tool.empty()) return "openmp mpi petsc";
  return (tool == g_tool && g_ranks == RankUse::shared) ? "openmp mpi petsc" : "openmp petsc";
#else
  (void)tool;
  return "openmp";
#endif
}

namespace {
// A tool started by a launcher on several ranks that cannot share one run among them (a build
// without MPI, or a tool that does not declare RankUse::shared) would run that many copies of
// the serial run, all writing the same outputs. Refused on every rank, said once, by rank 0.
std::optional<int> refuse_copies_on_ranks(const std::string& tool, RankUse use) {
  const int size = launched_ranks();
#ifdef TOMODEM_HAVE_MPI
  if (use == RankUse::shared || size <= 1) return std::nullopt;
#else
  (void)use;
  if (size <= 1) return std::nullopt;
#endif
  if (launched_rank() == 0) {
#ifdef TOMODEM_HAVE_MPI
    std::cerr << tool << ": error: " << tool << " does not run on several ranks yet (started on " << size
              << "; only dem, young, fracture and conduct share one run among ranks, docs/scaling.md): run it on one rank\n";
#else
    std::cerr << tool << ": error: this build has no MPI: started on " << size
              << " ranks, it would run that many copies of the serial run; configure with -DTOMODEM_MPI=ON, "
                 "or run it on one rank\n";
#endif
  }
  return exit_code::bad_input;
}

#ifdef TOMODEM_HAVE_MPI
void finalize_mpi_at_exit() {
  int done = 0;
  MPI_Finalized(&done);
  if (!done) MPI_Finalize();
}
#endif

/// A shared tool on several ranks: MPI is started here, before the tool's body (PETSc starts on
/// top of it; PETSc's own finalisation, registered later, runs first at exit).
bool start_ranks(RankUse use) {
#ifdef TOMODEM_HAVE_MPI
  if (use != RankUse::shared || launched_ranks() <= 1) return false;
  int started = 0;
  MPI_Initialized(&started);
  if (!started) {
    int provided = 0;
    MPI_Init_thread(nullptr, nullptr, MPI_THREAD_FUNNELED, &provided);
    std::atexit(finalize_mpi_at_exit);
  }
  return true;
#else
  (void)use;
  return false;
#endif
}

/// A failure on one rank of a shared run: the others may wait in a collective this rank never
/// reaches, so the whole job ends with the exit code (after the message is out).
[[noreturn]] void abort_ranks(int code) {
#ifdef TOMODEM_HAVE_MPI
  std::cerr.flush();
  MPI_Abort(MPI_COMM_WORLD, code);
#endif
  std::_Exit(code);
}
}  // namespace

int run_tool(const std::string& tool_name, const std::function<int()>& body, RankUse ranks, OutputCommit commit) {
  if (const auto refused = refuse_copies_on_ranks(tool_name, ranks)) return *refused;
  spin_briefly_unless_told();
  g_tool = tool_name;
  g_ranks = ranks;
  install_cleanup_handlers();
  const bool on_ranks = start_ranks(ranks);
  const bool speaks = !on_ranks || launched_rank() == 0;
  const std::string who = on_ranks ? tool_name + " (rank " + std::to_string(launched_rank()) + ")" : tool_name;
  // However the body ends, a temporary it did not commit must not stay behind.
  struct Cleanup {
    ~Cleanup() {
      discard_pending_outputs();
      remove_registered_temporaries();
    }
  } cleanup;
  if (commit == OutputCommit::together) defer_commits();
  try {
    const int code = body();
    commit_pending_outputs();
    return code;
  } catch (const InputError& e) {
    if (speaks) std::cerr << tool_name << ": error: " << e.what() << '\n';
    return exit_code::bad_input;
  } catch (const NumericalError& e) {
    std::cerr << who << ": numerical failure: " << e.what() << '\n';
    if (on_ranks) remove_registered_temporaries(), abort_ranks(exit_code::numerical);
    return exit_code::numerical;
  } catch (const std::exception& e) {
    std::cerr << who << ": failure: " << e.what() << '\n';
    if (on_ranks) remove_registered_temporaries(), abort_ranks(exit_code::failure);
    return exit_code::failure;
  }
}

}  // namespace tomodem
