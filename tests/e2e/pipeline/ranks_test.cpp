// End-to-end tests of MPI steps (`ranks: N`) in tomodem-run, and of a serial build's tools
// started on several ranks. The launcher is a stand-in script (TOMODEM_MPIRUN) that records its
// arguments and starts the command once per rank with the variables OpenMPI's mpirun sets, so
// the test needs no MPI and checks exactly what a real launcher would be given.
#include <gtest/gtest.h>
#include <sys/stat.h>
#include <sys/wait.h>

#include <cstdlib>
#include <filesystem>
#include <string>

#include "../../unit/pipeline/scratch.hpp"

using tomodem::test::Scratch;

namespace {
const std::string kBin = TOMODEM_BIN_DIR;

struct Result {
  int code = -1;
  std::string err;
};

Result sh(const Scratch& s, const std::string& cmd) {
  const std::string full = "cd '" + s.dir + "' && " + cmd + " > .stdout 2> .stderr";
  const int st = std::system(full.c_str());
  return {WIFEXITED(st) ? WEXITSTATUS(st) : -1, s.read(".stderr")};
}

// fake-mpirun -np N CMD...: writes "-np N CMD..." to launch.txt, runs CMD N times as ranks 0..N-1.
std::string fake_launcher(const Scratch& s) {
  const std::string path = s.write("fake-mpirun",
                                   "#!/bin/sh\n"
                                   "echo \"$*\" > \"$(dirname \"$0\")/launch.txt\"\n"
                                   "[ \"$1\" = -np ] || exit 99\n"
                                   "n=$2; shift 2; k=0; rc=0\n"
                                   "while [ $k -lt $n ]; do\n"
                                   "  OMPI_COMM_WORLD_SIZE=$n OMPI_COMM_WORLD_RANK=$k \"$@\" || rc=$?\n"
                                   "  k=$((k + 1))\n"
                                   "done\n"
                                   "exit $rc\n");
  ::chmod(path.c_str(), 0755);
  return path;
}

const char* kPipeline = R"(vars: {ranks: 2}
steps:
  sim:
    ranks: ${vars.ranks}
    threads: 1
    cmd: echo "rank $OMPI_COMM_WORLD_RANK of $OMPI_COMM_WORLD_SIZE threads $OMP_NUM_THREADS" >> ranks.txt && touch ${outs.0}
    outs: [sim.done]
  after:
    cmd: echo "$OMPI_COMM_WORLD_SIZE" > ${outs.0}
    deps: ['${steps.sim.outs.0}']
    outs: [after.txt]
)";
}  // namespace

TEST(Ranks, StepRunsThroughTheLauncherAndRanksIsProvenanceNotSignature) {
  Scratch s;
  const std::string launcher = fake_launcher(s);
  s.write("p.yaml", kPipeline);
  const std::string run = "TOMODEM_MPIRUN='" + launcher + "' '" + kBin + "/tomodem-run' p.yaml -j 2";
  const auto r = sh(s, run);
  ASSERT_EQ(r.code, 0) << r.err;
  // The launcher got -np 2 and the step's shell command; each rank ran it once.
  EXPECT_EQ(s.read("launch.txt").rfind("-np 2 /bin/sh -c echo", 0), 0u) << s.read("launch.txt");
  EXPECT_EQ(s.read("ranks.txt"), "rank 0 of 2 threads 1\nrank 1 of 2 threads 1\n");
  EXPECT_EQ(s.read("after.txt"), "\n");  // the serial step is started directly, not by the launcher
  const std::string lock = s.read("p.lock.json");
  EXPECT_NE(lock.find("\"launch\": \"" + launcher + " -np 2\""), std::string::npos) << lock;
  EXPECT_NE(lock.find("\"ranks\": 2"), std::string::npos) << lock;
  EXPECT_NE(s.read("p.logs/sim.log").find("# " + launcher + " -np 2 echo"), std::string::npos) << s.read("p.logs/sim.log");
  // Another rank count gives the same result (issue 22 item 2), so the step stays up to date.
  const auto again = sh(s, run + " --set ranks=3 --json summary.json");
  ASSERT_EQ(again.code, 0) << again.err;
  EXPECT_NE(s.read("summary.json").find("\"ran\": 0"), std::string::npos) << s.read("summary.json");
  EXPECT_EQ(s.read("ranks.txt"), "rank 0 of 2 threads 1\nrank 1 of 2 threads 1\n");
  // Forced, it runs on 3 ranks and the record says so.
  ASSERT_EQ(sh(s, run + " --set ranks=3 --force sim").code, 0);
  EXPECT_NE(s.read("ranks.txt").find("rank 2 of 3"), std::string::npos) << s.read("ranks.txt");
  EXPECT_NE(s.read("p.lock.json").find("\"launch\": \"" + launcher + " -np 3\""), std::string::npos);
}

