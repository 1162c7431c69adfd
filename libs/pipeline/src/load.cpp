// Reading a pipeline file: includes, variables, --set overrides, sweeps, references between
// steps, and the checks that must fail (exit 2) before anything runs.
#include <unistd.h>
#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <cerrno>
#include <climits>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <nlohmann/json.hpp>
#include <functional>
#include <optional>
#include <queue>
#include <set>
#include <sstream>

#include "template.hpp"
#include "tomodem/core/error.hpp"
#include "tomodem/core/yaml_keys.hpp"
#include "tomodem/pipeline/pipeline.hpp"

namespace tomodem::pipeline {

namespace {
namespace fs = std::filesystem;
using detail::RefError;

[[noreturn]] void fail(const Location& where, const std::string& field, const std::string& value,
                       const std::string& why) {
  throw InputError(where.str(), field, value, why);
}

Location at(const std::string& file, const YAML::Node& n) {
  const int line = n.Mark().line;
  return {file, line >= 0 ? line + 1 : 0};
}

std::string scalar(const YAML::Node& n, const std::string& file, const std::string& field) {
  if (!n.IsScalar()) fail(at(file, n), field, "", "expected a single value");
  return n.Scalar();
}

long long integer(const std::string& text, const Location& where, const std::string& field, long long lo) {
  char* end = nullptr;
  errno = 0;
  long long v = std::strtoll(text.c_str(), &end, 10);
  bool whole = !text.empty() && *end == '\0';
  if (whole && errno == ERANGE)  // strtoll clamps to +-(2^63 - 1): a seed 2^64 was run as 2^63 - 1
    fail(where, field, text, "out of range: an integer in [-2^63, 2^63 - 1] (not clamped)");
  if (!text.empty() && !whole) {  // "1e9" is an integer written as a float; "1.5" is not one
    const double d = std::strtod(text.c_str(), &end);
    whole = *end == '\0' && std::isfinite(d) && d == std::floor(d) && std::fabs(d) < 9e18;
    if (whole) v = static_cast<long long>(d);
  }
  if (!whole || v < lo)
    fail(where, field, text, lo == LLONG_MIN ? "expected an integer" : "expected an integer >= " + std::to_string(lo));
  return v;
}

bool is_name(const std::string& s) {
  return !s.empty() && std::all_of(s.begin(), s.end(), [](char c) {
    return std::isalnum(static_cast<unsigned char>(c)) || c == '_' || c == '-';
  });
}

std::string normal_path(const std::string& p) {
  std::string s = fs::path(p).lexically_normal().generic_string();
  while (s.size() > 1 && s.back() == '/') s.pop_back();
  return s;
}

// Step names and instance ids name log files (<id>.log), and a file name has at most 255 bytes.
constexpr std::size_t kMaxStepName = 200, kMaxInstanceId = 250;

// ---- the document after includes --------------------------------------------------------

struct Var {
  YAML::Node node;
  std::string file;  // for the lines of nested values
  Location where;
};
struct RawStep {
  std::string name;
  YAML::Node node;
  std::string file;
  Location where;
};
struct Raw {
  std::map<std::string, Var> vars;  // dotted names: a nested map `a: {b: 1}` gives "a.b"
  std::vector<RawStep> steps;
  std::string logs;
  std::string out;                 // `out:`, a root outside the pipeline folder outputs may use
  Location out_where, logs_where;
  std::vector<std::string> files;  // every pipeline file read (absolute): never an output
};

void flatten_vars(const YAML::Node& n, const std::string& prefix, const std::string& file,
                  std::map<std::string, Var>& out) {
  for (const auto& kv : n) {
    const std::string key = prefix + kv.first.Scalar();
    if (kv.second.IsMap())
      flatten_vars(kv.second, key + ".", file, out);
    else
      out[key] = Var{kv.second, file, at(file, kv.first)};
  }
}

void read_file(const fs::path& path, const std::string& shown, const Location& from, bool root, Raw& raw,
               std::vector<std::string>& stack) {
  std::error_code ec;
  const std::string key = fs::weakly_canonical(path, ec).string();
  if (std::find(stack.begin(), stack.end(), key) != stack.end())
    fail(from, "include", shown, "include cycle: this file includes itself, directly or not");
  YAML::Node doc;
  if (fs::is_directory(path, ec)) fail(from, root ? "" : "include", shown, "is a folder, not a pipeline file");
  try {
    doc = YAML::LoadFile(path.string());
    std::ifstream in(path);
    const std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    if (const auto r = find_repeated_key(text)) {
      const std::string field = r->path.empty() ? r->key : r->path + "." + r->key;
      if (r->first_line == 0)
        fail({shown, r->line}, "<<", "",
             "YAML merge keys (<<) are not supported: write the keys out, or share values through vars: and ${vars.NAME}");
      fail({shown, r->line}, field, "", "key '" + r->key + "' given twice (first at line " + std::to_string(r->first_line) + ")");
    }
  } catch (const YAML::BadFile&) {
    fail(from, root ? "" : "include", shown, "cannot read the file");
  } catch (const YAML::ParserException& e) {
    // The common case: `[out/${cell}.h5]`, where YAML's flow syntax claims the braces.
    const std::string hint = e.msg.find("flow") != std::string::npos
                                 ? " (inside [...] or {...}, quote values that use ${...})"
                                 : "";
    fail({shown, e.mark.line + 1}, "", "", "YAML syntax error: " + e.msg + hint);
  }
  if (doc.IsNull()) return;
  if (!doc.IsMap()) fail({shown, 1}, "", "", "a pipeline file is a map with a 'steps:' key");
  stack.push_back(key);
  raw.files.push_back(key);
  for (const auto& kv : doc) {
    const std::string k = kv.first.Scalar();
    if (k != "vars" && k != "include" && k != "steps" && k != "logs" && k != "out")
      fail(at(shown, kv.first), k, "", "unknown key (expected vars, include, steps, logs, out)");
  }
  // Included files come first: their steps are declared before ours, our vars override theirs.
  if (const YAML::Node inc = doc["include"]) {
    std::vector<YAML::Node> items;
    if (inc.IsSequence())
      for (const auto& i : inc) items.push_back(i);
    else
      items.push_back(inc);
    for (const auto& i : items) {
      const std::string name = scalar(i, shown, "include");
      read_file(path.parent_path() / name, normal_path((fs::path(shown).parent_path() / name).string()),
                at(shown, i), false, raw, stack);
    }
  }
  if (const YAML::Node vars = doc["vars"]) {
    if (!vars.IsMap()) fail(at(shown, vars), "vars", "", "expected a map of name: value");
    std::map<std::string, Var> mine;
    flatten_vars(vars, "", shown, mine);
    for (auto& [k, v] : mine) raw.vars[k] = v;
  }
  if (const YAML::Node logs = doc["logs"]) {
    raw.logs = scalar(logs, shown, "logs");
    raw.logs_where = at(shown, logs);
  }
  if (const YAML::Node out = doc["out"]) {
    raw.out = scalar(out, shown, "out");
    raw.out_where = at(shown, out);
  }
  if (const YAML::Node steps = doc["steps"]) {
    if (!steps.IsMap()) fail(at(shown, steps), "steps", "", "expected a map of step name: step");
    for (const auto& kv : steps) {
      const std::string name = kv.first.Scalar();
      const Location where = at(shown, kv.first);
      if (!is_name(name)) fail(where, "steps." + name, "", "a step name uses only letters, digits, '_' and '-'");
      // The name is part of its log file's name, which a file system caps at 255 bytes.
      if (name.size() > kMaxStepName)
        fail(where, "steps." + name.substr(0, 40) + "...", "",
             "a step name has at most " + std::to_string(kMaxStepName) + " bytes (this one has " + std::to_string(name.size()) + ")");
      for (const auto& s : raw.steps)
        if (s.name == name) fail(where, "steps." + name, "", "step defined twice (first at " + s.where.str() + ")");
      if (!kv.second.IsMap()) fail(where, "steps." + name, "", "a step is a map (cmd or tool, deps, outs, ...)");
      raw.steps.push_back(RawStep{name, kv.second, shown, where});
    }
  }
  stack.pop_back();
}

// ---- variables --------------------------------------------------------------------------

constexpr int kMaxVarDepth = 32;
constexpr std::size_t kMaxVarBytes = 1 << 20;

class Vars {
 public:
  explicit Vars(const std::map<std::string, Var>& v) : vars_(v) {}
  std::vector<std::string> get(const std::string& name, int depth = 0) const {
    if (depth > kMaxVarDepth)
      throw RefError{"variables refer to each other in a cycle, or nest deeper than " + std::to_string(kMaxVarDepth) +
                     " levels (at 'vars." + name + "')"};
    const auto it = vars_.find(name);
    if (it == vars_.end()) throw RefError{"unknown variable 'vars." + name + "'" + known_under(name)};
    const YAML::Node& n = it->second.node;
    const auto inner = [&](const std::string& r) {
      if (r.rfind("vars.", 0) != 0) throw RefError{"a variable can only refer to other variables"};
      return get(r.substr(5), depth + 1);
    };
    std::vector<std::string> out;
    if (n.IsScalar()) {
      for (auto& s : detail::substitute_list(n.Scalar(), inner)) out.push_back(s);
    } else if (n.IsSequence()) {
      for (const auto& e : n) {
        if (!e.IsScalar()) throw RefError{"variable 'vars." + name + "' holds a nested list"};
        for (auto& s : detail::substitute_list(e.Scalar(), inner)) out.push_back(s);
      }
    } else if (n.IsNull()) {
      out.push_back("");
    }
    // Variables that each refer several times to the one below grow exponentially (9 levels of 10
    // made a gigabyte): refused at the first one past a size no pipeline needs.
    std::size_t bytes = 0;
    for (const auto& s : out) bytes += s.size() + 1;
    if (bytes > kMaxVarBytes)
      throw RefError{"variable 'vars." + name + "' expands to more than 1 MB (" + std::to_string(bytes) +
                     " bytes): variables that refer many times to each other"};
    return out;
  }

