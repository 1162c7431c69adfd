#include "tomodem/geometry/psd.hpp"

#include <algorithm>
#include <cmath>
#include <fstream>
#include <numeric>
#include <random>
#include <sstream>

#include "tomodem/core/error.hpp"

namespace tomodem::geometry {

namespace {
constexpr double kPi = 3.14159265358979323846;
double phi(double z) { return 0.5 * std::erfc(-z / std::sqrt(2.0)); }
constexpr int kGrid = 4096;  // points of the number CDF of continuous and tabulated kinds
}  // namespace

std::string to_string(PsdKind k) {
  switch (k) {
    case PsdKind::monodisperse: return "monodisperse";
    case PsdKind::normal: return "normal";
    case PsdKind::lognormal: return "lognormal";
    case PsdKind::bimodal: return "bimodal";
    case PsdKind::tabulated: return "tabulated";
  }
  return "?";
}

bool parse(const std::string& s, PsdKind& k) {
  for (PsdKind c : {PsdKind::monodisperse, PsdKind::normal, PsdKind::lognormal, PsdKind::bimodal, PsdKind::tabulated})
    if (s == to_string(c)) return k = c, true;
  return false;
}

double SizeDistribution::d_min() const {
  switch (kind) {
    case PsdKind::monodisperse: return diameter;
    case PsdKind::normal: return diameter - truncation * sigma;
    case PsdKind::lognormal: return diameter * std::exp(-truncation * sigma);
    case PsdKind::bimodal: return std::min(diameter, diameter2);
    case PsdKind::tabulated: return table_d.empty() ? 0 : table_d.front();
  }
  return 0;
}

double SizeDistribution::d_max() const {
  switch (kind) {
    case PsdKind::monodisperse: return diameter;
    case PsdKind::normal: return diameter + truncation * sigma;
    case PsdKind::lognormal: return diameter * std::exp(truncation * sigma);
    case PsdKind::bimodal: return std::max(diameter, diameter2);
    case PsdKind::tabulated: return table_d.empty() ? 0 : table_d.back();
  }
  return 0;
}

double SizeDistribution::cdf(double d) const {
  switch (kind) {
    case PsdKind::monodisperse: return d < diameter ? 0.0 : 1.0;
    case PsdKind::normal:
    case PsdKind::lognormal: {
      if (d <= d_min()) return 0;
      if (d >= d_max()) return 1;
      const double z = kind == PsdKind::normal ? (d - diameter) / sigma : std::log(d / diameter) / sigma;
      const double lo = phi(-truncation), hi = phi(truncation);
      return (phi(z) - lo) / (hi - lo);
    }
    case PsdKind::bimodal: {
      const bool second_small = diameter2 < diameter;
      const double f_small = second_small ? fraction2 : 1 - fraction2;
      if (d < d_min()) return 0;
      if (d < d_max()) return f_small;
      return 1;
    }
    case PsdKind::tabulated: {
      if (d < table_d.front()) return 0;
      if (d >= table_d.back()) return 1;
      const auto it = std::upper_bound(table_d.begin(), table_d.end(), d);
      const std::size_t k = std::size_t(it - table_d.begin());  // table_d[k-1] <= d < table_d[k]
      const double t = (d - table_d[k - 1]) / (table_d[k] - table_d[k - 1]);
      return table_cdf[k - 1] + t * (table_cdf[k] - table_cdf[k - 1]);
    }
  }
  return 0;
}

void SizeDistribution::prepare() {
  grid_d.clear();
  grid_ncdf.clear();
  if (kind == PsdKind::monodisperse || kind == PsdKind::bimodal) return;
  // Grid in log d; a tabulated distribution also gets its own nodes (kinks of the CDF) and a
  // point mass at its first diameter when the table starts above 0.
  const double a = d_min(), b = d_max();
  std::vector<double> d;
  for (int k = 0; k <= kGrid; ++k) d.push_back(a * std::pow(b / a, double(k) / kGrid));
  if (kind == PsdKind::tabulated) d.insert(d.end(), table_d.begin(), table_d.end());
  std::sort(d.begin(), d.end());
  d.erase(std::unique(d.begin(), d.end()), d.end());
  std::vector<double> w(d.size(), 0.0);  // number weight of each node (volume → number: / d³)
  double prev = 0;
  for (std::size_t k = 0; k < d.size(); ++k) {
    const double c = cdf(d[k]);
    const double dm = k == 0 ? d[0] : 0.5 * (d[k] + d[k - 1]);
    const double dF = c - prev;
    prev = c;
    w[k] = basis == PsdBasis::volume ? dF / (dm * dm * dm) : dF;
  }
  // Piecewise linear number CDF between nodes (the mass of node k spread over (d[k-1], d[k]]).
  const double total = std::accumulate(w.begin(), w.end(), 0.0);
  double acc = 0;
  for (std::size_t k = 0; k < d.size(); ++k) {
    if (k == 0 && w[0] > 0) {  // point mass at the first diameter: a vertical step
      grid_d.push_back(d[0]);
      grid_ncdf.push_back(0);
    }
    acc += w[k];
    grid_d.push_back(d[k]);
    grid_ncdf.push_back(acc / total);
  }
  grid_ncdf.back() = 1;
}

double SizeDistribution::number_cdf(double d) const {
  if (basis == PsdBasis::number) return cdf(d);
  if (kind == PsdKind::monodisperse) return cdf(d);
  if (kind == PsdKind::bimodal) {
    const double ds = d_min(), dl = d_max();
    const double fv_small = diameter2 < diameter ? fraction2 : 1 - fraction2;
    const double ns = fv_small / (ds * ds * ds), nl = (1 - fv_small) / (dl * dl * dl);
    if (d < ds) return 0;
    if (d < dl) return ns / (ns + nl);
    return 1;
  }
  if (d < grid_d.front()) return 0;
  if (d >= grid_d.back()) return 1;
  const auto it = std::upper_bound(grid_d.begin(), grid_d.end(), d);
  const std::size_t k = std::size_t(it - grid_d.begin());
  const double t = (d - grid_d[k - 1]) / (grid_d[k] - grid_d[k - 1]);
  return grid_ncdf[k - 1] + t * (grid_ncdf[k] - grid_ncdf[k - 1]);
}

double SizeDistribution::mean_volume() const {
  const auto v = [](double d) { return kPi / 6 * d * d * d; };
  if (kind == PsdKind::monodisperse) return v(diameter);
  if (kind == PsdKind::bimodal) {
    const double fs = number_cdf(d_min());
    return fs * v(d_min()) + (1 - fs) * v(d_max());
  }
  double m = 0;
  for (std::size_t k = 1; k < grid_d.size(); ++k)
    m += (grid_ncdf[k] - grid_ncdf[k - 1]) * v(0.5 * (grid_d[k] + grid_d[k - 1]));
  return m;
}

std::vector<double> SizeDistribution::sample(std::size_t n, uint64_t seed) const {
  std::vector<double> d(n);
  for (std::size_t k = 0; k < n; ++k) {
    const double u = (double(k) + 0.5) / double(n);
    if (kind == PsdKind::monodisperse) {
      d[k] = diameter;
    } else if (kind == PsdKind::bimodal) {
      d[k] = u < number_cdf(d_min()) ? d_min() : d_max();
    } else {
      // Inverse of the piecewise linear number CDF.
      const auto it = std::lower_bound(grid_ncdf.begin(), grid_ncdf.end(), u);
      const std::size_t j = std::clamp<std::size_t>(std::size_t(it - grid_ncdf.begin()), 1, grid_ncdf.size() - 1);
      const double c0 = grid_ncdf[j - 1], c1 = grid_ncdf[j];
      const double t = c1 > c0 ? (u - c0) / (c1 - c0) : 1.0;
      d[k] = grid_d[j - 1] + t * (grid_d[j] - grid_d[j - 1]);
    }
  }
  std::mt19937_64 rng(seed);
  std::shuffle(d.begin(), d.end(), rng);
  return d;
}

void SizeDistribution::validate(const std::string& where, const std::string& field) const {
  const auto bad = [&](const std::string& key, double v, const std::string& why) {
    throw InputError(where, field + "." + key, value_text(v), why);
  };
  if (kind != PsdKind::tabulated && !(diameter > 0)) bad("diameter", diameter, "must be > 0 (metres)");
  if (kind == PsdKind::normal || kind == PsdKind::lognormal) {
    if (!(sigma > 0)) bad("sigma", sigma, "must be > 0 (use kind: monodisperse for a single size)");
    if (!(truncation > 0)) bad("truncation", truncation, "must be > 0 (in standard deviations)");
  }
  if (kind == PsdKind::normal && !(d_min() > 0))
    bad("sigma", sigma, "the normal distribution cut at mean - " + value_text(truncation) + " sigma reaches d <= 0; lower sigma or truncation");
  if (kind == PsdKind::bimodal) {
    if (!(diameter2 > 0)) bad("diameter2", diameter2, "must be > 0 (metres)");
    if (!(fraction2 >= 0 && fraction2 <= 1)) bad("fraction2", fraction2, "must lie in [0, 1]");
  }
  // Outside an atom .. a boulder the cell volume (~ N d^3) over- or underflows and the packer died
  // with a bare "cannot create std::vector larger than max_size()" (exit 1).
  const auto sane = [&](const char* key, double d) {
    if (!(d >= kMinDiameter && d <= kMaxDiameter))
      bad(key, d, "must lie in [" + value_text(kMinDiameter) + ", " + value_text(kMaxDiameter) + "] m");
  };
  if (kind != PsdKind::tabulated) sane("diameter", diameter);
  if (kind == PsdKind::bimodal) sane("diameter2", diameter2);
}

std::string SizeDistribution::describe() const {
  std::ostringstream s;
  s << to_string(kind) << " by " << (basis == PsdBasis::number ? "number" : "volume");
  if (kind == PsdKind::tabulated) s << " (" << source << ", " << table_d.size() << " rows)";
  else s << " d=" << diameter;
  if (sigma > 0) s << " sigma=" << sigma;
  if (kind == PsdKind::bimodal) s << " d2=" << diameter2 << " fraction2=" << fraction2;
  return s.str();
}

SizeDistribution read_psd_csv(const std::string& path, PsdBasis basis) {
  std::ifstream in(path);
  if (!in) throw InputError(path, "size_distribution.file", path, "cannot be opened for reading");
  SizeDistribution psd;
  psd.kind = PsdKind::tabulated;
  psd.basis = basis;
  psd.source = path;
  std::string line;
  int row = 0;
  bool first = true;
  while (std::getline(in, line)) {
    ++row;
    const auto hash = line.find('#');
    if (hash != std::string::npos) line.erase(hash);
    for (char& c : line)
      if (c == ',' || c == ';' || c == '\t') c = ' ';
    std::istringstream ls(line);
    std::string a, b, extra;
    if (!(ls >> a)) continue;
    const std::string field = "row " + std::to_string(row);
    if (!(ls >> b) || (ls >> extra))
      throw InputError(path, field, line, "expected two columns: diameter_m, cumulative_fraction");
    double d, c;
    try {
      std::size_t pa, pb;
      d = std::stod(a, &pa);
      c = std::stod(b, &pb);
      if (pa != a.size() || pb != b.size()) throw std::invalid_argument("trailing");
    } catch (const std::exception&) {
      if (first) {  // a header line
        first = false;
        continue;
      }
      throw InputError(path, field, line, "not two numbers (diameter_m, cumulative_fraction)");
    }
    first = false;
    if (!(d > 0) || !std::isfinite(d)) throw InputError(path, field + " diameter", a, "must be finite and > 0 (metres)");
    if (!(c >= 0 && c <= 1)) throw InputError(path, field + " cumulative_fraction", b, "must lie in [0, 1]");
    if (!psd.table_d.empty() && !(d > psd.table_d.back()))
      throw InputError(path, field + " diameter", a, "diameters must increase down the table");
    if (!psd.table_cdf.empty() && c < psd.table_cdf.back())
      throw InputError(path, field + " cumulative_fraction", b, "cumulative fractions must not decrease");
    psd.table_d.push_back(d);
    psd.table_cdf.push_back(c);
  }
  if (psd.table_d.size() < 2) throw InputError(path, "rows", std::to_string(psd.table_d.size()), "need at least two rows");
  if (std::abs(psd.table_cdf.back() - 1) > 1e-6)
    throw InputError(path, "last row cumulative_fraction", value_text(psd.table_cdf.back()), "must be 1");
  psd.table_cdf.back() = 1;
  return psd;
}

double max_cdf_deviation(const SizeDistribution& psd, const std::vector<double>& diameters) {
  if (diameters.empty()) return 1;
  std::vector<double> d = diameters;
  std::sort(d.begin(), d.end());
  const bool vol = psd.basis == PsdBasis::volume;
  double total = 0;
  for (double x : d) total += vol ? x * x * x : 1.0;
  double acc = 0, dev = 0;
  for (std::size_t k = 0; k < d.size();) {
    std::size_t e = k;
    double w = 0;
    while (e < d.size() && d[e] == d[k]) w += vol ? d[e] * d[e] * d[e] : 1.0, ++e;
    const double before = acc / total;
    acc += w;
    const double after = acc / total;
    const double left = psd.cdf(std::nextafter(d[k], 0.0));
    dev = std::max({dev, std::abs(before - left), std::abs(after - psd.cdf(d[k]))});
    k = e;
  }
  return dev;
}

}  // namespace tomodem::geometry
