#pragma once
// A test that runs tomodem tools in a folder of its own (removed afterwards): the fixture the
// e2e tests share. Commands run with that folder as the working directory, their stdout and
// stderr in stdout.txt and stderr.txt there.
#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>

namespace tomodem::test {

class ToolTest : public ::testing::Test {
 protected:
  /// `prefix` names the folder: <tmp>/<prefix>-<pid>-<test name>.
  explicit ToolTest(std::string prefix = "tomodem-e2e") : prefix_(std::move(prefix)) {}
  void SetUp() override {
    dir_ = std::filesystem::temp_directory_path() /
           (prefix_ + "-" + std::to_string(::getpid()) + "-" + ::testing::UnitTest::GetInstance()->current_test_info()->name());
    std::filesystem::remove_all(dir_);
    std::filesystem::create_directories(dir_);
  }
  void TearDown() override { std::filesystem::remove_all(dir_); }

  std::string path(const std::string& name) const { return (dir_ / name).string(); }
  /// The exit code of `cmd` run in the folder (-1 when it did not exit normally).
  int sh(const std::string& cmd) const {
    const int st = std::system(("cd '" + dir_.string() + "' && " + cmd + " > stdout.txt 2> stderr.txt").c_str());
    return WIFEXITED(st) ? WEXITSTATUS(st) : -1;
  }
  std::string text(const std::string& name) const {
    std::ifstream in(path(name));
    std::stringstream s;
    s << in.rdbuf();
    return s.str();
  }
  nlohmann::json json(const std::string& name) const { return nlohmann::json::parse(text(name)); }
  static std::string bin(const std::string& tool) { return std::string(TOMODEM_BIN_DIR) + "/" + tool; }
  static std::string src(const std::string& rel) { return std::string(TOMODEM_SOURCE_DIR) + "/" + rel; }

  std::filesystem::path dir_;

 private:
  std::string prefix_;
};

/// The first ```lang block after `marker` in the text `doc` ("" when there is none).
inline std::string block_after(const std::string& doc, const std::string& marker, const std::string& lang) {
  const auto m = doc.find(marker);
  if (m == std::string::npos) return "";
  const auto b = doc.find("```" + lang + "\n", m);
  if (b == std::string::npos) return "";
  const auto start = b + 4 + lang.size();
  return doc.substr(start, doc.find("```", start) - start);
}

}  // namespace tomodem::test
