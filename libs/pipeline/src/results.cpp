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

std::string html(const std::string& s) {
  std::string o;
  for (char c : s) {
    switch (c) {
      case '&': o += "&amp;"; break;
      case '<': o += "&lt;"; break;
      case '>': o += "&gt;"; break;
      case '"': o += "&quot;"; break;
      default: o += c;
    }
  }
  return o;
}

std::string number_text(double x) {
  std::ostringstream s;
  s.precision(10);
  s << x;
  return s.str();
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
  return row.dump(1) + "\n";
}

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
    else if (k == "y") {
      std::istringstream ys(v);
      for (std::string c; std::getline(ys, c, ',');)
        if (!c.empty()) p.y.push_back(c);
    } else
      throw InputError("", "--plot", spec, "unknown key '" + k + "' (name, x, y, by, title, xlabel, ylabel, logx, logy)");
  }
  if (p.name.empty() || p.name.find_first_not_of("abcdefghijklmnopqrstuvwxyzABCDEFGHIJKLMNOPQRSTUVWXYZ0123456789_-") !=
                            std::string::npos)
    throw InputError("", "--plot", spec, "needs name=NAME (letters, digits, '_', '-': the file name)");
  if (p.x.empty() || p.y.empty()) throw InputError("", "--plot", spec, "needs x=COLUMN and y=COLUMN[,COLUMN...]");
  if (p.xlabel.empty()) p.xlabel = p.x;
  if (p.ylabel.empty()) p.ylabel = p.y.size() == 1 ? p.y[0] : "";
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
}  // namespace

