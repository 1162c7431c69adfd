#pragma once
// A scratch folder per test, with helpers to write files into it.
#include <stdlib.h>

#include <filesystem>
#include <fstream>
#include <string>

namespace tomodem::test {

class Scratch {
 public:
  Scratch() {
    std::string t = (std::filesystem::temp_directory_path() / "tomodem-pipe-XXXXXX").string();
    dir = ::mkdtemp(t.data());
  }
  ~Scratch() {
    std::error_code ec;
    std::filesystem::remove_all(dir, ec);
  }
  std::string path(const std::string& name) const { return dir + "/" + name; }
  std::string write(const std::string& name, const std::string& text) const {
    const auto p = std::filesystem::path(path(name));
    std::filesystem::create_directories(p.parent_path());
    std::ofstream(p) << text;
    return p.string();
  }
  std::string read(const std::string& name) const {
    std::ifstream in(path(name));
    return std::string(std::istreambuf_iterator<char>(in), {});
  }
  std::string dir;
};

}  // namespace tomodem::test
