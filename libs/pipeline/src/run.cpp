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

#include "adaptive.hpp"
#include "state.hpp"
#include "template.hpp"
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
  // `existing`: lock a file that must not be created or written (the pipeline file itself);
  // where the file system cannot lock it (NFS refuses LOCK_EX on a read-only descriptor) the
  // lock is simply not held.
  FileLock(const std::string& path, int how, const std::string& busy, bool existing = false) {
    fd_ = existing ? ::open(path.c_str(), O_RDONLY | O_CLOEXEC) : ::open(path.c_str(), O_CREAT | O_RDWR | O_CLOEXEC, 0644);
    if (fd_ < 0) throw RuntimeFailure("cannot open " + path + ": " + std::strerror(errno));
    if (::flock(fd_, how | LOCK_NB) != 0) {
      const bool busy_now = errno == EWOULDBLOCK;
      ::close(fd_);
      fd_ = -1;
      if (!busy.empty() && (busy_now || !existing)) throw RuntimeFailure(busy + " (lock " + path + ")");
    }
  }
  ~FileLock() {
    if (fd_ >= 0) ::close(fd_);
  }
  bool held() const { return fd_ >= 0; }
  int fd() const { return fd_; }
  FileLock(const FileLock&) = delete;
  FileLock& operator=(const FileLock&) = delete;

 private:
  int fd_ = -1;
};

std::string run_lock_path(const Pipeline& p) { return (fs::path(p.logs_dir) / ".run.lock").string(); }

// The run lock lives in <logs>, which is named after the file's name: a symbolic (or hard) link
// to the pipeline under another name has other logs and would run beside it, both writing the
// same outputs. So the pipeline file itself (its inode, whatever the name) is locked too.
struct RunLock {
  RunLock(const Pipeline& p, bool shared) {
    const char* busy = shared ? "a plain tomodem-run is running this pipeline; shards wait until it ends"
                              : "another tomodem-run (plain or --shard) is running this pipeline";
    const int how = shared ? LOCK_SH : LOCK_EX;
    std::error_code ec;
    fs::create_directories(p.logs_dir, ec);
    logs.emplace(run_lock_path(p), how, busy);
    file.emplace(p.file, how, std::string(busy) + " (under this or another name)", true);
  }
  std::optional<FileLock> logs, file;
};

// A step's lock file holds the process group of the step's last start. The step's processes
// inherit the locked descriptor, so after a `kill -9` of the runner the lock stays held for as
// long as anything the step started still runs (and may still write its outputs).
pid_t recorded_group(const std::string& path) {
  std::ifstream in(path);
  long pgid = 0;
  in >> pgid;
  return pgid > 1 ? static_cast<pid_t>(pgid) : 0;
}

std::string lock_owner(const std::string& path) {
  const std::string pgid = std::to_string(recorded_group(path));
  return pgid == "0" ? "" : " or processes it started are still running (process group " + pgid +
                                "; `kill -- -" + pgid + "` stops them)";
}

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

