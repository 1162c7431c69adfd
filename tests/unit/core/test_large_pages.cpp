// The replacement operator new of tomodem_large_pages (libs/core/src/large_pages.cpp): a large
// block is advised for huge pages before its first touch, a small one is left alone, and the
// memory works as any other. The kernel's own record is read back: /proc/self/smaps lists the
// mapping's flags, "hg" for MADV_HUGEPAGE.
#include <gtest/gtest.h>

#include <cstdint>
#include <fstream>
#include <numeric>
#include <sstream>
#include <string>
#include <vector>

namespace {
// The VmFlags of the mapping that holds address a ("" when none is found).
std::string vm_flags_at(const void* a) {
  const auto x = reinterpret_cast<std::uintptr_t>(a);
  std::ifstream smaps("/proc/self/smaps");
  std::string line;
  bool inside = false;
  while (std::getline(smaps, line)) {
    std::uintptr_t lo = 0, hi = 0;
    char dash = 0;
    std::istringstream head(line);
    if (head >> std::hex >> lo >> dash >> hi && dash == '-' && line.find(':') > line.find(' ')) {
      inside = x >= lo && x < hi;
      continue;
    }
    if (inside && line.rfind("VmFlags:", 0) == 0) return line.substr(8) + " ";
  }
  return "";
}
bool has_flag(const std::string& flags, const std::string& f) { return flags.find(" " + f + " ") != std::string::npos; }
}  // namespace

TEST(LargePages, LargeBlocksAreAdvisedSmallOnesAreNot) {
  if (!std::ifstream("/sys/kernel/mm/transparent_hugepage/enabled"))
    GTEST_SKIP() << "this kernel has no transparent huge pages";
  std::vector<float> big(std::size_t(64) << 20 >> 2);  // 64 MiB: glibc maps it on its own
  const std::string flags = vm_flags_at(big.data() + big.size() / 2);
  ASSERT_FALSE(flags.empty()) << "no mapping found in /proc/self/smaps";
  EXPECT_TRUE(has_flag(flags, "hg")) << "VmFlags:" << flags;
  // The values are the vector's own: zero-initialised, then written and read back.
  EXPECT_EQ(std::accumulate(big.begin(), big.end(), 0.0), 0.0);
  std::iota(big.begin(), big.end(), 0.0f);
  EXPECT_EQ(big[12345], 12345.0f);

  std::vector<char> small(std::size_t(1) << 20);  // 1 MiB, below the limit: no advice
  EXPECT_FALSE(has_flag(vm_flags_at(small.data()), "hg"));
}