 private:
  // For a missing `a.b.c`: the keys the nearest existing map `a.b` or `a` has, so a computed
  // name (`${vars.scales.${vars.scale}.particles}`) with an unknown value lists the known ones.
  std::string known_under(const std::string& name) const {
    for (auto dot = name.rfind('.'); dot != std::string::npos && dot > 0; dot = name.rfind('.', dot - 1)) {
      const std::string map = name.substr(0, dot + 1);
      std::set<std::string> keys;
      for (auto it = vars_.lower_bound(map); it != vars_.end() && it->first.compare(0, map.size(), map) == 0; ++it)
        keys.insert(it->first.substr(map.size(), it->first.find('.', map.size()) - map.size()));
      if (keys.empty()) continue;
      std::string list;
      for (const auto& k : keys) list += (list.empty() ? "" : ", ") + k;
      return " (vars." + name.substr(0, dot) + " has: " + list + ")";
    }
    return "";
  }

  const std::map<std::string, Var>& vars_;
};

// ---- sweeps -----------------------------------------------------------------------------

struct Cell {
  std::vector<std::pair<std::string, std::string>> values;
  std::string name;
  int replica = -1;
};

// A sweep larger than this is a typo (replicas: 1000000000), not a study: refused before expansion.
constexpr double kMaxCells = 1e6;

void check_sweep_size(double cells, const Location& where, const std::string& field, const std::string& value) {
  if (cells > kMaxCells)
    fail(where, field, value,
         "the sweep would make " + std::to_string(static_cast<long long>(cells)) +
             " instances of the step; at most 1000000 per step (split the study into several pipelines)");
}

const std::set<std::string> kStepKeys = {"cmd", "tool", "args", "deps", "outs", "params", "threads", "ranks",
                                         "matrix", "cases", "cell", "replicas", "seed", "version", "desc"};

// What ${...} may name inside one instance. A null pointer means "not available here".
struct Scope {
  const Vars* vars = nullptr;
  const Cell* cell = nullptr;
  std::string step;
  long long seed = 0;
  int threads = 1, ranks = 1;
  const std::map<std::string, std::string>* params = nullptr;
  const NamedPaths* outs = nullptr;
  const NamedPaths* deps = nullptr;
  std::function<std::vector<std::string>(const std::string&)> steps;
  const std::string* replicas = nullptr;  // ${run.replicas}: only in deps, cmd and args of a pipeline that has one
};

std::vector<std::string> named(const NamedPaths* paths, const std::string& rest, const char* what) {
  if (!paths) throw RefError{std::string(what) + " cannot be used here"};
  std::vector<std::string> out;
  for (const auto& [k, v] : *paths)
    if (rest.empty() || k == rest) out.push_back(v);
  if (!rest.empty() && out.empty()) throw RefError{std::string("this step has no ") + what + " named '" + rest + "'"};
  return out;
}

std::vector<std::string> lookup(const Scope& s, const std::string& name) {
  const auto starts = [&](const char* p) { return name.rfind(p, 0) == 0; };
  if (starts("vars.")) return s.vars->get(name.substr(5));
  if (starts("matrix.")) {
    const std::string k = name.substr(7);
    if (s.cell)
      for (const auto& [key, v] : s.cell->values)
        if (key == k) return {v};
    throw RefError{"this step has no matrix key '" + k + "'"};
  }
  if (name == "cell") return {s.cell ? s.cell->name : ""};
  if (name == "step") return {s.step};
  if (name == "replica") {
    if (!s.cell || s.cell->replica < 0) throw RefError{"'${replica}' needs `replicas:` in the step"};
    return {std::to_string(s.cell->replica)};
  }
  if (name == "seed") return {std::to_string(s.seed)};
  if (name == "threads") return {std::to_string(s.threads)};
  if (name == "ranks") return {std::to_string(s.ranks)};
  if (starts("params.")) {
    if (!s.params) throw RefError{"params cannot be used here"};
    const auto it = s.params->find(name.substr(7));
    if (it == s.params->end()) throw RefError{"this step has no param '" + name.substr(7) + "'"};
    return {it->second};
  }
  if (name == "outs" || starts("outs.")) return named(s.outs, name.size() > 4 ? name.substr(5) : "", "outs");
  if (name == "deps" || starts("deps.")) return named(s.deps, name.size() > 4 ? name.substr(5) : "", "deps");
  if (starts("steps.")) {
    if (!s.steps) throw RefError{"other steps' outputs can be used only in deps, cmd and args"};
    return s.steps(name.substr(6));
  }
  if (name == "run.replicas") {
    if (!s.replicas)
      throw RefError{"${run.replicas} is the runner's record of adaptive replicas: it needs a step with "
                     "`replicas: {until: ...}` and can be used in deps, cmd and args"};
    return {*s.replicas};
  }
  throw RefError{"unknown reference '${" + name +
                 "}' (known: vars.*, matrix.*, params.*, outs[.*], deps[.*], steps.S.outs[.*], cell, replica, "
                 "seed, threads, ranks, step, run.replicas; write $${ for a literal ${)"};
}

std::vector<std::string> resolve_list(const std::string& text, const Scope& s, const Location& where,
                                      const std::string& field) {
  try {
    return detail::substitute_list(text, [&](const std::string& r) { return lookup(s, r); });
  } catch (const RefError& e) {
    fail(where, field, text, e.why);
  }
}

// A `cmd:` line: values are substituted as shell data (quoted), never as code.
std::string resolve_shell(const std::string& text, const Scope& s, const Location& where, const std::string& field) {
  try {
    return detail::substitute_shell(text, [&](const std::string& r) { return lookup(s, r); });
  } catch (const RefError& e) {
    fail(where, field, text, e.why);
  }
}

std::string resolve(const std::string& text, const Scope& s, const Location& where, const std::string& field) {
  try {
    return detail::substitute(text, [&](const std::string& r) { return lookup(s, r); });
  } catch (const RefError& e) {
    fail(where, field, text, e.why);
  }
}

// The cell values without the replica, sorted: what the replicas of one cell share.
std::string group_key(const std::vector<std::pair<std::string, std::string>>& values) {
  std::map<std::string, std::string> m;
  for (const auto& [k, v] : values)
    if (k != "replica") m[k] = v;
  std::string key;
  for (const auto& [k, v] : m) key += (key.empty() ? "" : ",") + k + "=" + v;
  return key;
}

std::string group_id(const std::string& step, const std::string& key) {
  return key.empty() ? step : step + "[" + key + "]";
}

// How many replicas a cell group of an adaptive step gets in this expansion.
using CountOf = std::function<int(const Adaptive&, const std::string& group_id)>;

std::vector<Cell> matrix_cells(const RawStep& st, const Scope& vs, bool& swept) {
  const std::string& f = st.file;
  const std::string base = "steps." + st.name + ".";
  std::vector<Cell> cells{Cell{}};
  const YAML::Node m = st.node["matrix"];
  if (!m) return cells;
  if (!m.IsMap() || m.size() == 0) fail(at(f, m), base + "matrix", "", "expected a map of key: [values]");
  swept = true;
  for (const auto& kv : m) {
    const std::string key = kv.first.Scalar();
    const std::string field = base + "matrix." + key;
    if (!is_name(key) || key == "replica") fail(at(f, kv.first), field, "", "bad matrix key");
    std::vector<std::string> values;
    if (kv.second.IsSequence()) {
      for (const auto& v : kv.second)
        for (auto& x : resolve_list(scalar(v, f, field), vs, at(f, v), field)) values.push_back(x);
    } else {
      values = resolve_list(scalar(kv.second, f, field), vs, at(f, kv.second), field);
    }
    if (values.empty()) fail(at(f, kv.second), field, "", "a matrix key needs at least one value");
    check_sweep_size(static_cast<double>(cells.size()) * static_cast<double>(values.size()), at(f, kv.second), field,
                     std::to_string(values.size()) + " values");
    std::vector<Cell> next;
    for (const auto& c : cells)
      for (const auto& v : values) {
        Cell n = c;
        n.values.emplace_back(key, v);
        next.push_back(n);
      }
    cells = next;
  }
  return cells;
}

void add_case_cells(const RawStep& st, const Scope& vs, std::vector<Cell>& cells, bool& swept) {
  const std::string& f = st.file;
  const std::string base = "steps." + st.name + ".";
  const YAML::Node cs = st.node["cases"];
  if (!cs) return;
  if (!cs.IsSequence() || cs.size() == 0) fail(at(f, cs), base + "cases", "", "expected a list of maps");
  if (!swept) cells.clear();
  swept = true;
  // Every cell gives the same keys, so a misspelt case key (`densty`) is reported here, at its
  // line, rather than as "no matrix key 'density'" where a command reads it.
  const auto key_set = [](const Cell& c) {
    std::set<std::string> k;
    for (const auto& kv : c.values) k.insert(kv.first);
    return k;
  };
  std::optional<std::set<std::string>> expected;
  if (!cells.empty()) expected = key_set(cells.front());
  for (const auto& c : cs) {
    if (!c.IsMap()) fail(at(f, c), base + "cases", "", "each case is a map of key: value");
    Cell cell;
    for (const auto& kv : c) {
      const std::string field = base + "cases." + kv.first.Scalar();
      if (!is_name(kv.first.Scalar())) fail(at(f, kv.first), field, "", "bad case key");
      cell.values.emplace_back(kv.first.Scalar(), resolve(scalar(kv.second, f, field), vs, at(f, kv.second), field));
    }
    const std::set<std::string> keys = key_set(cell);
    if (!expected) expected = keys;
    if (keys != *expected) {
      std::string list;
      for (const auto& k : *expected) list += (list.empty() ? "" : ", ") + k;
      for (const auto& kv : c)
        if (!expected->count(kv.first.Scalar()))
          fail(at(f, kv.first), base + "cases." + kv.first.Scalar(), "",
               "case key '" + kv.first.Scalar() + "' is not a key of the other cells (" + list + "); every cell gives the same keys");
      fail(at(f, c), base + "cases", "", "this case lacks a key the other cells have (" + list + ")");
    }
    cells.push_back(cell);
  }
}

// `replicas: {until: {KEY: target}, min: M, max: X, batch: B}`; every bad value is refused here,
// at load.
Adaptive adaptive_spec(const RawStep& st, const YAML::Node& r, const Scope& vs) {
  const std::string& f = st.file;
  const std::string field = "steps." + st.name + ".replicas";
  Adaptive a;
  a.step = st.name;
  a.where = at(f, r);
  for (const auto& kv : r)
    if (kv.first.Scalar() != "until" && kv.first.Scalar() != "min" && kv.first.Scalar() != "max" &&
        kv.first.Scalar() != "batch")
      fail(at(f, kv.first), field + "." + kv.first.Scalar(), "", "unknown key (expected until, min, max, batch)");
  const YAML::Node u = r["until"];
  if (!u || !u.IsMap() || u.size() == 0)
    fail(u ? at(f, u) : a.where, field + ".until", "", "expected a map KEY: target (relative 95 % half-width, 0.02 = 2 %)");
  for (const auto& kv : u) {
    const std::string key = kv.first.Scalar(), kf = field + ".until." + key;
    const std::string text = resolve(scalar(kv.second, f, kf), vs, at(f, kv.second), kf);
    char* end = nullptr;
    const double target = std::strtod(text.c_str(), &end);
    if (text.empty() || *end != '\0' || !std::isfinite(target) || target <= 0)
      fail(at(f, kv.second), kf, text, "a target is a relative 95 % half-width > 0 (0.02 = 2 %)");
    a.until.emplace_back(key, target);
    a.until_where.push_back(at(f, kv.first));
  }
  const auto bound = [&](const char* name, long long fallback) {
    const YAML::Node n = r[name];
    if (!n) return fallback;
    const std::string nf = field + "." + name;
    return integer(resolve(scalar(n, f, nf), vs, at(f, n), nf), at(f, n), nf, LLONG_MIN);
  };
  if (!r["max"]) fail(a.where, field + ".max", "", "adaptive replicas need max: (the most replicas per cell)");
  const long long lo = bound("min", 2), hi = bound("max", 0);
  if (lo < 2) fail(r["min"] ? at(f, r["min"]) : a.where, field + ".min", std::to_string(lo), "at least 2 replicas are needed for a spread");
  if (hi < lo) fail(at(f, r["max"]), field + ".max", std::to_string(hi), "max must be at least min (" + std::to_string(lo) + ")");
  check_sweep_size(static_cast<double>(hi), at(f, r["max"]), field + ".max", std::to_string(hi));
  a.min = static_cast<int>(lo);
  a.max = static_cast<int>(hi);
  if (const YAML::Node b = r["batch"]) {
    const std::string bf = field + ".batch", text = resolve(scalar(b, f, bf), vs, at(f, b), bf);
    char* end = nullptr;
    const long long k = std::strtoll(text.c_str(), &end, 10);
    if (text == "projected") a.batch = 0;
    else if (!text.empty() && *end == '\0' && k >= 1 && k <= hi) a.batch = static_cast<int>(k);
    else fail(at(f, b), bf, text, "replicas added per group and round: an integer from 1 to max (" + std::to_string(hi) + "), or projected");
  }
  return a;
}

void add_replicas(const RawStep& st, const Scope& vs, const CountOf& count, std::vector<Cell>& cells,
                  std::optional<Adaptive>& adaptive) {
  const std::string& f = st.file;
  const std::string field = "steps." + st.name + ".replicas";
  const YAML::Node r = st.node["replicas"];
  long long most = 0;
  if (r.IsMap()) {
    adaptive = adaptive_spec(st, r, vs);
    most = adaptive->max;
  } else {
    most = integer(resolve(scalar(r, f, field), vs, at(f, r), field), at(f, r), field, 1);
  }
  check_sweep_size(static_cast<double>(cells.size()) * static_cast<double>(most), at(f, r), field, std::to_string(most));
  std::vector<Cell> next;
  for (const auto& c : cells) {
    const long long n = adaptive ? count(*adaptive, group_id(st.name, group_key(c.values))) : most;
    for (int k = 0; k < n; ++k) {
      Cell x = c;
      x.values.emplace_back("replica", std::to_string(k));
      x.replica = k;
      next.push_back(x);
    }
  }
  cells = next;
}

void name_cells(const RawStep& st, const Scope& vs, std::vector<Cell>& cells) {
  const std::string& f = st.file;
  const std::string base = "steps." + st.name + ".";
  const YAML::Node tmpl = st.node["cell"];
  std::set<std::string> seen;
  for (auto& c : cells) {
    if (tmpl) {
      Scope s = vs;
      s.cell = &c;
      c.name = resolve(scalar(tmpl, f, base + "cell"), s, at(f, tmpl), base + "cell");
    } else {
      for (const auto& [k, v] : c.values) c.name += (c.name.empty() ? "" : "_") + k + "-" + v;
    }
    const Location where = tmpl ? at(f, tmpl) : st.where;
    if (c.name.empty() || c.name.find_first_of("/[] \t\n") != std::string::npos)
      fail(where, base + "cell", c.name, "a cell name must be non-empty, without '/', '[', ']' or blanks");
    if (!seen.insert(c.name).second)
      fail(where, base + "cell", c.name, "two cells get the same name; put every swept key in the `cell:` template");
  }
}

std::vector<Cell> cells_of(const RawStep& st, const Vars& vars, const CountOf& count, std::optional<Adaptive>& adaptive) {
  Scope vs;
  vs.vars = &vars;
  bool swept = false;
  std::vector<Cell> cells = matrix_cells(st, vs, swept);
  add_case_cells(st, vs, cells, swept);
  if (st.node["replicas"]) {
    add_replicas(st, vs, count, cells, adaptive);
    swept = true;
  }
  if (swept) name_cells(st, vs, cells);
  return cells;
}

// ---- tools ------------------------------------------------------------------------------

std::string self_dir() {
  char buf[PATH_MAX];
  const ssize_t n = ::readlink("/proc/self/exe", buf, sizeof buf - 1);
  if (n <= 0) return "";
  const std::string p(buf, static_cast<std::size_t>(n));
  return p.substr(0, p.find_last_of('/'));
}

std::string find_tool(const std::string& exe, const std::string& tool_dir) {
  std::vector<std::string> dirs;
  if (!tool_dir.empty()) dirs.push_back(tool_dir);
  dirs.push_back(self_dir());
  if (const char* path = std::getenv("PATH")) {
    std::string all = path;
    for (std::size_t b = 0, e; b <= all.size(); b = e + 1) {
      e = all.find(':', b);
      if (e == std::string::npos) e = all.size();
      if (e > b) dirs.push_back(all.substr(b, e - b));
    }
  }
  for (const auto& d : dirs) {
    const std::string p = d + "/" + exe;
    if (::access(p.c_str(), X_OK) == 0) return p;
  }
  return "";
}

// The whole `--version` output of a tool.
const std::string& version_output(const std::string& path) {
  static std::map<std::string, std::string> cache;  // one `--version` call per tool and process
  if (auto it = cache.find(path); it != cache.end()) return it->second;
  std::string out;
  if (FILE* f = ::popen((detail::shell_quote(path) + " --version 2>/dev/null").c_str(), "r")) {
    char buf[256];
    while (std::fgets(buf, sizeof buf, f)) out += buf;
    ::pclose(f);
  }
  while (!out.empty() && std::isspace(static_cast<unsigned char>(out.back()))) out.pop_back();
  return cache[path] = out;
}

// The first line is the version of the step's signature; the `features:` line is not part of it.
std::string tool_version(const std::string& path) {
  const std::string& out = version_output(path);
  return out.substr(0, out.find('\n'));
}

// "features: openmp mpi petsc" (the line every tool's --version prints), or "no features line".
std::string tool_features_line(const std::string& path) {
  std::istringstream lines(version_output(path));
  for (std::string line; std::getline(lines, line);)
    if (line.rfind("features:", 0) == 0) return line;
  return "no features line";
}

bool has_feature(const std::string& path, const std::string& feature) {
  std::istringstream words(tool_features_line(path));
  for (std::string w; words >> w;)
    if (w == feature) return true;
  return false;
}

// ---- building the instances -------------------------------------------------------------

// An instance while it is being built: where its pieces came from, for messages.
struct Pending {
  const RawStep* raw;
  Cell cell;
  long long seed = 0;
  std::vector<Location> dep_where, out_where;
};

void flatten_params(const YAML::Node& n, const std::string& prefix, const std::string& file,
                    std::vector<std::pair<std::string, YAML::Node>>& out) {
  for (const auto& kv : n) {
    const std::string key = prefix + kv.first.Scalar();
    if (kv.second.IsMap())
      flatten_params(kv.second, key + ".", file, out);
    else
      out.emplace_back(key, kv.second);
  }
}

// `deps:`/`outs:` as a list (names "0", "1", ...), a map (name: path) or one path.
std::vector<std::tuple<std::string, std::string, Location>> path_items(const YAML::Node& n, const std::string& file,
                                                                       const std::string& field) {
  std::vector<std::tuple<std::string, std::string, Location>> items;
  if (!n) return items;
  if (n.IsMap()) {
    for (const auto& kv : n) {
      if (!is_name(kv.first.Scalar())) fail(at(file, kv.first), field + "." + kv.first.Scalar(), "", "bad name");
      items.emplace_back(kv.first.Scalar(), scalar(kv.second, file, field), at(file, kv.second));
    }
  } else if (n.IsSequence()) {
    int k = 0;
    for (const auto& v : n) items.emplace_back(std::to_string(k++), scalar(v, file, field), at(file, v));
  } else {
    items.emplace_back("0", scalar(n, file, field), at(file, n));
  }
  return items;
}

std::string trimmed(const std::string& s) {
  const auto b = s.find_first_not_of(" \t\r\n");
  return b == std::string::npos ? "" : s.substr(b, s.find_last_not_of(" \t\r\n") - b + 1);
}

void apply_overrides(const std::vector<std::string>& overrides, Raw& raw,
                     std::map<std::string, std::map<std::string, std::string>>& param_sets) {
  for (const auto& o : overrides) {
    const Location cli{"--set", 0};
    const auto eq = o.find('=');
    if (eq == std::string::npos || eq == 0) fail(cli, o, "", "expected KEY=VALUE");
    // Spaces around the '=' or the value come from the shell line, never from intent (" 64" would
    // be a new param value, hence a re-run), and an empty value is most often an unset shell
    // variable (`--set densities=$D`): refused rather than turned into a cell named "d".
    std::string key = trimmed(o.substr(0, eq));
    const std::string value = trimmed(o.substr(eq + 1));
    if (key.empty()) fail(cli, o, "", "expected KEY=VALUE");
    if (value.empty()) fail(cli, key, o.substr(eq + 1), "empty value (give KEY=VALUE with a value)");
    if (key.rfind("steps.", 0) == 0) {
      const auto dot = key.find('.', 6);
      const std::string step = key.substr(6, dot == std::string::npos ? std::string::npos : dot - 6);
      if (dot == std::string::npos || key.compare(dot, 8, ".params.") != 0)
        fail(cli, key, value, "a step override is steps.STEP.params.KEY=VALUE");
      if (std::none_of(raw.steps.begin(), raw.steps.end(), [&](const RawStep& s) { return s.name == step; }))
        fail(cli, key, value, "unknown step '" + step + "'");
      param_sets[step][key.substr(dot + 8)] = value;
      continue;
    }
    if (key.rfind("vars.", 0) == 0) key = key.substr(5);
    const auto it = raw.vars.find(key);
    if (it == raw.vars.end()) fail(cli, key, value, "unknown variable (declare it under vars:)");
    // `--set densities=[0.5,0.7]` gives a list; any other value is taken verbatim (YAML would
    // drop a " #..." as a comment or strip quotes: the user's text must arrive as typed).
    YAML::Node n(value);
    if (!value.empty() && value.front() == '[') {
      try {
        n = YAML::Load(value);
      } catch (const YAML::Exception&) {
        fail(cli, key, value, "a value starting with '[' is a YAML list such as [0.5, 0.7]");
      }
      if (!n.IsSequence()) fail(cli, key, value, "a value starting with '[' is a YAML list such as [0.5, 0.7]");
    }
    it->second = Var{n, "--set", cli};
  }
}

// ---- where outputs may go -----------------------------------------------------------------

fs::path resolved(const fs::path& p) {
  std::error_code ec;
  const fs::path a = fs::weakly_canonical(fs::absolute(p, ec), ec);
  return ec ? fs::absolute(p).lexically_normal() : a;
}

bool strictly_inside(const fs::path& path, const fs::path& root) {
  const fs::path rel = path.lexically_relative(root);
  return !rel.empty() && rel != "." && *rel.begin() != "..";
}

// The runner replaces outputs (moving the old ones aside), so an output must be strictly inside
// the pipeline's folder or the declared `out:` root (symbolic links resolved), and never a
// pipeline file, the lock file, the logs or a folder that holds one of them.
class OutputRules {
 public:
  OutputRules(const Raw& raw, const Pipeline& p, const std::string& out_root) : dir_(p.dir) {
    roots_.push_back(resolved(p.dir));
    if (!out_root.empty()) {
      const fs::path root = resolved(fs::path(p.dir) / out_root);
      if (root == root.root_path())
        fail(raw.out_where, "out", out_root, "the output root cannot be the file system's root");
      roots_.push_back(root);
    }
    for (const auto& f : raw.files) kept_.push_back(resolved(f));
    kept_.push_back(resolved(p.lock_file));
    kept_.push_back(resolved(p.logs_dir));
    kept_.push_back(resolved(p.replicas_file));
    lock_stem_ = resolved(p.lock_file).replace_extension("").string();  // <stem>.lock: shard locks too
  }