ReportFiles write_report(const std::string& dir, const std::vector<std::string>& row_files, const ReportOptions& o) {
  if (row_files.empty()) throw InputError("", "rows", "", "no row files given");
  refuse_report_folder(dir, row_files);
  // ---- read the rows and add the ratios --------------------------------------------------
  std::vector<Row> rows;
  std::vector<std::string> all;  // every column, in order of first appearance
  std::set<std::string> known;
  const auto note = [&](const std::string& c) {
    if (known.insert(c).second) all.push_back(c);
  };
  for (const auto& f : row_files) {
    json j;
    try {
      j = json::parse(read_file(f, "rows"));
    } catch (const json::exception& e) {
      throw InputError(f, "rows", "", std::string("not valid JSON: ") + e.what());
    }
    if (!j.is_object() || std::any_of(j.begin(), j.end(), [](const json& v) { return v.is_structured(); }))
      throw InputError(f, "rows", "", "not a row file (a flat JSON object, made by `tomodem run row`)");
    const Row r = flatten_json(j.dump(), "", f);
    for (const auto& kv : r) note(kv.first);
    rows.push_back(std::move(r));
  }
  for (const auto& item : o.ratios) {
    const auto [name, expr] = split_eq(item, "--ratio");
    const auto slash = expr.find('/');
    if (slash == std::string::npos) throw InputError("", "--ratio", item, "expected NAME=A/B");
    const std::string a = expr.substr(0, slash), b = expr.substr(slash + 1);
    for (const auto& operand : {a, b})
      if (!known.count(operand) && !value_of(operand).number)
        throw InputError("", "--ratio", item, "'" + operand + "' is neither a column nor a number");
    note(name);
    for (auto& r : rows) {
      // A column's number, or the operand itself as a literal; NaN when the row lacks it.
      const auto num = [&](const std::string& s) {
        const Value* v = find(r, s);
        const Value lit = value_of(s);
        return v ? (v->number ? v->x : NAN) : lit.number ? lit.x : NAN;
      };
      const double x = num(a), y = num(b);
      if (std::isfinite(x) && std::isfinite(y) && y != 0)
        r.emplace_back(name, Value{number_text(x / y), true, x / y});
    }
  }
  const std::vector<std::string> columns = o.columns.empty() ? all : o.columns;
  for (const auto& c : columns)
    if (!known.count(c)) throw InputError("", "--columns", c, "no row has this column");
  std::vector<PlotRequest> plots;
  for (const auto& spec : o.plots) {
    PlotRequest p = parse_plot(spec);
    std::vector<std::string> used = p.y;
    used.push_back(p.x);
    if (!p.by.empty()) used.push_back(p.by);
    for (const auto& c : used)
      if (!known.count(c)) throw InputError("", "--plot", spec, "no row has the column '" + c + "'");
    for (const auto& q : plots)
      if (q.name == p.name) throw InputError("", "--plot", spec, "two plots named '" + p.name + "'");
    plots.push_back(std::move(p));
  }

  // ---- write everything into a temporary folder, then rename it -------------------------
  const fs::path final_dir = fs::path(dir).lexically_normal();
  const fs::path tmp = final_dir.string() + ".tmp" + std::to_string(::getpid());
  fs::remove_all(tmp);
  fs::create_directories(tmp);
  ReportFiles out;
  out.rows = rows.size();
  out.columns = columns.size();
  try {
    std::ostringstream csv;
    for (std::size_t k = 0; k < columns.size(); ++k) csv << (k ? "," : "") << csv_field(columns[k]);
    csv << "\n";
    for (const auto& r : rows) {
      for (std::size_t k = 0; k < columns.size(); ++k) {
        const Value* v = find(r, columns[k]);
        csv << (k ? "," : "") << (v ? csv_field(v->text) : "");
      }
      csv << "\n";
    }
    write_text_atomic((tmp / "table.csv").string(), csv.str());

    for (const auto& p : plots) {
      PlotSpec spec;
      spec.title = p.title;
      spec.xlabel = p.xlabel;
      spec.ylabel = p.ylabel;
      spec.logx = p.logx;
      spec.logy = p.logy;
      std::vector<std::string> groups;  // values of `by`, in order of appearance
      for (const auto& r : rows) {
        const Value* g = p.by.empty() ? nullptr : find(r, p.by);
        const std::string key = g ? g->text : "";
        if (std::find(groups.begin(), groups.end(), key) == groups.end()) groups.push_back(key);
      }
      for (const auto& g : groups)
        for (const auto& ycol : p.y) {
          std::map<double, std::pair<double, int>> sums;  // x -> (sum of y, count): the replica mean
          for (const auto& r : rows) {
            const Value* gv = p.by.empty() ? nullptr : find(r, p.by);
            if ((gv ? gv->text : "") != g) continue;
            const Value *xv = find(r, p.x), *yv = find(r, ycol);
            if (!xv || !yv || !xv->number || !yv->number) continue;
            if ((p.logx && xv->x <= 0) || (p.logy && yv->x <= 0)) continue;
            auto& s = sums[xv->x];
            s.first += yv->x;
            s.second += 1;
          }
          if (sums.empty()) continue;
          PlotSeries s;
          s.title = g.empty() ? ycol : p.y.size() > 1 ? g + " " + ycol : g;
          for (const auto& [x, sy] : sums) {
            s.x.push_back(x);
            s.y.push_back(sy.first / sy.second);
          }
          spec.series.push_back(std::move(s));
        }
      if (spec.series.empty())
        throw InputError("", "--plot", p.name, "no row has numbers in both '" + p.x + "' and the y columns");
      write_plot(tmp / p.name, spec);
      out.plots.push_back((final_dir / p.name).string());
    }

    // ---- the HTML report ----------------------------------------------------------------
    std::vector<std::string> shown = o.columns;
    if (shown.empty()) {
      for (const auto& p : plots) {
        for (const auto& c : {p.by, p.x})
          if (!c.empty() && std::find(shown.begin(), shown.end(), c) == shown.end()) shown.push_back(c);
        for (const auto& c : p.y)
          if (std::find(shown.begin(), shown.end(), c) == shown.end()) shown.push_back(c);
      }
      if (shown.empty()) shown = all;
    }
    std::ostringstream h;
    h << "<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n<title>" << html(o.title)
      << "</title>\n<style>body{font-family:sans-serif;max-width:60em;margin:2em auto;padding:0 1em}"
         "table{border-collapse:collapse;font-size:90%}td,th{border:1px solid #bbb;padding:2px 6px;text-align:right}"
         "figure{margin:1em 0}img{max-width:100%}code{background:#f4f4f4}</style>\n</head>\n<body>\n<h1>"
      << html(o.title) << "</h1>\n<p>" << rows.size() << " rows, " << columns.size() << " columns: <a href=\"table.csv\">table.csv</a>. "
      << "Made " << html(utc_now()) << " by " << html(version_string());
    if (!o.command.empty()) h << "; to make it again: <code>" << html(o.command) << "</code>";
    h << ".</p>\n";
    if (!plots.empty()) h << "<h2>Plots</h2>\n<p>Points are the mean over the rows (replicas) that share an x value.</p>\n";
    for (const auto& p : plots)
      h << "<figure>\n<img src=\"" << p.name << ".svg\" alt=\"" << html(p.title) << "\">\n<figcaption>" << html(p.title)
        << ": <a href=\"" << p.name << ".png\">PNG</a>, <a href=\"" << p.name << ".svg\">SVG</a>, <a href=\"" << p.name
        << ".gp\">gnuplot script</a>, <a href=\"" << p.name << ".dat\">data</a></figcaption>\n</figure>\n";
    constexpr std::size_t kMaxRows = 500;
    h << "<h2>Table</h2>\n";
    if (shown.size() < all.size()) h << "<p>Selected columns; every column is in <a href=\"table.csv\">table.csv</a>.</p>\n";
    h << "<table>\n<tr>";
    for (const auto& c : shown) h << "<th>" << html(c) << "</th>";
    h << "</tr>\n";
    for (std::size_t i = 0; i < rows.size() && i < kMaxRows; ++i) {
      h << "<tr>";
      for (const auto& c : shown) {
        const Value* v = find(rows[i], c);
        h << "<td>" << (v ? html(v->number ? number_text(v->x) : v->text) : "") << "</td>";
      }
      h << "</tr>\n";
    }
    h << "</table>\n";
    if (rows.size() > kMaxRows) h << "<p>(first " << kMaxRows << " of " << rows.size() << " rows)</p>\n";
    h << "</body>\n</html>\n";
    write_text_atomic((tmp / "index.html").string(), h.str());

    write_text_atomic((tmp / kReportMarker).string(), "made by tomodem-run report; the folder is replaced on each run\n");
    // The old report goes only once the new one is in place.
    std::error_code ec;
    const fs::path old = final_dir.string() + ".old" + std::to_string(::getpid());
    if (!final_dir.parent_path().empty()) fs::create_directories(final_dir.parent_path());
    if (fs::exists(final_dir, ec)) fs::rename(final_dir, old);
    fs::rename(tmp, final_dir);
    fs::remove_all(old, ec);
  } catch (...) {
    std::error_code ec;
    fs::remove_all(tmp, ec);
    throw;
  }
  out.table = (final_dir / "table.csv").string();
  out.html = (final_dir / "index.html").string();
  return out;
}

}  // namespace tomodem::pipeline