// Returns whether every output of a failed step is the last good one again (false when ok).
bool settle_outputs(const Pipeline& p, const Instance& in, bool ok) {
  bool restored = !ok;
  for (const auto& [name, path] : in.outs) {
    const fs::path out = fs::path(p.dir) / path, old = aside_path(out);
    std::error_code ec;
    if (ok) {
      fs::remove_all(old, ec);
    } else if (present(old)) {
      fs::remove_all(out, ec);  // what the failed step wrote
      fs::rename(old, out, ec);
      if (ec) restored = false;
    } else {
      fs::remove_all(out, ec);  // Make's .DELETE_ON_ERROR: nothing that could look finished
      restored = false;
    }
  }
  return restored;
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

// The launcher's words and the rank count, as recorded in the lock file ("" for a serial step).
std::string launch_text(const Instance& in, const Launcher& launcher) {
  if (in.ranks <= 1) return "";
  const std::vector<std::string> argv = launch_argv(in, launcher);
  std::string text;
  for (std::size_t k = 0; k + in.argv.size() < argv.size(); ++k) text += (k ? " " : "") + detail::shell_quote(argv[k]);
  return text;
}

pid_t spawn(const Pipeline& p, const Instance& in, const std::string& log, const Launcher& launcher, int lock_fd) {
  // A step starts from a clean slate; its old outputs wait aside until it has succeeded.
  move_outputs_aside(p, in);
  const int fd = ::open(log.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
  if (fd < 0) throw RuntimeFailure("cannot write log " + log + ": " + std::strerror(errno));
  const std::vector<std::string> words = launch_argv(in, launcher);
  const std::string launch = launch_text(in, launcher);
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
    ::fcntl(lock_fd, F_SETFD, 0);  // the step's lock goes with every process it starts (lock_owner)
    const int nul = ::open("/dev/null", O_RDONLY);
    if (nul >= 0) ::dup2(nul, 0);
    const std::string t = std::to_string(in.threads);
    ::setenv("OMP_NUM_THREADS", t.c_str(), 1);
    ::setenv("TOMODEM_THREADS", t.c_str(), 1);
    ::setenv("TOMODEM_STEP", in.step.c_str(), 1);  // `tomodem run row` records it (the report's cells)
    const std::string header = "# tomodem-run " + in.id + "\n# " + (launch.empty() ? "" : launch + " ") + in.command + "\n";
    if (::write(1, header.data(), header.size()) < 0) ::_exit(127);
    if (::chdir(p.dir.c_str()) != 0) {
      ::perror("chdir");
      ::_exit(127);
    }
    // execvp: a launcher (mpirun, srun) is found on PATH; steps' own argv[0] is a full path.
    std::vector<char*> argv;
    for (const auto& a : words) argv.push_back(const_cast<char*>(a.c_str()));
    argv.push_back(nullptr);
    ::execvp(argv[0], argv.data());
    ::perror(argv[0]);
    ::_exit(127);
  }
  ::setpgid(pid, pid);
  ::close(fd);
  const std::string pgid = std::to_string(pid) + "\n";
  if (::ftruncate(lock_fd, 0) != 0 || ::pwrite(lock_fd, pgid.data(), pgid.size(), 0) < 0) {
    // Only the message of a later run that finds the lock held would lack the process group.
  }
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

// One pass of the scheduler over a loaded pipeline: decides each instance when its inputs are
// final, starts what is stale as slots free up, and records every finished step.
class Scheduler {
 public:
  // `only`: the instances this pass may touch (an adaptive round), or nullptr for all.
  // `locked`: the caller already holds the pipeline's run lock.
  Scheduler(const Pipeline& p, const RunOptions& o, std::ostream* progress, const std::vector<char>* only, bool locked)
      : p_(p), o_(o), progress_(progress), n_(p.instances.size()), jobs_(std::max(1, o.jobs)), free_slots_(jobs_) {
    sum_.steps.resize(n_);
    for (std::size_t i = 0; i < n_; ++i) sum_.steps[i].id = p.instances[i].id;
    select(only);
    load_all_locks(p_, lock_, cache_);
    shard_mode_ = o_.shards > 0;
    lock_out_ = shard_mode_ ? shard_lock_file(p_, o_.shard) : p_.lock_file;
    if (shard_mode_) {
      HashCache unused;
      merge_lock(lock_out_, shard_kept_, unused);
    }
    if (!o_.dry_run) take_locks(locked);
    mark_outside(only);
  }

  RunSummary run() {
    const auto t_start = std::chrono::steady_clock::now();
    SignalScope signals;
    // However the loop ends (a lock file that cannot be written on a full disk, a failed fork),
    // the running steps are stopped and their old outputs put back.
    try {
      for (;;) {
        if (g_signal && !killed_) interrupt();
        start_ready();
        if (running_.empty()) break;
        wait_one();
      }
    } catch (...) {
      stop_all();
      throw;
    }
    sum_.files_hashed = cache_.files_hashed();
    sum_.wall_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t_start).count();
    return sum_;
  }

 private:
  // What this invocation may run: everything, one shard or one adaptive round; plus what that reads.
  void select(const std::vector<char>* only) {
    owner_.assign(n_, 1);
    if (o_.shards > 0) owner_ = shard_owners(p_, o_.shards);
    selected_.assign(n_, 0);
    needed_.assign(n_, 0);
    for (std::size_t i = 0; i < n_; ++i)
      needed_[i] = selected_[i] = (o_.shards <= 0 || owner_[i] == o_.shard) && (!only || (*only)[i]);
    for (std::size_t i = n_; i-- > 0;)
      if (needed_[i])
        for (const auto u : p_.instances[i].upstream) needed_[u] = 1;
    forced_.assign(n_, o_.force_all);
    for (const auto& name : o_.force)
      for (const auto i : pipeline::select(p_, name)) forced_[i] = 1;
    total_ = static_cast<int>(std::count(selected_.begin(), selected_.end(), 1));
  }

  void take_locks(bool locked) {
    fs::create_directories(p_.logs_dir);
    fs::create_directories(fs::path(p_.logs_dir) / ".step-locks");
    if (!locked) guard_.emplace(p_, shard_mode_);
    if (shard_mode_)
      shard_guard_.emplace((fs::path(p_.logs_dir) / (".run-shard-" + std::to_string(o_.shard) + ".lock")).string(), LOCK_EX,
                           "another tomodem-run is running shard " + std::to_string(o_.shard) + " of this pipeline");
    const auto shard_files = shard_lock_files(p_);
    if (!shard_mode_ && !shard_files.empty()) {
      save();  // fold the shards' records into the main lock, then drop them
      for (const auto& f : shard_files) fs::remove(f);
    }
  }

  void save() {
    if (!shard_mode_) return write_text_atomic(lock_out_, lock_json(lock_, cache_));
    // A shard writes only what it ran, so shards never overwrite each other's records. Its file
    // is named by K alone, so what an earlier `--shard K/M` (another M) recorded there is kept.
    LockFile part = shard_kept_;
    for (const auto& id : touched_) {
      part.steps.erase(id);
      part.failures.erase(id);
      if (auto it = lock_.steps.find(id); it != lock_.steps.end()) part.steps[id] = it->second;
      if (auto it = lock_.failures.find(id); it != lock_.failures.end()) part.failures[id] = it->second;
    }
    write_text_atomic(lock_out_, lock_json(part, cache_));
  }

  void mark_outside(const std::vector<char>* only) {
    st_.assign(n_, St::waiting);
    would_.assign(n_, 0);
    verdicts_.assign(n_, std::nullopt);
    for (std::size_t i = 0; i < n_; ++i)
      if (!needed_[i]) {
        st_[i] = St::outside;
        StepResult& res = sum_.steps[i];
        res.state = "not-in-shard";
        res.reason = only && !(*only)[i] ? "after the adaptive replicas are decided"
                     : owner_[i] < 0     ? "runs after the shards (gather)"
                     : owner_[i] == 0    ? "shared upstream (--shard 0/" + std::to_string(o_.shards) + ")"
                                         : "shard " + std::to_string(owner_[i]);
      }
  }

  void say(const std::string& line) const {
    if (progress_ && !o_.quiet) *progress_ << line << std::endl;
  }
  std::string counter() { return "[" + std::to_string(++decided_) + "/" + std::to_string(total_) + "] "; }

  void interrupt() {
    killed_ = stop_ = true;
    stop_after_ = "an interrupt";
    sum_.interrupted = true;
    for (const auto& r : running_) ::kill(-r.pid, SIGTERM);
  }

  void start_ready() {
    for (bool again = true; again;) {
      again = false;
      for (std::size_t i = 0; i < n_; ++i)
        if (st_[i] == St::waiting && consider(i)) again = true;
    }
  }

  // Why instance i cannot start: an upstream that failed or did not run ("" when none); sets
  // `ready` false while an upstream is still waiting or running.
  std::string blocked_by(const Instance& in, bool& ready, std::string& upstream_runs) const {
    std::string blocked;
    for (const auto u : in.upstream) {
      if (st_[u] == St::waiting || st_[u] == St::running) ready = false;
      else if (st_[u] == St::failed) blocked = "upstream " + p_.instances[u].id + " failed";
      else if (st_[u] == St::skipped && selected_[u]) blocked = "upstream " + p_.instances[u].id + " did not run";
      else if (st_[u] == St::skipped)
        blocked = "upstream " + p_.instances[u].id + " is not up to date and belongs to " +
                  (owner_[u] == 0 ? "the shared part: run --shard 0/" + std::to_string(o_.shards) + " first" : "another shard");
      if (would_[u]) upstream_runs = p_.instances[u].id;
    }
    return blocked;
  }

  // Decides or starts waiting instance i; true when its state changed (others may now move).
  bool consider(std::size_t i) {
    const Instance& in = p_.instances[i];
    StepResult& res = sum_.steps[i];
    bool ready = true;
    std::string upstream_runs;
    const std::string blocked = blocked_by(in, ready, upstream_runs);
    if (!ready) return false;
    if (!blocked.empty() || stop_) {
      st_[i] = St::skipped;
      res.state = selected_[i] ? "skipped" : "not-in-shard";
      res.reason = blocked.empty() ? "not started: the run stopped after " + stop_after_ : blocked;
      if (selected_[i]) {
        ++sum_.skipped;
        say(counter() + "skipped " + in.id + ": " + res.reason);
      }
      return true;
    }
    // Decided once, when all its inputs are final: content hashes give early cut-off.
    if (!verdicts_[i]) {
      if (forced_[i]) verdicts_[i] = Verdict{true, {"forced"}};
      else if (o_.dry_run && !upstream_runs.empty())
        verdicts_[i] = Verdict{true, {"upstream " + upstream_runs + " would run (its new outputs decide)"}};
      else {
        const auto it = lock_.steps.find(in.id);
        verdicts_[i] = check(in, it == lock_.steps.end() ? nullptr : &it->second, cache_, false, o_.rerun_on_rebuild);
      }
    }
    const Verdict& v = *verdicts_[i];
    if (!v.stale) {
      st_[i] = St::done;
      res.state = "up-to-date";
      if (selected_[i]) ++sum_.up_to_date, ++decided_;
      return true;
    }
    res.reason = v.reasons.front();
    if (!selected_[i]) {
      st_[i] = St::skipped;  // its dependants in this shard are blocked
      res.state = "not-in-shard";
      return true;
    }
    if (o_.dry_run) {
      st_[i] = St::done;
      would_[i] = 1;
      res.state = "would-run";
      ++sum_.would_run;
      say(counter() + "would run " + in.id + ": " + res.reason);
      return true;
    }
    return start(i);
  }

  bool start(std::size_t i) {
    const Instance& in = p_.instances[i];
    StepResult& res = sum_.steps[i];
    const int slots = std::min(in.threads * in.ranks, jobs_);
    if (slots > free_slots_) return false;  // wait for a slot; later, smaller steps may still fit
    const std::string lock_path = step_lock_path(p_, in);
    auto step_lock = std::make_shared<FileLock>(lock_path, LOCK_EX, "");
    if (!step_lock->held() && !shard_mode_) step_lock = stop_leftovers(in, lock_path);
    if (!step_lock->held()) {
      st_[i] = St::skipped;
      res.state = "skipped";
      res.reason = "another tomodem-run is running this step now" + lock_owner(lock_path);
      ++sum_.skipped;
      say(counter() + "skipped " + in.id + ": " + res.reason);
      return true;
    }
    res.log = log_path(p_, in);
    say("run  " + in.id + " (" + res.reason + ")");
    running_.push_back(Running{i, spawn(p_, in, res.log, launcher_, step_lock->fd()), std::chrono::steady_clock::now(), utc_now(), slots, std::move(step_lock)});
    free_slots_ -= slots;
    st_[i] = St::running;
    return true;
  }

  // A plain run holds the run lock alone, so no other runner of this pipeline is alive: a step
  // lock still held belongs to processes an earlier run of the step started before its runner
  // was killed (kill -9, an OOM kill). They would go on writing the outputs this run is about to
  // make, and the docs promise that steps go with their runner: they are stopped here. (A shard
  // run cannot tell them from another shard's step: it skips the step, naming the group.)
  std::shared_ptr<FileLock> stop_leftovers(const Instance& in, const std::string& path) {
    const pid_t pgid = recorded_group(path);
    if (pgid && pgid != ::getpgrp()) {
      say("stop process group " + std::to_string(pgid) + ": left running by an earlier run of " + in.id +
          " whose runner was killed");
      for (const int sig : {SIGTERM, SIGKILL}) {
        if (::kill(-pgid, sig) != 0) break;  // none left in the group
        for (int k = 0; k < 100; ++k) {      // up to 5 s for the last of them to exit
          auto lock = std::make_shared<FileLock>(path, LOCK_EX, "");
          if (lock->held()) return lock;
          ::usleep(50000);
        }
      }
    }
    return std::make_shared<FileLock>(path, LOCK_EX, "");
  }

  void wait_one() {
    int status = 0;
    const pid_t pid = ::waitpid(-1, &status, 0);
    if (pid < 0) {
      if (errno == EINTR) return;
      throw RuntimeFailure(std::string("waitpid: ") + std::strerror(errno));
    }
    const auto it = std::find_if(running_.begin(), running_.end(), [&](const Running& r) { return r.pid == pid; });
    if (it == running_.end()) return;
    const Running r = *it;
    running_.erase(it);
    free_slots_ += r.slots;
    finish(r, status);
  }

  void finish(const Running& r, int status) {
    const Instance& in = p_.instances[r.idx];
    StepResult& res = sum_.steps[r.idx];
    res.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - r.t0).count();
    bool ok = WIFEXITED(status) && WEXITSTATUS(status) == 0;
    std::string why;
    if (!ok)
      why = g_signal ? "interrupted"
            : WIFEXITED(status) ? "exit code " + std::to_string(WEXITSTATUS(status))
                                : "killed by signal " + std::to_string(WTERMSIG(status));
    for (const auto& [name, path] : in.outs)
      if (ok && !fs::exists(fs::path(p_.dir) / path)) {
        ok = false;
        why = "declared output " + path + " was not written";
      }
    touched_.insert(in.id);
    const bool restored = settle_outputs(p_, in, ok);
    if (ok) {
      lock_.steps[in.id] = record(in, cache_, r.started, res.seconds);
      lock_.steps[in.id].launch = launch_text(in, launcher_);
      lock_.failures.erase(in.id);
      st_[r.idx] = St::done;
      res.state = "ran";
      ++sum_.ran;
      say(counter() + "done " + in.id + " in " + seconds_text(res.seconds));
    } else {
      failed(r.idx, status, why, restored);
    }
    save();
  }

  // `restored`: the last good outputs are back in place, so the last success record still
  // describes them and is kept (going back to that configuration is then up to date again).
  void failed(std::size_t i, int status, std::string why, bool restored) {
    const Instance& in = p_.instances[i];
    StepResult& res = sum_.steps[i];
    const std::string tail = last_line(res.log);
    if (!tail.empty() && why != "interrupted") why += ": " + tail;
    res.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
    if (!restored) lock_.steps.erase(in.id);
    lock_.failures[in.id] = FailureRecord{res.exit_code, utc_now(), why, res.log};
    st_[i] = St::failed;
    res.state = "failed";
    res.reason = why;
    ++sum_.failed;
    say(counter() + "FAILED " + in.id + ": " + why + " (log: " + res.log + ")");
    if (!o_.keep_going && !stop_) {
      stop_ = true;
      stop_after_ = in.id;
    }
  }

  void stop_all() {
    for (const auto& r : running_) ::kill(-r.pid, SIGTERM);
    for (const auto& r : running_) {
      int status = 0;
      while (::waitpid(r.pid, &status, 0) < 0 && errno == EINTR) {
      }
      settle_outputs(p_, p_.instances[r.idx], false);
    }
  }

  const Pipeline& p_;
  const RunOptions& o_;
  std::ostream* progress_;
  const std::size_t n_;
  const int jobs_;
  const Launcher launcher_ = launcher_from_env();  // for steps with ranks: N > 1
  int free_slots_, total_ = 0, decided_ = 0;
  RunSummary sum_;
  std::vector<int> owner_;
  std::vector<char> selected_, needed_, forced_, would_;
  std::vector<St> st_;
  std::vector<std::optional<Verdict>> verdicts_;
  LockFile lock_, shard_kept_;  // shard_kept_: what this shard's lock file held when the run began
  HashCache cache_;
  bool shard_mode_ = false, stop_ = false, killed_ = false;
  std::string lock_out_, stop_after_;
  std::optional<RunLock> guard_;
  std::optional<FileLock> shard_guard_;
  std::set<std::string> touched_;
  std::vector<Running> running_;
};

