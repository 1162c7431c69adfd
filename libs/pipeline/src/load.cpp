// Reading a pipeline file: includes, variables, --set overrides, sweeps, references between
// steps, and the checks that must fail (exit 2) before anything runs.
#include <unistd.h>
#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <climits>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <functional>
#include <queue>
#include <set>

#include "template.hpp"
#include "tomodem/core/error.hpp"
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
  long long v = std::strtoll(text.c_str(), &end, 10);
  if (!text.empty() && *end != '\0') {  // "1e9" is an integer written as a float
    const double d = std::strtod(text.c_str(), &end);
    if (*end == '\0' && std::isfinite(d) && d == std::floor(d) && std::fabs(d) < 9e18) v = static_cast<long long>(d);
  }
  if (text.empty() || *end != '\0' || v < lo)
    fail(where, field, text, "expected an integer >= " + std::to_string(lo));
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
      for (const auto& s : raw.steps)
        if (s.name == name) fail(where, "steps." + name, "", "step defined twice (first at " + s.where.str() + ")");
      if (!kv.second.IsMap()) fail(where, "steps." + name, "", "a step is a map (cmd or tool, deps, outs, ...)");
      raw.steps.push_back(RawStep{name, kv.second, shown, where});
    }
  }
  stack.pop_back();
}

// ---- variables --------------------------------------------------------------------------

class Vars {
 public:
  explicit Vars(const std::map<std::string, Var>& v) : vars_(v) {}
  std::vector<std::string> get(const std::string& name, int depth = 0) const {
    if (depth > 32) throw RefError{"variables refer to each other in a cycle"};
    const auto it = vars_.find(name);
    if (it == vars_.end()) throw RefError{"unknown variable 'vars." + name + "'"};
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
    return out;
  }

