#pragma once
// A bonded-particle network as the mechanics tools see it: the shared packing plus the periodic
// image of j seen from i for every bond (dataset /bonds/image, docs/data-model.md), the bond
// laws from the materials, and the load-bearing part of the network.
#include <array>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "tomodem/core/packing.hpp"
#include "tomodem/dem/bonds.hpp"
#include "tomodem/spatial/clusters.hpp"
#include "tomodem/spatial/image.hpp"

namespace tomodem::mechanics {

using Image = spatial::Image;

struct Network {
  Packing packing;
  std::vector<Image> image;  ///< per bond: x_j + H·image − x_i is the bond vector
};

/// Reads a packing and its bond images (/bonds/image; when absent, the minimum image of each
/// bond, which is exact while bonds are shorter than half the cell).
Network read_network(const std::string& path);
/// Writes the packing and /bonds/image atomically (temporary name, renamed at the end).
void write_network(const std::string& path, const Network& net);
/// Minimum-image convention for every bond of `p`.
std::vector<Image> minimum_images(const Packing& p);
/// Bond vector x_j + H·image − x_i of bond b.
Vec3 bond_vector(const Packing& p, const Image& image, std::size_t b);

/// Options that turn materials into bond laws.
struct LawOptions {
  double g_n_coefficient = 4.0;  ///< g_n = 1 + c (a/R)² (dem::BondLaw default)
  double g_t_coefficient = 1.2;
  bool shear = true;             ///< false: normal bonds (G* = 0: no shear force, no twist)
  double damping_ratio = 0;      ///< ζ of the bond dashpots (explicit runs)
  /// Dense-network law: k_n, k_t capped at E A_face/L of the pair's Laguerre face
  /// (dem::face_cap_stiffness, docs/bond.md#dense-networks); false: every neck as if alone.
  bool face_cap = true;
};
/// One law per phase pair (n×n): 1/E* = Σ(1−ν²)/E, 1/G* = Σ(2−ν)/G (docs/physics.md#notation). Materials must
/// be present with E > 0, −1 < ν < 0.5 and, when `need_density`, density > 0: InputError
/// naming the file, the material and the value otherwise.
std::vector<dem::BondLaw> bond_laws(const Packing& p, const std::string& file, const LawOptions& o,
                                    bool need_density);

/// Command-line material overrides for every phase (each when given); a packing without
/// materials gets one per phase index ("phase0", ...).
void override_materials(Packing& p, const std::optional<double>& youngs_modulus,
                        const std::optional<double>& poisson_ratio, const std::optional<double>& density);
/// Refuses (InputError naming the option) overrides outside their range, whatever the method:
/// --youngs-modulus finite > 0, --poisson-ratio in (−1, 0.5), --density finite > 0.
void check_material_overrides(const std::optional<double>& youngs_modulus, const std::optional<double>& poisson_ratio,
                              const std::optional<double>& density);
/// Refuses --gn-coefficient / --gt-coefficient / a law damping ratio outside the bond law's
/// ranges (dem/law_registry.hpp: finite and >= 0).
void check_law_options(const LawOptions& o);
/// Refuses a bond dashpot ratio ζ (--damping-ratio of the explicit tests) outside the bond law's range.
void check_bond_damping_ratio(double zeta);

/// Per-bond stiffnesses (dem::bond_stiffness, the formula of the DEM bond loop), capped by the
/// pair's Laguerre face where the laws ask for it (dem::face_cap_stiffness).
struct BondStiffnesses {
  std::vector<double> kn, kt, ktwist, kbend;  ///< N/m, N/m, N m, N m
  long face_capped = 0;  ///< intact bonds whose k_n or k_t is at the face cap
  long no_face = 0;      ///< intact bonds whose pair shares no face (capped at 0)
};
BondStiffnesses bond_stiffnesses(const Packing& p, const std::vector<dem::BondLaw>& laws);
/// Per bond, the area of the face its two particles share in the radical (Laguerre) tessellation
/// of the packing (geometry::laguerre_faces; m², 0 where they share none, +inf on the hull of an
/// open cell direction).
std::vector<double> bond_face_areas(const Packing& p);

/// Connected components of the intact bonds (spatial::find_clusters).
using Clusters = spatial::Clusters;
Clusters find_clusters(const Packing& p, const std::vector<Image>& image);

}  // namespace tomodem::mechanics
