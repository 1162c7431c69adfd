#include "tomodem/core/plot.hpp"

#include <cmath>
#include <cstdlib>
#include <sstream>

#include "tomodem/core/error.hpp"
#include "tomodem/core/output.hpp"

namespace tomodem {
namespace {

// gnuplot strings are single-quoted: a quote inside is doubled.
std::string quoted(const std::string& s) {
  std::string out = "'";
  for (char c : s) out += (c == '\'') ? std::string("''") : std::string(1, c);
  return out + "'";
}

std::string shell_quoted(const std::string& s) {
  std::string out = "'";
  for (char c : s) out += (c == '\'') ? std::string("'\\''") : std::string(1, c);
  return out + "'";
}

}  // namespace

bool plotting_available() { return std::system("command -v gnuplot >/dev/null 2>&1") == 0; }

void write_plot(const std::filesystem::path& stem, const PlotSpec& spec) {
  for (const auto& s : spec.series)
    if (s.x.size() != s.y.size() || (!s.yerr.empty() && s.yerr.size() != s.y.size()))
      throw InputError(stem.string(), "series '" + s.title + "'", std::to_string(s.x.size()) + " x values",
                       "it has " + std::to_string(s.y.size()) + " y values; a series needs one y per x");
  if (!plotting_available())
    throw RuntimeFailure("plot " + stem.string() + ": gnuplot not found (install Debian's gnuplot-nox)");

  const std::string dat = stem.string() + ".dat", gp = stem.string() + ".gp";
  const std::string png = stem.string() + ".png", svg = stem.string() + ".svg";
  std::ostringstream data;
  data.precision(10);
  for (const auto& s : spec.series) {  // one block per series, addressed by `index` in the script
    data << "# " << s.title << "\n";
    for (std::size_t i = 0; i < s.x.size(); ++i)
      if (std::isfinite(s.x[i]) && std::isfinite(s.y[i])) {
        data << s.x[i] << ' ' << s.y[i];
        // A third column only for series with bars; a point without a spread gets a bar of 0.
        if (!s.yerr.empty()) data << ' ' << (i < s.yerr.size() && std::isfinite(s.yerr[i]) ? s.yerr[i] : 0.0);
        data << '\n';
      }
    data << "\n\n";
  }
  write_text_atomic(dat, data.str());

  // The script names the data file by its final name and leaves the terminal to the caller, so
  // `gnuplot -e "set terminal ...; set output ..." stem.gp` re-makes either picture.
  std::ostringstream script;
  script << "set title " << quoted(spec.title) << "\nset xlabel " << quoted(spec.xlabel) << "\nset ylabel "
         << quoted(spec.ylabel) << "\nset grid\nset key top left\n";
  if (spec.logx) script << "set logscale x\n";
  if (spec.logy) script << "set logscale y\n";
  const std::string dat_name = std::filesystem::path(dat).filename().string();
  script << "plot ";
  for (std::size_t i = 0; i < spec.series.size(); ++i) {
    const auto& s = spec.series[i];
    const bool bars = !s.yerr.empty();
    script << (i ? ", \\\n     " : "") << quoted(dat_name) << " index " << i << (bars ? " using 1:2:3 with " : " using 1:2 with ")
           << (bars ? (s.points_only ? "yerrorbars" : "yerrorlines") : s.points_only ? "points" : "linespoints")
           << " title " << quoted(s.title);
  }
  script << "\n";
  write_text_atomic(gp, script.str());

  const std::string dir = stem.has_parent_path() ? stem.parent_path().string() : ".";
  auto render = [&](const std::string& terminal, const std::string& out) {
    const std::string tmp = temporary_path(out);
    const std::string cmd = "cd " + shell_quoted(dir) + " && gnuplot -e " +
                            shell_quoted("set terminal " + terminal + "; set output " +
                                         quoted(std::filesystem::path(tmp).filename().string())) +
                            " " + shell_quoted(std::filesystem::path(gp).filename().string()) + " 2>&1";
    if (std::system(cmd.c_str()) != 0) {
      std::filesystem::remove(tmp);
      throw RuntimeFailure("plot " + out + ": gnuplot failed (script " + gp + ")");
    }
    commit_output(out);
  };
  render("pngcairo size 800,560 noenhanced", png);
  render("svg size 800,560 noenhanced", svg);
}

}  // namespace tomodem
