// `tomodem run export slurm` against a real Slurm: runs only where `sinfo` reports an idle node
// (Debian slurm-wlm with slurmctld + slurmd on localhost, see docs/pipelines.md), skipped
// otherwise. The submit script's three jobs (shared part, job array, gather) must run every
// step exactly once, and the gather run must fold the shards' lock files.
#include <gtest/gtest.h>

#include <chrono>
#include <set>
#include <sstream>
#include <thread>

#include "../../unit/pipeline/scratch.hpp"
#include "sharded_pipeline.hpp"

using tomodem::test::Scratch;
namespace fs = std::filesystem;

TEST(Slurm, SubmittedArrayAndGatherRunEachStepOnce) {
  if (std::system("sinfo -h -o %T 2>/dev/null | grep -Eq '^(idle|mixed)'") != 0)
    GTEST_SKIP() << "no Slurm with an idle node here (sinfo); the shard logic is tested without it";
  Scratch s;
  s.write("p.yaml", tomodem::pipeline::test::kShardedPipeline);
  const std::string run = std::string(TOMODEM_BIN_DIR) + "/tomodem-run";
  const std::string exp = "cd '" + s.dir + "' && '" + run + "' export slurm p.yaml --shards 2 --limit 2 --cpus 1 " +
                          "--time 00:05:00 --runner '" + run + "' 2> export.log";
  ASSERT_EQ(std::system(exp.c_str()), 0) << s.read("export.log");
  ASSERT_EQ(std::system(("cd '" + s.dir + "' && ./p.submit.sh > submit.log 2>&1").c_str()), 0) << s.read("submit.log");
  const auto t0 = std::chrono::steady_clock::now();
  while (!fs::exists(s.path("table.txt")) && std::chrono::steady_clock::now() - t0 < std::chrono::seconds(120))
    std::this_thread::sleep_for(std::chrono::milliseconds(200));
  ASSERT_TRUE(fs::exists(s.path("table.txt"))) << s.read("submit.log");
  // The gather job's tomodem-run writes the lock file after its step; give it a moment.
  std::this_thread::sleep_for(std::chrono::seconds(2));
  std::istringstream in(s.read("runs.txt"));
  std::multiset<std::string> runs;
  for (std::string l; std::getline(in, l);) runs.insert(l);
  EXPECT_EQ(runs, (std::multiset<std::string>{"prep", "d-1", "d-2", "d-3", "d-4", "gather"}));
  EXPECT_EQ(s.read("table.txt"), "prep\nprep\nprep\nprep\n");
  EXPECT_FALSE(fs::exists(s.path("p.lock.shard-1.json")));  // folded into p.lock.json by the gather run
  EXPECT_FALSE(fs::exists(s.path("p.lock.shard-2.json")));
}
