// Seeded mutation fuzzing of the in-process parsers (issue 16): the DEM scene loader, the pipeline
// loader, the pack config reader and the HDF5 packing reader get mutated copies of the files in
// corpus/ (byte flips, truncation, duplicated/removed lines, swapped values, numbers replaced by
// NaN/-1/1e300/huge integers, nested structures). A parser may refuse an input only with
// tomodem::InputError, RuntimeFailure or NumericalError; any other exception, a crash (the forked
// worker dies) or a hang (no end within TOMODEM_FUZZ_SLOW_SECONDS) fails the test.
//
// Every input is made from one seed alone (base seed + execution index), so a failure reproduces:
// the seed is printed, and the input is saved under corpus/crashes/ (commit it with a row in
// kKnownCrashes while the defect is open). Environment:
//   TOMODEM_FUZZ_SECONDS       time budget per parser (default 15)
//   TOMODEM_FUZZ_SEED          base seed (default 20261201)
//   TOMODEM_FUZZ_HANG_SECONDS  a single input running longer is looked at (default 5): it is run
//                              again alone; ending within TOMODEM_FUZZ_SLOW_SECONDS (default 60)
//                              it is a slow input (printed with its seed), else a hang
//   TOMODEM_FUZZ_MEMORY_MB     address-space cap of the worker (default 4096): a std::bad_alloc
//                              under it is counted apart (a valid but large request), not a failure
//   TOMODEM_FUZZ_REPLAY=FILE   run FILE once through the parser named by its prefix (debugging)
//   TOMODEM_FUZZ_RUN_OPEN=1    replay the known open crashes instead of skipping them
#include <execinfo.h>
#include <fcntl.h>
#include <gtest/gtest.h>
#include <signal.h>
#include <sys/mman.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <atomic>
#include <chrono>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <functional>
#include <new>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "tomodem/core/error.hpp"
#include "tomodem/core/packing_io.hpp"
#ifdef TOMODEM_FUZZ_DEM
#include "tomodem/dem/scene.hpp"
#endif
#ifdef TOMODEM_FUZZ_GEOMETRY
#include "tomodem/geometry/config.hpp"
#endif
#ifdef TOMODEM_FUZZ_PIPELINE
#include "tomodem/pipeline/pipeline.hpp"
#endif

namespace fs = std::filesystem;

