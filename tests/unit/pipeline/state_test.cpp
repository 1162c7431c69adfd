// Content hashes and the stat cache that spares re-reading unchanged files.
#include <fcntl.h>
#include <gtest/gtest.h>
#include <sys/stat.h>
#include <unistd.h>

#include <ctime>
#include <filesystem>
#include <sstream>

#include "scratch.hpp"
#include "tomodem/core/output.hpp"
#include "tomodem/pipeline/run.hpp"

using tomodem::test::Scratch;
namespace tp = tomodem::pipeline;

namespace {
// Sets the modification time `age_s` seconds in the past (older than the racy-stat window).
void age(const std::string& path, int age_s) {
  struct timespec t[2];
  ::clock_gettime(CLOCK_REALTIME, &t[0]);
  t[0].tv_sec -= age_s;
  t[1] = t[0];
  ASSERT_EQ(::utimensat(AT_FDCWD, path.c_str(), t, 0), 0);
}
}  // namespace

TEST(HashCache, MatchesCoreFileHash) {
  Scratch s;
  const auto f = s.write("a.txt", "some content");
  tp::HashCache c;
  c.root = s.dir;
  EXPECT_EQ(c.hash("a.txt"), tomodem::file_hash(f));
  EXPECT_EQ(c.hash("missing.txt"), "");
}

TEST(HashCache, UnchangedStatIsNotReadAgain) {
  Scratch s;
  const auto f = s.write("a.txt", "aaaa");
  age(f, 100);
  tp::HashCache c;
  c.root = s.dir;
  const std::string h1 = c.hash("a.txt");
  EXPECT_EQ(c.hash("a.txt"), h1);
  EXPECT_EQ(c.files_hashed(), 1);
  // A new timestamp makes it read the file again.
  age(f, 50);
  EXPECT_EQ(c.hash("a.txt"), h1);
  EXPECT_EQ(c.files_hashed(), 2);
}

namespace {
// Writes `text` into `f` in place (same inode) and puts its old size-preserving timestamps back,
// as `printf ... 1<> f; touch -r ref f` does. Only the status-change time (ctime) moves.
void rewrite_keeping_stat(const std::string& f, const std::string& text) {
  struct stat st {};
  ASSERT_EQ(::stat(f.c_str(), &st), 0);
  ::usleep(20000);  // ctime ticks coarsely: make sure it moves
  const int fd = ::open(f.c_str(), O_WRONLY);
  ASSERT_GE(fd, 0);
  ASSERT_EQ(::write(fd, text.data(), text.size()), static_cast<ssize_t>(text.size()));
  ::close(fd);
  struct timespec t[2] = {st.st_atim, st.st_mtim};
  ASSERT_EQ(::utimensat(AT_FDCWD, f.c_str(), t, 0), 0);
  struct stat after {};
  ASSERT_EQ(::stat(f.c_str(), &after), 0);
  ASSERT_EQ(after.st_ino, st.st_ino);
  ASSERT_EQ(after.st_size, st.st_size);
}
}  // namespace

TEST(HashCache, SameSizeMtimeAndInodeStillSeenThroughCtime) {
  // D16: size, mtime and inode all kept; the content changed. ctime (which touch cannot set) tells.
  Scratch s;
  const auto f = s.write("a.txt", "aaaa");
  age(f, 100);
  tp::HashCache c;
  c.root = s.dir;
  const std::string h1 = c.hash("a.txt");
  rewrite_keeping_stat(f, "bbbb");
  EXPECT_NE(c.hash("a.txt"), h1);
  EXPECT_EQ(c.hash("a.txt"), tomodem::file_hash(f));
}

TEST(HashCache, EntryWithoutCtimeIsReadAgain) {
  // An entry from a lock file written before ctime was kept (ctime_ns 0) is not trusted.
  Scratch s;
  const auto f = s.write("a.txt", "aaaa");
  age(f, 100);
  struct stat st {};
  ASSERT_EQ(::stat(f.c_str(), &st), 0);
  tp::HashCache c;
  c.root = s.dir;
  c.entries["a.txt"] = tp::HashCache::Entry{"stale", static_cast<std::int64_t>(st.st_size),
                                            static_cast<std::int64_t>(st.st_mtim.tv_sec) * 1000000000 + st.st_mtim.tv_nsec,
                                            static_cast<std::uint64_t>(st.st_ino), 0};
  EXPECT_EQ(c.hash("a.txt"), tomodem::file_hash(f));
  EXPECT_EQ(c.files_hashed(), 1);
}

