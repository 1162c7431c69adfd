// Transparent huge pages for the large arrays of the image tools (issue 19, scans larger than
// memory): a replacement of the global operator new, linked into the executables that hold
// volumes (the OBJECT library tomodem_large_pages; tools/*/CMakeLists.txt name which), never
// into a library.
//
// Why: Debian's kernel gives huge pages only where a program asks for them (THP "madvise"
// mode). A volume's arrays are hundreds of MB, and each block of a chunked run allocates them
// afresh: with 4 KiB pages the first touch of every page faults, and the distance transform's
// passes along y and z step one page per voxel, a TLB miss each. 512^3 chunked with grains, one
// thread, medians of three: 110.7 s, 16.4 s of it in the kernel; with 2 MiB pages 84.6 s, 5.0 s
// in the kernel (docs/benchmarks.md, "Huge pages"); tomodem-conduct --image 256^3 0.80x the
// wall time, tomodem-phantom 512^3 0.52x.
//
// How: what glibc's own glibc.malloc.hugetlb=1 tunable does for its mapped blocks, done here so
// that no environment variable is needed. Blocks of at least kLarge bytes are mapped by glibc on
// their own (its largest mmap threshold), untouched when malloc returns them; the advice marks
// their 2 MiB-aligned interior before the first touch. It is advice: where the kernel has no huge
// pages, or refuses, nothing changes. operator delete stays std::free.
#include <sys/mman.h>

#include <cstdint>
#include <cstdlib>
#include <new>

namespace {
constexpr std::size_t kLarge = std::size_t(32) << 20;   // glibc's DEFAULT_MMAP_THRESHOLD_MAX on 64-bit
constexpr std::uintptr_t kHuge = std::uintptr_t(2) << 20;  // x86-64 huge page

void* allocate(std::size_t n) {
  void* p = std::malloc(n ? n : 1);
  if (p && n >= kLarge) {
    const std::uintptr_t lo = (reinterpret_cast<std::uintptr_t>(p) + kHuge - 1) & ~(kHuge - 1);
    const std::uintptr_t hi = (reinterpret_cast<std::uintptr_t>(p) + n) & ~(kHuge - 1);
    if (hi > lo) madvise(reinterpret_cast<void*>(lo), hi - lo, MADV_HUGEPAGE);
  }
  return p;
}
}  // namespace

void* operator new(std::size_t n) {
  for (;;) {
    if (void* p = allocate(n)) return p;
    const std::new_handler handler = std::get_new_handler();
    if (!handler) throw std::bad_alloc();
    handler();
  }
}
void operator delete(void* p) noexcept { std::free(p); }
void operator delete(void* p, std::size_t) noexcept { std::free(p); }
