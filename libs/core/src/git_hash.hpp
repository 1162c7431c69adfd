#pragma once
// Private to libs/core: the build's git commit (git_hash.cpp).
namespace tomodem {
/// "1a2b3c4d5e6f", with "+dirty" when tracked files differed from it, or "unknown".
const char* git_hash();
}  // namespace tomodem