  void check(const std::string& path, const Location& where, const std::string& field) const {
    const fs::path full = resolved(fs::path(dir_) / path);
    // Inside the pipeline's folder, or inside or equal to the declared root.
    if (!strictly_inside(full, roots_[0]) && (roots_.size() < 2 || !(full == roots_[1] || strictly_inside(full, roots_[1]))))
      fail(where, field, path,
           "an output must be a path inside the pipeline's folder" +
               (roots_.size() > 1 ? " or the `out:` root " + roots_[1].string() : std::string()) + " (resolved: " +
               full.string() + "); to write elsewhere declare `out: DIR` at the top of the pipeline file");
    for (const auto& k : kept_)
      if (full == k || strictly_inside(k, full) || strictly_inside(full, k))
        fail(where, field, path, "this output would replace " + k.string() + " (a pipeline file, its lock file or logs)");
    if (full.string().rfind(lock_stem_, 0) == 0)
      fail(where, field, path, "this output would replace the pipeline's lock files (" + lock_stem_ + "*)");
  }

 private:
  std::string dir_;
  std::vector<fs::path> roots_, kept_;
  std::string lock_stem_;
};

// ---- expanding the steps into instances ---------------------------------------------------

// The pipeline's paths, before any step: the folder, lock file, logs and adaptive-replica record.
Pipeline skeleton(const std::string& file, const Raw& raw, const Vars& vars, std::string& out_root) {
  Pipeline p;
  p.file = file;
  const fs::path fp(file);
  p.dir = fp.parent_path().empty() ? "." : fp.parent_path().string();
  p.lock_file = (fp.parent_path() / (fp.stem().string() + ".lock.json")).string();
  p.logs_dir = (fp.parent_path() / (raw.logs.empty() ? fp.stem().string() + ".logs" : raw.logs)).string();
  p.replicas_file = (fp.parent_path() / (fp.stem().string() + ".replicas.json")).string();
  if (!raw.out.empty()) {
    Scope vs;
    vs.vars = &vars;
    out_root = resolve(raw.out, vs, raw.out_where, "out");
  }
  // The logs are rewritten on every run: they follow the rules of an output.
  if (!raw.logs.empty()) {
    const fs::path logs = resolved(p.logs_dir);
    if (!strictly_inside(logs, resolved(p.dir)) && !(!out_root.empty() && strictly_inside(logs, resolved(fs::path(p.dir) / out_root))))
      fail(raw.logs_where, "logs", raw.logs, "the log folder must be inside the pipeline's folder or the `out:` root");
  }
  return p;
}

void check_step_keys(const RawStep& st) {
  const std::string& f = st.file;
  const std::string base = "steps." + st.name + ".";
  for (const auto& kv : st.node)
    if (!kStepKeys.count(kv.first.Scalar()))
      fail(at(f, kv.first), base + kv.first.Scalar(), "",
           "unknown key (expected cmd, tool, args, deps, outs, params, threads, ranks, matrix, cases, cell, replicas, "
           "seed, version, desc)");
  if (!st.node["cmd"] == !st.node["tool"]) fail(st.where, "steps." + st.name, "", "a step needs one of cmd: or tool:");
  if (const YAML::Node cmd = st.node["cmd"]) {
    const std::string text = scalar(cmd, f, base + "cmd");
    if (text.find_first_not_of(" \t\r\n") == std::string::npos)
      fail(at(f, cmd), base + "cmd", text, "an empty command (it would run nothing and write none of its outputs)");
  }
  if (st.node["args"] && !st.node["tool"]) fail(at(f, st.node["args"]), base + "args", "", "args: goes with tool:");
}

// The replica counts of the last run (<stem>.replicas.json), so `status` and `explain` see the
// pipeline as it was last brought up to date.
std::map<std::string, int> recorded_counts(const std::string& file) {
  std::map<std::string, int> counts;
  std::ifstream in(file);
  if (!in) return counts;
  try {
    const nlohmann::json j = nlohmann::json::parse(in);
    for (const auto& g : j.at("groups")) counts[g.at("id").get<std::string>()] = g.at("n").get<int>();
  } catch (const nlohmann::json::exception& e) {
    throw InputError(file, "", "", std::string("unreadable record of adaptive replicas (delete it to start afresh): ") + e.what());
  }
  return counts;
}

class Expander {
 public:
  Expander(const Raw& raw, const Vars& vars, const LoadOptions& options,
           const std::map<std::string, std::map<std::string, std::string>>& param_sets, const Pipeline& base,
           const std::string& out_root, CountOf count)
      : raw_(raw), vars_(vars), options_(options), param_sets_(param_sets), p_(base), rules_(raw, base, out_root),
        count_(std::move(count)) {
    replicas_ref_ = fs::path(p_.replicas_file).filename().string();
  }

