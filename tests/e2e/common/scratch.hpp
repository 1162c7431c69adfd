#pragma once
// Helpers for tests that run tools with plain functions rather than the ToolTest fixture
// (tool_test.hpp): one copy, so that a fix reaches every test that uses them.
#include <sys/wait.h>
#include <unistd.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

namespace tomodem::test {

/// The exit code of `cmd` (-1 when it did not exit normally), its stderr in *err, stdout dropped.
/// The stderr file is this process's: ctest -j runs the tests of one binary side by side.
inline int run_err(const std::string& cmd, std::string* err) {
  const std::string ef =
      (std::filesystem::temp_directory_path() / ("tomodem-stderr-" + std::to_string(::getpid()) + ".txt")).string();
  const int r = std::system((cmd + " >/dev/null 2>" + ef).c_str());
  {
    std::ifstream in(ef);
    err->assign(std::istreambuf_iterator<char>(in), {});
  }
  std::error_code ec;
  std::filesystem::remove(ef, ec);  // one file per test process was left in /tmp
  return WIFEXITED(r) ? WEXITSTATUS(r) : -1;
}

/// An empty folder <tmp>/<prefix><name>-<pid> (emptied when it exists), removed when the process
/// ends. The pid keeps it this process's: ctest -j runs the tests of one binary side by side, and
/// two of them setting up one shared input folder removed each other's files.
inline std::filesystem::path fresh_dir(const std::string& prefix, const std::string& name) {
  struct RemovedAtExit {
    std::vector<std::filesystem::path> dirs;
    ~RemovedAtExit() {
      std::error_code ec;
      for (const auto& d : dirs) std::filesystem::remove_all(d, ec);
    }
  };
  static RemovedAtExit made;
  const std::filesystem::path p =
      std::filesystem::temp_directory_path() / (prefix + name + "-" + std::to_string(::getpid()));
  std::filesystem::remove_all(p);
  std::filesystem::create_directories(p);
  made.dirs.push_back(p);
  return p;
}

inline nlohmann::json read_json(const std::filesystem::path& p) {
  nlohmann::json j;
  std::ifstream(p) >> j;
  return j;
}

}  // namespace tomodem::test