namespace {

const fs::path kCorpus = fs::path(TOMODEM_SOURCE_DIR) / "tests/unit/fuzz/corpus";

double env_number(const char* name, double fallback) {
  const char* v = std::getenv(name);
  return v && *v ? std::atof(v) : fallback;
}

std::string slurp(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}
void spit(const fs::path& p, const std::string& s) { std::ofstream(p, std::ios::binary) << s; }

// ---- deterministic random numbers (splitmix64: the same stream on every platform)
struct Rng {
  std::uint64_t s;
  std::uint64_t next() {
    std::uint64_t z = (s += 0x9E3779B97F4A7C15ull);
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
    return z ^ (z >> 31);
  }
  std::size_t below(std::size_t n) { return n ? std::size_t(next() % n) : 0; }
};

// ---- mutations
const char* kNumbers[] = {".nan", "nan", "NaN", "-1", "0", "-0", "1e300", "-1e300", ".inf", "-.inf", "inf",
                          "1e-320", "99999999999999999999999", "1000000000000", "4294967296", "-2147483649",
                          "9223372036854775808", "1e12", "0x7fffffff", "1.5", "3e8"};
const char* kNested[] = {"{a: {b: [1, [2, {c: 3}]]}}", "[[[[[]]]]]", "{}", "[]", "~", "null", "''", "\"\"",
                         "[1, 2, 3]", "{x: 1}", "&a [*a]", "!!binary AAAA", "|\n  text\n  more", "? [1]\n: 2"};

std::vector<std::string> split_lines(const std::string& s) {
  std::vector<std::string> v;
  std::size_t k = 0;
  while (k < s.size()) {
    const auto e = s.find('\n', k);
    if (e == std::string::npos) {
      v.push_back(s.substr(k));
      break;
    }
    v.push_back(s.substr(k, e - k + 1));
    k = e + 1;
  }
  return v;
}
std::string join(const std::vector<std::string>& v) {
  std::string s;
  for (const auto& l : v) s += l;
  return s;
}

/// Spans of scalar values: numbers anywhere, and what follows ": " up to , } ] or the line end.
std::vector<std::pair<std::size_t, std::size_t>> value_spans(const std::string& s, bool numbers_only) {
  std::vector<std::pair<std::size_t, std::size_t>> v;
  for (std::size_t k = 0; k < s.size(); ++k) {
    const bool start = (k == 0 || std::strchr(" :[{,-\n", s[k - 1])) && (std::isdigit((unsigned char)s[k]) || s[k] == '.');
    if (start) {
      std::size_t e = k;
      while (e < s.size() && (std::isalnum((unsigned char)s[e]) || std::strchr(".+-", s[e]))) ++e;
      if (e > k) v.emplace_back(k, e - k);
      k = e;
    } else if (!numbers_only && s[k] == ':' && k + 1 < s.size() && s[k + 1] == ' ') {
      std::size_t b = k + 2, e = b;
      while (e < s.size() && !std::strchr(",}]\n#", s[e])) ++e;
      if (e > b) v.emplace_back(b, e - b);
    }
  }
  return v;
}

std::string nested(Rng& r) {
  if (r.below(4) == 0) {  // a deep but bounded nesting
    const std::size_t depth = 1 + r.below(64);
    return std::string(depth, '[') + "1" + std::string(depth, ']');
  }
  return kNested[r.below(std::size(kNested))];
}

std::string mutate_text(std::string s, Rng& r) {
  const int n = 1 + int(r.below(4));
  for (int m = 0; m < n; ++m) {
    if (s.empty()) s = "x";
    switch (r.below(9)) {
      case 0: {  // byte flip
        s[r.below(s.size())] ^= char(1u << r.below(8));
        break;
      }
      case 1:  // truncation
        s.resize(r.below(s.size()));
        break;
      case 2: {  // duplicated line
        auto l = split_lines(s);
        const auto k = r.below(l.size());
        l.insert(l.begin() + long(k), l[k]);
        s = join(l);
        break;
      }
      case 3: {  // removed line
        auto l = split_lines(s);
        l.erase(l.begin() + long(r.below(l.size())));
        s = join(l);
        break;
      }
      case 4:
      case 5: {  // a number replaced by NaN, -1, 1e300, a huge integer ...
        const auto v = value_spans(s, true);
        if (v.empty()) break;
        const auto [at, len] = v[r.below(v.size())];
        s.replace(at, len, kNumbers[r.below(std::size(kNumbers))]);
        break;
      }
      case 6: {  // two values swapped
        const auto v = value_spans(s, false);
        if (v.size() < 2) break;
        auto a = v[r.below(v.size())], b = v[r.below(v.size())];
        if (a.first > b.first) std::swap(a, b);
        if (a.first + a.second > b.first) break;
        const std::string va = s.substr(a.first, a.second), vb = s.substr(b.first, b.second);
        s.replace(b.first, b.second, va);
        s.replace(a.first, a.second, vb);
        break;
      }
      case 7: {  // a value replaced by a nested structure
        const auto v = value_spans(s, false);
        if (v.empty()) break;
        const auto [at, len] = v[r.below(v.size())];
        s.replace(at, len, nested(r));
        break;
      }
      case 8: {  // a line moved (indentation and order)
        auto l = split_lines(s);
        if (l.size() < 2) break;
        const auto a = r.below(l.size()), b = r.below(l.size());
        std::swap(l[a], l[b]);
        if (r.below(2)) l[b] = "  " + l[b];
        s = join(l);
        break;
      }
    }
  }
  return s;
}

std::string mutate_binary(std::string s, Rng& r) {
  const int n = 1 + int(r.below(8));
  for (int m = 0; m < n; ++m) {
    if (s.empty()) s = std::string(1, '\0');
    switch (r.below(5)) {
      case 0:
      case 1:  // byte flips, mostly in the first 4 KiB (superblock, object headers)
        for (int k = 0; k < 4; ++k) {
          const std::size_t span = r.below(3) ? std::min<std::size_t>(s.size(), 4096) : s.size();
          s[r.below(span)] ^= char(1u << r.below(8));
        }
        break;
      case 2:  // truncation
        s.resize(r.below(s.size()));
        break;
      case 3: {  // a run set to 0x00 or 0xFF
        const std::size_t at = r.below(s.size()), len = std::min(s.size() - at, 1 + r.below(64));
        std::memset(&s[at], r.below(2) ? 0xFF : 0x00, len);
        break;
      }
      case 4: {  // a run copied from elsewhere (a valid-looking but wrong header or address)
        const std::size_t len = 1 + r.below(16), from = r.below(s.size()), to = r.below(s.size());
        if (from + len <= s.size() && to + len <= s.size()) std::memmove(&s[to], &s[from], len);
        break;
      }
    }
  }
  return s;
}

// ---- the parsers
struct Target {
  std::string name;    // corpus files are <name>_*.<ext>
  std::string ext;
  bool binary;
  std::function<void(const std::string&)> parse;
  /// One fresh worker per input: libhdf5 keeps process-wide state (free lists, caches) that a
  /// damaged file can corrupt without crashing, so a later input would crash for it and its
  /// seed would not reproduce. The tools read one packing per process, as this then does.
  bool fresh_process = false;
};

std::vector<Target> targets() {
  std::vector<Target> t;
#ifdef TOMODEM_FUZZ_DEM
  t.push_back({"scene", "yaml", false, [](const std::string& p) { (void)tomodem::dem::load_scene(p, 1); }});
#endif
#ifdef TOMODEM_FUZZ_PIPELINE
  t.push_back({"pipeline", "yaml", false, [](const std::string& p) {
                 tomodem::pipeline::LoadOptions o;
                 o.tool_dir = TOMODEM_BIN_DIR;
                 (void)tomodem::pipeline::load(p, o);
               }});
#endif
#ifdef TOMODEM_FUZZ_GEOMETRY
  t.push_back({"pack", "yaml", false, [](const std::string& p) {
                 const auto c = tomodem::geometry::load_pack_config(p);
                 tomodem::geometry::validate(c.spec);  // what tomodem-pack does before any work
               }});
#endif
  t.push_back({"packing", "h5", true, [](const std::string& p) { (void)tomodem::read_packing(p); }, true});
  return t;
}

std::vector<fs::path> corpus_of(const Target& t) {
  std::vector<fs::path> v;
  for (const auto& e : fs::directory_iterator(kCorpus))
    if (e.is_regular_file() && e.path().filename().string().rfind(t.name + "_", 0) == 0 &&
        e.path().extension() == "." + t.ext)
      v.push_back(e.path());
  std::sort(v.begin(), v.end());
  return v;
}

/// The input of one seed: a corpus file, mutated.
std::string input_of(const Target& t, const std::vector<std::string>& corpus, std::uint64_t seed) {
  Rng r{seed};
  const std::string& base = corpus[r.below(corpus.size())];
  return t.binary ? mutate_binary(base, r) : mutate_text(base, r);
}

/// The corpus files beside each input: what the inputs refer to (a scene's packing, a pipeline's
/// config) is found relative to the input.
void stage_side_files(const fs::path& dir) {
  for (const auto& e : fs::directory_iterator(kCorpus))
    if (e.is_regular_file()) fs::copy_file(e.path(), dir / e.path().filename(), fs::copy_options::overwrite_existing);
}

/// Shared between the parent and its forked worker.
struct Shared {
  std::atomic<std::uint64_t> index;     // execution being run now
  std::atomic<std::uint64_t> done;      // executions finished
  std::atomic<std::uint64_t> refused;   // ... that ended in a tomodem error
  std::atomic<std::uint64_t> bad_alloc; // ... that ran out of the worker's memory cap
  std::atomic<int> unexpected;          // 1: the worker stopped on an unexpected exception
  char what[1024];
};

enum class Outcome { accepted, refused, bad_alloc, unexpected };

Outcome run_one(const Target& t, const std::string& path, std::string* what) {
  try {
    t.parse(path);
    return Outcome::accepted;
  } catch (const tomodem::InputError&) {
    return Outcome::refused;
  } catch (const tomodem::RuntimeFailure&) {
    return Outcome::refused;
  } catch (const tomodem::NumericalError&) {
    return Outcome::refused;
  } catch (const std::bad_alloc&) {
    return Outcome::bad_alloc;
  } catch (const std::exception& e) {
    *what = std::string(typeid(e).name()) + ": " + e.what();
    return Outcome::unexpected;
  } catch (...) {
    *what = "a non-standard exception";
    return Outcome::unexpected;
  }
}

/// Known defects outside this test, by the stack of the worker when it died or hung (a frame
/// name, matched as a substring). Findings of a known class are counted, not failed; each has a
/// committed reproducer under corpus/crashes/, replayed by Fuzz/KnownCrash (skipped while open).
struct KnownCrash {
  const char* target;
  const char* frame;   // a function on the stack of every crash of this class
  const char* file;    // the reproducer under corpus/crashes/
  const char* open;    // what is wrong today ("" once fixed: the replay must then pass)
};
const std::vector<KnownCrash> kKnownCrashes = {
    // fixed in 47c5e59 (string attributes read once in a child process first);
    // was: libhdf5 1.10 dies (SIGSEGV in H5HG_read) reading a variable-length string attribute whose
    // global-heap reference is corrupt: tomodem::h5::File::attr_string <- read_packing_groups
    // (libs/core/src/h5.cpp)
    {"packing", "H5HG_read", "packing-20261259.h5", ""},
    // fixed in 47c5e59;
    // was: libhdf5 1.10 loops for ever (H5C_protect <- H5HG_read) on a corrupt global-heap reference
    // of a variable-length string attribute: tomodem::h5::File::attr_string <- Reader::materials
    // (libs/core/src/h5.cpp)
    {"packing", "H5HG_read", "packing-20261292.h5", ""},
    // fixed in 47c5e59;
    // was: libhdf5 1.10 dies (SIGSEGV in H5FL_blk_free <- H5T__conv_vlen) converting a damaged
    // variable-length string attribute: tomodem::h5::File::attr_string <- read_packing_groups
    // (libs/core/src/h5.cpp)
    {"packing", "H5T__conv_vlen", "packing-1235.h5", ""},
    // refused by the attribute check of 47c5e59 before the group listing;
    // was: libhdf5 1.10 dies (SIGSEGV in H5F__accum_read <- H5HL_protect <- H5G__stab_iterate)
    // listing a group whose local heap is damaged: tomodem::h5::File::children <-
    // read_packing_groups (libs/core/src/h5.cpp)
    {"packing", "H5G__stab_iterate", "packing-1683.h5", ""},
    {"packing", "H5F__dest", "packing-1685.h5",
     "libhdf5 1.10 aborts ('double free or corruption', SIGABRT in H5MM_xfree <- H5C__flush_single_entry <- "
     "H5F__dest) closing a damaged file: tomodem::h5::File::~File <- read_packing; tomodem-conduct exits 134"},
    // fixed in 602ac27 (restitution at least 1e-3);
    // was: restitution 1e-5 (values swapped by the mutator) makes load_scene take 7 s:
    // hertz_damping_for_restitution integrates up to ~100 collisions of up to 10^7 RK4 steps
    // each (libs/dem/src/model.cpp; e = 1e-8: 16 s)
    {"scene", "hertz_restitution_for_damping", "scene-20261801.yaml", ""},
    // refused since 602ac27 (usable memory honours ulimit -v);
    // was: cells: 150 (13.5 million particles, under the memory check) past the worker's 4 GB:
    // std::bad_alloc is thrown inside the OpenMP region of Simulation::Impl::linked_cells
    // (vector::reserve) and std::terminate aborts the process (SIGABRT, no message) instead of
    // exit 1 (libs/dem/src/simulation.cpp, via Simulation::contacts in read_scene)
    {"scene", "linked_cells", "scene-4076.yaml", ""},
    // fixed in 602ac27 (insertion grid sized by the count);
    // was: radius 1e-12 in a 2 mm cell (arrangement random): random_sites (libs/dem/src/scene.cpp)
    // sizes its bin grid by the radius and throws std::length_error; tomodem-dem exits 1 'cannot
    // create std::vector larger than max_size()' instead of 2 naming particles.generate.radius
    {"scene", "std::vector larger than max_size", "scene-17254.yaml", ""},
    // fixed with the unused-variable check's walk (each collection once);
    // was: a self-alias (`desc: &a [*a]`) is a cycle in yaml-cpp's node graph, and var_uses
    // (libs/pipeline/src/load.cpp) recursed through it until the stack overflowed (SIGSEGV)
    {"pipeline", "var_uses", "pipeline-20265055.yaml", ""},
};

const KnownCrash* known_class(const std::string& target, const std::string& stack) {
  for (const auto& k : kKnownCrashes)
    if (target == k.target && *k.open && stack.find(k.frame) != std::string::npos) return &k;
  return nullptr;
}

// ---- the worker's last words: its stack when it crashes (SIGSEGV ...) or is found hung (SIGUSR1)
char g_stack_path[4096];
void dump_stack(int sig) {
  void* frames[64];
  const int n = ::backtrace(frames, 64);
  const int fd = ::open(g_stack_path, O_CREAT | O_TRUNC | O_WRONLY, 0644);
  if (fd >= 0) {
    ::backtrace_symbols_fd(frames, n, fd);
    ::close(fd);
  }
  ::signal(sig, SIG_DFL);
  ::raise(sig);
}
void install_stack_dump(const std::string& path) {
  std::snprintf(g_stack_path, sizeof g_stack_path, "%s", path.c_str());
  void* warm[2];
  ::backtrace(warm, 2);  // loads libgcc now, not inside the handler
  static std::vector<char> alt(1 << 16);
  stack_t ss{};
  ss.ss_sp = alt.data();
  ss.ss_size = alt.size();
  ::sigaltstack(&ss, nullptr);  // a stack overflow still gets its dump
  struct sigaction sa {};
  sa.sa_handler = dump_stack;
  sa.sa_flags = SA_ONSTACK;
  for (int sig : {SIGSEGV, SIGBUS, SIGFPE, SIGILL, SIGABRT, SIGUSR1}) ::sigaction(sig, &sa, nullptr);
}

/// How one input ended when run alone in a fresh worker.
struct Alone {
  double seconds = 0;
  bool timed_out = false;
  int status = 0;  // waitpid status
  bool clean() const { return !timed_out && WIFEXITED(status) && WEXITSTATUS(status) == 0; }
};

/// Runs one input in a fresh worker (the same memory cap, its stack dumped on a crash).
Alone run_alone(const Target& t, const std::string& path, const std::string& data, double memory_mb, double limit,
                const std::string& stack_file) {
  spit(path, data);
  const auto t0 = std::chrono::steady_clock::now();
  const pid_t pid = ::fork();
  if (pid == 0) {
    rlimit lim{rlim_t(memory_mb * 1048576.0), rlim_t(memory_mb * 1048576.0)};
    ::setrlimit(RLIMIT_AS, &lim);
    if (::chdir(fs::path(path).parent_path().c_str()) != 0) ::_exit(12);
    install_stack_dump(stack_file);
    std::string what;
    const Outcome o = run_one(t, path, &what);
    ::_exit(o == Outcome::unexpected ? 10 : 0);
  }
  Alone a;
  while (::waitpid(pid, &a.status, WNOHANG) == 0) {
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
    if (std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count() > limit) {
      ::kill(pid, SIGUSR1);
      std::this_thread::sleep_for(std::chrono::milliseconds(500));
      ::kill(pid, SIGKILL);
      ::waitpid(pid, &a.status, 0);
      a.timed_out = true;
      break;
    }
  }
  a.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return a;
}

void fuzz(const Target& t) {
  const auto files = corpus_of(t);
  ASSERT_FALSE(files.empty()) << "no corpus files " << t.name << "_*." << t.ext << " in " << kCorpus;
  std::vector<std::string> corpus;
  for (const auto& f : files) corpus.push_back(slurp(f));
  const double budget = env_number("TOMODEM_FUZZ_SECONDS", 15);
  const double hang = env_number("TOMODEM_FUZZ_HANG_SECONDS", 5);
  const double slow = env_number("TOMODEM_FUZZ_SLOW_SECONDS", 60);
  const double memory_mb = env_number("TOMODEM_FUZZ_MEMORY_MB", 4096);
  const auto base = std::uint64_t(env_number("TOMODEM_FUZZ_SEED", 20261201));
  const fs::path dir = fs::temp_directory_path() / ("tomodem-fuzz-" + t.name + "-" + std::to_string(::getpid()));
  fs::remove_all(dir);
  fs::create_directories(dir);
  stage_side_files(dir);
  const std::string input = (dir / ("input." + t.ext)).string();

  auto* sh = static_cast<Shared*>(
      ::mmap(nullptr, sizeof(Shared), PROT_READ | PROT_WRITE, MAP_SHARED | MAP_ANONYMOUS, -1, 0));
  ASSERT_NE(sh, MAP_FAILED);
  new (sh) Shared{};
  const auto start = std::chrono::steady_clock::now();
  const auto elapsed = [&] { return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count(); };
  std::uint64_t next = 0, executions = 0, refused = 0, bad_alloc = 0, known_hits = 0;
  std::vector<std::string> findings, slow_inputs;
  const std::string stack_file = (dir / "stack.txt").string();

  while (elapsed() < budget) {
    sh->index = next;
    sh->done = 0;
    sh->refused = 0;
    sh->bad_alloc = 0;
    sh->unexpected = 0;
    const double left = budget - elapsed();
    const pid_t pid = ::fork();
    ASSERT_GE(pid, 0);
    if (pid == 0) {  // the worker: runs inputs until the budget is spent or something goes wrong
      if (::chdir(dir.c_str()) != 0) ::_exit(12);
      install_stack_dump(stack_file);
      rlimit lim{rlim_t(memory_mb * 1048576.0), rlim_t(memory_mb * 1048576.0)};
      ::setrlimit(RLIMIT_AS, &lim);
      const auto w0 = std::chrono::steady_clock::now();
      for (std::uint64_t i = next;; ++i) {
        if (std::chrono::duration<double>(std::chrono::steady_clock::now() - w0).count() > left) ::_exit(0);
        sh->index = i;
        spit(input, input_of(t, corpus, base + i));
        std::string what;
        const Outcome o = run_one(t, input, &what);
        if (o == Outcome::unexpected) {
          std::snprintf(sh->what, sizeof sh->what, "%s", what.c_str());
          sh->unexpected = 1;
          ::_exit(10);
        }
        sh->refused += o == Outcome::refused;
        sh->bad_alloc += o == Outcome::bad_alloc;
        ++sh->done;
        if (t.fresh_process) ::_exit(20);  // the next input gets a fresh worker
      }
    }
    // the parent: watch for progress; a stuck input is a hang
    std::uint64_t seen = sh->index;
    auto last = std::chrono::steady_clock::now();
    int status = 0;
    bool hung = false;
    while (::waitpid(pid, &status, WNOHANG) == 0) {
      std::this_thread::sleep_for(std::chrono::milliseconds(20));
      if (sh->index != seen) seen = sh->index, last = std::chrono::steady_clock::now();
      if (std::chrono::duration<double>(std::chrono::steady_clock::now() - last).count() > hang) {
        ::kill(pid, SIGUSR1);  // its stack, then it dies; SIGKILL if that does not work
        for (int k = 0; k < 100 && ::waitpid(pid, &status, WNOHANG) == 0; ++k)
          std::this_thread::sleep_for(std::chrono::milliseconds(20));
        ::kill(pid, SIGKILL);
        ::waitpid(pid, &status, 0);
        hung = true;
        break;
      }
    }
    executions += sh->done;
    refused += sh->refused;
    bad_alloc += sh->bad_alloc;
    const std::uint64_t i = sh->index;
    if (!hung && WIFEXITED(status) && WEXITSTATUS(status) == 20) {  // one input done (fresh_process)
      next = i + 1;
      continue;
    }
    std::string kind;
    if (hung) kind = "hang (no progress for " + std::to_string(int(hang)) + " s)";
    else if (WIFSIGNALED(status)) kind = std::string("crash: ") + strsignal(WTERMSIG(status));
    else if (WIFEXITED(status) && WEXITSTATUS(status) == 10) kind = std::string("unexpected exception: ") + sh->what;
    else if (WIFEXITED(status) && WEXITSTATUS(status) != 0) kind = "worker exit " + std::to_string(WEXITSTATUS(status));
    if (kind.empty()) break;  // the budget is spent
    ++executions;
    next = i + 1;  // go on past the finding
    const std::uint64_t seed = base + i;
    std::string stack = slurp(stack_file);
    fs::remove(stack_file);
    if (stack.empty()) stack = kind;  // an unexpected exception: its type and message
    if (const KnownCrash* k = known_class(t.name, stack)) {
      ++known_hits;
      std::cout << "[ fuzz ] " << t.name << " seed " << seed << ": " << kind << " of the known class " << k->frame
                << " (" << k->file << ")" << std::endl;
      continue;
    }
    if (hung) {  // slow or stuck? Run the input alone, with a long limit: a slow end is no hang.
      const Alone a = run_alone(t, input, input_of(t, corpus, seed), memory_mb, slow, stack_file);
      if (a.clean()) {
        slow_inputs.push_back(t.name + " seed " + std::to_string(seed) + ": " + std::to_string(a.seconds) + " s");
        std::cout << "[ fuzz ] " << t.name << " seed " << seed << ": slow, not stuck (" << a.seconds << " s alone)"
                  << std::endl;
        continue;
      }
      if (a.timed_out) kind = "hang (no end within " + std::to_string(int(slow)) + " s)";
      else if (WIFSIGNALED(a.status)) kind = std::string("crash when run alone: ") + strsignal(WTERMSIG(a.status));
      else kind = "unexpected exception when run alone";
      const std::string again = slurp(stack_file);
      fs::remove(stack_file);
      if (!again.empty()) stack = again;
      if (const KnownCrash* k = known_class(t.name, stack)) {
        ++known_hits;
        std::cout << "[ fuzz ] " << t.name << " seed " << seed << ": " << kind << " of the known class " << k->frame
                  << " (" << k->file << ")" << std::endl;
        continue;
      }
    }
    const fs::path crashes = kCorpus / "crashes";
    fs::create_directories(crashes);
    const fs::path repro = crashes / (t.name + "-" + std::to_string(seed) + "." + t.ext);
    spit(repro, input_of(t, corpus, seed));
    findings.push_back(t.name + " seed " + std::to_string(seed) + ": " + kind + "; reproducer " + repro.string() +
                       "\nstack:\n" + stack);
  }
  ::munmap(sh, sizeof(Shared));
  fs::remove_all(dir);
  std::cout << "[ fuzz ] " << t.name << ": " << executions << " executions in " << elapsed() << " s (budget " << budget
            << " s, base seed " << base << "), " << refused << " refused with a tomodem error, " << bad_alloc
            << " over the " << memory_mb << " MB worker cap, " << slow_inputs.size() << " slow (valid but large), "
            << known_hits << " of a known open class, "
            << findings.size() << " failures" << std::endl;
  for (const auto& f : findings) ADD_FAILURE() << f;
  EXPECT_GT(executions, 0u);
}

const Target* target_named(const std::string& name) {
  static const std::vector<Target> all = targets();
  for (const auto& t : all)
    if (t.name == name) return &t;
  return nullptr;
}

}  // namespace