  Pipeline build() {
    for (const auto& st : raw_.steps) add_step(st);
    check_unique_outputs();
    for (std::size_t i = 0; i < inst_.size(); ++i) resolve_inputs(i);
    check_output_folders();
    return finish(order(needed()));
  }

 private:
  // Pass 1: cells, params and outputs of every step (outputs may not name other steps).
  void add_step(const RawStep& st) {
    p_.steps.push_back(st.name);
    check_step_keys(st);
    std::optional<Adaptive> adaptive;
    for (auto& cell : cells_of(st, vars_, count_, adaptive)) {
      Pending pe{&st, cell, 0, {}, {}};
      Instance in = make_instance(st, pe);
      of_step_[st.name].push_back(inst_.size());
      inst_.push_back(std::move(in));
      pend_.push_back(std::move(pe));
    }
    if (adaptive) {
      adaptive_of_[st.name] = p_.adaptive.size();
      p_.adaptive.push_back(*adaptive);
    }
  }

  Instance make_instance(const RawStep& st, Pending& pe) {
    const std::string& f = st.file;
    const std::string base = "steps." + st.name + ".";
    const Cell& cell = pe.cell;
    Instance in;
    in.step = st.name;
    in.cell = cell.name;
    in.id = cell.name.empty() ? st.name : st.name + "[" + cell.name + "]";
    if (in.id.size() > kMaxInstanceId)
      fail(st.node["cell"] ? at(f, st.node["cell"]) : st.where, base + "cell", cell.name,
           "the instance id " + in.id.substr(0, 40) + "... has " + std::to_string(in.id.size()) + " bytes, more than " +
               std::to_string(kMaxInstanceId) + " (it names the step's log file): use a shorter `cell:` template");
    in.where = st.where;
    in.replica = cell.replica;
    for (const auto& [k, v] : cell.values) in.matrix[k] = v;
    Scope s;
    s.vars = &vars_;
    s.cell = &pe.cell;
    s.step = st.name;
    if (const YAML::Node sd = st.node["seed"])
      pe.seed = integer(resolve(scalar(sd, f, base + "seed"), s, at(f, sd), base + "seed"), at(f, sd), base + "seed", LLONG_MIN);
    s.seed = pe.seed = pe.seed + std::max(cell.replica, 0);
    if (const YAML::Node th = st.node["threads"])
      in.threads = static_cast<int>(
          integer(resolve(scalar(th, f, base + "threads"), s, at(f, th), base + "threads"), at(f, th), base + "threads", 1));
    s.threads = in.threads;
    if (const YAML::Node rk = st.node["ranks"])  // 0, negative or not an integer: exit 2 naming it
      in.ranks = static_cast<int>(
          integer(resolve(scalar(rk, f, base + "ranks"), s, at(f, rk), base + "ranks"), at(f, rk), base + "ranks", 1));
    s.ranks = in.ranks;
    in.params = params_of(st, s);
    s.params = &in.params;
    for (const auto& [name, text, where] : path_items(st.node["outs"], f, base + "outs")) {
      for (auto& path : resolve_list(text, s, where, base + "outs." + name)) {
        if (path.empty()) fail(where, base + "outs." + name, text, "empty path");
        rules_.check(path, where, base + "outs." + name);
        in.outs.emplace_back(name, normal_path(path));
        pe.out_where.push_back(where);
      }
    }
    return in;
  }

