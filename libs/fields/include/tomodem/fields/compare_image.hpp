#pragma once
// Image and model side by side (docs/cg.md#image-and-model-side-by-side): the local solid
// fraction of a segmented scan and of the packing carved from it, coarse-grained with one kernel
// on one grid, their agreement, and the tortuosity of the scan next to the network's.
#include <cstdint>
#include <set>
#include <vector>

#include "tomodem/core/packing.hpp"
#include "tomodem/fields/cg.hpp"
#include "tomodem/network/image_transport.hpp"

namespace tomodem::fields {

/// CG solid fraction of a packing: the CG density with every particle's mass its volume (4/3 π r³).
std::vector<double> packing_solid_fraction(const Packing& packing, const Kernel& kernel, const GridSpec& grid,
                                           int threads);

/// CG solid fraction of a scan: every voxel whose label is in `solid` is a point of its volume at
/// its centre. The image is placed as tomodem-carve places it by default: its centre on the
/// cell's centre, scale 1 (voxel i of n at centre + (i + ½ − n/2)·spacing); voxels outside the
/// cell are left out (nothing wraps: a scan is not periodic).
std::vector<double> image_solid_fraction(const network::LabelImage& image, const std::set<int>& solid, const Cell& cell,
                                         const Kernel& kernel, const GridSpec& grid, int threads);

/// Pearson correlation, mean absolute difference and means of two fields over the nodes where
/// mask is 1 (all nodes when mask is empty).
struct FieldAgreement {
  double correlation = 0, mean_absolute_difference = 0, mean_a = 0, mean_b = 0;
  std::size_t nodes = 0;
};
FieldAgreement compare_fields(const std::vector<double>& a, const std::vector<double>& b,
                              const std::vector<uint8_t>& mask = {});

}  // namespace tomodem::fields
