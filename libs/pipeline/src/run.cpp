// Execution: a single-threaded scheduler that forks one process per step instance and waits
// for them; the lock file is rewritten after every finished step.
#include <fcntl.h>
#include <sys/file.h>
#include <sys/prctl.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <csignal>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <functional>
#include <memory>
#include <optional>
#include <ostream>
#include <set>
#include <sstream>

#include "state.hpp"
#include "tomodem/core/error.hpp"
#include "tomodem/core/output.hpp"
#include "tomodem/pipeline/run.hpp"

namespace tomodem::pipeline {

namespace fs = std::filesystem;
using namespace detail;

namespace {

volatile std::sig_atomic_t g_signal = 0;
extern "C" void on_signal(int s) { g_signal = s; }

// A plain run holds the pipeline's run lock alone; shard runs share it (shards of one sweep run
// side by side on a cluster) and each holds its own shard lock. Every running step also holds
// a lock of its own, so no two runners ever run one step at once.
class FileLock {
 public:
  FileLock(const std::string& path, int how, const std::string& busy) {
    fd_ = ::open(path.c_str(), O_CREAT | O_RDWR | O_CLOEXEC, 0644);
    if (fd_ < 0) throw RuntimeFailure("cannot open " + path + ": " + std::strerror(errno));
    if (::flock(fd_, how | LOCK_NB) != 0) {
      ::close(fd_);
      fd_ = -1;
      if (!busy.empty()) throw RuntimeFailure(busy + " (lock " + path + ")");
    }
  }
  ~FileLock() {
    if (fd_ >= 0) ::close(fd_);
  }
  bool held() const { return fd_ >= 0; }
  FileLock(const FileLock&) = delete;
  FileLock& operator=(const FileLock&) = delete;

 private:
  int fd_ = -1;
};

std::string step_lock_path(const Pipeline& p, const Instance& in) {
  char hex[17];
  std::snprintf(hex, sizeof hex, "%016zx", std::hash<std::string>{}(in.id));
  return (fs::path(p.logs_dir) / ".step-locks" / (std::string(hex) + ".lock")).string();
}

// A step's old outputs are moved aside while it runs (".NAME.tomodem-old" beside each): restored
// when it fails, dropped when it succeeds. Nothing is removed that the step did not make.
fs::path aside_path(const fs::path& out) {
  return out.parent_path() / ("." + out.filename().string() + ".tomodem-old");
}

bool present(const fs::path& f) {
  std::error_code ec;
  return fs::exists(fs::symlink_status(f, ec));
}

void move_outputs_aside(const Pipeline& p, const Instance& in) {
  for (const auto& [name, path] : in.outs) {
    const fs::path out = fs::path(p.dir) / path, old = aside_path(out);
    std::error_code ec;
    if (out.has_parent_path()) fs::create_directories(out.parent_path(), ec);
    if (present(old)) {
      // A runner was killed while this step ran: `old` is the last good output and `out`, if
      // any, what the killed step wrote.
      fs::remove_all(out, ec);
    } else if (present(out)) {
      fs::rename(out, old, ec);
      if (ec) throw RuntimeFailure("cannot move the old output " + out.string() + " aside: " + ec.message());
    }
  }
}

void settle_outputs(const Pipeline& p, const Instance& in, bool ok) {
  for (const auto& [name, path] : in.outs) {
    const fs::path out = fs::path(p.dir) / path, old = aside_path(out);
    std::error_code ec;
    if (ok) {
      fs::remove_all(old, ec);
    } else if (present(old)) {
      fs::remove_all(out, ec);  // what the failed step wrote
      fs::rename(old, out, ec);
    } else {
      fs::remove_all(out, ec);  // Make's .DELETE_ON_ERROR: nothing that could look finished
    }
  }
}

// Restores the caller's SIGINT/SIGTERM handlers however the run ends.
class SignalScope {
 public:
  SignalScope() {
    g_signal = 0;
    struct sigaction sa {};
    sa.sa_handler = on_signal;
    sigemptyset(&sa.sa_mask);
    sa.sa_flags = 0;  // no SA_RESTART: waitpid returns EINTR so the run can stop its children
    ::sigaction(SIGINT, &sa, &old_int_);
    ::sigaction(SIGTERM, &sa, &old_term_);
  }
  ~SignalScope() {
    ::sigaction(SIGINT, &old_int_, nullptr);
    ::sigaction(SIGTERM, &old_term_, nullptr);
  }