  std::map<std::string, std::string> params_of(const RawStep& st, const Scope& s) const {
    const std::string& f = st.file;
    const std::string base = "steps." + st.name + ".";
    std::vector<std::pair<std::string, YAML::Node>> params;
    if (const YAML::Node pn = st.node["params"]) {
      if (!pn.IsMap()) fail(at(f, pn), base + "params", "", "expected a map of name: value");
      flatten_params(pn, "", f, params);
    }
    std::map<std::string, std::string> sets, out;
    if (const auto it = param_sets_.find(st.name); it != param_sets_.end()) sets = it->second;
    for (const auto& [k, node] : params) {
      const std::string field = base + "params." + k;
      if (auto it = sets.find(k); it != sets.end()) {
        out[k] = it->second;
        sets.erase(it);
        continue;
      }
      std::string v;
      if (node.IsSequence()) {
        for (const auto& e : node) v += (v.empty() ? "" : " ") + resolve(scalar(e, f, field), s, at(f, e), field);
      } else if (!node.IsNull()) {
        v = resolve(scalar(node, f, field), s, at(f, node), field);
      }
      out[k] = v;
    }
    if (!sets.empty()) fail({"--set", 0}, base + "params." + sets.begin()->first, "", "the step has no such param");
    return out;
  }

  // A path as the file system sees it (symbolic links resolved, absolute): `x.txt`,
  // `/abs/dir/x.txt` and `self/x.txt` (self -> .) are one file, so outputs and the inputs that
  // read them are matched by this key, never by their spelling.
  const std::string& key_of(const std::string& path) {
    auto it = keys_.find(path);
    if (it == keys_.end()) it = keys_.emplace(path, resolved(fs::path(p_.dir) / path).string()).first;
    return it->second;
  }

