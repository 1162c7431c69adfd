#pragma once
// Line plots for tool outputs and study reports, drawn by gnuplot (Debian gnuplot-nox) so the
// figures come from a well-kept plotting tool and can be re-made or restyled from the kept script.
// Every figure has one look: libs/core/share/plot_style.gp (font, line widths, colours, terminal,
// size), compiled in here; callers give data and labels, never a style.
#include <filesystem>
#include <string>
#include <vector>

namespace tomodem {

/// How a series' points are joined.
enum class PlotDraw {
  points_and_lines,  ///< markers joined by lines (a sampled curve)
  points,            ///< markers only (scattered data such as replicas)
  lines,             ///< lines only, point to point as given: a saw-tooth whose drops are vertical segments
  steps,             ///< a histogram outline: x are bin centres, each bin flat (gnuplot histeps)
};

struct PlotSeries {
  std::string title;  ///< the legend: a readable name (units belong on the axes)
  std::vector<double> x, y;
  bool points_only = false;  ///< markers without a line (same as draw = points; kept for callers)
  std::vector<double> yerr;  ///< error bar half-heights, one per y (empty: no bars; NaN: none at that point)
  PlotDraw draw = PlotDraw::points_and_lines;
  /// Asymmetric bars: their lower and upper ends where given (finite), else y -/+ yerr; either
  /// empty or one per y (an interval cut at a physical bound).
  std::vector<double> ylow, yhigh;
};

struct PlotSpec {
  /// Axis labels end with their unit in brackets: "time (s)", "load [N]", "strain (-)" or
  /// "E/E_s [1]" for a pure number (axis_label_unit); write_plot refuses a label without one.
  std::string title, xlabel, ylabel;
  bool logx = false, logy = false;
  std::vector<PlotSeries> series;
};

/// The unit an axis label states in its closing (...) or [...] group: "time (s)" -> "s",
/// "CPU time (s, sum over replicas)" -> "s", "strain (-)" -> "-", "K (Pa m^0.5)" -> "Pa m^0.5".
/// "" when the label ends in no group or the group does not start with a unit ("a/R (bin centre)").
/// Units: SI symbols with prefixes and exponents (m, um/µm, s, K, Pa, N, J, W, S, V, A, Hz, mol,
/// eV, rad, B ...), products and quotients of them, and "-", "1" or "%" for pure numbers.
std::string axis_label_unit(const std::string& label);

/// True when a gnuplot executable is on PATH.
bool plotting_available();

/// The house style as gnuplot commands (libs/core/share/plot_style.gp), for callers that write a
/// gnuplot script of their own.
const std::string& plot_style();

/// Writes stem.png and stem.svg, keeping stem.dat (the data, one block per series) and stem.gp (the
/// script, style included: `gnuplot stem.gp` re-makes stem.png, `gnuplot -e "output_file='x.svg'"
/// stem.gp` an SVG) beside them. A log axis spanning a decade or more is labelled 10^n with minor
/// ticks at 2..9 times each decade. Every file is written under a temporary name and renamed at the
/// end. Throws InputError for a series whose x, y (and yerr) differ in length or an axis label
/// without a unit, before anything is written, and RuntimeFailure when gnuplot is missing or fails.
void write_plot(const std::filesystem::path& stem, const PlotSpec& spec);

/// The four files write_plot(stem) writes, in the order png, svg, dat, gp: a tool checks each
/// against its inputs before any work and lists them as its outputs.
std::vector<std::string> plot_files(const std::string& stem);

}  // namespace tomodem
