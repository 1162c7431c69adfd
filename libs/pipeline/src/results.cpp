// Rows, the results table, plots and the HTML report (results.hpp).
#include "tomodem/pipeline/results.hpp"

#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <nlohmann/json.hpp>
#include <set>
#include <sstream>

#include "tomodem/core/error.hpp"
#include "tomodem/core/output.hpp"
#include "tomodem/core/plot.hpp"
#include "tomodem/core/tool.hpp"
#include "tomodem/pipeline/stats.hpp"

namespace tomodem::pipeline {

namespace {
namespace fs = std::filesystem;
// ordered_json keeps the tools' key order, so the columns come in the order a summary lists them.
using json = nlohmann::ordered_json;

std::string read_file(const std::string& path, const std::string& field) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw InputError(path, field, path, "cannot read the file");
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

// A number when the whole text parses as one (so "0.5" is a number and "d0.5" is not).
Value value_of(const std::string& text) {
  Value v{text, false, 0};
  if (text.empty()) return v;
  char* end = nullptr;
  const double x = std::strtod(text.c_str(), &end);
  if (*end == '\0' && std::isfinite(x)) v.number = true, v.x = x;
  return v;
}

void flatten(const json& j, const std::string& prefix, Row& out) {
  for (auto it = j.begin(); it != j.end(); ++it) {
    const std::string key = prefix.empty() ? it.key() : prefix + "." + it.key();
    const json& v = it.value();
    // A summary's provenance (command line, host, time) is not a result: no columns.
    if (it.key() == "provenance" && v.is_object()) continue;
    if (v.is_object())
      flatten(v, key, out);
    else if (v.is_number())
      out.emplace_back(key, Value{v.dump(), true, v.get<double>()});
    else if (v.is_boolean())
      out.emplace_back(key, Value{v.get<bool>() ? "1" : "0", true, v.get<bool>() ? 1.0 : 0.0});
    else if (v.is_string())
      out.emplace_back(key, value_of(v.get<std::string>()));
    // arrays and nulls: no column
  }
}

std::pair<std::string, std::string> split_eq(const std::string& item, const std::string& field) {
  const auto eq = item.find('=');
  if (eq == std::string::npos || eq == 0) throw InputError("", field, item, "expected NAME=VALUE");
  return {item.substr(0, eq), item.substr(eq + 1)};
}

const Value* find(const Row& r, const std::string& column) {
  for (const auto& [k, v] : r)
    if (k == column) return &v;
  return nullptr;
}

std::string csv_field(const std::string& s) {
  if (s.find_first_of(",\"\n\r") == std::string::npos) return s;
  std::string q = "\"";
  for (char c : s) q += c == '"' ? std::string("\"\"") : std::string(1, c);
  return q + "\"";
}

std::string number_text(double x) {
  std::ostringstream s;
  s.precision(10);
  s << x;
  return s.str();
}
double number_in(const Row& r, const std::string& c) {
  const Value* v = find(r, c);
  return v && v->number ? v->x : NAN;
}

// A tool's own 1-sigma error of column `c` as an absolute number: `<c>_error` is relative
// (issue 18's convention) unless the summary's units name another unit for it
// (`<prefix>.units.<key>_error`: "Pa" makes it absolute); NaN when the row has none. A per-axis
// value `a.sigma_eff.x` finds its error as `a.sigma_eff.x_error` or, as tomodem-conduct writes
// it, `a.sigma_eff_error.x` (unit `a.units.sigma_eff_error`).
double tool_error(const Row& r, const std::string& c, double value) {
  const auto units_of = [](const std::string& key) {
    const auto d = key.rfind('.');
    return d == std::string::npos ? "units." + key : key.substr(0, d) + ".units." + key.substr(d + 1);
  };
  std::string key = c + "_error";
  double e = number_in(r, key);
  const auto dot = c.rfind('.');
  if (!std::isfinite(e) && dot != std::string::npos) {
    key = c.substr(0, dot) + "_error";
    e = number_in(r, key + c.substr(dot));
  }
  if (!std::isfinite(e)) return NAN;
  // An error the tool marks random (`<key>_error_kind: "random"`: independent between runs, as
  // fracture's crack-tip discreteness) is already in the replicas' scatter; adding it again as
  // systematic would count it twice.
  if (const Value* kind = find(r, key + "_kind"); kind && kind->text == "random") return NAN;
  const Value* unit = find(r, units_of(key));
  const bool relative = !unit || unit->text.empty() || unit->text == "relative" || unit->text == "1";
  return relative ? std::fabs(e * value) : std::fabs(e);
}

}  // namespace

Row flatten_json(const std::string& json_text, const std::string& prefix, const std::string& file) {
  json j;
  try {
    j = json::parse(json_text);
  } catch (const json::exception& e) {
    throw InputError(file, prefix, "", std::string("not valid JSON: ") + e.what());
  }
  if (!j.is_object()) throw InputError(file, prefix, "", "expected a JSON object (a tool's summary)");
  Row r;
  flatten(j, prefix, r);
  return r;
}

std::string make_row(const std::vector<std::string>& values, const std::vector<std::string>& summaries) {
  json row = json::object();
  const auto put = [&](const std::string& k, const Value& v) { row[k] = v.number ? json(v.x) : json(v.text); };
  for (const auto& item : values) {
    const auto [k, v] = split_eq(item, "--value");
    put(k, value_of(v));
  }
  for (const auto& item : summaries) {
    const auto [name, file] = split_eq(item, "--summary");
    for (const auto& [k, v] : flatten_json(read_file(file, "--summary " + name), name, file)) put(k, v);
  }
  // The step that wrote the row (set by the runner): the report matches adaptive stops by it.
  if (const char* step = std::getenv("TOMODEM_STEP"); step && *step && !row.contains("step")) row["step"] = step;
  return row.dump(1) + "\n";
}

double own_error(const Row& row, const std::string& column, double value) { return tool_error(row, column, value); }

PlotRequest parse_plot(const std::string& spec) {
  PlotRequest p;
  std::istringstream in(spec);
  for (std::string item; std::getline(in, item, ';');) {
    if (item.empty()) continue;
    const auto eq = item.find('=');
    const std::string k = item.substr(0, eq), v = eq == std::string::npos ? "" : item.substr(eq + 1);
    if (eq == std::string::npos && k == "logx") p.logx = true;
    else if (eq == std::string::npos && k == "logy") p.logy = true;
    else if (eq == std::string::npos) throw InputError("", "--plot", spec, "unknown flag '" + k + "' (logx, logy)");
    else if (k == "name") p.name = v;
    else if (k == "x") p.x = v;
    else if (k == "by") p.by = v;
    else if (k == "title") p.title = v;
    else if (k == "xlabel") p.xlabel = v;
    else if (k == "ylabel") p.ylabel = v;
    else if (k == "y" || k == "legend") {
      std::istringstream ys(v);
      for (std::string c; std::getline(ys, c, ',');)
        if (!c.empty()) (k == "y" ? p.y : p.legend).push_back(c);
    } else
      throw InputError("", "--plot", spec, "unknown key '" + k + "' (name, x, y, by, legend, title, xlabel, ylabel, logx, logy)");
  }
  if (p.name.empty() || p.name.find_first_not_of("abcdefghijklmnopqrstuvwxyzABCDEFGHIJKLMNOPQRSTUVWXYZ0123456789_-") !=
                            std::string::npos)
    throw InputError("", "--plot", spec, "needs name=NAME (letters, digits, '_', '-': the file name)");
  if (p.x.empty() || p.y.empty()) throw InputError("", "--plot", spec, "needs x=COLUMN and y=COLUMN[,COLUMN...]");
  if (!p.legend.empty() && p.legend.size() != p.y.size())
    throw InputError("", "--plot", spec, "legend= needs one name per y column (" + std::to_string(p.y.size()) + ")");
  // Axis labels carry their unit (core/plot.hpp), so a column name alone is no label: refused
  // here, before the report is made, rather than by gnuplot's caller at the end.
  for (const auto& [key, label] : {std::pair{"xlabel", &p.xlabel}, std::pair{"ylabel", &p.ylabel}})
    if (axis_label_unit(*label).empty())
      throw InputError("", "--plot", spec,
                       std::string("needs ") + key + "=LABEL ending with its unit in brackets, e.g. 'relative density (-)' or 'time (s)'" +
                           (label->empty() ? "" : "; '" + *label + "' has none"));
  if (p.title.empty()) p.title = p.name;
  return p;
}

namespace {
constexpr const char* kReportMarker = ".tomodem-report";

// The report folder is replaced as a whole, so it must be a report folder: new, empty, or one
// this command made (its marker, or table.csv and index.html); never ".", a folder above the
// current one, or a folder that holds a row file.
void refuse_report_folder(const std::string& dir, const std::vector<std::string>& row_files) {
  std::error_code ec;
  const fs::path d = fs::weakly_canonical(fs::absolute(dir), ec);
  const fs::path here = fs::current_path(ec);
  const fs::path rel = here.lexically_relative(d);
  if (d == d.root_path() || (!rel.empty() && *rel.begin() != ".."))
    throw InputError("", "-o", dir, "the report folder would hold the current folder; name a new folder");
  refuse_output_over_input(dir, "-o", row_files, true);
  if (!fs::is_directory(d, ec)) {
    if (fs::exists(d, ec)) throw InputError("", "-o", dir, "exists and is not a folder");
    return;
  }
  const bool made_here = fs::exists(d / kReportMarker, ec) || (fs::exists(d / "table.csv", ec) && fs::exists(d / "index.html", ec));
  if (!made_here && !fs::is_empty(d, ec))
    throw InputError("", "-o", dir,
                     "this folder is not a tomodem report and is not empty; the report replaces its folder, so name "
                     "a new one");
}

// ---- the table ----------------------------------------------------------------------------

struct Table {
  std::vector<Row> rows;
  std::vector<std::string> files;  // the row file of each row, as given
  std::vector<std::string> all;  // every column, in order of first appearance
  std::set<std::string> known;
  void note(const std::string& c) {
    if (known.insert(c).second) all.push_back(c);
  }
};

Table read_rows(const std::vector<std::string>& row_files) {
  Table t;
  // One file named twice (a.json and ./a.json, a glob and the file) would count as two
  // replicas of itself: a zero-width interval. Compared by resolved path.
  std::map<fs::path, std::string> seen;
  for (const auto& f : row_files) {
    std::error_code ec;
    const fs::path resolved = fs::weakly_canonical(fs::absolute(f), ec);
    if (const auto [it, fresh] = seen.emplace(ec ? fs::path(f) : resolved, f); !fresh)
      throw InputError(f, "rows", f,
                       "the same row file as '" + it->second + "': given twice, it would count as two replicas");
    json j;
    try {
      j = json::parse(read_file(f, "rows"));
    } catch (const json::exception& e) {
      throw InputError(f, "rows", "", std::string("not valid JSON: ") + e.what());
    }
    if (!j.is_object() || std::any_of(j.begin(), j.end(), [](const json& v) { return v.is_structured(); }))
      throw InputError(f, "rows", "", "not a row file (a flat JSON object, made by `tomodem run row`)");
    Row r = flatten_json(j.dump(), "", f);
    for (const auto& kv : r) t.note(kv.first);
    t.rows.push_back(std::move(r));
    t.files.push_back(f);
  }
  return t;
}

// Ratio columns; `warnings` gets the rows where a divisor column is 0 (the ratio is empty there).
void add_ratios(Table& t, const std::vector<std::string>& ratios, std::vector<std::string>& warnings) {
  for (const auto& item : ratios) {
    const auto [name, expr] = split_eq(item, "--ratio");
    const auto slash = expr.find('/');
    if (slash == std::string::npos) throw InputError("", "--ratio", item, "expected NAME=A/B");
    const std::string a = expr.substr(0, slash), b = expr.substr(slash + 1);
    for (const auto& operand : {a, b})
      if (!t.known.count(operand) && !value_of(operand).number)
        throw InputError("", "--ratio", item, "'" + operand + "' is neither a column nor a number");
    // A name that is taken would leave two columns of one name, of which only the first is read.
    for (const auto& c : {name, name + "_error"})
      if (t.known.count(c))
        throw InputError("", "--ratio", item, "the column '" + c + "' exists already (in the rows or from an earlier --ratio)");
    if (const Value lit = value_of(b); !t.known.count(b) && lit.number && lit.x == 0) throw InputError("", "--ratio", item, "divides by the number 0");
    t.note(name);
    bool error_column = false;
    std::string zero_rows;
    for (auto& r : t.rows) {
      // A column's number, or the operand itself as a literal; NaN when the row lacks it.
      const auto num = [&](const std::string& s) {
        const Value* v = find(r, s);
        const Value lit = value_of(s);
        return v ? (v->number ? v->x : NAN) : lit.number ? lit.x : NAN;
      };
      const double x = num(a), y = num(b);
      if (std::isfinite(x) && y == 0) zero_rows += (zero_rows.empty() ? "" : ", ") + t.files[std::size_t(&r - t.rows.data())];
      if (!(std::isfinite(x) && std::isfinite(y) && y != 0)) continue;
      // The operands' own relative errors carry over in quadrature (independent errors).
      const double ea = t.known.count(a) ? tool_error(r, a, x) / std::fabs(x) : NAN;
      const double eb = t.known.count(b) ? tool_error(r, b, y) / std::fabs(y) : NAN;
      r.emplace_back(name, Value{number_text(x / y), true, x / y});
      if (std::isfinite(ea) || std::isfinite(eb)) {
        const double e = std::hypot(std::isfinite(ea) ? ea : 0, std::isfinite(eb) ? eb : 0);
        r.emplace_back(name + "_error", Value{number_text(e), true, e});
        error_column = true;
      }
    }
    if (error_column) t.note(name + "_error");
    if (!zero_rows.empty()) warnings.push_back("--ratio " + item + ": '" + b + "' is 0 in " + zero_rows + ", so '" + name + "' is empty there");
  }
}

std::vector<PlotRequest> plot_requests(const Table& t, const std::vector<std::string>& specs) {
  std::vector<PlotRequest> plots;
  for (const auto& spec : specs) {
    PlotRequest p = parse_plot(spec);
    std::vector<std::string> used = p.y;
    used.push_back(p.x);
    if (!p.by.empty()) used.push_back(p.by);
    for (const auto& c : used)
      if (!t.known.count(c)) throw InputError("", "--plot", spec, "no row has the column '" + c + "'");
    for (const auto& q : plots)
      if (q.name == p.name) throw InputError("", "--plot", spec, "two plots named '" + p.name + "'");
    plots.push_back(std::move(p));
  }
  return plots;
}

// ---- physical bounds (--bound NAME=LO:HI) ----------------------------------------------------

// One side of a bound: a column (a bound per row: the Voigt or Hashin-Shtrikman bound of its
// sample), a number, or neither (no bound on that side). Decided once, when parsed.
struct Side {
  std::string text, column;
  double value = NAN;
  double in(const Row& r) const { return column.empty() ? value : number_in(r, column); }
};
struct Bound {
  Side lo, hi;
};
using Bounds = std::map<std::string, Bound>;

Bounds bounds_of(const Table& t, const std::vector<std::string>& specs) {
  Bounds out;
  for (const auto& item : specs) {
    const auto [name, range] = split_eq(item, "--bound");
    const auto colon = range.find(':');
    if (colon == std::string::npos) throw InputError("", "--bound", item, "expected NAME=LO:HI (a side may be empty: E_rel=0:)");
    if (!t.known.count(name)) throw InputError("", "--bound", item, "no row has the column '" + name + "'");
    if (std::none_of(t.rows.begin(), t.rows.end(), [&](const Row& r) { return std::isfinite(number_in(r, name)); }))
      throw InputError("", "--bound", item, "the column '" + name + "' holds no numbers");
    const auto side = [&](const std::string& text) {
      Side s{text, "", NAN};
      if (text.empty()) return s;
      if (t.known.count(text)) s.column = text;
      else if (const Value v = value_of(text); v.number) s.value = v.x;
      else throw InputError("", "--bound", item, "'" + text + "' is neither a column nor a finite number");
      return s;
    };
    const Bound b{side(range.substr(0, colon)), side(range.substr(colon + 1))};
    if (b.lo.text.empty() && b.hi.text.empty()) throw InputError("", "--bound", item, "names neither a lower nor an upper bound");
    if (!(b.lo.value < b.hi.value) && std::isfinite(b.lo.value) && std::isfinite(b.hi.value))
      throw InputError("", "--bound", item, "the lower bound must be below the upper");
    // A bound column must give a number in every row that has a number to check against it:
    // a row without one would pass unchecked, and its cell's interval would not be cut.
    for (const Side* sd : {&b.lo, &b.hi})
      for (std::size_t i = 0; i < t.rows.size() && !sd->column.empty(); ++i)
        if (std::isfinite(number_in(t.rows[i], name)) && !std::isfinite(number_in(t.rows[i], sd->column))) {
          const Value* v = find(t.rows[i], sd->column);
          throw InputError(t.files[i], "--bound " + item, v ? v->text : "",
                           v ? "the bound column '" + sd->column + "' holds no number in this row"
                             : "this row has '" + name + "' but no bound column '" + sd->column + "'");
        }
    if (!out.emplace(name, b).second) throw InputError("", "--bound", item, "a second bound for '" + name + "'");
  }
  return out;
}

// The range of a cell's mean: the lowest of its rows' lower bounds and the highest of their
// upper ones (each row's value lies within its own); infinite where there is none.
struct Range {
  double lo = -INFINITY, hi = INFINITY;
};
Range range_of(const Bounds& bs, const std::string& c, const std::vector<const Row*>& rows) {
  const auto it = bs.find(c);
  if (it == bs.end()) return {};
  double lo = INFINITY, hi = -INFINITY;
  for (const Row* r : rows) {
    if (const double l = it->second.lo.in(*r); std::isfinite(l)) lo = std::min(lo, l);
    if (const double h = it->second.hi.in(*r); std::isfinite(h)) hi = std::max(hi, h);
  }
  return {std::isfinite(lo) ? lo : -INFINITY, std::isfinite(hi) ? hi : INFINITY};
}

// Rounding slack at a bound: 1e-12 of it.
double slack(double bound) { return 1e-12 * std::fabs(bound); }

// The 95 % interval, cut at the range: the true mean lies in it, so the cut interval covers it
// at least as often. Each side is cut where the mean satisfies that side's bound; a mean
// outside a bound (replicas outside it) is flagged, and that side stays uncut, as it must still
// hold the mean.
struct Interval {
  double lo = NAN, hi = NAN;
  bool cut = false, mean_outside = false;
};
Interval interval_of(const stats::Estimate& e, const Range& r) {
  Interval i;
  const bool below = e.mean < r.lo - slack(r.lo), above = e.mean > r.hi + slack(r.hi);
  i.mean_outside = e.n > 0 && (below || above);
  if (!std::isfinite(e.half95)) return i;
  i.lo = e.mean - e.half95, i.hi = e.mean + e.half95;
  if (!below && i.lo < r.lo) i.lo = r.lo, i.cut = true;
  if (!above && i.hi > r.hi) i.hi = r.hi, i.cut = true;
  return i;
}

// Replica values outside their own row's bound (beyond rounding: 1e-12 of the bound).
std::vector<json> outside_bounds(const Table& t, const Bounds& bs, const std::vector<std::string>& files) {
  std::vector<json> out;
  for (std::size_t i = 0; i < t.rows.size(); ++i)
    for (const auto& [c, b] : bs) {
      const double x = number_in(t.rows[i], c);
      if (!std::isfinite(x)) continue;
      const double lo = b.lo.in(t.rows[i]), hi = b.hi.in(t.rows[i]);
      const bool below = std::isfinite(lo) && x < lo - slack(lo), above = std::isfinite(hi) && x > hi + slack(hi);
      if (!below && !above) continue;
      const Side& side = below ? b.lo : b.hi;
      const double bound = below ? lo : hi;
      out.push_back({{"row_file", files[i]}, {"column", c}, {"value", x}, {below ? "lower_bound" : "upper_bound", bound},
                     {"text", files[i] + ": " + c + " = " + number_text(x) + (below ? " is below its lower" : " is above its upper") +
                                  " bound " + number_text(bound) + (side.column.empty() ? "" : " (" + side.column + ")")}});
    }
  return out;
}

std::string csv_text(const Table& t, const std::vector<std::string>& columns) {
  std::ostringstream csv;
  for (std::size_t k = 0; k < columns.size(); ++k) csv << (k ? "," : "") << csv_field(columns[k]);
  csv << "\n";
  for (const auto& r : t.rows) {
    for (std::size_t k = 0; k < columns.size(); ++k) {
      const Value* v = find(r, columns[k]);
      csv << (k ? "," : "") << (v ? csv_field(v->text) : "");
    }
    csv << "\n";
  }
  return csv.str();
}

// ---- statistics of replicas ---------------------------------------------------------------

stats::Estimate estimate_of(const std::vector<const Row*>& rows, const std::string& c) {
  std::vector<double> xs, errs;
  for (const Row* r : rows) {
    const double x = number_in(*r, c);
    if (!std::isfinite(x)) continue;
    xs.push_back(x);
    errs.push_back(tool_error(*r, c, x));
  }
  return stats::estimate(xs, errs);
}

// CPU time a row cost: its columns named cpu_time_s (one per step summary), else wall_time_s.
double row_cpu(const Row& r) {
  const auto sum_of = [&](const std::string& leaf) {
    double s = 0;
    bool any = false;
    for (const auto& [k, v] : r)
      if (v.number && (k == leaf || (k.size() > leaf.size() && k.compare(k.size() - leaf.size() - 1, std::string::npos, "." + leaf) == 0)))
        s += v.x, any = true;
    return any ? s : NAN;
  };
  const double cpu = sum_of("cpu_time_s");
  return std::isfinite(cpu) ? cpu : sum_of("wall_time_s");
}

bool is_property(const std::string& c, const std::vector<std::string>& group) {
  const auto ends = [&](const std::string& s) { return c.size() >= s.size() && c.compare(c.size() - s.size(), s.size(), s) == 0; };
  return std::find(group.begin(), group.end(), c) == group.end() && c != "replica" && c != "seed" &&
         c.find("_error") == std::string::npos && !ends("_time_s") && !ends("_bytes");
}

// One adaptive-replica cell from the runner's record: its step, matrix values and why it stopped.
struct Stop {
  std::string step;
  std::map<std::string, std::string> matrix;
  std::string because;
  std::size_t n = 0;
};

std::vector<Stop> read_stops(const std::string& file) {
  std::vector<Stop> out;
  if (file.empty()) return out;
  try {
    const json j = json::parse(read_file(file, "--replicas"));
    for (const auto& g : j.at("groups")) {
      Stop s;
      s.step = g.at("step").get<std::string>();
      for (auto it = g.at("matrix").begin(); it != g.at("matrix").end(); ++it) s.matrix[it.key()] = it.value().get<std::string>();
      s.because = g.at("stopped_because").get<std::string>();
      s.n = g.at("n").get<std::size_t>();
      out.push_back(std::move(s));
    }
  } catch (const json::exception& e) {
    throw InputError(file, "--replicas", file, std::string("not a tomodem-run replica record: ") + e.what());
  }
  return out;
}

bool same_value(const std::string& a, const std::string& b) {
  if (a == b) return true;
  const Value x = value_of(a), y = value_of(b);
  return x.number && y.number && x.x == y.x;
}

// The rows of one step that share the group values: the replicas of one cell.
struct Cell {
  std::string step;                                      // the row's `step` column ("" without one)
  std::vector<std::pair<std::string, std::string>> key;  // group column -> value text
  std::vector<const Row*> rows;
  double cpu_s = 0;
  std::string stopped_because = "fixed replicas";
};

std::vector<Cell> cells_of(const Table& t, const std::vector<std::string>& group, const std::vector<Stop>& stops) {
  std::vector<Cell> cells;
  for (const auto& r : t.rows) {
    std::vector<std::pair<std::string, std::string>> key;
    for (const auto& g : group) {
      const Value* v = find(r, g);
      key.emplace_back(g, v ? v->text : "");
    }
    const Value* sv = find(r, "step");
    const std::string step = sv ? sv->text : "";
    auto it = std::find_if(cells.begin(), cells.end(), [&](const Cell& c) { return c.step == step && c.key == key; });
    if (it == cells.end()) it = cells.insert(cells.end(), Cell{step, key, {}, 0, "fixed replicas"});
    it->rows.push_back(&r);
  }
  // Two steps with the same group values: the step becomes the last group column, so the
  // cells are told apart on the page and only cells of one step are ranked against each other.
  const bool clash = std::any_of(cells.begin(), cells.end(), [&](const Cell& a) {
    return std::any_of(cells.begin(), cells.end(), [&](const Cell& b) { return &a != &b && a.key == b.key; });
  });
  if (clash && std::find(group.begin(), group.end(), "step") == group.end())
    for (auto& c : cells) c.key.emplace_back("step", c.step);
  // Replicas in the order they were made, so the error-against-time curve follows the run.
  const auto replica = [](const Row* r) { return number_in(*r, "replica"); };
  for (auto& c : cells) {
    std::stable_sort(c.rows.begin(), c.rows.end(), [&](const Row* a, const Row* b) { return replica(a) < replica(b); });
    for (const Row* r : c.rows)
      if (const double cpu = row_cpu(*r); std::isfinite(cpu)) c.cpu_s += cpu;
    for (const auto& s : stops) {
      // By step and values; a row without a step (not written by `tomodem run row` under the
      // runner) by its values alone.
      if (!c.step.empty() && c.step != s.step) continue;
      const bool match = std::all_of(s.matrix.begin(), s.matrix.end(), [&](const auto& kv) {
        const auto k = std::find_if(c.key.begin(), c.key.end(), [&](const auto& x) { return x.first == kv.first; });
        return k == c.key.end() || same_value(k->second, kv.second);
      });
      if (match) {
        c.stopped_because = s.because;
        break;
      }
    }
  }
  return cells;
}

std::string cell_text(const std::vector<std::pair<std::string, std::string>>& key, std::size_t from = 0) {
  std::string s;
  for (std::size_t k = from; k < key.size(); ++k) s += (s.empty() ? "" : ", ") + key[k].first + "=" + key[k].second;
  return s;
}

// A cell's group values, numbers as numbers.
json key_json(const Cell& c) {
  json j = json::object();
  for (const auto& [k, v] : c.key) {
    const Value x = value_of(v);
    j[k] = x.number ? json(x.x) : json(v);
  }
  return j;
}

json cell_json(const Cell& c, const std::string& property, const stats::Estimate& e, const Range& r) {
  json j = key_json(c);
  j["property"] = property;
  j["n"] = e.n;
  j["mean"] = e.mean;
  j["sd"] = e.sd;
  j["sem"] = e.sem;
  j["tool_error"] = e.tool;
  j["u"] = e.u;
  // JSON has no infinity: null when the dof is infinite (no replica scatter) or undefined (n < 2).
  j["dof"] = e.n >= 2 && std::isfinite(e.dof) ? json(e.dof) : json(nullptr);
  const Interval ci = interval_of(e, r);
  j["ci95"] = std::isfinite(ci.lo) ? json::array({ci.lo, ci.hi}) : json(nullptr);
  if (std::isfinite(r.lo) || std::isfinite(r.hi)) {
    j["bounds"] = json::array({std::isfinite(r.lo) ? json(r.lo) : json(nullptr), std::isfinite(r.hi) ? json(r.hi) : json(nullptr)});
    j["ci95_cut_at_bound"] = ci.cut;
    j["mean_outside_bound"] = ci.mean_outside;
  }
  j["half_width95"] = e.half95;
  j["rel_half_width95"] = e.rel_half95();
  j["stopped_because"] = c.stopped_because;
  j["cpu_s"] = c.cpu_s;
  return j;
}

struct Ranking {
  std::string property, at, text;
  double p = NAN;  // Welch's two-sided p
  json j;
};

// A cell left out of the rankings of a property because it has one replica of it.
struct Unranked {
  std::size_t cell;
  std::string property, text;
};

// Pairs of cells that differ only in the first group column, per property: which is lower, and
// whether Welch's test resolves it at 5 %. A pair with a cell of one replica cannot be tested:
// that cell goes to `unranked`, so its absence from the rankings is said.
std::vector<Ranking> rankings_of(const std::vector<Cell>& cells, const std::vector<std::string>& props,
                                 std::vector<Unranked>& unranked) {
  std::vector<Ranking> out;
  if (cells.empty() || cells[0].key.empty()) return out;
  for (const auto& prop : props)
    for (std::size_t a = 0; a < cells.size(); ++a)
      for (std::size_t b = a + 1; b < cells.size(); ++b) {
        const auto& ka = cells[a].key;
        const auto& kb = cells[b].key;
        if (!std::equal(ka.begin() + 1, ka.end(), kb.begin() + 1)) continue;
        std::vector<double> xa, xb;
        for (const Row* r : cells[a].rows)
          if (std::isfinite(number_in(*r, prop))) xa.push_back(number_in(*r, prop));
        for (const Row* r : cells[b].rows)
          if (std::isfinite(number_in(*r, prop))) xb.push_back(number_in(*r, prop));
        if (xa.size() < 2 || xb.size() < 2) {
          for (const auto& [c, n] : {std::pair{a, xa.size()}, std::pair{b, xb.size()}})
            if (n == 1 && std::none_of(unranked.begin(), unranked.end(),
                                       [&](const Unranked& u) { return u.cell == c && u.property == prop; }))
              unranked.push_back({c, prop,
                                  (cells[c].key.empty() ? std::string("all rows") : cell_text(cells[c].key)) + ": " + prop +
                                      " has 1 replica, not ranked (Welch's test needs 2 or more)"});
          continue;
        }
        const stats::Welch w = stats::welch(xa, xb);
        const double ma = stats::estimate(xa).mean, mb = stats::estimate(xb).mean;
        const bool a_low = ma <= mb;
        const std::string lo = a_low ? ka[0].second : kb[0].second, hi = a_low ? kb[0].second : ka[0].second;
        const std::string at = cell_text(ka, 1);
        Ranking r;
        r.property = prop;
        r.at = at;
        r.p = w.p;
        r.j = {{"property", prop}, {"at", at},   {"lower", lo},         {"higher", hi}, {"mean_lower", a_low ? ma : mb},
               {"mean_higher", a_low ? mb : ma}, {"t", std::fabs(w.t)}, {"dof", w.dof}, {"p", w.p}};
        out.push_back(std::move(r));
      }
  // Resolved by the Benjamini-Hochberg q over every ranking of the report: a study ranks many
  // pairs (properties x densities), and at p < 0.05 each, one in twenty differences that are not
  // there would be called resolved.
  std::vector<double> p;
  for (const auto& r : out) p.push_back(r.p);
  const std::vector<double> q = stats::benjamini_hochberg(p);
  for (std::size_t i = 0; i < out.size(); ++i) {
    Ranking& r = out[i];
    const bool resolved = q[i] < 0.05;
    const std::string lo = r.j["lower"], hi = r.j["higher"];
    r.text = (resolved ? lo + " < " + hi : lo + " vs " + hi) + " in " + r.property + (r.at.empty() ? "" : " at " + r.at) + ": " +
             (resolved ? "" : "not resolved, ") + "Welch " + stats::p_phrase(p[i]) +
             (out.size() > 1 ? ", q " + std::string(q[i] < 1e-4 ? "" : "= ") + stats::p_text(q[i]) + " over " +
                                   std::to_string(out.size()) + " rankings"
                             : "");
    r.j["q"] = q[i];
    r.j["rankings_in_report"] = out.size();
    r.j["resolved"] = resolved;
    r.j["text"] = r.text;
  }
  return out;
}

// ---- plots ----------------------------------------------------------------------------------

// Each point: the mean over the rows sharing its x value and series, with its 95 % half-width.
PlotSpec plot_spec(const Table& t, const PlotRequest& p, const Bounds& bounds) {
  PlotSpec spec;
  spec.title = p.title;
  spec.xlabel = p.xlabel;
  spec.ylabel = p.ylabel;
  spec.logx = p.logx;
  spec.logy = p.logy;
  std::vector<std::string> groups;  // values of `by`, in order of appearance
  for (const auto& r : t.rows) {
    const Value* g = p.by.empty() ? nullptr : find(r, p.by);
    const std::string key = g ? g->text : "";
    if (std::find(groups.begin(), groups.end(), key) == groups.end()) groups.push_back(key);
  }
  for (const auto& g : groups)
    for (const auto& ycol : p.y) {
      std::map<double, std::vector<const Row*>> at_x;
      for (const auto& r : t.rows) {
        const Value* gv = p.by.empty() ? nullptr : find(r, p.by);
        if ((gv ? gv->text : "") != g) continue;
        const Value *xv = find(r, p.x), *yv = find(r, ycol);
        if (!xv || !yv || !xv->number || !yv->number) continue;
        if ((p.logx && xv->x <= 0) || (p.logy && yv->x <= 0)) continue;
        at_x[xv->x].push_back(&r);
      }
      if (at_x.empty()) continue;
      PlotSeries s, single;  // points with an interval (bars), points of one replica (none)
      const std::string yname = p.legend.empty() ? ycol : p.legend[std::size_t(&ycol - p.y.data())];
      s.title = g.empty() ? yname : p.y.size() > 1 ? g + ", " + yname : g;
      for (const auto& [x, rows] : at_x) {
        const stats::Estimate e = estimate_of(rows, ycol);
        if (e.n < 2) {
          single.x.push_back(x);
          single.y.push_back(e.mean);
          continue;
        }
        const Interval ci = interval_of(e, range_of(bounds, ycol, rows));
        s.x.push_back(x);
        s.y.push_back(e.mean);
        s.yerr.push_back(e.half95);
        s.ylow.push_back(ci.lo);
        s.yhigh.push_back(ci.hi);
      }
      // A point of one replica has no interval, and a bar of length 0 would make it look exact:
      // such points are a series of their own without bars, joined by lines only when the whole
      // series is of single replicas (a sweep without replicas keeps its curve).
      if (!single.x.empty()) {
        single.title = s.title + " (n = 1: no interval)";
        single.draw = s.x.empty() ? PlotDraw::points_and_lines : PlotDraw::points;
      }
      for (PlotSeries* series : {&s, &single})
        if (!series->x.empty()) spec.series.push_back(std::move(*series));
    }
  if (spec.series.empty()) throw InputError("", "--plot", p.name, "no row has numbers in both '" + p.x + "' and the y columns");
  return spec;
}

std::string file_stem(const std::string& s) {
  std::string o;
  for (const char c : s) o += std::isalnum(static_cast<unsigned char>(c)) || c == '-' || c == '_' ? c : '_';
  return o;
}

// Relative 95 % half-width after the first k replicas of each cell against the CPU time they
// cost: the error-against-run-time curve, one series per cell. Empty when no cell has one.
PlotSpec error_vs_cpu(const std::vector<Cell>& cells, const std::string& prop) {
  PlotSpec spec;
  spec.title = "95 % half-width of the mean of " + prop + " against CPU time";
  spec.xlabel = "CPU time spent (s, sum over replicas)";
  spec.ylabel = "relative 95 % half-width (-)";
  spec.logx = spec.logy = true;
  for (const auto& c : cells) {
    PlotSeries s;
    s.title = c.key.empty() ? "all" : cell_text(c.key);
    std::vector<const Row*> first;
    double cpu = 0;
    for (const Row* r : c.rows) {
      first.push_back(r);
      cpu += row_cpu(*r);
      const double rel = estimate_of(first, prop).rel_half95();
      if (first.size() >= 2 && std::isfinite(cpu) && cpu > 0 && std::isfinite(rel) && rel > 0) {
        s.x.push_back(cpu);
        s.y.push_back(rel);
      }
    }
    if (!s.x.empty()) spec.series.push_back(std::move(s));
  }
  return spec;
}

// ---- the HTML page --------------------------------------------------------------------------

struct Page {
  const Table& t;
  const std::vector<std::string>& columns;
  const std::vector<PlotRequest>& plots;
  const std::vector<std::string>& error_plots;  // stems, with the property each is about
  const std::vector<Cell>& cells;
  const std::vector<std::string>& shown_props;
  const std::vector<Ranking>& rankings;
  const std::vector<Unranked>& unranked;
  const Bounds& bounds;
  const std::vector<json>& outside;  // replica values outside their bounds
  const ReportOptions& o;
};

std::string figure(const std::string& name, const std::string& title) {
  return "<figure>\n<img src=\"" + name + ".svg\" alt=\"" + xml_escape(title) + "\">\n<figcaption>" + xml_escape(title) + ": <a href=\"" +
         name + ".png\">PNG</a>, <a href=\"" + name + ".svg\">SVG</a>, <a href=\"" + name + ".gp\">gnuplot script</a>, <a href=\"" +
         name + ".dat\">data</a></figcaption>\n</figure>\n";
}

// Four significant digits: enough to read an interval, the full numbers are in summary.json.
std::string short_number(double x) {
  std::ostringstream s;
  s.precision(4);
  s << x;
  return s.str();
}

std::string html_statistics(const Page& pg) {
  std::string g;
  for (const auto& c : pg.o.group) g += (g.empty() ? "" : " &times; ") + xml_escape(c);
  std::ostringstream h;
  h << "<h2>Statistics</h2>\n<p>Cells: " << (g.empty() ? "all rows" : g)
    << ". Mean of the replicas, 95 % confidence interval t<sub>0.975,&nu;</sub> u with u = &radic;(sem&sup2; + "
       "tool error&sup2;) (Student 1908; effective dof &nu; by Welch&ndash;Satterthwaite), every cell and property in "
       "<a href=\"summary.json\">summary.json</a>.</p>\n<table>\n<tr><th>cell</th><th>property</th><th>n</th><th>mean</th>"
       "<th>95 % CI</th><th>&plusmn; %</th><th>stopped because</th><th>CPU s</th></tr>\n";
  bool any_cut = false, any_outside = false;
  for (const auto& prop : pg.shown_props)
    for (const auto& c : pg.cells) {
      const stats::Estimate e = estimate_of(c.rows, prop);
      if (e.n == 0) continue;
      const Interval ci = interval_of(e, range_of(pg.bounds, prop, c.rows));
      any_cut = any_cut || ci.cut;
      any_outside = any_outside || ci.mean_outside;
      // One replica has no interval: say so, rather than leave a blank that reads as exact.
      std::string interval = e.n < 2 ? "n = 1: no interval"
                             : std::isfinite(ci.lo) ? short_number(ci.lo) + " &ndash; " + short_number(ci.hi) + (ci.cut ? " *" : "")
                                                    : "";
      if (ci.mean_outside) interval += " <b style=\"color:#b00\">mean outside its bound</b>";
      h << "<tr><td>" << xml_escape(cell_text(c.key)) << "</td><td>" << xml_escape(prop) << "</td><td>" << e.n << "</td><td>"
        << short_number(e.mean) << "</td><td>" << interval << "</td><td>" << (std::isfinite(e.rel_half95()) ? short_number(100 * e.rel_half95()) : "") << "</td><td>"
        << xml_escape(c.stopped_because) << "</td><td>" << short_number(c.cpu_s) << "</td></tr>\n";
    }
  h << "</table>\n";
  if (any_cut)
    h << "<p>* cut at the property's physical bound (<code>--bound</code>): t u reaches past it, so the replicas "
         "cannot pin the mean down more closely than that bound does.</p>\n";
  if (any_outside)
    h << "<p style=\"color:#b00\"><b>Mean outside its bound</b>: the cell's mean lies outside the property's "
         "<code>--bound</code> range, so some of its replicas do (listed below); its interval is cut only at the "
         "bound the mean is within.</p>\n";
  if (!pg.outside.empty()) {
    h << "<p style=\"color:#b00\"><b>Replica values outside their physical bounds</b> (a result outside its bound is "
         "not an answer: check the run or the bound):</p>\n<ul>\n";
    for (const auto& o : pg.outside) h << "<li>" << xml_escape(o.at("text").get<std::string>()) << "</li>\n";
    h << "</ul>\n";
  }
  const auto shown = [&](const std::string& prop) {
    return std::find(pg.shown_props.begin(), pg.shown_props.end(), prop) != pg.shown_props.end();
  };
  const bool any_unranked = std::any_of(pg.unranked.begin(), pg.unranked.end(), [&](const Unranked& u) { return shown(u.property); });
  if (!pg.rankings.empty() || any_unranked) h << "<h3>Rankings</h3>\n";
  if (!pg.rankings.empty()) {
    h << "<p>Welch's t-test (Welch 1947), two-sided p; \"not resolved\" when the "
         "Benjamini&ndash;Hochberg q over all " << pg.rankings.size() << " rankings is &ge; 0.05 (among the "
         "resolved ones, fewer than one in twenty is expected to be a difference that is not there).</p>\n<ul>\n";
    for (const auto& r : pg.rankings)
      if (shown(r.property)) h << "<li>" << xml_escape(r.text) << "</li>\n";
    h << "</ul>\n";
  }
  if (any_unranked) {
    h << "<p>Not ranked (fewer than 2 replicas):</p>\n<ul>\n";
    for (const auto& u : pg.unranked)
      if (shown(u.property)) h << "<li>" << xml_escape(u.text) << "</li>\n";
    h << "</ul>\n";
  }
  for (const auto& stem : pg.error_plots) h << figure(stem, "error against CPU time: " + stem.substr(13));
  return h.str();
}

std::string html_page(const Page& pg) {
  const Table& t = pg.t;
  std::vector<std::string> shown = pg.o.columns;
  if (shown.empty()) {
    for (const auto& p : pg.plots) {
      for (const auto& c : {p.by, p.x})
        if (!c.empty() && std::find(shown.begin(), shown.end(), c) == shown.end()) shown.push_back(c);
      for (const auto& c : p.y)
        if (std::find(shown.begin(), shown.end(), c) == shown.end()) shown.push_back(c);
    }
    if (shown.empty()) shown = t.all;
  }
  std::ostringstream h;
  h << "<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n<title>" << xml_escape(pg.o.title)
    << "</title>\n<style>body{font-family:sans-serif;max-width:60em;margin:2em auto;padding:0 1em}"
       "table{border-collapse:collapse;font-size:90%}td,th{border:1px solid #bbb;padding:2px 6px;text-align:right}"
       "figure{margin:1em 0}img{max-width:100%}code{background:#f4f4f4}</style>\n</head>\n<body>\n<h1>"
    << xml_escape(pg.o.title) << "</h1>\n<p>" << t.rows.size() << " rows, " << pg.columns.size()
    << " columns: <a href=\"table.csv\">table.csv</a>. "
    << "Made " << xml_escape(utc_now()) << " by " << xml_escape(version_string());
  if (!pg.o.command.empty()) h << "; to make it again: <code>" << xml_escape(pg.o.command) << "</code>";
  h << ".</p>\n";
  if (!pg.plots.empty())
    h << "<h2>Plots</h2>\n<p>Points are the mean over the rows (replicas) that share an x value; error bars are its "
         "95 % confidence interval (see Statistics). A point of one row has no interval and no bar: its series is "
         "titled \"n = 1: no interval\".</p>\n";
  for (const auto& p : pg.plots) h << figure(p.name, p.title);
  h << html_statistics(pg);
  constexpr std::size_t kMaxRows = 500;
  h << "<h2>Table</h2>\n";
  if (shown.size() < t.all.size()) h << "<p>Selected columns; every column is in <a href=\"table.csv\">table.csv</a>.</p>\n";
  h << "<table>\n<tr>";
  for (const auto& c : shown) h << "<th>" << xml_escape(c) << "</th>";
  h << "</tr>\n";
  for (std::size_t i = 0; i < t.rows.size() && i < kMaxRows; ++i) {
    h << "<tr>";
    for (const auto& c : shown) {
      const Value* v = find(t.rows[i], c);
      h << "<td>" << (v ? xml_escape(v->number ? number_text(v->x) : v->text) : "") << "</td>";
    }
    h << "</tr>\n";
  }
  h << "</table>\n";
  if (t.rows.size() > kMaxRows) h << "<p>(first " << kMaxRows << " of " << t.rows.size() << " rows)</p>\n";
  h << "</body>\n</html>\n";
  return h.str();
}

// The old report goes only once the new one is in place.
void replace_folder(const fs::path& tmp, const fs::path& final_dir) {
  write_text_atomic((tmp / kReportMarker).string(), "made by tomodem-run report; the folder is replaced on each run\n");
  std::error_code ec;
  const fs::path old = final_dir.string() + ".old" + std::to_string(::getpid());
  if (!final_dir.parent_path().empty()) fs::create_directories(final_dir.parent_path());
  if (fs::exists(final_dir, ec)) fs::rename(final_dir, old);
  fs::rename(tmp, final_dir);
  fs::remove_all(old, ec);
}

// A column named twice in one list (--stats y --stats y) would be reported twice: refused.
void refuse_repeats(const std::vector<std::string>& list, const std::string& field) {
  for (auto it = list.begin(); it != list.end(); ++it)
    if (std::find(list.begin(), it, *it) != it) throw InputError("", field, *it, "named twice");
}

// Defaults of the statistics options, and their checks.
void statistics_options(const Table& t, const std::vector<PlotRequest>& plots, ReportOptions& o) {
  refuse_repeats(o.group, "--group");
  refuse_repeats(o.stats, "--stats");
  const bool group_given = !o.group.empty();
  if (o.group.empty())
    for (const auto& p : plots)
      for (const auto& c : {p.by, p.x})
        if (!c.empty() && std::find(o.group.begin(), o.group.end(), c) == o.group.end()) o.group.push_back(c);
  for (const auto& c : o.group)
    if (!t.known.count(c)) throw InputError("", "--group", c, "no row has this column");
  for (const auto& c : o.stats)
    if (!t.known.count(c)) throw InputError("", "--stats", c, "no row has this column");
  // A row without a group column would make a cell of its own with an empty value.
  for (std::size_t i = 0; i < t.rows.size(); ++i)
    for (const auto& c : o.group)
      if (!find(t.rows[i], c))
        throw InputError(t.files[i], "--group", c,
                         "this row has no such column, so it belongs to no cell" +
                             std::string(group_given ? "" : " (the default group: the plots' by and x columns)"));
}

// A column with one number in every row that has it (E_s, the solid's modulus): nothing to summarise.
bool constant(const Table& t, const std::string& c) {
  double first = NAN;
  for (const auto& r : t.rows) {
    const double x = number_in(r, c);
    if (!std::isfinite(x)) continue;
    if (std::isnan(first)) first = x;
    else if (x != first) return false;
  }
  return true;
}

std::vector<std::string> properties(const Table& t, const ReportOptions& o) {
  if (!o.stats.empty()) return o.stats;
  std::vector<std::string> props;
  for (const auto& c : t.all)
    if (is_property(c, o.group) && !constant(t, c)) props.push_back(c);
  return props;
}

json summary_of(const std::vector<Cell>& cells, const std::vector<std::string>& props, const std::vector<Ranking>& ranks,
                const std::vector<Unranked>& unranked, const Bounds& bounds, const std::vector<json>& outside,
                const ReportOptions& o) {
  json j = json::object();
  j["format"] = "tomodem report summary 1";
  j["group"] = o.group;
  j["method"] =
      "per cell and property: mean of the replicas; sem = sd/sqrt(n); tool_error = mean of the replicas' own "
      "1-sigma errors (<key>_error, relative unless its unit says otherwise), taken as systematic; u = sqrt(sem^2 + "
      "tool_error^2); dof = u^4/(sem^4/(n-1)) (Welch-Satterthwaite); ci95 = mean -/+ t(0.975, dof) u (Student 1908), "
      "cut at the property's bounds where --bound gives them (ci95_cut_at_bound), at a bound the mean is within "
      "(mean_outside_bound: it is not); n < 2: no interval, dof null (also null when infinite, sd = 0). "
      "Rankings: Welch (1947) t-test between cells differing in the first group column, two-sided p; "
      "q = Benjamini-Hochberg (1995) adjusted p over every ranking of the report; resolved when q < 0.05.";
  j["cells"] = json::array();
  for (const auto& prop : props)
    for (const auto& c : cells) {
      const stats::Estimate e = estimate_of(c.rows, prop);
      if (e.n) j["cells"].push_back(cell_json(c, prop, e, range_of(bounds, prop, c.rows)));
    }
  j["outside_bounds"] = outside;
  j["rankings"] = json::array();
  for (const auto& r : ranks) j["rankings"].push_back(r.j);
  j["not_ranked"] = json::array();
  for (const auto& u : unranked) {
    json x = key_json(cells[u.cell]);
    x["property"] = u.property;
    x["n"] = 1;
    x["text"] = u.text;
    j["not_ranked"].push_back(x);
  }
  return j;
}
}  // namespace

ReportFiles write_report(const std::string& dir, const std::vector<std::string>& row_files, const ReportOptions& options) {
  if (row_files.empty()) throw InputError("", "rows", "", "no row files given");
  std::vector<std::string> inputs = row_files;
  if (!options.replicas.empty()) inputs.push_back(options.replicas);  // the folder must not hold it either
  refuse_report_folder(dir, inputs);
  ReportOptions o = options;
  Table t = read_rows(row_files);
  std::vector<std::string> warnings;
  add_ratios(t, o.ratios, warnings);
  const Bounds bounds = bounds_of(t, o.bounds);
  refuse_repeats(o.columns, "--columns");
  const std::vector<std::string> columns = o.columns.empty() ? t.all : o.columns;
  for (const auto& c : columns)
    if (!t.known.count(c)) throw InputError("", "--columns", c, "no row has this column");
  const std::vector<PlotRequest> plots = plot_requests(t, o.plots);
  statistics_options(t, plots, o);
  const std::vector<std::string> props = properties(t, o);
  const std::vector<Cell> cells = cells_of(t, o.group, read_stops(o.replicas));
  std::vector<Unranked> unranked;
  const std::vector<Ranking> ranks = rankings_of(cells, props, unranked);
  const std::vector<json> outside = outside_bounds(t, bounds, row_files);
  for (const auto& prop : props)
    for (const auto& c : cells) {
      const stats::Estimate e = estimate_of(c.rows, prop);
      const Range r = range_of(bounds, prop, c.rows);
      if (interval_of(e, r).mean_outside)
        warnings.push_back((c.key.empty() ? std::string("all rows") : cell_text(c.key)) + ": the mean of " + prop + ", " +
                           number_text(e.mean) + ", is outside its bound [" + (std::isfinite(r.lo) ? number_text(r.lo) : "") + ", " +
                           (std::isfinite(r.hi) ? number_text(r.hi) : "") + "]");
    }
  // The page shows the plotted (or asked-for) properties; summary.json has every one.
  std::vector<std::string> shown = o.stats;
  for (const auto& p : plots)
    for (const auto& y : p.y)
      if (options.stats.empty() && std::find(shown.begin(), shown.end(), y) == shown.end()) shown.push_back(y);
  if (shown.empty()) shown = props;

  const fs::path final_dir = fs::path(dir).lexically_normal();
  const fs::path tmp = final_dir.string() + ".tmp" + std::to_string(::getpid());
  fs::remove_all(tmp);
  fs::create_directories(tmp);
  ReportFiles out;
  out.rows = t.rows.size();
  out.columns = columns.size();
  out.cells = cells.size();
  out.rankings = ranks.size();
  try {
    write_text_atomic((tmp / "table.csv").string(), csv_text(t, columns));
    for (const auto& p : plots) {
      write_plot(tmp / p.name, plot_spec(t, p, bounds));
      out.plots.push_back((final_dir / p.name).string());
    }
    std::vector<std::string> error_plots;
    for (const auto& prop : shown) {
      const PlotSpec spec = error_vs_cpu(cells, prop);
      if (spec.series.empty()) continue;
      const std::string stem = "error-vs-cpu_" + file_stem(prop);
      write_plot(tmp / stem, spec);
      error_plots.push_back(stem);
      out.plots.push_back((final_dir / stem).string());
    }
    write_text_atomic((tmp / "summary.json").string(), summary_of(cells, props, ranks, unranked, bounds, outside, o).dump(1) + "\n");
    write_text_atomic((tmp / "index.html").string(),
                      html_page(Page{t, columns, plots, error_plots, cells, shown, ranks, unranked, bounds, outside, o}));
    replace_folder(tmp, final_dir);
  } catch (...) {
    std::error_code ec;
    fs::remove_all(tmp, ec);
    throw;
  }
  out.table = (final_dir / "table.csv").string();
  out.html = (final_dir / "index.html").string();
  out.summary = (final_dir / "summary.json").string();
  for (const auto& x : outside) out.outside_bounds.push_back(x.at("text").get<std::string>());
  out.warnings = warnings;
  for (const auto& u : unranked) out.not_ranked.push_back(u.text);
  return out;
}

}  // namespace tomodem::pipeline
