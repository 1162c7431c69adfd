#pragma once
// The grains' markers and watershed on a distance map (own code, used by morph_itk.cpp).
#include "tomodem/image/volume.hpp"

namespace tomodem::image {

/// The markers of the grains: the regional maxima (`connectivity` 6 or 26, a flat image is one
/// maximum) of the h-maxima transform of `height` (its reconstruction by dilation, 6-connected,
/// from height - h; h rounded to float, as ITK's HMaximaImageFilter does), within the solid
/// (0/1). The same voxels as ITK's HMaximaImageFilter and RegionalMaximaImageFilter.
Mask grain_markers(const float* height, const Mask& solid, double h, int connectivity);

/// Floods `solid` from the labelled `markers` (> 0), the highest `height` first: Meyer's flooding
/// with a hierarchical queue, one first-in-first-out queue per distinct height. A voxel takes the
/// label of the voxel that reaches it first; the voxels of one height are taken in the order they
/// were reached, the markers first in raster order. Pore voxels stay 0, and so do solid voxels
/// no marker reaches through the solid. `connectivity` is 6 or 26.
Labels flood_from_markers(const float* height, const Mask& solid, const Labels& markers, int connectivity);

}  // namespace tomodem::image