 private:
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

const std::set<std::string> kStepKeys = {"cmd", "tool", "args", "deps", "outs", "params", "threads", "matrix",
                                         "cases", "cell", "replicas", "seed", "version", "desc"};

// What ${...} may name inside one instance. A null pointer means "not available here".
struct Scope {
  const Vars* vars = nullptr;
  const Cell* cell = nullptr;
  std::string step;
  long long seed = 0;
  int threads = 1;
  const std::map<std::string, std::string>* params = nullptr;
  const NamedPaths* outs = nullptr;
  const NamedPaths* deps = nullptr;
  std::function<std::vector<std::string>(const std::string&)> steps;
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
  throw RefError{"unknown reference '${" + name +
                 "}' (known: vars.*, matrix.*, params.*, outs[.*], deps[.*], steps.S.outs[.*], cell, replica, "
                 "seed, threads, step; write $${ for a literal ${)"};
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

std::vector<Cell> cells_of(const RawStep& st, const Vars& vars) {
  const std::string& f = st.file;
  const std::string base = "steps." + st.name + ".";
  std::vector<Cell> cells{Cell{}};
  Scope vs;
  vs.vars = &vars;
  bool swept = false;
  if (const YAML::Node m = st.node["matrix"]) {
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
  }
  if (const YAML::Node cs = st.node["cases"]) {
    if (!cs.IsSequence() || cs.size() == 0) fail(at(f, cs), base + "cases", "", "expected a list of maps");
    if (!swept) cells.clear();
    swept = true;
    for (const auto& c : cs) {
      if (!c.IsMap()) fail(at(f, c), base + "cases", "", "each case is a map of key: value");
      Cell cell;
      for (const auto& kv : c) {
        const std::string field = base + "cases." + kv.first.Scalar();
        if (!is_name(kv.first.Scalar())) fail(at(f, kv.first), field, "", "bad case key");
        cell.values.emplace_back(kv.first.Scalar(), resolve(scalar(kv.second, f, field), vs, at(f, kv.second), field));
      }
      cells.push_back(cell);
    }
  }
  if (const YAML::Node r = st.node["replicas"]) {
    const std::string field = base + "replicas";
    const long long n = integer(resolve(scalar(r, f, field), vs, at(f, r), field), at(f, r), field, 1);
    check_sweep_size(static_cast<double>(cells.size()) * static_cast<double>(n), at(f, r), field, std::to_string(n));
    std::vector<Cell> next;
    for (const auto& c : cells)
      for (int k = 0; k < n; ++k) {
        Cell x = c;
        x.values.emplace_back("replica", std::to_string(k));
        x.replica = k;
        next.push_back(x);
      }
    cells = next;
    swept = true;
  }
  if (!swept) return cells;
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

std::string tool_version(const std::string& path) {
  static std::map<std::string, std::string> cache;  // one `--version` call per tool and process
  if (auto it = cache.find(path); it != cache.end()) return it->second;
  std::string out;
  if (FILE* f = ::popen((detail::shell_quote(path) + " --version 2>/dev/null").c_str(), "r")) {
    char buf[256];
    while (std::fgets(buf, sizeof buf, f)) out += buf;
    ::pclose(f);
  }
  while (!out.empty() && std::isspace(static_cast<unsigned char>(out.back()))) out.pop_back();
  return cache[path] = out.substr(0, out.find('\n'));
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

void apply_overrides(const std::vector<std::string>& overrides, Raw& raw,
                     std::map<std::string, std::map<std::string, std::string>>& param_sets) {
  for (const auto& o : overrides) {
    const Location cli{"--set", 0};
    const auto eq = o.find('=');
    if (eq == std::string::npos || eq == 0) fail(cli, o, "", "expected KEY=VALUE");
    std::string key = o.substr(0, eq);
    const std::string value = o.substr(eq + 1);
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

}  // namespace

Pipeline load(const std::string& file, const LoadOptions& options) {
  Raw raw;
  std::vector<std::string> stack;
  read_file(file, file, Location{file, 0}, true, raw, stack);
  if (raw.steps.empty()) fail({file, 0}, "steps", "", "the pipeline declares no steps");
  std::map<std::string, std::map<std::string, std::string>> param_sets;
  apply_overrides(options.overrides, raw, param_sets);
  const Vars vars(raw.vars);

  Pipeline p;
  p.file = file;
  const fs::path fp(file);
  p.dir = fp.parent_path().empty() ? "." : fp.parent_path().string();
  p.lock_file = (fp.parent_path() / (fp.stem().string() + ".lock.json")).string();
  p.logs_dir = (fp.parent_path() / (raw.logs.empty() ? fp.stem().string() + ".logs" : raw.logs)).string();

  std::string out_root;
  if (!raw.out.empty()) {
    Scope vs;
    vs.vars = &vars;
    out_root = resolve(raw.out, vs, raw.out_where, "out");
  }
  const OutputRules rules(raw, p, out_root);
  // The logs are rewritten on every run: they follow the rules of an output.
  if (!raw.logs.empty()) {
    const fs::path logs = resolved(p.logs_dir);
    if (!strictly_inside(logs, resolved(p.dir)) && !(!out_root.empty() && strictly_inside(logs, resolved(fs::path(p.dir) / out_root))))
      fail(raw.logs_where, "logs", raw.logs, "the log folder must be inside the pipeline's folder or the `out:` root");
  }

  // Pass 1: cells, params and outputs of every step (outputs may not name other steps).
  std::vector<Instance> inst;
  std::vector<Pending> pend;
  std::map<std::string, std::vector<std::size_t>> of_step;
  for (const auto& st : raw.steps) {
    p.steps.push_back(st.name);
    const std::string& f = st.file;
    const std::string base = "steps." + st.name + ".";
    for (const auto& kv : st.node)
      if (!kStepKeys.count(kv.first.Scalar()))
        fail(at(f, kv.first), base + kv.first.Scalar(), "",
             "unknown key (expected cmd, tool, args, deps, outs, params, threads, matrix, cases, cell, replicas, "
             "seed, version, desc)");
    if (!st.node["cmd"] == !st.node["tool"]) fail(st.where, "steps." + st.name, "", "a step needs one of cmd: or tool:");
    if (st.node["args"] && !st.node["tool"]) fail(at(f, st.node["args"]), base + "args", "", "args: goes with tool:");
    for (auto& cell : cells_of(st, vars)) {
      Instance in;
      Pending pe{&st, cell, 0, {}, {}};
      in.step = st.name;
      in.cell = cell.name;
      in.id = cell.name.empty() ? st.name : st.name + "[" + cell.name + "]";
      in.where = st.where;
      for (const auto& [k, v] : cell.values) in.matrix[k] = v;
      Scope s;
      s.vars = &vars;
      s.cell = &pe.cell;
      s.step = st.name;
      if (const YAML::Node sd = st.node["seed"])
        pe.seed = integer(resolve(scalar(sd, f, base + "seed"), s, at(f, sd), base + "seed"), at(f, sd), base + "seed",
                          LLONG_MIN);
      s.seed = pe.seed = pe.seed + std::max(cell.replica, 0);
      if (const YAML::Node th = st.node["threads"])
        in.threads = static_cast<int>(integer(resolve(scalar(th, f, base + "threads"), s, at(f, th), base + "threads"),
                                              at(f, th), base + "threads", 1));
      s.threads = in.threads;
      std::vector<std::pair<std::string, YAML::Node>> params;
      if (const YAML::Node pn = st.node["params"]) {
        if (!pn.IsMap()) fail(at(f, pn), base + "params", "", "expected a map of name: value");
        flatten_params(pn, "", f, params);
      }
      auto sets = param_sets[st.name];
      for (const auto& [k, node] : params) {
        const std::string field = base + "params." + k;
        if (auto it = sets.find(k); it != sets.end()) {
          in.params[k] = it->second;
          sets.erase(it);
          continue;
        }
        std::string v;
        if (node.IsSequence()) {
          for (const auto& e : node) v += (v.empty() ? "" : " ") + resolve(scalar(e, f, field), s, at(f, e), field);
        } else if (!node.IsNull()) {
          v = resolve(scalar(node, f, field), s, at(f, node), field);
        }
        in.params[k] = v;
      }
      if (!sets.empty()) fail({"--set", 0}, base + "params." + sets.begin()->first, "", "the step has no such param");
      s.params = &in.params;
      for (const auto& [name, text, where] : path_items(st.node["outs"], f, base + "outs")) {
        for (auto& path : resolve_list(text, s, where, base + "outs." + name)) {
          if (path.empty()) fail(where, base + "outs." + name, text, "empty path");
          rules.check(path, where, base + "outs." + name);
          in.outs.emplace_back(name, normal_path(path));
          pe.out_where.push_back(where);
        }
      }
      of_step[st.name].push_back(inst.size());
      inst.push_back(std::move(in));
      pend.push_back(std::move(pe));
    }
  }

  // Two instances writing one file would race and make staleness meaningless.
  std::map<std::string, std::size_t> producer;
  for (std::size_t i = 0; i < inst.size(); ++i)
    for (std::size_t k = 0; k < inst[i].outs.size(); ++k) {
      const auto [it, fresh] = producer.emplace(inst[i].outs[k].second, i);
      if (!fresh)
        fail(pend[i].out_where[k], "steps." + inst[i].step + ".outs." + inst[i].outs[k].first, inst[i].outs[k].second,
             "output also written by '" + inst[it->second].id + "' (" + pend[it->second].out_where[0].str() + ")");
    }

  // Pass 2: inputs, references to other steps, the command.
  for (std::size_t i = 0; i < inst.size(); ++i) {
    Instance& in = inst[i];
    Pending& pe = pend[i];
    const RawStep& st = *pe.raw;
    const std::string& f = st.file;
    const std::string base = "steps." + st.name + ".";
    NamedPaths implicit;  // outputs of other steps named in cmd/args but not in deps
    Scope s;
    s.vars = &vars;
    s.cell = &pe.cell;
    s.step = st.name;
    s.seed = pe.seed;
    s.threads = in.threads;
    s.params = &in.params;
    s.outs = &in.outs;
    s.steps = [&](const std::string& ref) {
      const auto dot = ref.find('.');
      const std::string step = ref.substr(0, dot);
      const std::string rest = dot == std::string::npos ? "" : ref.substr(dot + 1);
      if (!of_step.count(step)) throw RefError{"unknown step '" + step + "'"};
      if (step == in.step) throw RefError{"a step cannot read its own outputs"};
      if (rest != "outs" && rest.rfind("outs.", 0) != 0)
        throw RefError{"write ${steps." + step + ".outs} or ${steps." + step + ".outs.NAME}"};
      const std::string key = rest.size() > 4 ? rest.substr(5) : "";
      std::vector<std::string> paths;
      bool matched = false;
      for (const std::size_t j : of_step[step]) {
        // A cell of the other step matches when it agrees on the swept keys both steps have.
        const bool agree = std::all_of(inst[j].matrix.begin(), inst[j].matrix.end(), [&](const auto& kv) {
          const auto it = in.matrix.find(kv.first);
          return it == in.matrix.end() || it->second == kv.second;
        });
        if (!agree) continue;
        matched = true;
        bool found = false;
        for (const auto& [k, v] : inst[j].outs)
          if (key.empty() || k == key) {
            paths.push_back(v);
            found = true;
            if (std::none_of(implicit.begin(), implicit.end(), [&](const auto& x) { return x.second == v; }))
              implicit.emplace_back("steps." + step + ".outs." + k, v);
          }
        if (!found) {
          std::string names;
          for (const auto& o : inst[j].outs) names += (names.empty() ? "" : ", ") + o.first;
          throw RefError{"step '" + step + "' has no output '" + key + "' (outputs: " + names + ")"};
        }
      }
      if (!matched) throw RefError{"no cell of step '" + step + "' matches cell '" + in.cell + "'"};
      return paths;
    };
    for (const auto& [name, text, where] : path_items(st.node["deps"], f, base + "deps")) {
      for (auto& path : resolve_list(text, s, where, base + "deps." + name)) {
        if (path.empty()) fail(where, base + "deps." + name, text, "empty path");
        in.deps.emplace_back(name, normal_path(path));
        pe.dep_where.push_back(where);
      }
    }
    s.deps = &in.deps;
    if (const YAML::Node cmd = st.node["cmd"]) {
      in.command = resolve_shell(scalar(cmd, f, base + "cmd"), s, at(f, cmd), base + "cmd");
      in.argv = {"/bin/sh", "-c", in.command};
      if (const YAML::Node v = st.node["version"]) in.version = resolve(scalar(v, f, base + "version"), s, at(f, v), base + "version");
    } else {
      const YAML::Node tool = st.node["tool"];
      in.tool = scalar(tool, f, base + "tool");
      if (!is_name(in.tool)) fail(at(f, tool), base + "tool", in.tool, "a tool is a verb such as pack or young");
      const std::string exe = find_tool("tomodem-" + in.tool, options.tool_dir);
      if (exe.empty())
        fail(at(f, tool), base + "tool", in.tool,
             "unknown tool: no executable tomodem-" + in.tool + " beside tomodem-run or on PATH");
      in.argv = {exe};
      in.command = "tomodem-" + in.tool;
      if (const YAML::Node args = st.node["args"]) {
        if (!args.IsSequence()) fail(at(f, args), base + "args", "", "expected a list of arguments");
        for (const auto& a : args)
          for (auto& v : resolve_list(scalar(a, f, base + "args"), s, at(f, a), base + "args")) {
            in.argv.push_back(v);
            in.command += " " + detail::shell_quote(v);
          }
      }
      in.version = tool_version(exe);
    }
    for (const auto& d : implicit)
      if (std::none_of(in.deps.begin(), in.deps.end(), [&](const auto& x) { return x.second == d.second; })) {
        in.deps.push_back(d);
        pe.dep_where.push_back(st.where);
      }
    // Edges: an input another instance writes makes that instance upstream.
    for (std::size_t k = 0; k < in.deps.size(); ++k) {
      const std::string& path = in.deps[k].second;
      if (const auto it = producer.find(path); it != producer.end()) {
        if (it->second == i)
          fail(pe.dep_where[k], base + "deps." + in.deps[k].first, path, "a step cannot read its own output");
        if (std::find(in.upstream.begin(), in.upstream.end(), it->second) == in.upstream.end())
          in.upstream.push_back(it->second);
      } else if (options.check_inputs && !fs::exists(fs::path(p.dir) / path)) {
        fail(pe.dep_where[k], base + "deps." + in.deps[k].first, path,
             "missing input file (no such file, and no step writes it)");
      }
    }
  }

  // An output folder must not hold a file the user made (an input no step writes): the runner
  // would move it aside with the folder.
  std::map<std::string, std::pair<std::size_t, fs::path>> sources;  // input no step writes -> reader
  for (std::size_t i = 0; i < inst.size(); ++i)
    for (const auto& d : inst[i].deps)
      if (!producer.count(d.second) && !sources.count(d.second))
        sources.emplace(d.second, std::make_pair(i, resolved(fs::path(p.dir) / d.second)));
  if (!sources.empty())
    for (const auto& [path, j] : producer) {
      const fs::path out = resolved(fs::path(p.dir) / path);
      for (const auto& [dep, source] : sources)
        if (strictly_inside(source.second, out)) {
          const std::size_t i = source.first;
          const auto& o = inst[j].outs;
          const auto it = std::find_if(o.begin(), o.end(), [&](const auto& x) { return x.second == path; });
          fail(pend[j].out_where[static_cast<std::size_t>(it - o.begin())], "steps." + inst[j].step + ".outs." + it->first,
               path, "this output folder holds the input " + dep + " of '" + inst[i].id +
                         "', which no step makes: the runner would replace it");
        }
    }

  // Topological order, stable in declaration order; a leftover means a cycle.
  const std::size_t n = inst.size();
  std::vector<int> indegree(n, 0);
  std::vector<std::vector<std::size_t>> down(n);
  for (std::size_t i = 0; i < n; ++i)
    for (const std::size_t u : inst[i].upstream) {
      ++indegree[i];
      down[u].push_back(i);
    }
  std::priority_queue<std::size_t, std::vector<std::size_t>, std::greater<>> ready;
  for (std::size_t i = 0; i < n; ++i)
    if (!indegree[i]) ready.push(i);
  std::vector<std::size_t> order;
  while (!ready.empty()) {
    const std::size_t i = ready.top();
    ready.pop();
    order.push_back(i);
    for (const std::size_t d : down[i])
      if (--indegree[d] == 0) ready.push(d);
  }
  if (order.size() != n) {
    // Walk upstream among the leftovers until an instance repeats: that is a cycle.
    std::size_t cur = 0;
    while (indegree[cur] == 0) ++cur;
    std::vector<std::size_t> path;
    while (std::find(path.begin(), path.end(), cur) == path.end()) {
      path.push_back(cur);
      for (const std::size_t u : inst[cur].upstream)
        if (indegree[u] > 0) {
          cur = u;
          break;
        }
    }
    std::string text;
    for (auto it = std::find(path.begin(), path.end(), cur); it != path.end(); ++it) text = " -> " + inst[*it].id + text;
    fail(inst[cur].where, "steps." + inst[cur].step, "", "cycle between steps: " + inst[cur].id + text);
  }
  std::vector<std::size_t> pos(n);
  for (std::size_t k = 0; k < n; ++k) pos[order[k]] = k;
  for (const std::size_t i : order) {
    Instance in = std::move(inst[i]);
    for (auto& u : in.upstream) u = pos[u];
    std::sort(in.upstream.begin(), in.upstream.end());
    p.instances.push_back(std::move(in));
  }
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
