#pragma once
// Results of a pipeline: one row per sweep cell made from the JSON summaries of its steps, a
// table (CSV) of the rows, plots (gnuplot, PNG + SVG) and a short HTML report that links them.
// The row and report steps of pipelines/demo.yaml and pipelines/study.yaml run these through
// `tomodem run row` and `tomodem run report` (docs/pipelines.md, "Results").
#include <string>
#include <utility>
#include <vector>

namespace tomodem::pipeline {

/// One cell of a table: its text as written to the CSV, and whether it is a number.
struct Value {
  std::string text;
  bool number = false;
  double x = 0;  // the number, when `number`
};
/// Columns in order of first appearance.
using Row = std::vector<std::pair<std::string, Value>>;

/// The scalars of a JSON object as columns "prefix.key.sub" (numbers, strings, booleans as
/// 0/1); arrays and nulls are left out. Throws InputError naming `file` when the text is not a
/// JSON object.
Row flatten_json(const std::string& json_text, const std::string& prefix, const std::string& file);

/// A row from `KEY=VALUE` texts (values that parse as numbers become numbers) and
/// `NAME=FILE.json` summaries (flattened with the prefix NAME), as a JSON object text.
/// Bad items (no '=', an unreadable or malformed file) throw InputError naming them.
std::string make_row(const std::vector<std::string>& values, const std::vector<std::string>& summaries);

/// A tool's own 1-sigma error of `column` in a row, as an absolute number: the column
/// `<column>_error` is relative unless the summary's units (`<prefix>.units.<key>_error`) name
/// another unit; NaN when the row has none. `value` is the column's value.
double own_error(const Row& row, const std::string& column, double value);

/// One plot, parsed from "name=N;x=COL;y=COL[,COL...][;by=COL][;logx][;logy][;title=T][;xlabel=L][;ylabel=L]".
/// For every value of `by` (or once) and every y column, a series of the mean of y over the
/// rows that share an x value (replicas), sorted by x.
struct PlotRequest {
  std::string name, x, by, title, xlabel, ylabel;
  std::vector<std::string> y;
  std::vector<std::string> legend;  // legend=NAME,...: one readable name per y column (default: the column)
  bool logx = false, logy = false;
};
PlotRequest parse_plot(const std::string& spec);

struct ReportOptions {
  std::string title = "tomodem results";
  std::vector<std::string> columns;  // the CSV's columns, in order (empty: every column)
  std::vector<std::string> ratios;   // "NAME=A/B": a column A/B (A, B columns or numbers)
  std::vector<std::string> plots;    // plot specs (parse_plot)
  std::string command;               // the command line, shown in the report
  // Statistics (docs/pipelines.md, "Statistics"): rows sharing the values of `group` are the
  // replicas of one cell (default: the plots' `by` and `x` columns); `stats` are the properties
  // (default: every number column but the group, replica, seed, *_error*, *_time_s, *_bytes).
  std::vector<std::string> group, stats;
  std::string replicas;              // the runner's adaptive-replica record (${run.replicas}), or ""
  // "NAME=LO:HI": the physical range of a column (LO, HI: numbers or columns; one may be empty,
  // as in E_rel=0:). A 95 % interval that reaches past it is cut there; a replica outside it is
  // listed (ReportFiles::outside_bounds, summary.json) and marked on the page.
  std::vector<std::string> bounds;
};

/// What write_report wrote, for the caller's summary.
struct ReportFiles {
  std::string table, html, summary;  // summary.json: per cell and property mean, sem, ci95, n, ...
  std::vector<std::string> plots;  // stems; each has .png, .svg, .gp, .dat (error-vs-cpu plots too)
  std::size_t cells = 0, rankings = 0;
  std::size_t rows = 0, columns = 0;
  std::vector<std::string> outside_bounds;  // one text per replica value outside its --bound
  std::vector<std::string> warnings;        // a cell's mean outside its --bound; a --ratio's divisor 0 in some rows
  std::vector<std::string> not_ranked;      // cells left out of the rankings: one replica of a property
};

/// Reads the row files (make_row's JSON), adds the ratio columns and writes `dir`/table.csv,
/// `dir`/<plot>.{png,svg,gp,dat} (points: replica means with 95 % error bars),
/// `dir`/summary.json (statistics per cell and property, rankings with Welch p-values),
/// `dir`/error-vs-cpu_<property>.* and `dir`/index.html. The folder is built under a temporary
/// name and renamed, so it never exists half-written. Bad specs, unknown columns and unreadable
/// rows throw InputError before anything is written.
ReportFiles write_report(const std::string& dir, const std::vector<std::string>& row_files, const ReportOptions& o);

}  // namespace tomodem::pipeline
