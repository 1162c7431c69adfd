// Adaptive replicas (adaptive.hpp): the stop rule is stats::stop_decision on the relative 95 %
// half-width that `tomodem run report` also gives, so the report shows what the runner decided.
#include "adaptive.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <map>
#include <nlohmann/json.hpp>
#include <ostream>
#include <sstream>

#include "tomodem/core/error.hpp"
#include "tomodem/core/output.hpp"
#include "tomodem/pipeline/results.hpp"
#include "tomodem/pipeline/stats.hpp"

namespace tomodem::pipeline::detail {

namespace {
using json = nlohmann::json;

struct KeyState {
  std::string key;
  double target = 0;
  stats::Estimate e;
  bool met = false;
};

struct GroupState {
  std::size_t n = 0;
  std::size_t next = 0;  // replicas after the next round, while `because` is ""
  std::string because;  // "" while replicas are still added
  std::vector<KeyState> keys;
};

bool ends_with(const std::string& s, const std::string& tail) {
  return s.size() >= tail.size() && s.compare(s.size() - tail.size(), tail.size(), tail) == 0;
}

// The scalars of an instance's JSON outputs, flattened as `tomodem run row` does.
Row json_outputs(const Pipeline& p, const Instance& in, std::string& files) {
  Row all;
  for (const auto& [name, path] : in.outs) {
    if (!ends_with(path, ".json")) continue;
    std::ifstream f(std::filesystem::path(p.dir) / path);
    std::stringstream text;
    text << f.rdbuf();
    files += (files.empty() ? "" : ", ") + path;
    for (auto& kv : flatten_json(text.str(), "", path)) all.push_back(std::move(kv));
  }
  return all;
}

const Value* column(const Row& r, const std::string& key) {
  for (const auto& [k, v] : r)
    if (k == key) return &v;
  return nullptr;
}

// Replicas the next round adds to an open group: `batch`, or for `projected` half of what the
// spread so far says is missing (at least one): the spread of a few replicas is uncertain by a
// factor of 2-3, so going all the way at once could overshoot by as much.
std::size_t batch(const Adaptive& a, const GroupState& gs) {
  if (a.batch > 0) return static_cast<std::size_t>(a.batch);
  std::size_t want = gs.n + 1;
  for (const auto& k : gs.keys)
    if (!k.met) want = std::max(want, stats::projected_replicas(k.e, k.target, static_cast<std::size_t>(a.max)));
  return std::max<std::size_t>(1, (want - gs.n + 1) / 2);
}

GroupState assess(const Pipeline& p, const ReplicaGroup& g, const RunSummary& s) {
  const Adaptive& a = p.adaptive[g.adaptive];
  GroupState gs;
  gs.n = g.instances.size();
  std::vector<Row> rows;
  std::vector<std::string> files;
  for (const auto i : g.instances) {
    if (s.steps[i].state != "ran" && s.steps[i].state != "up-to-date") {
      gs.because = "replica failed";
      return gs;
    }
    files.emplace_back();
    rows.push_back(json_outputs(p, p.instances[i], files.back()));
  }
  bool all_met = true;
  for (std::size_t k = 0; k < a.until.size(); ++k) {
    const auto& [key, target] = a.until[k];
    std::vector<double> xs, errs;
    for (std::size_t r = 0; r < rows.size(); ++r) {
      const Value* v = column(rows[r], key);
      if (!v || !v->number)
        throw InputError(a.until_where[k].str(), "steps." + a.step + ".replicas.until." + key, key,
                         "replica " + p.instances[g.instances[r]].id + " wrote no number '" + key + "' in its JSON output (" +
                             files[r] + ")");
      xs.push_back(v->x);
      errs.push_back(own_error(rows[r], key, v->x));
    }
    KeyState ks{key, target, stats::estimate(xs, errs), false};
    ks.met = ks.e.n >= 2 && ks.e.rel_half95() <= target;
    all_met = all_met && ks.met;
    gs.keys.push_back(ks);
  }
  gs.because = stats::stop_decision(gs.n, static_cast<std::size_t>(a.min), static_cast<std::size_t>(a.max), all_met);
  if (gs.because.empty()) gs.next = std::min(gs.n + batch(a, gs), static_cast<std::size_t>(a.max));
  return gs;
}

std::string percent(double x) {
  if (!std::isfinite(x)) return "n/a";
  std::ostringstream o;
  o.precision(3);
  o << 100 * x << " %";
  return o.str();
}

std::string progress_line(const ReplicaGroup& g, const GroupState& gs) {
  std::string s = "replicas " + g.id + ": " + std::to_string(gs.n);
  for (const auto& k : gs.keys) s += ", " + k.key + " +-" + percent(k.e.rel_half95()) + " (target " + percent(k.target) + ")";
  if (!gs.because.empty()) return s + ": " + gs.because;
  return s + (gs.next == gs.n + 1 ? ": one more" : ": " + std::to_string(gs.next - gs.n) + " more");
}

// The record `${run.replicas}` names: no times in it, so an unchanged decision leaves it
// byte-identical and the steps that read it up to date.
std::string record_json(const Pipeline& p, const std::map<std::string, GroupState>& states) {
  json j;
  j["format"] = "tomodem-run replicas 1";
  j["groups"] = json::array();
  for (const auto& g : p.groups) {
    const Adaptive& a = p.adaptive[g.adaptive];
    const auto it = states.find(g.id);
    json x = {{"id", g.id}, {"step", a.step}, {"matrix", g.matrix}, {"n", g.instances.size()},
              {"min", a.min}, {"max", a.max}, {"stopped_because", it == states.end() ? "" : it->second.because}};
    x["until"] = json::object();
    if (it != states.end())
      for (const auto& k : it->second.keys)
        x["until"][k.key] = {{"target", k.target},          {"mean", k.e.mean},
                             {"half_width95", k.e.half95},  {"rel_half_width95", k.e.rel_half95()},
                             {"met", k.met}};
    j["groups"].push_back(x);
  }
  return j.dump(1) + "\n";
}

// The instances of the groups still adding replicas, and everything they read.
std::vector<char> open_groups(const Pipeline& p, const std::map<std::string, GroupState>& states) {
  std::vector<char> only(p.instances.size(), 0);
  for (const auto& g : p.groups) {
    const auto it = states.find(g.id);
    if (it == states.end() || it->second.because.empty())
      for (const auto i : g.instances) only[i] = 1;
  }
  for (std::size_t i = p.instances.size(); i-- > 0;)
    if (only[i])
      for (const auto u : p.instances[i].upstream) only[u] = 1;
  return only;
}

// --force and -B apply once per invocation: a replica forced and run in one round is not run
// again in the next.
RunOptions forced_once(const Pipeline& q, const RunOptions& o, const std::map<std::string, StepResult>& earlier) {
  RunOptions r = o;
  r.force.clear();
  r.force_all = false;
  std::vector<std::size_t> idx;
  if (o.force_all)
    for (std::size_t i = 0; i < q.instances.size(); ++i) idx.push_back(i);
  for (const auto& name : o.force)
    for (const auto i : select(q, name)) idx.push_back(i);
  for (const auto i : idx)
    if (!earlier.count(q.instances[i].id)) r.force.push_back(q.instances[i].id);
  return r;
}

// Rounds' results folded into the last pass: a step that ran in an earlier round ran.
RunSummary merged(RunSummary last, const std::map<std::string, StepResult>& earlier, double wall_s, int hashed) {
  last.ran = last.up_to_date = last.failed = last.skipped = last.would_run = 0;
  for (auto& r : last.steps) {
    const auto it = earlier.find(r.id);
    if (it != earlier.end() && r.state != "ran" && r.state != "failed") r = it->second;
    last.ran += r.state == "ran";
    last.up_to_date += r.state == "up-to-date";
    last.failed += r.state == "failed";
    last.skipped += r.state == "skipped";
    last.would_run += r.state == "would-run";
  }
  last.wall_s = wall_s;
  last.files_hashed = hashed;
  return last;
}
}  // namespace

RunSummary run_adaptive(const Pipeline& p, const RunOptions& o, std::ostream& progress) {
  const auto t0 = std::chrono::steady_clock::now();
  LoadOptions lo = p.options;
  lo.use_counts = true;
  lo.replica_counts.clear();  // every decision is made again from `min`: the same data, the same stop
  std::map<std::string, GroupState> states;
  std::map<std::string, StepResult> earlier;
  int hashed = 0;
  const auto elapsed = [&] { return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count(); };
  for (;;) {
    const Pipeline q = load(p.file, lo);
    const std::vector<char> only = open_groups(q, states);
    const RunSummary s = run_pass(q, forced_once(q, o, earlier), &progress, &only, true);
    hashed += s.files_hashed;
    for (const auto& r : s.steps)
      if (r.state == "ran" || r.state == "failed" || r.state == "skipped") earlier[r.id] = r;
    // A failed replica ends the rounds: the steps after the replicas would read an open cell.
    if (s.interrupted || s.failed || s.skipped) {
      write_text_atomic(q.replicas_file, record_json(q, states));
      return merged(s, earlier, elapsed(), hashed);
    }
    bool more = false;
    for (const auto& g : q.groups) {
      if (auto it = states.find(g.id); it != states.end() && !it->second.because.empty()) continue;
      GroupState gs = assess(q, g, s);
      if (!o.quiet) progress << progress_line(g, gs) << std::endl;
      if (gs.because.empty()) {
        lo.replica_counts[g.id] = static_cast<int>(gs.next);
        more = true;
      }
      states[g.id] = gs;
    }
    write_text_atomic(q.replicas_file, record_json(q, states));
    if (!more) break;
  }
  const Pipeline q = load(p.file, lo);
  const RunSummary last = run_pass(q, forced_once(q, o, earlier), &progress, nullptr, true);
  return merged(last, earlier, elapsed(), hashed + last.files_hashed);
}

}  // namespace tomodem::pipeline::detail