  std::string out_field(std::size_t i, std::size_t k) const {
    return "steps." + inst_[i].step + ".outs." + inst_[i].outs[k].first;
  }

  // Two instances writing one file would race and make staleness meaningless. An output inside
  // another instance's output folder is the same thing: re-running the folder's step moves the
  // whole folder aside, and the other output with it.
  void check_unique_outputs() {
    std::map<std::string, std::pair<std::size_t, std::size_t>> where;  // key -> (instance, output)
    for (std::size_t i = 0; i < inst_.size(); ++i)
      for (std::size_t k = 0; k < inst_[i].outs.size(); ++k) {
        const std::string& key = key_of(inst_[i].outs[k].second);
        const auto [it, fresh] = producer_.emplace(key, i);
        if (!fresh) {
          const auto [j, l] = where.at(key);
          fail(pend_[i].out_where[k], out_field(i, k), inst_[i].outs[k].second,
               "output also written by '" + inst_[j].id + "' as " + inst_[j].outs[l].second + " (" + pend_[j].out_where[l].str() + ")");
        }
        where.emplace(key, std::make_pair(i, k));
      }
    for (const auto& [key, ik] : where) {
      const auto [i, k] = ik;
      for (fs::path up = fs::path(key).parent_path(); up.has_relative_path(); up = up.parent_path()) {
        const auto outer = where.find(up.string());
        if (outer == where.end() || outer->second.first == i) continue;
        const auto [j, l] = outer->second;
        fail(pend_[i].out_where[k], out_field(i, k), inst_[i].outs[k].second,
             "this output lies inside the output folder " + inst_[j].outs[l].second + " of '" + inst_[j].id + "' (" +
                 pend_[j].out_where[l].str() + "): re-running '" + inst_[j].id +
                 "' would remove it; give the two steps separate folders");
      }
    }
  }

  // ${steps.S.outs[.NAME]} from instance i: the outputs of the cells of S that agree with i on
  // the swept keys both have; each also becomes an input of i.
  std::vector<std::string> step_outputs(std::size_t i, const std::string& ref, NamedPaths& implicit) const {
    const Instance& in = inst_[i];
    const auto dot = ref.find('.');
    const std::string step = ref.substr(0, dot);
    const std::string rest = dot == std::string::npos ? "" : ref.substr(dot + 1);
    const auto cells = of_step_.find(step);
    if (cells == of_step_.end()) throw RefError{"unknown step '" + step + "'"};
    if (step == in.step) throw RefError{"a step cannot read its own outputs"};
    if (rest != "outs" && rest.rfind("outs.", 0) != 0)
      throw RefError{"write ${steps." + step + ".outs} or ${steps." + step + ".outs.NAME}"};
    const std::string key = rest.size() > 4 ? rest.substr(5) : "";
    std::vector<std::string> paths;
    bool matched = false;
    for (const std::size_t j : cells->second) {
      const bool agree = std::all_of(inst_[j].matrix.begin(), inst_[j].matrix.end(), [&](const auto& kv) {
        const auto it = in.matrix.find(kv.first);
        return it == in.matrix.end() || it->second == kv.second;
      });
      if (!agree) continue;
      matched = true;
      bool found = false;
      for (const auto& [k, v] : inst_[j].outs)
        if (key.empty() || k == key) {
          paths.push_back(v);
          found = true;
          if (std::none_of(implicit.begin(), implicit.end(), [&](const auto& x) { return x.second == v; }))
            implicit.emplace_back("steps." + step + ".outs." + k, v);
        }
      if (!found) {
        std::string names;
        for (const auto& o : inst_[j].outs) names += (names.empty() ? "" : ", ") + o.first;
        throw RefError{"step '" + step + "' has no output '" + key + "' (outputs: " + names + ")"};
      }
    }
    if (!matched) throw RefError{"no cell of step '" + step + "' matches cell '" + in.cell + "'"};
    return paths;
  }

  // Pass 2: inputs, references to other steps, the command, the edges.
  void resolve_inputs(std::size_t i) {
    Instance& in = inst_[i];
    Pending& pe = pend_[i];
    const RawStep& st = *pe.raw;
    const std::string base = "steps." + st.name + ".";
    NamedPaths implicit;  // outputs of other steps named in cmd/args but not in deps
    Scope s;
    s.vars = &vars_;
    s.cell = &pe.cell;
    s.step = st.name;
    s.seed = pe.seed;
    s.threads = in.threads;
    s.ranks = in.ranks;
    s.params = &in.params;
    s.outs = &in.outs;
    if (!adaptive_of_.empty()) s.replicas = &replicas_ref_;
    s.steps = [&](const std::string& ref) { return step_outputs(i, ref, implicit); };
    for (const auto& [name, text, where] : path_items(st.node["deps"], st.file, base + "deps")) {
      for (auto& path : resolve_list(text, s, where, base + "deps." + name)) {
        if (path.empty()) fail(where, base + "deps." + name, text, "empty path");
        in.deps.emplace_back(name, normal_path(path));
        pe.dep_where.push_back(where);
      }
    }
    s.deps = &in.deps;
    resolve_command(in, st, s);
    for (const auto& d : implicit)
      if (std::none_of(in.deps.begin(), in.deps.end(), [&](const auto& x) { return x.second == d.second; })) {
        in.deps.push_back(d);
        pe.dep_where.push_back(st.where);
      }
    add_edges(i);
    if (const auto a = adaptive_of_.find(in.step); a != adaptive_of_.end()) check_until(in, p_.adaptive[a->second]);
  }

  // A file named literally in `args:` (`g2.yaml`, `--config=g2.yaml`) that exists in the pipeline's
  // folder but is not a dep or out of the step is not tracked: editing it would not re-run the
  // step. A warning, not an error: the file may be meant untracked (Make would not track it either).
  void warn_untracked_arg(const Instance& in, const RawStep& st, const std::string& text, const Location& where) {
    if (text.find("${") != std::string::npos) return;  // a reference: its file is declared where it comes from
    std::string name = text;
    if (name.rfind("-", 0) == 0) {
      const auto eq = name.find('=');
      if (eq == std::string::npos) return;
      name = name.substr(eq + 1);
    }
    if (name.empty()) return;
    std::error_code ec;
    const fs::path file = resolved(fs::path(p_.dir) / name);
    if (!fs::is_regular_file(file, ec) || !strictly_inside(file, resolved(p_.dir))) return;
    for (const auto* paths : {&in.deps, &in.outs})
      for (const auto& [k, path] : *paths)
        if (resolved(fs::path(p_.dir) / path) == file) return;
    const std::string w = where.str() + ": step '" + st.name + "' names the file " + name +
                          " in args: but not in deps:, so a change to it will not re-run the step (list it under "
                          "deps: and write ${deps.NAME} in args:)";
    if (std::find(p_.warnings.begin(), p_.warnings.end(), w) == p_.warnings.end()) p_.warnings.push_back(w);
  }

  void resolve_command(Instance& in, const RawStep& st, const Scope& s) {
    const std::string& f = st.file;
    const std::string base = "steps." + st.name + ".";
    if (const YAML::Node cmd = st.node["cmd"]) {
      in.command = resolve_shell(scalar(cmd, f, base + "cmd"), s, at(f, cmd), base + "cmd");
      in.argv = {"/bin/sh", "-c", in.command};
      if (const YAML::Node v = st.node["version"]) in.version = resolve(scalar(v, f, base + "version"), s, at(f, v), base + "version");
      return;
    }
    const YAML::Node tool = st.node["tool"];
    in.tool = scalar(tool, f, base + "tool");
    if (!is_name(in.tool)) fail(at(f, tool), base + "tool", in.tool, "a tool is a verb such as pack or young");
    const std::string exe = find_tool("tomodem-" + in.tool, options_.tool_dir);
    if (exe.empty())
      fail(at(f, tool), base + "tool", in.tool, "unknown tool: no executable tomodem-" + in.tool + " beside tomodem-run or on PATH");
    in.argv = {exe};
    in.command = "tomodem-" + in.tool;
    if (const YAML::Node args = st.node["args"]) {
      if (!args.IsSequence()) fail(at(f, args), base + "args", "", "expected a list of arguments");
      for (const auto& a : args) {
        warn_untracked_arg(in, st, scalar(a, f, base + "args"), at(f, a));
        for (auto& v : resolve_list(scalar(a, f, base + "args"), s, at(f, a), base + "args")) {
          in.argv.push_back(v);
          in.command += " " + detail::shell_quote(v);
        }
      }
    }
    in.version = tool_version(exe);
    // A tool of a build without MPI would run `ranks` copies of the serial run: refused here,
    // before anything runs, rather than by every copy at its start.
    if (in.ranks > 1 && !has_feature(exe, "mpi"))
      fail(at(f, st.node["ranks"]), base + "ranks", std::to_string(in.ranks),
           "tomodem-" + in.tool + " has no MPI (its --version says '" + tool_features_line(exe) +
               "'): build tomodem with -DTOMODEM_MPI=ON, or use ranks: 1");
  }

