#include "state.hpp"

#include <sys/stat.h>
#include <xxhash.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <set>

#include "tomodem/core/error.hpp"
#include "tomodem/core/output.hpp"

namespace tomodem::pipeline {

namespace fs = std::filesystem;
using nlohmann::json;

namespace {
std::int64_t now_ns() {
  return std::chrono::duration_cast<std::chrono::nanoseconds>(std::chrono::system_clock::now().time_since_epoch())
      .count();
}
}  // namespace

std::string HashCache::hash(const std::string& path) {
  const fs::path full = fs::path(root) / path;
  struct stat st {};
  if (::stat(full.c_str(), &st) != 0) return "";
  if (S_ISDIR(st.st_mode)) {
    // A folder output: hash of its sorted relative names and their content hashes.
    std::vector<std::string> files;
    for (const auto& e : fs::recursive_directory_iterator(full))
      if (e.is_regular_file()) files.push_back(fs::relative(e.path(), full).generic_string());
    std::sort(files.begin(), files.end());
    std::string text;
    for (const auto& f : files) text += f + '\0' + hash((fs::path(path) / f).generic_string()) + '\n';
    const XXH128_hash_t h = XXH3_128bits(text.data(), text.size());
    char hex[40];
    std::snprintf(hex, sizeof hex, "d%016llx%016llx", static_cast<unsigned long long>(h.high64),
                  static_cast<unsigned long long>(h.low64));
    return hex;
  }
  const std::int64_t mtime = static_cast<std::int64_t>(st.st_mtim.tv_sec) * 1000000000 + st.st_mtim.tv_nsec;
  const std::int64_t ctime = static_cast<std::int64_t>(st.st_ctim.tv_sec) * 1000000000 + st.st_ctim.tv_nsec;
  if (const auto it = entries.find(path); it != entries.end()) {
    const Entry& e = it->second;
    if (e.size == st.st_size && e.mtime_ns == mtime && e.inode == st.st_ino && e.ctime_ns == ctime) return e.hash;
  }
  const std::string h = file_hash(full.string());
  ++hashed_;
  // Racy-git rule: a file changed within the last 2 s could change again within the same
  // timestamp tick, so it is not trusted from the cache until it has been stable.
  if (now_ns() - mtime > 2'000'000'000LL)
    entries[path] = Entry{h, static_cast<std::int64_t>(st.st_size), mtime, static_cast<std::uint64_t>(st.st_ino), ctime};
  else
    entries.erase(path);
  return h;
}

namespace detail {

void merge_lock(const std::string& path, LockFile& lock, HashCache& cache) {
  std::ifstream in(path);
  if (!in) return;
  json j;
  try {
    j = json::parse(in);
    // Named copies: iterating items() of a temporary would dangle.
    const json steps = j.value("steps", json::object()), failures = j.value("failures", json::object()),
               files = j.value("files", json::object());
    for (const auto& [id, e] : steps.items()) {
      LockEntry x;
      x.command = e.at("cmd").get<std::string>();
      x.version = e.value("version", "");
      x.params = e.value("params", std::map<std::string, std::string>{});
      x.deps = e.value("deps", std::map<std::string, std::string>{});
      x.outs = e.value("outs", std::map<std::string, std::string>{});
      x.started = e.value("started", "");
      x.finished = e.value("finished", "");
      x.seconds = e.value("seconds", 0.0);
      x.ranks = e.value("ranks", 1);
      x.launch = e.value("launch", "");
      lock.steps[id] = x;
      lock.failures.erase(id);
    }
    // A later file's failure replaces an earlier success, but one file may hold both for a step:
    // the failed re-run put the last good outputs back, and their success record was kept.
    for (const auto& [id, e] : failures.items()) {
      lock.failures[id] = FailureRecord{e.value("exit_code", 1), e.value("finished", ""), e.value("reason", ""),
                                        e.value("log", "")};
      if (!steps.contains(id)) lock.steps.erase(id);
    }
    for (const auto& [f, e] : files.items())
      cache.entries[f] = HashCache::Entry{e.at("hash").get<std::string>(), e.at("size").get<std::int64_t>(),
                                          e.at("mtime_ns").get<std::int64_t>(), e.at("inode").get<std::uint64_t>(),
                                          e.value("ctime_ns", std::int64_t{0})};  // absent in older lock files
  } catch (const json::exception& e) {
    throw InputError(path, "", "", std::string("unreadable lock file (delete it to start afresh): ") + e.what());
  }
}

std::string lock_json(const LockFile& lock, HashCache& cache) {
  json j;
  j["format"] = "tomodem-run lock 1";
  j["steps"] = json::object();
  for (const auto& [id, e] : lock.steps) {
    j["steps"][id] = {{"cmd", e.command}, {"version", e.version},   {"params", e.params},
                      {"deps", e.deps},   {"outs", e.outs},         {"started", e.started},
                      {"finished", e.finished}, {"seconds", e.seconds}, {"ranks", e.ranks}};
    if (!e.launch.empty()) j["steps"][id]["launch"] = e.launch;
  }
  j["failures"] = json::object();
  for (const auto& [id, f] : lock.failures)
    j["failures"][id] = {{"exit_code", f.exit_code}, {"finished", f.finished}, {"reason", f.reason}, {"log", f.log}};
  j["files"] = json::object();
  for (auto it = cache.entries.begin(); it != cache.entries.end();) {
    if (!fs::exists(fs::path(cache.root) / it->first)) {
      it = cache.entries.erase(it);
      continue;
    }
    j["files"][it->first] = {{"hash", it->second.hash},
                             {"size", it->second.size},
                             {"mtime_ns", it->second.mtime_ns},
                             {"inode", it->second.inode},
                             {"ctime_ns", it->second.ctime_ns}};
    ++it;
  }
  return j.dump(1) + "\n";
}

std::string shard_lock_file(const Pipeline& p, int shard) {
  std::string base = p.lock_file.substr(0, p.lock_file.size() - 5);  // strip ".json"
  return base + ".shard-" + std::to_string(shard) + ".json";
}

std::vector<std::string> shard_lock_files(const Pipeline& p) {
  const fs::path lock(p.lock_file);
  const std::string prefix = lock.stem().string() + ".shard-";
  std::vector<std::string> out;
  std::error_code ec;
  for (const auto& e : fs::directory_iterator(lock.parent_path().empty() ? "." : lock.parent_path(), ec)) {
    const std::string name = e.path().filename().string();
    if (name.rfind(prefix, 0) == 0 && e.path().extension() == ".json") out.push_back(e.path().string());
  }
  std::sort(out.begin(), out.end());
  return out;
}

void load_all_locks(const Pipeline& p, LockFile& lock, HashCache& cache) {
  cache.root = p.dir;
  merge_lock(p.lock_file, lock, cache);
  for (const auto& f : shard_lock_files(p)) merge_lock(f, lock, cache);
}

std::string release_of(const std::string& version) {
  const auto b = version.rfind(" (git ");
  return b != std::string::npos && version.back() == ')' ? version.substr(0, b) : version;
}

Verdict check(const Instance& in, const LockEntry* e, HashCache& cache, bool all, bool rerun_on_rebuild) {
  Verdict v;
  const auto add = [&](std::string r) {
    v.stale = true;
    v.reasons.push_back(std::move(r));
    return !all;
  };
  if (!e) {
    add("no record of a successful run");
    return v;
  }
  for (const auto& [name, path] : in.outs)
    if (!fs::exists(fs::path(cache.root) / path) && add("output " + path + " is missing")) return v;
  std::set<std::string> keys;
  for (const auto& kv : in.params) keys.insert(kv.first);
  for (const auto& kv : e->params) keys.insert(kv.first);
  for (const auto& k : keys) {
    const auto a = e->params.find(k), b = in.params.find(k);
    if (a == e->params.end()) {
      if (add("param " + k + " added: " + b->second)) return v;
    } else if (b == in.params.end()) {
      if (add("param " + k + " removed (was " + a->second + ")")) return v;
    } else if (a->second != b->second && add("param " + k + " changed: " + a->second + " -> " + b->second)) {
      return v;
    }
  }
  // After params: a param change usually changes the command too, and names the cause better.
  // A tool's release names its physics; its build (git hash) changes with every commit, so by
  // default a rebuild alone does not re-run a study of hours (as Make ignores a new compiler).
  // A `version:` of a cmd step is the user's own string and is compared whole.
  const bool same_build = e->version == in.version;
  const bool ignore_build = !in.tool.empty() && !rerun_on_rebuild && release_of(e->version) == release_of(in.version);
  if (!same_build && ignore_build)
    v.notes.push_back("made by another build of the same release ('" + e->version + "', now '" + in.version +
                      "'): not re-run without --rerun-on-rebuild");
  if (!same_build && !ignore_build && add("version changed: '" + e->version + "' -> '" + in.version + "'")) return v;
  if (e->command != in.command && add("command changed (was: " + e->command + ")")) return v;
  std::set<std::string> now;
  for (const auto& [name, path] : in.deps) {
    now.insert(path);
    const auto it = e->deps.find(path);
    if (it == e->deps.end()) {
      if (add("new input " + path)) return v;
      continue;
    }
    const std::string h = cache.hash(path);
    if (h.empty()) {
      if (add("input " + path + " is missing")) return v;
    } else if (h != it->second && add("input " + path + " changed")) {
      return v;
    }
  }
  for (const auto& kv : e->deps)
    if (!now.count(kv.first) && add("input " + kv.first + " no longer used")) return v;
  for (const auto& [name, path] : in.outs) {
    const auto it = e->outs.find(path);
    if (it == e->outs.end()) {
      if (add("new output " + path)) return v;
      continue;
    }
    const std::string h = cache.hash(path);
    if (!h.empty() && h != it->second && add("output " + path + " was modified after the step made it")) return v;
  }
  return v;
}

LockEntry record(const Instance& in, HashCache& cache, const std::string& started, double seconds) {
  LockEntry e;
  e.command = in.command;
  e.version = in.version;
  e.params = in.params;
  for (const auto& [name, path] : in.deps) e.deps[path] = cache.hash(path);
  for (const auto& [name, path] : in.outs) e.outs[path] = cache.hash(path);
  e.started = started;
  e.finished = utc_now();
  e.seconds = seconds;
  e.ranks = in.ranks;
  return e;
}

std::string log_path(const Pipeline& p, const Instance& in) {
  std::string name = in.id;
  for (char& c : name)
    if (c == '[') c = '@';
  name.erase(std::remove(name.begin(), name.end(), ']'), name.end());
  return (fs::path(p.logs_dir) / (name + ".log")).string();
}

}  // namespace detail
}  // namespace tomodem::pipeline
