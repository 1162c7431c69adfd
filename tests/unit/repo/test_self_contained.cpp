// The repository stands alone: no tracked file may refer to reading material outside it (the
// formulas are in docs/physics.md, the conventions in docs/architecture.md, the peer benchmark
// inputs in tests/bench/peers). The test lists the tracked files with `git ls-files` in the
// source tree (or walks the tree when it is not a git checkout), searches each text file for the
// strings below (case-sensitive) and fails with file:line of every hit. The strings are put
// together from pieces, so this file holds none of them and is checked like every other.
#include <gtest/gtest.h>

#include "repo_files.hpp"

#include <array>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <string_view>
#include <vector>

namespace fs = std::filesystem;

namespace {

const std::vector<std::string>& forbidden() {
  const std::string folder = std::string("sha") + "red", md = ".md", work = std::string("/wo") + "rk/";
  static const std::vector<std::string> k = {
      "../" + folder,      work + folder,      folder + "/PHYSICS", folder + "/peers", "PHYSICS" + md,
      "DESIGN" + md,       "CONVENTIONS" + md, "STYLE" + md,        std::string("STYLE") + " P",
      // Any absolute path into the machine the repository was written on (its workspace, the
      // tool library beside it): a clone elsewhere has neither.
      work, std::string("/.lib") + "rary/",
  };
  return k;
}

}  // namespace

TEST(Repository, NoFileRefersOutsideTheRepository) {
  const fs::path root = TOMODEM_SOURCE_DIR;
  const std::vector<std::string> files = tomodem::test::repository_files(root);
  ASSERT_FALSE(files.empty()) << "no files found under " << root;

  std::ostringstream hits;
  int count = 0;
  std::size_t scanned = 0;
  for (const std::string& rel : files) {
    std::ifstream in(root / rel, std::ios::binary);
    if (!in) continue;  // listed by git but deleted in the work tree
    std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    if (text.find('\0') != std::string::npos) continue;  // binary (images, HDF5)
    ++scanned;
    std::size_t line_start = 0;
    for (int line = 1; line_start <= text.size(); ++line) {
      std::size_t end = text.find('\n', line_start);
      if (end == std::string::npos) end = text.size();
      const std::string_view l(text.data() + line_start, end - line_start);
      for (const std::string& s : forbidden())
        if (l.find(s) != std::string_view::npos) {
          hits << "  " << rel << ":" << line << ": '" << s << "': " << l.substr(0, 160) << "\n";
          ++count;
          break;
        }
      line_start = end + 1;
    }
  }
  EXPECT_GT(scanned, 10u) << "too few text files scanned";
  EXPECT_EQ(count, 0) << count << " line(s) refer outside the repository (" << "git ls-files, else a tree walk"
                      << " of " << root << "); write the content into the repository instead "
                      << "(docs/physics.md, docs/architecture.md, tests/bench/peers):\n"
                      << hits.str();
}