TEST(Fuzz, SceneLoader) {
  const Target* t = target_named("scene");
  if (!t) GTEST_SKIP() << "tomodem_dem is not part of this build";
  fuzz(*t);
}

TEST(Fuzz, PipelineLoader) {
  const Target* t = target_named("pipeline");
  if (!t) GTEST_SKIP() << "tomodem_pipeline is not part of this build";
  fuzz(*t);
}

TEST(Fuzz, PackConfigReader) {
  const Target* t = target_named("pack");
  if (!t) GTEST_SKIP() << "tomodem_geometry is not part of this build";
  fuzz(*t);
}

TEST(Fuzz, PackingReader) { fuzz(*target_named("packing")); }

// The valid corpus itself must load (else the fuzzer only ever tests the error paths).
TEST(Fuzz, CorpusLoads) {
  const fs::path dir = fs::temp_directory_path() / ("tomodem-fuzz-corpus-" + std::to_string(::getpid()));
  fs::create_directories(dir);
  stage_side_files(dir);
  for (const char* name : {"scene", "pipeline", "pack", "packing"}) {
    const Target* t = target_named(name);
    if (!t) continue;
    for (const auto& f : corpus_of(*t)) {
      const fs::path p = dir / f.filename();
      fs::copy_file(f, p, fs::copy_options::overwrite_existing);
      std::string what;
      const fs::path cwd = fs::current_path();
      fs::current_path(dir);
      EXPECT_NO_THROW(t->parse(p.string())) << f;
      fs::current_path(cwd);
    }
  }
  fs::remove_all(dir);
}

