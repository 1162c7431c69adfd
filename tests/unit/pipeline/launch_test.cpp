// MPI steps (`ranks: N`): the launcher chosen from the environment, the command lines it makes
// for a local run (mpirun) and inside a Slurm job (srun), and the tasks the Slurm export asks for.
// The expected command lines are written out here from docs/pipelines.md ("MPI steps").
#include <gtest/gtest.h>

#include "scratch.hpp"
#include "tomodem/core/error.hpp"
#include "tomodem/pipeline/pipeline.hpp"
#include "tomodem/pipeline/run.hpp"

namespace tp = tomodem::pipeline;
using tomodem::test::Scratch;
using Words = std::vector<std::string>;

namespace {
tp::Instance step(int ranks, int threads) {
  tp::Instance in;
  in.argv = {"/opt/bin/tomodem-dem", "scene.yaml", "-o", "out.h5"};
  in.ranks = ranks;
  in.threads = threads;
  return in;
}
}  // namespace

TEST(Launch, LauncherIsMpirunLocallySrunInASlurmJobAndTomodemMpirunWhenSet) {
  EXPECT_EQ(tp::make_launcher(nullptr, nullptr).words, Words{"mpirun"});
  EXPECT_FALSE(tp::make_launcher(nullptr, nullptr).srun);
  EXPECT_EQ(tp::make_launcher(nullptr, "4242").words, Words{"srun"});
  EXPECT_TRUE(tp::make_launcher(nullptr, "4242").srun);
  EXPECT_EQ(tp::make_launcher(nullptr, "").words, Words{"mpirun"});  // an empty SLURM_JOB_ID is no job
  // The user's launcher wins, in a Slurm job too; blanks separate its words.
  const auto own = tp::make_launcher("  mpirun  --oversubscribe ", "4242");
  EXPECT_EQ(own.words, (Words{"mpirun", "--oversubscribe"}));
  EXPECT_FALSE(own.srun);
  EXPECT_EQ(tp::make_launcher(" ", nullptr).words, Words{"mpirun"});  // blank: as if unset
  EXPECT_TRUE(tp::make_launcher("/usr/bin/srun --mpi=pmix", nullptr).srun);
  EXPECT_FALSE(tp::make_launcher("/opt/mysrun", nullptr).srun);  // only a program named srun takes -n/-c
}

TEST(Launch, CommandLinesForMpirunAndSrun) {
  const auto local = tp::make_launcher(nullptr, nullptr);
  const auto slurm = tp::make_launcher(nullptr, "4242");
  EXPECT_EQ(tp::launch_argv(step(4, 2), local),
            (Words{"mpirun", "-np", "4", "/opt/bin/tomodem-dem", "scene.yaml", "-o", "out.h5"}));
  EXPECT_EQ(tp::launch_argv(step(4, 2), slurm),
            (Words{"srun", "-n", "4", "-c", "2", "/opt/bin/tomodem-dem", "scene.yaml", "-o", "out.h5"}));
  EXPECT_EQ(tp::launch_argv(step(3, 1), tp::make_launcher("mpirun --oversubscribe", nullptr)),
            (Words{"mpirun", "--oversubscribe", "-np", "3", "/opt/bin/tomodem-dem", "scene.yaml", "-o", "out.h5"}));
  // ranks: 1 (or absent) runs exactly as without MPI, whatever the launcher.
  EXPECT_EQ(tp::launch_argv(step(1, 2), local), step(1, 2).argv);
  EXPECT_EQ(tp::launch_argv(step(1, 2), slurm), step(1, 2).argv);
}

TEST(Launch, RanksIsReadWithReferencesAndOneByDefault) {
  Scratch s;
  const auto p = tp::load(s.write("p.yaml", "vars: {n: 3}\nsteps:\n"
                                            "  a:\n    ranks: ${vars.n}\n    cmd: echo ${ranks} > ${outs.0}\n    outs: [a.txt]\n"
                                            "  b:\n    cmd: echo ${ranks} > ${outs.0}\n    outs: [b.txt]\n"));
  ASSERT_EQ(p.instances.size(), 2u);
  EXPECT_EQ(p.instances[0].ranks, 3);
  EXPECT_EQ(p.instances[0].command, "echo 3 > a.txt");
  EXPECT_EQ(p.instances[1].ranks, 1);
  EXPECT_EQ(p.instances[1].command, "echo 1 > b.txt");
}

TEST(Launch, SlurmExportAsksForTheLargestRankCountAsTasks) {
  Scratch s;
  const char* mpi = "steps:\n  sim:\n    matrix: {d: [1, 2]}\n    ranks: 4\n    threads: 2\n"
                    "    cmd: touch ${outs.0}\n    outs: ['s${cell}']\n"
                    "  small:\n    matrix: {d: [1, 2]}\n    ranks: 2\n    cmd: touch ${outs.0}\n    outs: ['t${cell}']\n";
  const auto f = tp::slurm_scripts(tp::load(s.write("p.yaml", mpi)), {});
  EXPECT_NE(f.array_script.find("#SBATCH --ntasks=4\n"), std::string::npos) << f.array_script;
  EXPECT_NE(f.array_script.find("#SBATCH --cpus-per-task=2\n"), std::string::npos) << f.array_script;
  // The shared and gather jobs may hold MPI steps too.
  EXPECT_NE(f.submit_script.find(" --ntasks=4 --cpus-per-task=2"), std::string::npos) << f.submit_script;
  // The runner in the job starts the steps; it picks srun there (SLURM_JOB_ID), so the script
  // names no launcher and the same pipeline file runs on a laptop.
  EXPECT_EQ(f.array_script.find("mpirun"), std::string::npos);
  const char* serial = "steps:\n  c:\n    matrix: {d: [1, 2]}\n    threads: 2\n    cmd: touch ${outs.0}\n    outs: ['c${cell}']\n";
  const auto g = tp::slurm_scripts(tp::load(s.write("q.yaml", serial)), {});
  EXPECT_EQ(g.array_script.find("--ntasks"), std::string::npos) << g.array_script;
  EXPECT_EQ(g.submit_script.find("--ntasks"), std::string::npos) << g.submit_script;
}

TEST(Launch, BadRanksAreRefusedNamingFileStepFieldAndValue) {
  for (const std::string v : {"0", "-2", "1.5", "many", "''"}) {
    Scratch s;
    const std::string file = s.write("p.yaml", "steps:\n  sim:\n    cmd: touch ${outs.0}\n    ranks: " + v +
                                                   "\n    outs: [a.txt]\n");
    try {
      tp::load(file);
      ADD_FAILURE() << "ranks: " << v << " was accepted";
    } catch (const tomodem::InputError& e) {
      const std::string m = e.what();
      EXPECT_NE(m.find("p.yaml:4"), std::string::npos) << m;
      EXPECT_NE(m.find("steps.sim.ranks"), std::string::npos) << m;
      if (v != "''") EXPECT_NE(m.find("value '" + v + "'"), std::string::npos) << m;  // an empty value has none to name
    }
  }
}