  // An input another instance writes makes that instance upstream; any other must exist (the
  // runner's record of adaptive replicas excepted: the runner writes it before any step runs).
  void add_edges(std::size_t i) {
    Instance& in = inst_[i];
    const Pending& pe = pend_[i];
    const std::string base = "steps." + in.step + ".";
    for (std::size_t k = 0; k < in.deps.size(); ++k) {
      const std::string& path = in.deps[k].second;
      if (const auto it = producer_.find(key_of(path)); it != producer_.end()) {
        if (it->second == i) fail(pe.dep_where[k], base + "deps." + in.deps[k].first, path, "a step cannot read its own output");
        if (std::find(in.upstream.begin(), in.upstream.end(), it->second) == in.upstream.end()) in.upstream.push_back(it->second);
      } else if (options_.check_inputs && path != replicas_ref_ && !fs::exists(fs::path(p_.dir) / path)) {
        fail(pe.dep_where[k], base + "deps." + in.deps[k].first, path, "missing input file (no such file, and no step writes it)");
      }
    }
  }

  // An `until` key must be one the step writes. Knowable for `tool: run` rows (their --value
  // names and --summary NAME.* columns); for other steps the key is looked up when the first
  // replica has finished. Either way the step needs a JSON output to read it from.
  void check_until(const Instance& in, const Adaptive& a) const {
    const bool json_out = std::any_of(in.outs.begin(), in.outs.end(), [](const auto& o) {
      return o.second.size() > 5 && o.second.compare(o.second.size() - 5, 5, ".json") == 0;
    });
    std::vector<std::string> columns, prefixes;
    const bool row = in.tool == "run" && in.argv.size() > 1 && in.argv[1] == "row";
    for (std::size_t j = 1; row && j + 1 < in.argv.size(); ++j) {
      const std::string name = in.argv[j + 1].substr(0, in.argv[j + 1].find('='));
      if (in.argv[j] == "--value") columns.push_back(name);
      if (in.argv[j] == "--summary") prefixes.push_back(name + ".");
    }
    for (std::size_t k = 0; k < a.until.size(); ++k) {
      const std::string& key = a.until[k].first;
      const std::string field = "steps." + in.step + ".replicas.until." + key;
      if (!json_out)
        fail(a.until_where[k], field, key, "the step declares no JSON output (an outs: path ending in .json) to read it from");
      const bool known = std::find(columns.begin(), columns.end(), key) != columns.end() ||
                         std::any_of(prefixes.begin(), prefixes.end(), [&](const std::string& pre) { return key.rfind(pre, 0) == 0; });
      if (row && !known) {
        std::string have;
        for (const auto& c : columns) have += (have.empty() ? "" : ", ") + c;
        for (const auto& c : prefixes) have += (have.empty() ? "" : ", ") + c + "*";
        fail(a.until_where[k], field, key, "the step does not write this key (its row's columns: " + have + ")");
      }
    }
  }

  // An output folder must not hold a file the user made (an input no step writes): the runner
  // would move it aside with the folder.
  void check_output_folders() {
    std::map<std::string, std::pair<std::size_t, fs::path>> sources;  // input no step writes -> reader
    for (std::size_t i = 0; i < inst_.size(); ++i)
      for (const auto& d : inst_[i].deps)
        if (!producer_.count(key_of(d.second)) && !sources.count(d.second))
          sources.emplace(d.second, std::make_pair(i, resolved(fs::path(p_.dir) / d.second)));
    if (sources.empty()) return;
    for (const auto& [key, j] : producer_) {
      const fs::path out(key);
      for (const auto& [dep, source] : sources)
        if (strictly_inside(source.second, out)) {
          const auto& o = inst_[j].outs;
          const auto it = std::find_if(o.begin(), o.end(), [&, k = key](const auto& x) { return key_of(x.second) == k; });
          fail(pend_[j].out_where[static_cast<std::size_t>(it - o.begin())], "steps." + inst_[j].step + ".outs." + it->first,
               it->second, "this output folder holds the input " + dep + " of '" + inst_[source.first].id +
                         "', which no step makes: the runner would replace it");
        }
    }
  }

  // Replica cells of steps that adaptive steps read run only when a replica that runs reads
  // them: pack[r7] waits until the adaptive step asks for replica 7.
  std::vector<char> needed() const {
    const std::size_t n = inst_.size();
    std::vector<char> keep(n, 1);
    if (adaptive_of_.empty()) return keep;
    std::vector<char> feeds(n, 0);
    std::vector<std::size_t> stack;
    for (std::size_t i = 0; i < n; ++i)
      if (adaptive_of_.count(inst_[i].step)) stack.push_back(i);
    while (!stack.empty()) {
      const std::size_t i = stack.back();
      stack.pop_back();
      for (const auto u : inst_[i].upstream)
        if (!feeds[u]) feeds[u] = 1, stack.push_back(u);
    }
    std::set<std::string> feeding;
    for (std::size_t i = 0; i < n; ++i)
      if (feeds[i]) feeding.insert(inst_[i].step);
    const auto optional = [&](std::size_t i) {
      return inst_[i].replica >= 0 && feeding.count(inst_[i].step) && !adaptive_of_.count(inst_[i].step);
    };
    std::vector<int> readers(n, 0);
    for (const auto& in : inst_)
      for (const auto u : in.upstream) ++readers[u];
    for (std::size_t i = 0; i < n; ++i)
      if (optional(i) && readers[i] == 0) stack.push_back(i);
    while (!stack.empty()) {
      const std::size_t i = stack.back();
      stack.pop_back();
      keep[i] = 0;
      for (const auto u : inst_[i].upstream)
        if (--readers[u] == 0 && optional(u) && keep[u]) stack.push_back(u);
    }
    return keep;
  }

  // Topological order of the kept instances, stable in declaration order; a leftover is a cycle.
  std::vector<std::size_t> order(const std::vector<char>& keep) const {
    const std::size_t n = inst_.size();
    std::vector<int> indegree(n, 0);
    std::vector<std::vector<std::size_t>> down(n);
    for (std::size_t i = 0; i < n; ++i)
      if (keep[i])
        for (const std::size_t u : inst_[i].upstream) {
          ++indegree[i];
          down[u].push_back(i);
        }
    std::priority_queue<std::size_t, std::vector<std::size_t>, std::greater<>> ready;
    for (std::size_t i = 0; i < n; ++i)
      if (keep[i] && !indegree[i]) ready.push(i);
    std::vector<std::size_t> out;
    while (!ready.empty()) {
      const std::size_t i = ready.top();
      ready.pop();
      out.push_back(i);
      for (const std::size_t d : down[i])
        if (--indegree[d] == 0) ready.push(d);
    }
    if (out.size() != static_cast<std::size_t>(std::count(keep.begin(), keep.end(), 1))) fail_cycle(indegree);
    return out;
  }

  // Walk upstream among the leftovers until an instance repeats: that is a cycle.
  [[noreturn]] void fail_cycle(const std::vector<int>& indegree) const {
    std::size_t cur = 0;
    while (indegree[cur] == 0) ++cur;
    std::vector<std::size_t> path;
    while (std::find(path.begin(), path.end(), cur) == path.end()) {
      path.push_back(cur);
      for (const std::size_t u : inst_[cur].upstream)
        if (indegree[u] > 0) {
          cur = u;
          break;
        }
    }
    std::string text;
    for (auto it = std::find(path.begin(), path.end(), cur); it != path.end(); ++it) text = " -> " + inst_[*it].id + text;
    fail(inst_[cur].where, "steps." + inst_[cur].step, "", "cycle between steps: " + inst_[cur].id + text);
  }

