#include "tomodem/core/output.hpp"

#include <fcntl.h>
#include <signal.h>
#include <sys/resource.h>
#include <sys/stat.h>
#include <unistd.h>
#include <xxhash.h>

#include <algorithm>
#include <atomic>
#include <cctype>
#include <cerrno>
#include <chrono>
#include <climits>
#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <ctime>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "tomodem/core/error.hpp"
#include "tomodem/core/tool.hpp"

namespace tomodem {

namespace {
namespace fs = std::filesystem;

// Temporaries a signal handler may have to remove. Fixed storage: the handler can neither
// allocate nor lock. A slot is claimed by CAS on `state` (0 free, 1 being written, 2 live).
constexpr int kSlots = 128;
struct Slot {
  std::atomic<int> state{0};
  char path[PATH_MAX];
};
Slot g_slots[kSlots];

void register_temporary(const std::string& tmp) {
  if (tmp.size() >= PATH_MAX) return;
  for (auto& s : g_slots)
    if (s.state.load() == 2 && tmp == s.path) return;
  for (auto& s : g_slots) {
    int expected = 0;
    if (s.state.compare_exchange_strong(expected, 1)) {
      std::memcpy(s.path, tmp.c_str(), tmp.size() + 1);
      s.state.store(2);
      return;
    }
  }
}

void unregister_temporary(const std::string& tmp) {
  for (auto& s : g_slots)
    if (s.state.load() == 2 && tmp == s.path) s.state.store(0);
}

extern "C" void cleanup_and_reraise(int sig) {
  remove_registered_temporaries();
  std::signal(sig, SIG_DFL);
  std::raise(sig);
}

std::string errno_text(int e) { return e == ENOSPC ? "no space left on device" : std::strerror(e); }

}  // namespace

bool writes_outputs() {
  // Decided once the tool is named (run_tool names it before its body runs); before that, and in
  // programs that are not tools (tests under mpirun), every rank writes.
  static const bool silent = launched_rank() > 0;
  return !silent || tool_name() == "tomodem";
}

namespace {
// An existing output that is not a regular file (/dev/null, a FIFO, a terminal): it is written
// through, never renamed over. Renaming a temporary onto /dev/null replaced the device with a file.
bool is_special_file(const std::string& path) {
  struct stat st {};
  return ::stat(path.c_str(), &st) == 0 && !S_ISREG(st.st_mode) && !S_ISDIR(st.st_mode);
}

// Copies the finished temporary into the special file `final_path`.
void write_through(const std::string& tmp, const std::string& final_path) {
  const int in = ::open(tmp.c_str(), O_RDONLY | O_CLOEXEC);
  const int out = in < 0 ? -1 : ::open(final_path.c_str(), O_WRONLY | O_CLOEXEC);
  int e = in < 0 || out < 0 ? errno : 0;
  char buf[1 << 16];
  for (ssize_t n; e == 0 && (n = ::read(in, buf, sizeof buf)) != 0;) {
    if (n < 0) {
      if (errno != EINTR) e = errno;
      continue;
    }
    for (ssize_t done = 0; e == 0 && done < n;) {
      const ssize_t w = ::write(out, buf + done, std::size_t(n - done));
      if (w < 0 && errno == EINTR) continue;
      if (w <= 0) e = w < 0 ? errno : ENOSPC;
      else done += w;
    }
  }
  if (in >= 0) ::close(in);
  if (out >= 0 && ::close(out) != 0 && e == 0) e = errno;
  ::unlink(tmp.c_str());
  if (e != 0) throw RuntimeFailure("cannot write " + final_path + ": " + std::strerror(e));
}
}  // namespace

std::string temporary_path(const std::string& final_path) {
  // Same folder as the result, so the final rename stays on one file system (atomic); for a
  // special file (/dev/null) the temporary goes to the temporary folder instead of /dev.
  const std::string tmp =
      is_special_file(final_path)
          ? (fs::temp_directory_path() / ("tomodem-" + fs::path(final_path).filename().string())).string() +
                ".tmp" + std::to_string(::getpid())
          : final_path + ".tmp" + std::to_string(::getpid());
  // A silent rank creates no temporary (HDF5 builds its files in memory, text is not written).
  if (writes_outputs()) register_temporary(tmp);
  return tmp;
}

void remove_registered_temporaries() {
  for (auto& s : g_slots)
    if (s.state.load() == 2) ::unlink(s.path);
}

void install_cleanup_handlers() {
  struct sigaction sa {};
  sa.sa_handler = cleanup_and_reraise;
  sigemptyset(&sa.sa_mask);
  sa.sa_flags = SA_RESETHAND;
  ::sigaction(SIGINT, &sa, nullptr);
  ::sigaction(SIGTERM, &sa, nullptr);
  ::sigaction(SIGHUP, &sa, nullptr);
}

namespace {
// Outputs committed while commits are deferred, in commit order (final paths).
bool g_deferred = false;
std::vector<std::string> g_pending;

void rename_onto(const std::string& final_path) {
  const std::string tmp = temporary_path(final_path);
  if (!writes_outputs()) {  // rank 0 writes the file; whatever a writer left under this rank's name goes
    ::unlink(tmp.c_str());
    return;
  }
  if (is_special_file(final_path)) {
    unregister_temporary(tmp);
    write_through(tmp, final_path);
    return;
  }
  if (std::rename(tmp.c_str(), final_path.c_str()) != 0) {
    const int e = errno;
    ::unlink(tmp.c_str());
    unregister_temporary(tmp);
    throw RuntimeFailure("cannot rename " + tmp + " to " + final_path + ": " + std::strerror(e));
  }
  unregister_temporary(tmp);
}
}  // namespace

void discard_output(const std::string& final_path) {
  const std::string tmp = temporary_path(final_path);
  ::unlink(tmp.c_str());
  unregister_temporary(tmp);
  g_pending.erase(std::remove(g_pending.begin(), g_pending.end(), final_path), g_pending.end());
}

void defer_commits() { g_deferred = true; }

void commit_output(const std::string& final_path, Commit when) {
  if (g_deferred && when == Commit::with_run && writes_outputs()) {
    // The temporary must exist now: a missing one is the writer's error, said where it happens.
    const std::string tmp = temporary_path(final_path);
    if (::access(tmp.c_str(), F_OK) != 0) {
      const int e = errno;
      throw RuntimeFailure("cannot rename " + tmp + " to " + final_path + ": " + std::strerror(e));
    }
    if (std::find(g_pending.begin(), g_pending.end(), final_path) == g_pending.end()) g_pending.push_back(final_path);
    return;
  }
  g_pending.erase(std::remove(g_pending.begin(), g_pending.end(), final_path), g_pending.end());
  rename_onto(final_path);
}

void commit_pending_outputs() {
  g_deferred = false;
  std::vector<std::string> pending;
  pending.swap(g_pending);
  for (std::size_t i = 0; i < pending.size(); ++i) {
    try {
      rename_onto(pending[i]);
    } catch (...) {
      for (std::size_t j = i + 1; j < pending.size(); ++j) discard_output(pending[j]);
      throw;
    }
  }
}

void discard_pending_outputs() {
  g_deferred = false;
  std::vector<std::string> pending;
  pending.swap(g_pending);
  for (const auto& f : pending) discard_output(f);
}

void write_text_atomic(const std::string& path, const std::string& text) {
  if (!writes_outputs()) return;
  const std::string tmp = temporary_path(path);
  const auto fail = [&](int fd, int e) {
    if (fd >= 0) ::close(fd);
    discard_output(path);
    throw RuntimeFailure("cannot write " + path + ": " + errno_text(e));
  };
  const int fd = ::open(tmp.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
  if (fd < 0) fail(-1, errno);
  for (std::size_t done = 0; done < text.size();) {
    const ssize_t n = ::write(fd, text.data() + done, text.size() - done);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) fail(fd, n < 0 ? errno : ENOSPC);
    done += static_cast<std::size_t>(n);
  }
  // The data must be on disk before the rename makes it the file: a crash or a full disk
  // after the rename would otherwise leave an empty file where a good one was.
  if (::fdatasync(fd) != 0 && errno != EINVAL) fail(fd, errno);
  if (::close(fd) != 0) fail(-1, errno);
  commit_output(path);
}

void refuse_output_over_input(const std::string& output, const std::string& option,
                              const std::vector<std::string>& inputs, bool output_is_folder) {
  if (output.empty() || output == "-") return;
  std::error_code ec;
  const fs::path out = fs::weakly_canonical(fs::absolute(output, ec), ec);
  for (const auto& in : inputs) {
    if (in.empty()) continue;
    const fs::path inp = fs::weakly_canonical(fs::absolute(in, ec), ec);
    bool same = out == inp || fs::equivalent(output, in, ec);
    if (!same && output_is_folder) {
      const auto rel = inp.lexically_relative(out);
      same = !rel.empty() && *rel.begin() != "..";
    }
    if (same)
      throw InputError("", option, output,
                       output_is_folder ? "the output folder holds the input " + in + ": choose another folder"
                                        : "this is the input " + in + ": writing it would destroy it; choose another name");
  }
}

namespace {
// Temporaries of `output` left by an earlier run killed by SIGKILL (no handler runs): NAME.tmpPID,
// or NAME.tmpPID.EXT for ITK's formats, whose process is gone. A live process's temporary is left
// alone: that run is writing the same output now, which check_outputs cannot see.
void remove_stale_temporaries(const fs::path& output) {
  const fs::path folder = output.parent_path().empty() ? fs::path(".") : output.parent_path();
  const std::string prefix = output.filename().string() + ".tmp";
  std::error_code ec;
  for (fs::directory_iterator it(folder, ec), end; !ec && it != end; it.increment(ec)) {
    const std::string name = it->path().filename().string();
    if (name.compare(0, prefix.size(), prefix) != 0 || !it->is_regular_file(ec)) continue;
    std::size_t digits = prefix.size();
    while (digits < name.size() && std::isdigit(static_cast<unsigned char>(name[digits]))) ++digits;
    if (digits == prefix.size() || (digits < name.size() && name[digits] != '.')) continue;
    const long pid = std::strtol(name.c_str() + prefix.size(), nullptr, 10);
    if (pid <= 0 || pid == ::getpid() || ::kill(pid_t(pid), 0) == 0 || errno != ESRCH) continue;
    if (::unlink(it->path().c_str()) == 0)
      info("removed " + it->path().string() + ", the temporary of a run that was killed (process " +
           std::to_string(pid) + " is gone)");
  }
}
}  // namespace

void check_outputs(const std::vector<std::string>& inputs, const std::vector<OutputName>& outputs) {
  const auto is_file = [](const std::string& p) { return !p.empty() && p != "-"; };
  for (const OutputName& o : outputs) {
    if (!is_file(o.path)) continue;
    refuse_output_over_input(o.path, o.option, inputs);
    std::error_code ec;
    if (fs::is_directory(o.path, ec)) throw InputError("", o.option, o.path, "is a folder; give the name of a file to write");
    const fs::path parent = fs::path(o.path).parent_path();
    if (!parent.empty() && !fs::is_directory(parent, ec))
      throw InputError("", o.option, o.path, "the folder " + parent.string() + " does not exist");
    // A folder that exists but cannot take a file (read-only mount, immutable, no permission)
    // would otherwise be found only at the end, after the work and the other outputs. A special
    // file (/dev/stdout, a FIFO) is written through, not replaced: its folder need not take one.
    if (fs::exists(o.path, ec) && !fs::is_regular_file(o.path, ec)) continue;
    const fs::path probe = (parent.empty() ? fs::path(".") : parent) / (".tomodem-probe-" + std::to_string(::getpid()));
    const int fd = ::open(probe.c_str(), O_WRONLY | O_CREAT | O_EXCL, 0600);
    if (fd < 0 && errno != EEXIST)
      throw InputError("", o.option, o.path,
                       "the folder " + (parent.empty() ? std::string(".") : parent.string()) +
                           " cannot be written: " + std::strerror(errno));
    if (fd >= 0) ::close(fd), ::unlink(probe.c_str());
    remove_stale_temporaries(o.path);
  }
  const auto same = [](const std::string& a, const std::string& b) {
    std::error_code ec;
    return fs::weakly_canonical(fs::absolute(a, ec), ec) == fs::weakly_canonical(fs::absolute(b, ec), ec) ||
           fs::equivalent(a, b, ec);
  };
  for (std::size_t a = 0; a < outputs.size(); ++a)
    for (std::size_t b = a + 1; b < outputs.size(); ++b)
      if (is_file(outputs[a].path) && is_file(outputs[b].path) && same(outputs[a].path, outputs[b].path))
        throw InputError("", outputs[b].option, outputs[b].path,
                         "the same file as " + outputs[a].option + " " + outputs[a].path +
                             ": two outputs cannot share one file; choose another name");
}

std::string xdmf_sidecar_of(const std::string& path) {
  const auto slash = path.find_last_of('/');
  const auto dot = path.find_last_of('.');
  const bool ext = dot != std::string::npos && (slash == std::string::npos || dot > slash + 1);
  return (ext ? path.substr(0, dot) : path) + ".xdmf";
}

void refuse_output_outside(const std::string& path, const std::string& folder, const std::string& file,
                           const std::string& field) {
  const fs::path p(path);
  const fs::path norm = p.lexically_normal();
  if (p.is_absolute() || norm.empty() || norm == "." || *norm.begin() == "..")
    throw InputError(file, field, path,
                     "an output must be a file inside the output folder " + folder +
                         " (a relative path without '..')");
}

std::uint64_t usable_memory_bytes() {
  const long pages = ::sysconf(_SC_PHYS_PAGES), page = ::sysconf(_SC_PAGE_SIZE);
  std::uint64_t bytes = pages > 0 && page > 0 ? static_cast<std::uint64_t>(pages) * static_cast<std::uint64_t>(page)
                                              : std::uint64_t(1) << 34;
  // A container or a Slurm job may give less than the machine has.
  for (const char* f : {"/sys/fs/cgroup/memory.max", "/sys/fs/cgroup/memory/memory.limit_in_bytes"}) {
    std::ifstream in(f);
    unsigned long long limit = 0;
    if (in >> limit && limit > 0 && limit < bytes) bytes = limit;
  }
  // So may `ulimit -v` / `ulimit -d` (a batch system's per-process limits).
  for (const int which : {RLIMIT_AS, RLIMIT_DATA}) {
    rlimit lim{};
    if (::getrlimit(which, &lim) == 0 && lim.rlim_cur != RLIM_INFINITY && lim.rlim_cur < bytes) bytes = lim.rlim_cur;
  }
  return bytes;
}

std::string bytes_text(double bytes) {
  const char* units[] = {"B", "kB", "MB", "GB", "TB", "PB", "EB"};
  int u = 0;
  while (bytes >= 1000 && u < 6) bytes /= 1000, ++u;
  std::ostringstream s;
  s.precision(bytes < 10 ? 2 : 3);
  s << bytes << " " << units[u];
  return s.str();
}

void check_memory_request(double bytes, const std::string& file, const std::string& field,
                          const std::string& value, const std::string& what) {
  const double have = static_cast<double>(usable_memory_bytes());
  if (!(bytes <= have))  // also catches NaN and inf
    throw InputError(file, field, value,
                     what + " would need " + bytes_text(bytes) + " of memory; this machine has " + bytes_text(have));
}

std::string read_input_text(const std::string& path, const std::string& what) {
  std::error_code ec;
  if (fs::is_directory(path, ec)) throw InputError(path, "", "", "is a folder, not a " + what);
  std::ifstream in(path, std::ios::binary);
  if (!in) throw InputError(path, "", "", "cannot open the " + what + ": " + std::strerror(errno));
  std::ostringstream s;
  s << in.rdbuf();
  if (in.bad()) throw InputError(path, "", "", "cannot read the " + what);
  return s.str();
}

std::string csv_table(const std::vector<std::string>& columns, const std::vector<std::vector<double>>& rows) {
  std::ostringstream s;
  s.precision(10);
  for (std::size_t c = 0; c < columns.size(); ++c) s << (c ? "," : "") << columns[c];
  s << '\n';
  for (const auto& r : rows) {
    for (std::size_t c = 0; c < r.size(); ++c) s << (c ? "," : "") << r[c];
    s << '\n';
  }
  return s.str();
}

std::string file_hash(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw InputError(path, "", "", "cannot open file");
  XXH3_state_t* st = XXH3_createState();
  XXH3_128bits_reset(st);
  char buf[1 << 16];
  while (in) {
    in.read(buf, sizeof buf);
    XXH3_128bits_update(st, buf, static_cast<std::size_t>(in.gcount()));
  }
  const XXH128_hash_t h = XXH3_128bits_digest(st);
  XXH3_freeState(st);
  char hex[33];
  std::snprintf(hex, sizeof hex, "%016llx%016llx", static_cast<unsigned long long>(h.high64),
                static_cast<unsigned long long>(h.low64));
  return hex;
}

std::string utc_now() {
  const std::time_t t = std::chrono::system_clock::to_time_t(std::chrono::system_clock::now());
  std::tm tm{};
  gmtime_r(&t, &tm);
  char buf[32];
  std::strftime(buf, sizeof buf, "%Y-%m-%dT%H:%M:%SZ", &tm);
  return buf;
}

std::string xml_escape(const std::string& s) {
  std::string out;
  for (char c : s) {
    switch (c) {
      case '&': out += "&amp;"; break;
      case '<': out += "&lt;"; break;
      case '>': out += "&gt;"; break;
      case '"': out += "&quot;"; break;
      case '\'': out += "&apos;"; break;
      default: out += c;
    }
  }
  return out;
}

}  // namespace tomodem