TEST(Ranks, ToolWithoutMpiIsRefusedBeforeAnythingRuns) {
  Scratch s;
  s.write("p.yaml", "steps:\n  first:\n    cmd: touch ${outs.0}\n    outs: [first.txt]\n"
                    "  row:\n    tool: run\n    ranks: 2\n    args: [row, -o, '${outs.0}', --value, 'a=1']\n"
                    "    outs: [row.json]\n");
  const auto r = sh(s, "'" + kBin + "/tomodem-run' p.yaml");
  EXPECT_EQ(r.code, 2) << r.err;
  EXPECT_NE(r.err.find("p.yaml:7"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("field 'steps.row.ranks': value '2'"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("tomodem-run has no MPI (its --version says 'features: openmp')"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("-DTOMODEM_MPI=ON"), std::string::npos) << r.err;
  EXPECT_FALSE(std::filesystem::exists(s.path("first.txt")));  // refused at load: nothing ran
  EXPECT_FALSE(std::filesystem::exists(s.path("p.lock.json")));
}

TEST(Ranks, BadRanksExitTwoNamingFileStepFieldAndValue) {
  for (const std::string v : {"0", "-1", "2.5", "four"}) {
    Scratch s;
    s.write("p.yaml", "steps:\n  sim:\n    ranks: " + v + "\n    cmd: touch ${outs.0}\n    outs: [a.txt]\n");
    const auto r = sh(s, "'" + kBin + "/tomodem-run' p.yaml");
    EXPECT_EQ(r.code, 2) << v << ": " << r.err;
    EXPECT_NE(r.err.find("p.yaml:3: field 'steps.sim.ranks': value '" + v + "': expected an integer >= 1"),
              std::string::npos)
        << r.err;
    EXPECT_FALSE(std::filesystem::exists(s.path("a.txt")));
  }
}

TEST(Ranks, SerialBuildStartedOnSeveralRanksExitsTwoSayingSoOnRankZeroOnly) {
  // The variables of OpenMPI's mpirun, of MPICH/PMI and of srun, each on rank 0 and rank 1.
  const char* launchers[][2] = {{"OMPI_COMM_WORLD_SIZE=2 OMPI_COMM_WORLD_RANK=", ""},
                                {"PMI_SIZE=3 PMI_RANK=", ""},
                                {"SLURM_STEP_NUM_TASKS=2 SLURM_PROCID=", ""}};
  for (const auto& l : launchers)
    for (const std::string rank : {"0", "1"}) {
      Scratch s;
      const auto r = sh(s, std::string(l[0]) + rank + " '" + kBin + "/tomodem-run' row -o row.json --value a=1");
      EXPECT_EQ(r.code, 2) << l[0] << rank << ": " << r.err;
      if (rank == "0")
        EXPECT_EQ(r.err.rfind("tomodem-run: error: this build has no MPI: started on ", 0), 0u) << r.err;
      else
        EXPECT_EQ(r.err, "") << l[0] << rank;
      EXPECT_NE(rank == "0" ? r.err.find("configure with -DTOMODEM_MPI=ON") : 0, std::string::npos) << r.err;
      EXPECT_FALSE(std::filesystem::exists(s.path("row.json")));  // nothing left behind
      EXPECT_EQ(std::distance(std::filesystem::directory_iterator(s.dir), {}), 2);  // .stdout, .stderr
    }
  // One rank, or the batch script of a Slurm job with --ntasks (SLURM_NTASKS, no job step): runs.
  for (const std::string env : {"OMPI_COMM_WORLD_SIZE=1 OMPI_COMM_WORLD_RANK=0", "SLURM_NTASKS=4 SLURM_PROCID=0"}) {
    Scratch s;
    const auto r = sh(s, env + " '" + kBin + "/tomodem-run' row -o row.json --value a=1");
    EXPECT_EQ(r.code, 0) << env << ": " << r.err;
    EXPECT_TRUE(std::filesystem::exists(s.path("row.json"))) << env;
  }
}