 private:
  struct sigaction old_int_ {}, old_term_ {};
};

pid_t spawn(const Pipeline& p, const Instance& in, const std::string& log) {
  // A step starts from a clean slate; its old outputs wait aside until it has succeeded.
  move_outputs_aside(p, in);
  const int fd = ::open(log.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
  if (fd < 0) throw RuntimeFailure("cannot write log " + log + ": " + std::strerror(errno));
  const pid_t parent = ::getpid();
  const pid_t pid = ::fork();
  if (pid < 0) throw RuntimeFailure(std::string("fork failed: ") + std::strerror(errno));
  if (pid == 0) {
    ::setpgid(0, 0);
    // If the runner is killed outright, its steps go with it rather than finishing unrecorded.
    ::prctl(PR_SET_PDEATHSIG, SIGTERM);
    if (::getppid() != parent) ::_exit(128 + SIGTERM);
    ::dup2(fd, 1);
    ::dup2(fd, 2);
    const int nul = ::open("/dev/null", O_RDONLY);
    if (nul >= 0) ::dup2(nul, 0);
    const std::string t = std::to_string(in.threads);
    ::setenv("OMP_NUM_THREADS", t.c_str(), 1);
    ::setenv("TOMODEM_THREADS", t.c_str(), 1);
    const std::string header = "# tomodem-run " + in.id + "\n# " + in.command + "\n";
    if (::write(1, header.data(), header.size()) < 0) ::_exit(127);
    if (::chdir(p.dir.c_str()) != 0) {
      ::perror("chdir");
      ::_exit(127);
    }
    std::vector<char*> argv;
    for (const auto& a : in.argv) argv.push_back(const_cast<char*>(a.c_str()));
    argv.push_back(nullptr);
    ::execv(argv[0], argv.data());
    ::perror(argv[0]);
    ::_exit(127);
  }
  ::setpgid(pid, pid);
  ::close(fd);
  return pid;
}

std::string last_line(const std::string& path) {
  std::ifstream in(path);
  std::string line, last;
  while (std::getline(in, line))
    if (!line.empty() && line[0] != '#') last = line;
  if (last.size() > 200) last = last.substr(0, 200) + "...";
  return last;
}

std::string seconds_text(double s) {
  std::ostringstream o;
  o.precision(s < 10 ? 2 : 3);
  o << s << " s";
  return o.str();
}

enum class St { waiting, running, done, failed, skipped, outside };

struct Running {
  std::size_t idx;
  pid_t pid;
  std::chrono::steady_clock::time_point t0;
  std::string started;
  int slots;
  std::shared_ptr<FileLock> step_lock;
};

RunSummary execute(const Pipeline& p, const RunOptions& o, std::ostream* progress) {
  const auto t_start = std::chrono::steady_clock::now();
  const std::size_t n = p.instances.size();
  const int jobs = std::max(1, o.jobs);
  RunSummary sum;
  sum.steps.resize(n);
  for (std::size_t i = 0; i < n; ++i) sum.steps[i].id = p.instances[i].id;

  // What this invocation may run: everything, or one shard; plus what that reads.
  std::vector<int> owner(n, 1);
  if (o.shards > 0) owner = shard_owners(p, o.shards);
  std::vector<char> selected(n), needed(n);
  for (std::size_t i = 0; i < n; ++i) needed[i] = selected[i] = o.shards <= 0 || owner[i] == o.shard;
  for (std::size_t i = n; i-- > 0;)
    if (needed[i])
      for (const auto u : p.instances[i].upstream) needed[u] = 1;
  std::vector<char> forced(n, o.force_all);
  for (const auto& name : o.force)
    for (const auto i : select(p, name)) forced[i] = 1;

  LockFile lock;
  HashCache cache;
  load_all_locks(p, lock, cache);
  std::optional<FileLock> guard, shard_guard;
  const bool shard_mode = o.shards > 0;
  const std::string lock_out = shard_mode ? shard_lock_file(p, o.shard) : p.lock_file;
  std::set<std::string> touched;
  const auto save = [&] {
    if (!shard_mode) return write_text_atomic(lock_out, lock_json(lock, cache));
    // A shard writes only what it ran, so shards never overwrite each other's records.
    LockFile part;
    for (const auto& id : touched) {
      if (auto it = lock.steps.find(id); it != lock.steps.end()) part.steps[id] = it->second;
      if (auto it = lock.failures.find(id); it != lock.failures.end()) part.failures[id] = it->second;
    }
    write_text_atomic(lock_out, lock_json(part, cache));
  };
  if (!o.dry_run) {
    fs::create_directories(p.logs_dir);
    fs::create_directories(fs::path(p.logs_dir) / ".step-locks");
    const std::string run_lock = (fs::path(p.logs_dir) / ".run.lock").string();
    guard.emplace(run_lock, shard_mode ? LOCK_SH : LOCK_EX,
                  shard_mode ? "a plain tomodem-run is running this pipeline; shards wait until it ends"
                             : "another tomodem-run (plain or --shard) is running this pipeline");
    if (shard_mode)
      shard_guard.emplace((fs::path(p.logs_dir) / (".run-shard-" + std::to_string(o.shard) + ".lock")).string(), LOCK_EX,
                          "another tomodem-run is running shard " + std::to_string(o.shard) + " of this pipeline");
    const auto shard_files = shard_lock_files(p);
    if (!shard_mode && !shard_files.empty()) {
      save();  // fold the shards' records into the main lock, then drop them
      for (const auto& f : shard_files) fs::remove(f);
    }
  }

  std::vector<St> st(n, St::waiting);
  std::vector<char> would(n, 0);
  for (std::size_t i = 0; i < n; ++i)
    if (!needed[i]) {
      st[i] = St::outside;
      sum.steps[i].state = "not-in-shard";
      sum.steps[i].reason = owner[i] < 0 ? "runs after the shards (gather)"
                                         : owner[i] == 0 ? "shared upstream (--shard 0/" + std::to_string(o.shards) + ")"
                                                         : "shard " + std::to_string(owner[i]);
    }
  const int total = static_cast<int>(std::count(selected.begin(), selected.end(), 1));
  int decided = 0, free_slots = jobs;
  std::string stop_after;
  bool stop = false, killed = false;
  std::vector<Running> running;
  std::vector<std::optional<Verdict>> verdicts(n);
  const auto say = [&](const std::string& line) {
    if (progress && !o.quiet) *progress << line << std::endl;
  };
  const auto counter = [&] { return "[" + std::to_string(++decided) + "/" + std::to_string(total) + "] "; };
  SignalScope signals;

  const auto finish = [&](const Running& r, int status) {
    const Instance& in = p.instances[r.idx];
    StepResult& res = sum.steps[r.idx];
    res.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - r.t0).count();
    bool ok = WIFEXITED(status) && WEXITSTATUS(status) == 0;
    std::string why;
    if (!ok)
      why = g_signal ? "interrupted"
            : WIFEXITED(status) ? "exit code " + std::to_string(WEXITSTATUS(status))
                                : "killed by signal " + std::to_string(WTERMSIG(status));
    for (const auto& [name, path] : in.outs)
      if (ok && !fs::exists(fs::path(p.dir) / path)) {
        ok = false;
        why = "declared output " + path + " was not written";
      }
    touched.insert(in.id);
    settle_outputs(p, in, ok);
    if (ok) {
      lock.steps[in.id] = record(in, cache, r.started, res.seconds);
      lock.failures.erase(in.id);
      st[r.idx] = St::done;
      res.state = "ran";
      ++sum.ran;
      say(counter() + "done " + in.id + " in " + seconds_text(res.seconds));
    } else {
      const std::string tail = last_line(res.log);
      if (!tail.empty() && why != "interrupted") why += ": " + tail;
      res.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
      lock.steps.erase(in.id);
      lock.failures[in.id] = FailureRecord{res.exit_code, utc_now(), why, res.log};
      st[r.idx] = St::failed;
      res.state = "failed";
      res.reason = why;
      ++sum.failed;
      say(counter() + "FAILED " + in.id + ": " + why + " (log: " + res.log + ")");
      if (!o.keep_going && !stop) {
        stop = true;
        stop_after = in.id;
      }
    }
    save();
  };

  // However the loop ends (a lock file that cannot be written on a full disk, a failed fork),
  // the running steps are stopped and their old outputs put back.
  try {
    for (;;) {
      if (g_signal && !killed) {
        killed = stop = true;
        stop_after = "an interrupt";
        sum.interrupted = true;
        for (const auto& r : running) ::kill(-r.pid, SIGTERM);
      }
      for (bool again = true; again;) {
        again = false;
        for (std::size_t i = 0; i < n; ++i) {
          if (st[i] != St::waiting) continue;
          const Instance& in = p.instances[i];
          StepResult& res = sum.steps[i];
          bool ready = true;
          std::string blocked, upstream_runs;
          for (const auto u : in.upstream) {
            if (st[u] == St::waiting || st[u] == St::running) ready = false;
            else if (st[u] == St::failed) blocked = "upstream " + p.instances[u].id + " failed";
            else if (st[u] == St::skipped && selected[u]) blocked = "upstream " + p.instances[u].id + " did not run";
            else if (st[u] == St::skipped)
              blocked = "upstream " + p.instances[u].id + " is not up to date and belongs to " +
                        (owner[u] == 0 ? "the shared part: run --shard 0/" + std::to_string(o.shards) + " first"
                                       : "another shard");
            if (would[u]) upstream_runs = p.instances[u].id;
          }
          if (!ready) continue;
          if (!blocked.empty() || stop) {
            again = true;
            st[i] = St::skipped;
            res.state = selected[i] ? "skipped" : "not-in-shard";
            res.reason = blocked.empty() ? "not started: the run stopped after " + stop_after : blocked;
            if (selected[i]) {
              ++sum.skipped;
              say(counter() + "skipped " + in.id + ": " + res.reason);
            }
            continue;
          }
          // Decided once, when all its inputs are final: content hashes give early cut-off.
          if (!verdicts[i]) {
            if (forced[i]) verdicts[i] = Verdict{true, {"forced"}};
            else if (o.dry_run && !upstream_runs.empty())
              verdicts[i] = Verdict{true, {"upstream " + upstream_runs + " would run (its new outputs decide)"}};
            else {
              const auto it = lock.steps.find(in.id);
              verdicts[i] = check(in, it == lock.steps.end() ? nullptr : &it->second, cache, false);
            }
          }
          const Verdict& v = *verdicts[i];
          if (!v.stale) {
            again = true;
            st[i] = St::done;
            res.state = "up-to-date";
            if (selected[i]) ++sum.up_to_date, ++decided;
            continue;
          }
          res.reason = v.reasons.front();
          if (!selected[i]) {
            again = true;
            st[i] = St::skipped;  // its dependants in this shard are blocked
            res.state = "not-in-shard";
            continue;
          }
          if (o.dry_run) {
            again = true;
            st[i] = St::done;
            would[i] = 1;
            res.state = "would-run";
            ++sum.would_run;
            say(counter() + "would run " + in.id + ": " + res.reason);
            continue;
          }
          const int slots = std::min(in.threads, jobs);
          if (slots > free_slots) continue;  // wait for a slot; later, smaller steps may still fit
          auto step_lock = std::make_shared<FileLock>(step_lock_path(p, in), LOCK_EX, "");
          if (!step_lock->held()) {
            again = true;
            st[i] = St::skipped;
            res.state = "skipped";
            res.reason = "another tomodem-run is running this step now";
            ++sum.skipped;
            say(counter() + "skipped " + in.id + ": " + res.reason);
            continue;
          }
          res.log = log_path(p, in);
          say("run  " + in.id + " (" + res.reason + ")");
          running.push_back(
              Running{i, spawn(p, in, res.log), std::chrono::steady_clock::now(), utc_now(), slots, std::move(step_lock)});
          free_slots -= slots;
          st[i] = St::running;
          again = true;
        }
      }
      if (running.empty()) break;
      int status = 0;
      const pid_t pid = ::waitpid(-1, &status, 0);
      if (pid < 0) {
        if (errno == EINTR) continue;
        throw RuntimeFailure(std::string("waitpid: ") + std::strerror(errno));
      }
      const auto it = std::find_if(running.begin(), running.end(), [&](const Running& r) { return r.pid == pid; });
      if (it == running.end()) continue;
      const Running r = *it;
      running.erase(it);
      free_slots += r.slots;
      finish(r, status);
    }
  } catch (...) {
    for (const auto& r : running) ::kill(-r.pid, SIGTERM);
    for (const auto& r : running) {
      int status = 0;
      while (::waitpid(r.pid, &status, 0) < 0 && errno == EINTR) {
      }
      settle_outputs(p, p.instances[r.idx], false);
    }
    throw;
  }
  sum.files_hashed = cache.files_hashed();
  sum.wall_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t_start).count();
  return sum;
}

const char* fill(const std::string& state) {
  if (state == "would-run") return "#ffd7a8";
  if (state == "not-in-shard") return "#e0e0e0";
  return "#c8f0c8";
}

}  // namespace