RunSummary execute(const Pipeline& p, const RunOptions& o, std::ostream* progress) {
  return Scheduler(p, o, progress, nullptr, false).run();
}

// Adaptive replicas decide as replicas finish, which shards on separate machines cannot share.
void refuse_shards(const Pipeline& p, const RunOptions& o) {
  if (o.shards > 0 && !p.adaptive.empty())
    throw InputError(p.adaptive[0].where.str(), "steps." + p.adaptive[0].step + ".replicas", "until",
                     "adaptive replicas are decided as replicas finish: run without --shard (or give replicas: N)");
}

const char* fill(const std::string& state) {
  if (state == "would-run") return "#ffd7a8";
  if (state == "not-in-shard") return "#e0e0e0";
  return "#c8f0c8";
}

}  // namespace

namespace detail {
RunSummary run_pass(const Pipeline& p, const RunOptions& o, std::ostream* progress, const std::vector<char>* only,
                    bool locked) {
  return Scheduler(p, o, progress, only, locked).run();
}
}  // namespace detail

RunSummary run(const Pipeline& p, const RunOptions& options, std::ostream& progress) {
  refuse_shards(p, options);
  if (p.adaptive.empty() || options.dry_run) return execute(p, options, &progress);
  // One lock over every round, so no other runner slips in between them.
  const RunLock guard(p, false);
  return detail::run_adaptive(p, options, progress);
}

RunSummary status(const Pipeline& p, const RunOptions& options) {
  RunOptions o = options;
  o.dry_run = true;
  return execute(p, o, nullptr);
}

std::string explain(const Pipeline& p, const std::string& name, const RunOptions& options) {
  const auto idx = select(p, name);
  const RunSummary s = status(p, options);
  LockFile lock;
  HashCache cache;
  load_all_locks(p, lock, cache);
  std::ostringstream out;
  for (const auto i : idx) {
    const Instance& in = p.instances[i];
    const auto e = lock.steps.find(in.id);
    const LockEntry* rec = e == lock.steps.end() ? nullptr : &e->second;
    const Verdict v = check(in, rec, cache, true, options.rerun_on_rebuild);
    out << in.id << ": " << (s.steps[i].state == "would-run" ? "would run" : "up to date") << " ("
        << in.where.str() << ")\n";
    for (const auto& r : v.reasons) out << "  because " << r << '\n';
    for (const auto& n : v.notes) out << "  note: " << n << '\n';
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
