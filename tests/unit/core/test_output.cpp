// core/output.hpp: CSV tables, atomic text writes, content hashes, timestamps.
#include "tomodem/core/output.hpp"

#include <gtest/gtest.h>

#include <regex>

#include "tmpdir.hpp"
#include "tomodem/core/error.hpp"

namespace tomodem {
namespace {

using test::TmpDir;

class Output : public TmpDir {};

TEST(CsvTable, HeaderThenRows) {
  const std::string t = csv_table({"time_s", "kinetic_energy_J"}, {{0, 1.5}, {1e-6, 0.1}});
  EXPECT_EQ(t, "time_s,kinetic_energy_J\n0,1.5\n1e-06,0.1\n");
}

TEST(CsvTable, TenSignificantDigits) {
  // Precision 10: enough for plots and fits, stable text for diffs.
  EXPECT_EQ(csv_table({"x"}, {{1.0 / 3.0}}), "x\n0.3333333333\n");
  EXPECT_EQ(csv_table({"a", "b"}, {}), "a,b\n");
}

TEST(TemporaryPath, SameFolderDifferentName) {
  const std::string t = temporary_path("/some/dir/out.h5");
  EXPECT_EQ(t.rfind("/some/dir/out.h5", 0), 0u);  // same folder: rename stays atomic
  EXPECT_NE(t, "/some/dir/out.h5");
}

TEST_F(Output, WriteTextAtomicWritesAndReplaces) {
  write_text_atomic(file("a.txt"), "first\n");
  EXPECT_EQ(test::slurp(file("a.txt")), "first\n");
  write_text_atomic(file("a.txt"), std::string("sec\0ond", 7));  // binary-safe
  EXPECT_EQ(test::slurp(file("a.txt")), std::string("sec\0ond", 7));
  EXPECT_EQ(test::entries(dir), (std::vector<std::string>{"a.txt"}));  // no temporary left
}

TEST_F(Output, WriteTextAtomicFailsCleanly) {
  EXPECT_THROW(write_text_atomic(file("missing/dir/a.txt"), "x"), RuntimeFailure);
  EXPECT_TRUE(test::entries(dir).empty());
}

TEST_F(Output, CommitWithoutTemporaryFails) {
  EXPECT_THROW(commit_output(file("never_written.h5")), RuntimeFailure);
}

TEST_F(Output, FileHashStableAndContentSensitive) {
  write_text_atomic(file("a"), "hello world\n");
  write_text_atomic(file("b"), "hello world\n");
  write_text_atomic(file("c"), "hello world!");
  write_text_atomic(file("empty"), "");
  const std::string ha = file_hash(file("a"));
  EXPECT_TRUE(std::regex_match(ha, std::regex("[0-9a-f]{32}"))) << ha;  // XXH3-128 in hex
  EXPECT_EQ(ha, file_hash(file("a")));
  EXPECT_EQ(ha, file_hash(file("b")));  // content, not name
  EXPECT_NE(ha, file_hash(file("c")));
  // XXH3-128 of no bytes is a published constant: pins the algorithm and the hex order (high first).
  EXPECT_EQ(file_hash(file("empty")), "99aa06d3014798d86001c324468d497f");
  // Larger than the 64 KiB read buffer: a change in the last byte must still show.
  std::string big(200000, 'x');
  write_text_atomic(file("big1"), big);
  big.back() = 'y';
  write_text_atomic(file("big2"), big);
  EXPECT_NE(file_hash(file("big1")), file_hash(file("big2")));
}

TEST_F(Output, FileHashMissingFileIsInputError) {
  try {
    file_hash(file("nope"));
    FAIL() << "no exception";
  } catch (const InputError& e) {
    EXPECT_EQ(e.file(), file("nope"));
  }
}

TEST(UtcNow, Iso8601) {
  EXPECT_TRUE(std::regex_match(utc_now(), std::regex(R"(\d{4}-\d\d-\d\dT\d\d:\d\d:\d\dZ)"))) << utc_now();
}

}  // namespace
}  // namespace tomodem
