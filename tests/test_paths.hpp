// The folders a test reads from, starts tools in and keeps its inputs in, as TOMODEM_TEST_DATA,
// TOMODEM_BIN_DIR, TOMODEM_SOURCE_DIR and TOMODEM_BUILD_DIR (const char*). They are defined in test_paths.cpp, which CMake writes for
// each build tree, rather than on every test's command line: the test objects then do not depend
// on where the checkout lies, and a compiler cache serves them to a second clone (build.sh).
// Force-included into every test that links the library tomodem_test_paths (tests/CMakeLists.txt).
#pragma once

namespace tomodem_test_paths {
extern const char* const data_dir;    // <source>/data
extern const char* const bin_dir;     // <build>/bin
extern const char* const source_dir;  // <source>
extern const char* const build_dir;   // <build>
}  // namespace tomodem_test_paths

#define TOMODEM_TEST_DATA (::tomodem_test_paths::data_dir)
#define TOMODEM_BIN_DIR (::tomodem_test_paths::bin_dir)
#define TOMODEM_SOURCE_DIR (::tomodem_test_paths::source_dir)
#define TOMODEM_BUILD_DIR (::tomodem_test_paths::build_dir)