RunSummary run(const Pipeline& p, const RunOptions& options, std::ostream& progress) {
  return execute(p, options, &progress);
}

RunSummary status(const Pipeline& p, const RunOptions& options) {
  RunOptions o = options;
  o.dry_run = true;
  return execute(p, o, nullptr);
}

std::string explain(const Pipeline& p, const std::string& name) {
  const auto idx = select(p, name);
  const RunSummary s = status(p, {});
  LockFile lock;
  HashCache cache;
  load_all_locks(p, lock, cache);
  std::ostringstream out;
  for (const auto i : idx) {
    const Instance& in = p.instances[i];
    const auto e = lock.steps.find(in.id);
    const LockEntry* rec = e == lock.steps.end() ? nullptr : &e->second;
    const Verdict v = check(in, rec, cache, true);
    out << in.id << ": " << (s.steps[i].state == "would-run" ? "would run" : "up to date") << " ("
        << in.where.str() << ")\n";
    for (const auto& r : v.reasons) out << "  because " << r << '\n';
    for (const auto u : in.upstream)
      if (s.steps[u].state == "would-run")
        out << "  because upstream " << p.instances[u].id << " would run (then its new outputs decide)\n";
    if (rec && !v.stale) out << "  last run " << rec->finished << " took " << seconds_text(rec->seconds) << '\n';
    if (auto f = lock.failures.find(in.id); f != lock.failures.end())
      out << "  last failure " << f->second.finished << ": " << f->second.reason << '\n';
    out << "  command: " << in.command << '\n';
    if (!in.version.empty()) out << "  version: " << in.version << '\n';
    for (const auto& [k, val] : in.params) out << "  param " << k << " = " << val << '\n';
    for (const auto& [k, path] : in.deps) out << "  input " << path << (k.find('.') == std::string::npos ? "" : "  (" + k + ")") << '\n';
    for (const auto& [k, path] : in.outs) out << "  output " << path << '\n';
    out << "  log: " << log_path(p, in) << '\n';
  }
  return out.str();
}

std::string dot(const Pipeline& p) {
  const RunSummary s = status(p, {});
  std::ostringstream out;
  out << "digraph pipeline {\n  rankdir=LR;\n  node [shape=box, style=\"rounded,filled\"];\n";
  for (std::size_t i = 0; i < p.instances.size(); ++i) {
    const Instance& in = p.instances[i];
    out << "  \"" << in.id << "\" [label=\"" << in.step << (in.cell.empty() ? "" : "\\n" + in.cell)
        << "\", fillcolor=\"" << fill(s.steps[i].state) << "\", tooltip=\"" << s.steps[i].state << "\"];\n";
  }
  for (const auto& in : p.instances)
    for (const auto u : in.upstream) out << "  \"" << p.instances[u].id << "\" -> \"" << in.id << "\";\n";
  out << "}\n";
  return out.str();
}

}  // namespace tomodem::pipeline
