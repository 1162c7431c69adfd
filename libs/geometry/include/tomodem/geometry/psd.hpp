#pragma once
// Particle size distributions (diameters, metres): monodisperse, normal, lognormal, bimodal and
// tabulated (CSV of diameter and cumulative fraction), each given by number or by volume.
// Sampling is stratified (quantiles at (k + 1/2)/N of the number distribution, shuffled), so the
// realised distribution follows the requested one to about one particle's weight.
#include <cstdint>
#include <string>
#include <vector>

namespace tomodem::geometry {

enum class PsdKind { monodisperse, normal, lognormal, bimodal, tabulated };
enum class PsdBasis { number, volume };

/// The diameters a size distribution may give (m): 0.1 nm to 1 km.
inline constexpr double kMinDiameter = 1e-10, kMaxDiameter = 1e3;

struct SizeDistribution {
  PsdKind kind = PsdKind::monodisperse;
  PsdBasis basis = PsdBasis::number;  ///< what the CDF counts (tabulated: volume unless said)
  double diameter = 0;   ///< m: monodisperse d; normal mean; lognormal median; bimodal first mode
  double sigma = 0;      ///< normal: standard deviation, m; lognormal: σ of ln d
  double diameter2 = 0;  ///< bimodal: second mode, m
  double fraction2 = 0;  ///< bimodal: fraction of the second mode (by `basis`)
  double truncation = 3; ///< normal/lognormal: cut at ±truncation σ (CDF renormalised)
  std::vector<double> table_d, table_cdf;  ///< tabulated: increasing d (m), cumulative fraction, last = 1
  std::string source;    ///< file of a tabulated distribution (messages)

  double d_min() const;
  double d_max() const;
  /// Requested cumulative fraction (in `basis`) of diameters ≤ d.
  double cdf(double d) const;
  /// Number-weighted cumulative fraction (converted from a volume basis when needed).
  double number_cdf(double d) const;
  /// Mean particle volume π⟨d³⟩/6 of the number distribution, m³.
  double mean_volume() const;
  /// n diameters by stratified sampling of the number distribution, shuffled with `seed`.
  std::vector<double> sample(std::size_t n, uint64_t seed) const;
  /// Throws InputError (file `where`, field `field`) when a parameter is impossible.
  void validate(const std::string& where, const std::string& field) const;
  std::string describe() const;

  // Number CDF on a fine grid (filled by prepare(); continuous kinds and tables).
  void prepare();
  std::vector<double> grid_d, grid_ncdf;
};

/// Reads a tabulated distribution: CSV rows "diameter_m, cumulative_fraction" (an optional
/// header line; '#' comments). Errors name the file, the row and the value.
SizeDistribution read_psd_csv(const std::string& path, PsdBasis basis);

/// Maximum deviation between the realised CDF of `diameters` (weighted by number or volume as
/// the distribution's basis) and the requested CDF: the Kolmogorov–Smirnov distance.
double max_cdf_deviation(const SizeDistribution& psd, const std::vector<double>& diameters);

std::string to_string(PsdKind);
bool parse(const std::string&, PsdKind&);

}  // namespace tomodem::geometry
