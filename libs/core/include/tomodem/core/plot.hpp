#pragma once
// Line plots for tool outputs and study reports, drawn by gnuplot (Debian gnuplot-nox) so the
// figures come from a well-kept plotting tool and can be re-made or restyled from the kept script.
#include <filesystem>
#include <string>
#include <vector>

namespace tomodem {

struct PlotSeries {
  std::string title;
  std::vector<double> x, y;
  bool points_only = false;  ///< markers without a line (scattered data such as replicas)
  std::vector<double> yerr;  ///< error bar half-heights, one per y (empty: no bars; NaN: none at that point)
};

struct PlotSpec {
  std::string title, xlabel, ylabel;
  bool logx = false, logy = false;
  std::vector<PlotSeries> series;
};

/// True when a gnuplot executable is on PATH.
bool plotting_available();

/// Writes stem.png and stem.svg, keeping stem.dat (the data, one block per series) and stem.gp (the
/// script) beside them so a user can re-run `gnuplot stem.gp`. Every file is written under a
/// temporary name and renamed at the end. Throws InputError for a series whose x and y differ in
/// length and RuntimeFailure when gnuplot is missing or fails.
void write_plot(const std::filesystem::path& stem, const PlotSpec& spec);

}  // namespace tomodem
