// Starting the MPI steps of a pipeline (`ranks: N`): which launcher, and its command line.
// The launcher is the machine's business, not the pipeline's, so the same file runs on a laptop
// (mpirun) and in a Slurm job (srun) unchanged.
#include <cstdlib>
#include <sstream>

#include "tomodem/pipeline/run.hpp"

namespace tomodem::pipeline {

Launcher make_launcher(const char* tomodem_mpirun, const char* slurm_job_id) {
  Launcher l;
  if (tomodem_mpirun) {
    std::istringstream words(tomodem_mpirun);
    for (std::string w; words >> w;) l.words.push_back(w);
  }
  if (l.words.empty()) l.words = {slurm_job_id && *slurm_job_id ? "srun" : "mpirun"};
  const std::string& first = l.words.front();
  l.srun = first == "srun" || (first.size() > 5 && first.compare(first.size() - 5, 5, "/srun") == 0);
  return l;
}

Launcher launcher_from_env() { return make_launcher(std::getenv("TOMODEM_MPIRUN"), std::getenv("SLURM_JOB_ID")); }

std::vector<std::string> launch_argv(const Instance& in, const Launcher& launcher) {
  if (in.ranks <= 1) return in.argv;
  std::vector<std::string> argv = launcher.words;
  if (launcher.srun) {
    // srun places the tasks in the job's allocation; -c gives each rank its threads' cores.
    argv.insert(argv.end(), {"-n", std::to_string(in.ranks), "-c", std::to_string(in.threads)});
  } else {
    // mpirun passes its environment (OMP_NUM_THREADS, TOMODEM_THREADS) to the local ranks.
    argv.insert(argv.end(), {"-np", std::to_string(in.ranks)});
  }
  argv.insert(argv.end(), in.argv.begin(), in.argv.end());
  return argv;
}

}  // namespace tomodem::pipeline
