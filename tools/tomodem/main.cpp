// `tomodem VERB ARGS...` runs `tomodem-VERB ARGS...` found next to this executable or on PATH,
// as git does for its subcommands.
#include <unistd.h>

#include <climits>
#include <cstring>
#include <iostream>
#include <string>
#include <vector>

#include "tomodem/core/error.hpp"
#include "tomodem/core/tool.hpp"

namespace {
const char* kUsage =
    "usage: tomodem VERB [ARGS...]\n"
    "verbs: segment, phantom, pack, carve, sinter, bond, young, fracture, conduct, cg, dem, run\n"
    "Each verb is the executable tomodem-VERB; `tomodem VERB --help` shows its options.\n"
    "Options every verb shares (--json FILE, -q, -o FILE, --threads 0, lengths with units): docs/cli.md\n";

std::string self_dir() {
  char buf[PATH_MAX];
  const ssize_t n = ::readlink("/proc/self/exe", buf, sizeof buf - 1);
  if (n <= 0) return "";
  std::string p(buf, static_cast<std::size_t>(n));
  return p.substr(0, p.find_last_of('/'));
}
}  // namespace

int main(int argc, char** argv) {
  if (argc < 2 || !std::strcmp(argv[1], "-h") || !std::strcmp(argv[1], "--help")) {
    std::cout << kUsage;
    return argc < 2 ? tomodem::exit_code::bad_input : 0;
  }
  if (!std::strcmp(argv[1], "--version")) {
    std::cout << tomodem::version_string() << "\nfeatures: " << tomodem::build_features() << '\n';
    return 0;
  }
  const std::string tool = std::string("tomodem-") + argv[1];
  std::vector<char*> args;
  args.push_back(const_cast<char*>(tool.c_str()));
  for (int k = 2; k < argc; ++k) args.push_back(argv[k]);
  args.push_back(nullptr);
  const std::string beside = self_dir() + "/" + tool;
  if (::access(beside.c_str(), X_OK) == 0) ::execv(beside.c_str(), args.data());
  ::execvp(tool.c_str(), args.data());
  std::cerr << "tomodem: unknown verb '" << argv[1] << "' (no executable " << tool << ")\n" << kUsage;
  return tomodem::exit_code::bad_input;
}
