// Cutting a sweep into shards for Slurm arrays, and the scripts that submit them.
// No Slurm runs here (none in the test environment); the scripts are checked with `bash -n`.
#include <gtest/gtest.h>

#include <cstdlib>
#include <set>
#include <sstream>

#include "scratch.hpp"
#include "tomodem/core/error.hpp"
#include "tomodem/pipeline/run.hpp"

using tomodem::test::Scratch;
namespace tp = tomodem::pipeline;

namespace {
const char* kStudy = R"(steps:
  prep:
    cmd: echo > ${outs.0}
    outs: [prep.txt]
  pack:
    matrix: {d: [0.5, 0.7, 0.9]}
    cmd: cat ${steps.prep.outs.0} > ${outs.0}
    outs: ['pack-${cell}.txt']
  young:
    matrix: {d: [0.5, 0.7, 0.9]}
    replicas: 3
    cmd: cat ${steps.pack.outs.0} > ${outs.0}
    outs: ['young-${cell}.txt']
  gather:
    cmd: cat ${steps.young.outs} > ${outs.0}
    outs: [table.txt]
)";

int owner_of(const tp::Pipeline& p, const std::vector<int>& o, const std::string& id) {
  for (std::size_t i = 0; i < p.instances.size(); ++i)
    if (p.instances[i].id == id) return o[i];
  return -99;
}
}  // namespace

TEST(Shards, ThreeShardsKeepEachDensityWithItsPacking) {
  Scratch s;
  const auto p = tp::load(s.write("p.yaml", kStudy));
  const auto o = tp::shard_owners(p, 3);
  EXPECT_EQ(owner_of(p, o, "prep"), 0);     // read by every shard: run once, before the array
  EXPECT_EQ(owner_of(p, o, "gather"), -1);  // after the array
  EXPECT_EQ(owner_of(p, o, "pack[d-0.5]"), 1);
  EXPECT_EQ(owner_of(p, o, "young[d-0.5_replica-2]"), 1);
  EXPECT_EQ(owner_of(p, o, "pack[d-0.9]"), 3);
  EXPECT_EQ(owner_of(p, o, "young[d-0.9_replica-0]"), 3);
}

TEST(Shards, EveryLeafInExactlyOneShardAndUpstreamNeverInAnother) {
  Scratch s;
  const auto p = tp::load(s.write("p.yaml", kStudy));
  for (int n = 1; n <= 12; ++n) {
    const auto o = tp::shard_owners(p, n);
    std::set<int> used;
    for (std::size_t i = 0; i < p.instances.size(); ++i) {
      const auto& in = p.instances[i];
      if (in.step == "young") {
        EXPECT_GE(o[i], 1) << in.id << " n=" << n;
        EXPECT_LE(o[i], n) << in.id << " n=" << n;
        used.insert(o[i]);
      }
      // A shard may read only its own instances or the shared ones computed before it.
      if (o[i] >= 1)
        for (const auto u : in.upstream) EXPECT_TRUE(o[u] == o[i] || o[u] == 0) << in.id << " n=" << n;
      if (o[i] == 0) {
        // Shared means: needed by two shards at least.
        std::set<int> readers;
        for (std::size_t j = i + 1; j < p.instances.size(); ++j)
          for (const auto u : p.instances[j].upstream)
            if (u == i && o[j] != -1) readers.insert(o[j]);
        EXPECT_TRUE(readers.size() >= 2 || readers.count(0)) << in.id << " n=" << n;
      }
    }
    EXPECT_EQ(static_cast<int>(used.size()), std::min(n, 9)) << "n=" << n;
  }
}

TEST(Shards, ParseShard) {
  EXPECT_EQ(tp::parse_shard("2/5"), std::make_pair(2, 5));
  EXPECT_EQ(tp::parse_shard("0/5"), std::make_pair(0, 5));
  for (const char* bad : {"6/5", "1/0", "a/b", "3", "1/2x", "-1/2"})
    EXPECT_THROW(tp::parse_shard(bad), tomodem::InputError) << bad;
}

TEST(SlurmExport, ArrayHasOneTaskPerShardWithConcurrencyLimit) {
  Scratch s;
  const auto p = tp::load(s.write("p.yaml", kStudy));
  tp::SlurmOptions o;
  o.shards = 3;
  o.limit = 2;
  o.partition = "short";
  const auto f = tp::slurm_scripts(p, o);
  EXPECT_NE(f.array_script.find("#SBATCH --array=1-3%2\n"), std::string::npos) << f.array_script;
  EXPECT_NE(f.array_script.find("--shard \"${SLURM_ARRAY_TASK_ID}/3\""), std::string::npos) << f.array_script;
  EXPECT_NE(f.array_script.find("#SBATCH --partition=short"), std::string::npos);
  EXPECT_NE(f.submit_script.find("--shard 0/3"), std::string::npos) << f.submit_script;
  EXPECT_NE(f.submit_script.find("--dependency=afterok:${shared}"), std::string::npos);
  EXPECT_NE(f.submit_script.find("--dependency=afterok:${array}"), std::string::npos);
  // Both must at least be valid bash.
  const auto a = s.write("a.sbatch", f.array_script), b = s.write("submit.sh", f.submit_script);
  EXPECT_EQ(std::system(("bash -n " + a + " && bash -n " + b).c_str()), 0);
}

TEST(SlurmExport, DefaultsToOneShardPerLeafAndRefusesAPipelineWithoutASweep) {
  Scratch s;
  const auto f = tp::slurm_scripts(tp::load(s.write("p.yaml", kStudy)), {});
  EXPECT_NE(f.array_script.find("--array=1-9%8"), std::string::npos) << f.array_script;
  const auto q = tp::load(s.write("q.yaml", "steps:\n  a:\n    cmd: true\n"));
  EXPECT_THROW(tp::slurm_scripts(q, {}), tomodem::InputError);
}

// Review D3: shard lock files are named by K alone, so `--shard 0/2` after `--shard 0/3` wrote
// shard-0's file afresh and dropped the record of prep (shared under N = 3, not under N = 2).
TEST(Shards, AShardRunUnderAnotherCountKeepsTheRecordsOfItsLockFile) {
  Scratch s;
  const auto p = tp::load(s.write("p.yaml", kStudy));
  std::ostringstream progress;
  tp::RunOptions o;
  o.shard = 0;
  o.shards = 3;
  ASSERT_EQ(tp::run(p, o, progress).ran, 1) << progress.str();  // prep
  o.shards = 2;
  const auto second = tp::run(p, o, progress);
  EXPECT_EQ(second.ran, 1) << progress.str();  // pack[d-0.7], which both halves read
  EXPECT_EQ(second.up_to_date, 1);
  const auto st = tp::status(p, {});
  for (std::size_t i = 0; i < p.instances.size(); ++i)
    if (p.instances[i].id == "prep" || p.instances[i].id == "pack[d-0.7]")
      EXPECT_EQ(st.steps[i].state, "up-to-date") << p.instances[i].id << ": " << st.steps[i].reason;
}
