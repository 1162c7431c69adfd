// The repository stands alone: no tracked file may refer to reading material outside it (the
// formulas are in docs/physics.md, the conventions in docs/architecture.md, the peer benchmark
// inputs in tests/bench/peers). The test lists the tracked files with `git ls-files` in the
// source tree (or walks the tree when it is not a git checkout), searches each text file for the
// strings below (case-sensitive) and fails with file:line of every hit. The strings are put
// together from pieces, so this file holds none of them and is checked like every other.
#include <gtest/gtest.h>

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

// Tracked files, relative to `root`; empty when `root` is not a git work tree (or git is missing).
std::vector<std::string> git_files(const fs::path& root, bool& ok) {
  std::vector<std::string> files;
  ok = false;
  const std::string cmd = "git -C '" + root.string() + "' ls-files -z 2>/dev/null";
  FILE* pipe = popen(cmd.c_str(), "r");
  if (!pipe) return files;
  std::string all;
  std::array<char, 65536> buf;
  std::size_t n;
  while ((n = std::fread(buf.data(), 1, buf.size(), pipe)) > 0) all.append(buf.data(), n);
  const int status = pclose(pipe);
  if (status != 0) return files;
  std::size_t start = 0;
  for (std::size_t i = 0; i < all.size(); ++i)
    if (all[i] == '\0') {
      if (i > start) files.push_back(all.substr(start, i - start));
      start = i + 1;
    }
  ok = !files.empty();
  return files;
}

// Fallback for a source tree without git: every regular file, leaving out hidden folders and
// build folders (build*), which are not part of the repository's content.
std::vector<std::string> walked_files(const fs::path& root) {
  std::vector<std::string> files;
  for (auto it = fs::recursive_directory_iterator(root); it != fs::recursive_directory_iterator(); ++it) {
    const std::string name = it->path().filename().string();
    if (it->is_directory() && (name.rfind('.', 0) == 0 || name.rfind("build", 0) == 0)) {
      it.disable_recursion_pending();
      continue;
    }
    if (it->is_regular_file()) files.push_back(fs::relative(it->path(), root).generic_string());
  }
  return files;
}

}  // namespace

TEST(Repository, NoFileRefersOutsideTheRepository) {
  const fs::path root = TOMODEM_SOURCE_DIR;
  bool from_git = false;
  std::vector<std::string> files = git_files(root, from_git);
  if (!from_git) files = walked_files(root);
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
  EXPECT_EQ(count, 0) << count << " line(s) refer outside the repository (" << (from_git ? "git ls-files" : "tree walk")
                      << " of " << root << "); write the content into the repository instead "
                      << "(docs/physics.md, docs/architecture.md, tests/bench/peers):\n"
                      << hits.str();
}