// Known crashes: each reproducer runs in a forked worker (the fuzzer's memory cap and time limit)
// and must end in a tomodem error or in success; the row is skipped (with its reason) while open.
class FuzzKnownCrash : public ::testing::TestWithParam<std::size_t> {};
TEST_P(FuzzKnownCrash, Replay) {
  if (GetParam() >= kKnownCrashes.size()) GTEST_SKIP() << "no known crashes";
  const auto& k = kKnownCrashes[GetParam()];
  // TOMODEM_FUZZ_RUN_OPEN=1 replays the open ones too (to see which ones a fix has closed).
  if (*k.open && !std::getenv("TOMODEM_FUZZ_RUN_OPEN")) GTEST_SKIP() << "open: " << k.file << ": " << k.open;
  const Target* t = target_named(k.target);
  if (!t) GTEST_SKIP() << "no parser " << k.target << " in this build";
  const fs::path dir = fs::temp_directory_path() / ("tomodem-fuzz-replay-" + std::to_string(::getpid()));
  fs::create_directories(dir);
  stage_side_files(dir);
  const std::string input = (dir / ("input." + t->ext)).string();
  const Alone a = run_alone(*t, input, slurp(kCorpus / "crashes" / k.file), env_number("TOMODEM_FUZZ_MEMORY_MB", 4096),
                            env_number("TOMODEM_FUZZ_SLOW_SECONDS", 60), (dir / "stack.txt").string());
  EXPECT_TRUE(a.clean()) << k.file << (a.timed_out ? ": still running after the time limit" : ": did not end cleanly")
                         << "\n" << slurp(dir / "stack.txt");
  EXPECT_LT(a.seconds, env_number("TOMODEM_FUZZ_HANG_SECONDS", 5)) << k.file << ": ends, but slowly";
  fs::remove_all(dir);
}
INSTANTIATE_TEST_SUITE_P(Fuzz, FuzzKnownCrash, ::testing::Range<std::size_t>(0, std::max<std::size_t>(1, kKnownCrashes.size())));

// TOMODEM_FUZZ_REPLAY=corpus/crashes/scene-123.yaml runs one file in this process (for gdb).
TEST(Fuzz, Replay) {
  const char* f = std::getenv("TOMODEM_FUZZ_REPLAY");
  if (!f || !*f) GTEST_SKIP() << "set TOMODEM_FUZZ_REPLAY=FILE to replay one input";
  const std::string name = fs::path(f).filename().string();
  const Target* t = target_named(name.substr(0, name.find_first_of("-_")));
  ASSERT_TRUE(t) << "no parser for " << name;
  std::string what;
  EXPECT_NE(run_one(*t, f, &what), Outcome::unexpected) << what;
}
