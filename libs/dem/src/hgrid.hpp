#pragma once
// Hierarchical grid neighbour search (Ogarko & Luding, Comput. Phys. Commun. 183 (2012) 931)
// for wide size distributions. Same output as the linked cells of Simulation::Impl: the CSR
// half list (for each i the pairs (j, image code) with i < j, and i == j once for the positive
// half of the images), image code (ix+1)*9 + (iy+1)*3 + (iz+1), a pair kept when
// |x_j + H·n − x_i| < r_i + r_j + extra (extra = skin + adhesive reach).
//
// Particles are sorted into levels by radius; level l has its own grid whose bins are at least
// 2 r_max(l) + extra wide. A particle searches its own level and every level of larger
// particles only (at most 3³ bins per level, since r_i ≤ r_max(h)), so a small particle never
// visits the many bins of a fine level from a coarse one and a big particle never scans a fine
// grid: cost O(N · levels) whatever the size ratio, where single-level linked cells sized by
// the largest sphere cost O(N · (R_max/R_min)³).
#include <cstdint>
#include <vector>

#include "tomodem/core/packing.hpp"
#include "tomodem/core/vec3.hpp"

namespace tomodem::dem {

/// Which neighbour search Simulation uses. `automatic` picks the hierarchical grid when the
/// size ratio reaches kHgridSizeRatio. The override is process-wide (tests and benchmarks);
/// the environment variable TOMODEM_NEIGHBOR_SEARCH=cells|hgrid sets it as well.
enum class NeighborSearch { automatic, linked_cells, hgrid };
void set_neighbor_search(NeighborSearch s);
NeighborSearch neighbor_search();

/// r_max / r_min from which `automatic` chooses the hierarchical grid (docs/pack.md: measured
/// break-even of the two searches).
inline constexpr double kHgridSizeRatio = 2.5;

/// Whether build_neighbors should use the hierarchical grid for these radii.
bool use_hgrid(const std::vector<double>& r);

/// Builds the half list. `shift` is the table of 27 image shifts H·n (n from the image code),
/// positions must be wrapped into the periodic cell already. The cut-off of a pair is
/// r_i + r_j + skin + reach, summed in that order (as the linked cells do, so both searches
/// keep exactly the same pairs). Outputs are replaced; each particle's pairs come sorted by
/// (j, image), so the list is the same for any thread count.
void hgrid_half_list(const std::vector<Vec3>& x, const std::vector<double>& r, const Cell& cell, const Vec3* shift,
                     double skin, double reach, std::vector<int32_t>& start, std::vector<int32_t>& j,
                     std::vector<uint8_t>& image, int threads = 1);

/// Levels the grid would use for these radii (reported by benchmarks): upper radius per level.
std::vector<double> hgrid_levels(const std::vector<double>& r);

}  // namespace tomodem::dem
