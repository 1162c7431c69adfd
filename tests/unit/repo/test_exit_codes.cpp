// Exit code 4 (a run that ends short of what was asked, README.md) is decided by one function,
// exit_code_of_summary (libs/core/src/summary.cpp), from the summary's `target_reached`: a tool
// that returned the code itself could say 4 with `target_reached: true` in its summary, or the
// reverse. The test searches the libraries' and tools' sources for the constant.
#include <gtest/gtest.h>

#include <fstream>
#include <iterator>
#include <set>
#include <sstream>
#include <string>

#include "repo_files.hpp"

namespace fs = std::filesystem;

TEST(Repository, ExitCodeFourIsDecidedByTheSummaryAlone) {
  const fs::path root = TOMODEM_SOURCE_DIR;
  const std::set<std::string> allowed = {"libs/core/include/tomodem/core/error.hpp",    // its definition
                                         "libs/core/include/tomodem/core/summary.hpp",  // exit_code_of_summary
                                         "libs/core/src/summary.cpp"};
  const std::string constant = std::string("exit_code::") + "target_not_reached";
  std::ostringstream hits;
  std::size_t scanned = 0;
  for (const std::string& rel : tomodem::test::repository_files(root)) {
    const bool source = (rel.rfind("libs/", 0) == 0 || rel.rfind("tools/", 0) == 0) &&
                        (fs::path(rel).extension() == ".cpp" || fs::path(rel).extension() == ".hpp");
    if (!source || allowed.count(rel)) continue;
    std::ifstream in(root / rel);
    if (!in) continue;  // listed by git but deleted in the work tree
    const std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    ++scanned;
    if (text.find(constant) != std::string::npos) hits << "  " << rel << "\n";
  }
  EXPECT_GT(scanned, 50u) << "too few sources scanned under " << root;
  EXPECT_TRUE(hits.str().empty()) << "these return " << constant
                                  << " themselves; return exit_code_of_summary(summary) instead:\n"
                                  << hits.str();
}