TEST(HashCache, FreshlyWrittenFilesAreNotTrustedYet) {
  // A file written in the last 2 s may change again within one timestamp tick (racy stat).
  Scratch s;
  s.write("a.txt", "aaaa");
  tp::HashCache c;
  c.root = s.dir;
  c.hash("a.txt");
  c.hash("a.txt");
  EXPECT_EQ(c.files_hashed(), 2);
  EXPECT_EQ(c.entries.count("a.txt"), 0u);
}

TEST(HashCache, FolderHashFollowsItsFiles) {
  Scratch s;
  s.write("d/x.txt", "1");
  s.write("d/sub/y.txt", "2");
  tp::HashCache c;
  c.root = s.dir;
  const std::string h1 = c.hash("d");
  EXPECT_EQ(tp::HashCache{}.hash(s.dir + "/d"), h1);  // absolute paths work too
  s.write("d/sub/y.txt", "3");
  EXPECT_NE(c.hash("d"), h1);
}

namespace {
// A stand-in tool whose --version names a release and a build, as every tomodem tool's does.
std::string fake_tool(const Scratch& s, const std::string& dir, const std::string& version) {
  const std::string exe = s.write(dir + "/tomodem-fake", "#!/bin/sh\nif [ \"$1\" = --version ]; then echo '" + version +
                                                            "'; echo 'features: openmp'; exit 0; fi\necho made > \"$1\"\n");
  std::filesystem::permissions(exe, std::filesystem::perms::owner_all);
  return s.path(dir);
}

tp::RunSummary run_with(const std::string& pipeline, const std::string& tool_dir, bool rerun_on_rebuild = false) {
  tp::LoadOptions lo;
  lo.tool_dir = tool_dir;
  tp::RunOptions ro;
  ro.quiet = true;
  ro.rerun_on_rebuild = rerun_on_rebuild;
  std::ostringstream progress;
  return tp::run(tp::load(pipeline, lo), ro, progress);
}
}  // namespace

TEST(Staleness, AnotherBuildOfTheSameReleaseIsUpToDateUnlessAsked) {
  Scratch s;
  const std::string pipe = s.write("p.yaml", "steps:\n  make:\n    tool: fake\n    args: ['${outs.0}']\n    outs: [out.txt]\n");
  EXPECT_EQ(run_with(pipe, fake_tool(s, "build-a", "tomodem 0.9.0 (git aaaaaaa)")).ran, 1);
  // The same release from another commit: up to date, and explain says why it was not re-run.
  const std::string build_b = fake_tool(s, "build-b", "tomodem 0.9.0 (git bbbbbbb)");
  EXPECT_EQ(run_with(pipe, build_b).up_to_date, 1);
  tp::LoadOptions lo;
  lo.tool_dir = build_b;
  EXPECT_NE(tp::explain(tp::load(pipe, lo), "make").find("note: made by another build"), std::string::npos);
  // Asked for: the rebuild makes it stale.
  EXPECT_EQ(run_with(pipe, build_b, true).ran, 1);
  // A new release always re-runs it.
  EXPECT_EQ(run_with(pipe, fake_tool(s, "build-c", "tomodem 0.9.1 (git bbbbbbb)")).ran, 1);
}

TEST(Staleness, FailedRerunKeepsTheLastGoodRecordWhenItsOutputIsBack) {
  // D17: tag one runs; tag bad fails and the runner puts tag one's output back; going back to
  // tag one is then up to date, not a re-run.
  Scratch s;
  const auto pipe = [&](const std::string& tag) {
    return s.write("p.yaml", "steps:\n  a:\n    params: {tag: " + tag +
                                 "}\n    cmd: test ${params.tag} != bad && echo ${params.tag} > ${outs.0}\n    outs: [a.txt]\n");
  };
  EXPECT_EQ(run_with(pipe("one"), "").ran, 1);
  EXPECT_EQ(run_with(pipe("bad"), "").failed, 1);
  EXPECT_EQ(s.read("a.txt"), "one\n");
  const tp::RunSummary back = run_with(pipe("one"), "");
  EXPECT_EQ(back.ran, 0);
  EXPECT_EQ(back.up_to_date, 1);
  // The failure is still reported by explain, beside the kept record.
  const std::string why = tp::explain(tp::load(pipe("bad"), {}), "a");
  EXPECT_NE(why.find("would run"), std::string::npos);
}
