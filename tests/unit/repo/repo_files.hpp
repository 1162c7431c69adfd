#pragma once
// The repository's files for the repository-level tests: tracked files (`git ls-files` in the
// source tree), or every file when the tree is not a git checkout.
#include <array>
#include <cstdio>
#include <filesystem>
#include <string>
#include <vector>

namespace tomodem::test {

namespace fs = std::filesystem;

// Tracked files, relative to `root`; empty when `root` is not a git work tree (or git is missing).
inline std::vector<std::string> git_files(const fs::path& root, bool& ok) {
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
inline std::vector<std::string> walked_files(const fs::path& root) {
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

// Relative paths of the repository's files under `root`.
inline std::vector<std::string> repository_files(const fs::path& root) {
  bool from_git = false;
  std::vector<std::string> files = git_files(root, from_git);
  if (!from_git) files = walked_files(root);
  return files;
}

}  // namespace tomodem::test
