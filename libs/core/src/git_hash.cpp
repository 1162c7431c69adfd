// The commit of the build (git_hash.inc, written at build time by cmake/git_hash.cmake): kept in
// its own file so that a new commit recompiles only this one.
#include "git_hash.hpp"

namespace tomodem {
const char* git_hash() {
  return
#include "git_hash.inc"
      ;
}
}  // namespace tomodem