  Pipeline finish(const std::vector<std::size_t>& order) {
    std::vector<std::size_t> pos(inst_.size());
    for (std::size_t k = 0; k < order.size(); ++k) pos[order[k]] = k;
    for (const std::size_t i : order) {
      Instance in = std::move(inst_[i]);
      for (auto& u : in.upstream) u = pos[u];
      std::sort(in.upstream.begin(), in.upstream.end());
      p_.instances.push_back(std::move(in));
    }
    for (std::size_t i = 0; i < p_.instances.size(); ++i) {
      const Instance& in = p_.instances[i];
      const auto a = adaptive_of_.find(in.step);
      if (a == adaptive_of_.end()) continue;
      std::vector<std::pair<std::string, std::string>> values(in.matrix.begin(), in.matrix.end());
      const std::string id = group_id(in.step, group_key(values));
      auto g = std::find_if(p_.groups.begin(), p_.groups.end(), [&](const ReplicaGroup& x) { return x.id == id; });
      if (g == p_.groups.end()) {
        ReplicaGroup x;
        x.id = id;
        x.adaptive = a->second;
        for (const auto& [k, v] : in.matrix)
          if (k != "replica") x.matrix[k] = v;
        g = p_.groups.insert(p_.groups.end(), x);
      }
      g->instances.push_back(i);
    }
    for (auto& g : p_.groups)
      std::sort(g.instances.begin(), g.instances.end(),
                [&](std::size_t a, std::size_t b) { return p_.instances[a].replica < p_.instances[b].replica; });
    return std::move(p_);
  }

  const Raw& raw_;
  const Vars& vars_;
  const LoadOptions& options_;
  const std::map<std::string, std::map<std::string, std::string>>& param_sets_;
  Pipeline p_;
  const OutputRules rules_;
  const CountOf count_;
  std::string replicas_ref_;  // the record's path as ${run.replicas} gives it
  std::vector<Instance> inst_;
  std::vector<Pending> pend_;
  std::map<std::string, std::vector<std::size_t>> of_step_;
  std::map<std::string, std::size_t> producer_;  // output (resolved, key_of) -> instance
  std::map<std::string, std::string> keys_;      // path as written -> key_of(path)
  std::map<std::string, std::size_t> adaptive_of_;  // step -> index into p_.adaptive
};

}  // namespace

// ---- variables nothing uses ---------------------------------------------------------------

// Every `${vars.NAME}` written in `text`: exact names, and the fixed start of computed ones
// (`${vars.scales.${vars.scale}.n}` may use any variable under `scales.`).
void var_uses(const std::string& text, std::set<std::string>& exact, std::set<std::string>& prefixes) {
  std::vector<std::string> refs;
  try {
    refs = detail::references(text);
  } catch (const RefError&) {
    return;  // a malformed reference is reported where it is resolved, with its line
  }
  for (const auto& r : refs) {
    const auto inner = r.find("${");
    const bool var = r.rfind("vars.", 0) == 0;
    if (inner == std::string::npos) {
      if (var) exact.insert(r.substr(5));
      continue;
    }
    if (var && inner >= 5) prefixes.insert(r.substr(5, inner - 5));
    var_uses(r, exact, prefixes);  // the references the name is computed from
  }
}

// Each collection once: an anchor is one node however many aliases name it, so a self-alias
// (`desc: &a [*a]`, a cycle) or an alias bomb is walked once (found by the fuzzer: a stack
// overflow). A collection is known by where it was parsed (nodes of one file); one made in
// memory (no mark) is walked to a depth of 64.
void var_uses(const YAML::Node& n, std::set<std::string>& exact, std::set<std::string>& prefixes,
              std::set<int>& walked, int depth = 0) {
  if (n.IsScalar()) return var_uses(n.Scalar(), exact, prefixes);
  if (!n.IsSequence() && !n.IsMap()) return;
  const int pos = n.Mark().pos;
  if (pos >= 0 ? !walked.insert(pos).second : depth > 64) return;
  if (n.IsSequence())
    for (const auto& e : n) var_uses(e, exact, prefixes, walked, depth + 1);
  if (n.IsMap())
    for (const auto& kv : n) {
      var_uses(kv.first, exact, prefixes, walked, depth + 1);
      var_uses(kv.second, exact, prefixes, walked, depth + 1);
    }
}

void var_uses(const YAML::Node& n, std::set<std::string>& exact, std::set<std::string>& prefixes) {
  std::set<int> walked;  // per tree: positions are unique within one file
  var_uses(n, exact, prefixes, walked);
}

std::size_t edit_distance(const std::string& a, const std::string& b) {
  std::vector<std::size_t> row(b.size() + 1);
  for (std::size_t j = 0; j <= b.size(); ++j) row[j] = j;
  for (std::size_t i = 1; i <= a.size(); ++i) {
    std::size_t diag = row[0];
    row[0] = i;
    for (std::size_t j = 1; j <= b.size(); ++j) {
      const std::size_t up = row[j];
      row[j] = std::min({row[j] + 1, row[j - 1] + 1, diag + (a[i - 1] == b[j - 1] ? 0 : 1)});
      diag = up;
    }
  }
  return row[b.size()];
}

// A variable that no `${vars.NAME}` uses is almost always a misspelt override of an included
// one (`partciles: 800` beside an included `particles: 500`), which would otherwise be silently
// a new variable while the old value is used: refused, naming the closest existing name.
// `declared`: the variables as the files give them (before --set), for their lines. Only the
// pipeline's own variables are checked: an included file may be shared by several pipelines,
// each using some of its variables.
void refuse_unused_vars(const std::string& file, const std::map<std::string, Var>& declared, const Raw& raw,
                        const LoadOptions& options) {
  std::set<std::string> exact, prefixes;
  for (const auto& [name, v] : raw.vars) var_uses(v.node, exact, prefixes);
  for (const auto& [name, v] : declared) var_uses(v.node, exact, prefixes);
  for (const auto& st : raw.steps) var_uses(st.node, exact, prefixes);
  for (const auto& text : {raw.logs, raw.out}) var_uses(text, exact, prefixes);
  for (const auto& o : options.overrides) var_uses(o, exact, prefixes);
  const auto used = [&](const std::string& name) {
    return exact.count(name) ||
           std::any_of(prefixes.begin(), prefixes.end(), [&](const std::string& p) { return name.rfind(p, 0) == 0; });
  };
  for (const auto& [name, v] : declared) {
    if (used(name) || v.where.file != file) continue;
    std::string hint;
    std::size_t best = 3;
    for (const auto& [other, w] : declared)
      if (other != name && used(other))
        if (const std::size_t d = edit_distance(name, other); d < best) {
          best = d;
          hint = " (did you mean 'vars." + other + "', defined at " + w.where.str() + "?)";
        }
    fail(v.where, "vars." + name, "",
         "variable not used by any ${vars." + name + "} in the pipeline or the files it includes" + hint +
             "; remove it or use it");
  }
}

Pipeline load(const std::string& file, const LoadOptions& options) {
  Raw raw;
  std::vector<std::string> stack;
  read_file(file, file, Location{file, 0}, true, raw, stack);
  if (raw.steps.empty()) fail({file, 0}, "steps", "", "the pipeline declares no steps");
  std::map<std::string, std::map<std::string, std::string>> param_sets;
  const std::map<std::string, Var> declared = raw.vars;
  apply_overrides(options.overrides, raw, param_sets);
  const Vars vars(raw.vars);
  std::string out_root;
  Pipeline base = skeleton(file, raw, vars, out_root);
  base.options = options;
  const bool adaptive = std::any_of(raw.steps.begin(), raw.steps.end(), [](const RawStep& s) {
    const YAML::Node r = s.node["replicas"];
    return r && r.IsMap();
  });
  // Checked last, so that an error with a more precise cause is reported first.
  if (!adaptive) {
    Pipeline p = Expander(raw, vars, options, param_sets, base, out_root, nullptr).build();
    refuse_unused_vars(file, declared, raw, options);
    return p;
  }
  // Every replica an adaptive step may get is checked now, so no later round meets bad input
  // (the runner's rounds, which give the counts, come after such a load).
  if (!options.use_counts)
    Expander(raw, vars, options, param_sets, base, out_root, [](const Adaptive& a, const std::string&) { return a.max; }).build();
  const std::map<std::string, int> counts = options.use_counts ? options.replica_counts : recorded_counts(base.replicas_file);
  Pipeline p = Expander(raw, vars, options, param_sets, base, out_root, [&counts](const Adaptive& a, const std::string& id) {
                 const auto it = counts.find(id);
                 return std::clamp(it == counts.end() ? a.min : it->second, a.min, a.max);
               }).build();
  refuse_unused_vars(file, declared, raw, options);
  return p;
}

std::vector<std::size_t> select(const Pipeline& p, const std::string& name) {
  std::vector<std::size_t> out;
  for (std::size_t i = 0; i < p.instances.size(); ++i)
    if (p.instances[i].id == name) return {i};
  for (std::size_t i = 0; i < p.instances.size(); ++i)
    if (p.instances[i].step == name) out.push_back(i);
  if (out.empty()) throw InputError("", "step", name, "no such step or instance in " + p.file);
  return out;
}

}  // namespace tomodem::pipeline
