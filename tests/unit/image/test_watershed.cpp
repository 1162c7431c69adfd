// The grains' markers and watershed (flood.cpp, through grain_peaks and watershed_from_markers)
// against independent implementations of the same operations, ITK's HMaximaImageFilter,
// RegionalMaximaImageFilter and MorphologicalWatershedFromMarkers (what tomodem used before,
// issue 19), and against geometry: two equal balls part on their bisecting plane.
#include <gtest/gtest.h>

#include <itkImage.h>
#include <itkHMaximaImageFilter.h>
#include <itkMorphologicalWatershedFromMarkersImageFilter.h>
#include <itkRegionalMaximaImageFilter.h>
#include <itkSignedMaurerDistanceMapImageFilter.h>

#include <algorithm>

#include "tomodem/image/phantom.hpp"
#include "tomodem/image/segment.hpp"

using namespace tomodem::image;

namespace {

template <class P, class T>
typename itk::Image<P, 3>::Pointer to_itk(const Grid<T>& g) {
  auto img = itk::Image<P, 3>::New();
  typename itk::Image<P, 3>::SizeType size;
  size[0] = g.dims.nx;
  size[1] = g.dims.ny;
  size[2] = g.dims.nz;
  img->SetRegions(typename itk::Image<P, 3>::RegionType(size));
  img->Allocate();
  std::transform(g.v.begin(), g.v.end(), img->GetBufferPointer(), [](T x) { return static_cast<P>(x); });
  return img;
}

using FI = itk::Image<float, 3>;

// ITK's signed Maurer distance (inside positive), in voxels of the finest axis, as tomodem used
// it before issue 19 (now signed_contour_distance).
FI::Pointer itk_distance(const Mask& solid) {
  auto dist = itk::SignedMaurerDistanceMapImageFilter<itk::Image<uint8_t, 3>, FI>::New();
  auto in = to_itk<uint8_t>(solid);
  const double finest = std::min({solid.spacing[0], solid.spacing[1], solid.spacing[2]});
  itk::Image<uint8_t, 3>::SpacingType sp;
  for (unsigned a = 0; a < 3; ++a) sp[a] = solid.spacing[a] / finest;
  in->SetSpacing(sp);
  dist->SetInput(in);
  dist->SetInsideIsPositive(true);
  dist->SetSquaredDistance(false);
  dist->SetUseImageSpacing(true);
  dist->SetBackgroundValue(0);
  dist->Update();
  return dist->GetOutput();
}

// ITK's markers: the regional maxima of the h-maxima transform of the distance, in the solid.
Mask itk_peaks(const Mask& solid, double h, int connectivity) {
  auto hmax = itk::HMaximaImageFilter<FI, FI>::New();
  hmax->SetInput(itk_distance(solid));
  hmax->SetHeight(float(h));
  auto maxima = itk::RegionalMaximaImageFilter<FI, itk::Image<uint8_t, 3>>::New();
  maxima->SetInput(hmax->GetOutput());
  maxima->SetFullyConnected(connectivity == 26);
  maxima->SetFlatIsMaxima(true);
  maxima->SetForegroundValue(1);
  maxima->SetBackgroundValue(0);
  maxima->Update();
  Mask out;
  out.copy_geometry(solid);
  out.v.assign(maxima->GetOutput()->GetBufferPointer(), maxima->GetOutput()->GetBufferPointer() + solid.v.size());
  for (std::size_t i = 0; i < solid.v.size(); ++i) out.v[i] = out.v[i] && solid.v[i];
  return out;
}

// ITK's watershed: the whole volume flooded on -distance from the markers (pores last), the
// pores cut away.
Labels itk_watershed(const Mask& solid, const Labels& markers, int connectivity) {
  const FI::Pointer d = itk_distance(solid);
  auto neg = FI::New();
  neg->SetRegions(d->GetLargestPossibleRegion());
  neg->Allocate();
  for (std::size_t i = 0; i < solid.v.size(); ++i) neg->GetBufferPointer()[i] = -d->GetBufferPointer()[i];
  auto ws = itk::MorphologicalWatershedFromMarkersImageFilter<FI, itk::Image<int32_t, 3>>::New();
  ws->SetInput(neg);
  ws->SetMarkerImage(to_itk<int32_t>(markers));
  ws->SetMarkWatershedLine(false);
  ws->SetFullyConnected(connectivity == 26);
  ws->Update();
  Labels out;
  out.copy_geometry(solid);
  out.v.assign(ws->GetOutput()->GetBufferPointer(), ws->GetOutput()->GetBufferPointer() + solid.v.size());
  for (std::size_t i = 0; i < solid.v.size(); ++i)
    if (!solid.v[i]) out.v[i] = 0;
  return out;
}

Mask packing_solid(uint64_t seed) {
  PhantomOptions o;
  o.kind = PhantomKind::packing;
  o.n = 64;
  o.seed = seed;
  o.n_grains = 40;
  const Phantom p = make_phantom(o);
  Mask solid;
  solid.copy_geometry(p.truth);
  solid.v.resize(p.truth.v.size());
  for (std::size_t i = 0; i < solid.v.size(); ++i) solid.v[i] = p.truth.v[i] > 0;
  return solid;
}

}  // namespace

// The own signed distance against ITK's Maurer filter: every voxel equal on isotropic voxels
// (integer squared distances, exact in float on both sides); on anisotropic voxels ITK weighs,
// squares and sums the steps in float where we do it in double and round once, so the two part
// in the last bits (measured: up to 7.6e-6 relative at z spacing 1.7; bound 2e-5).
// The packings touch the volume's faces, and the slab checks a solid that fills whole planes.
TEST(Watershed, OwnSignedDistanceIsItksMaurerDistance) {
  for (uint64_t seed : {1, 2, 3})
    for (double sz : {1.0, 1.7}) {
      Mask solid = packing_solid(seed);
      solid.spacing = {1e-5, 1e-5, sz * 1e-5};
      const std::vector<float> ours = signed_contour_distance(solid);
      const FI::Pointer itk = itk_distance(solid);
      std::size_t differ = 0;
      double worst = 0;
      for (std::size_t i = 0; i < solid.v.size(); ++i) {
        const double a = ours[i], b = itk->GetBufferPointer()[i];
        differ += a != b;
        worst = std::max(worst, std::abs(a - b) / std::max(1.0, std::abs(b)));
      }
      if (sz == 1.0) {
        EXPECT_EQ(differ, 0u) << "seed " << seed;
      }
      EXPECT_LT(worst, 2e-5) << "seed " << seed << ", z spacing " << sz;
    }
  Mask slab(Dims{12, 10, 9});
  for (std::size_t i = 0; i < slab.v.size(); ++i) slab.v[i] = i / (12 * 10) < 4;  // z < 4 solid
  const std::vector<float> ours = signed_contour_distance(slab);
  const FI::Pointer itk = itk_distance(slab);
  for (std::size_t i = 0; i < slab.v.size(); ++i) ASSERT_EQ(ours[i], itk->GetBufferPointer()[i]) << "voxel " << i;
  EXPECT_EQ(ours[slab.index(5, 5, 0)], 3.0f);   // three planes above the contour plane z = 3
  EXPECT_EQ(ours[slab.index(5, 5, 6)], -3.0f);  // three planes above the solid
}

// The h-maxima transform and the regional maxima are defined without ties (a reconstruction and
// the plateaus with no greater neighbour): the same marker voxels as ITK's, for heights below,
// at and above the voxel size and both connectivities of the maxima.
TEST(Watershed, SameMarkersAsItksHMaximaAndRegionalMaxima) {
  for (uint64_t seed : {1, 2})
    for (double h : {0.5, 1.0, 2.5})
      for (int connectivity : {26, 6}) {
        const Mask solid = packing_solid(seed);
        GrainOptions go;
        go.h = h;
        go.connectivity = connectivity;
        const Mask ours = grain_peaks(solid, go), itk = itk_peaks(solid, h, connectivity);
        std::size_t differ = 0, peaks = 0;
        for (std::size_t i = 0; i < solid.v.size(); ++i) {
          differ += ours.v[i] != itk.v[i];
          peaks += itk.v[i];
        }
        EXPECT_GT(peaks, 20u);
        EXPECT_EQ(differ, 0u) << "seed " << seed << ", h " << h << ", " << connectivity << "-connected, of " << peaks << " marker voxels";
      }
}

// Both floods take the highest distance first and, within one height, the voxels in the order
// they were reached, the markers in raster order: the same labels voxel for voxel (ties
// included), for both connectivities, on three packings of touching spheres.
TEST(Watershed, SameGrainsAsItksFloodingOnPackings) {
  for (uint64_t seed : {1, 2, 3})
    for (int connectivity : {26, 6}) {
      const Mask solid = packing_solid(seed);
      GrainOptions go;
      go.connectivity = connectivity;
      int n = 0;
      const Labels markers = components(grain_peaks(solid, go), 26, &n);
      ASSERT_GT(n, 20);
      const Labels ours = watershed_from_markers(solid, markers, go), itk = itk_watershed(solid, markers, connectivity);
      std::size_t differ = 0, solid_voxels = 0, unlabelled = 0;
      for (std::size_t i = 0; i < solid.v.size(); ++i) {
        differ += ours.v[i] != itk.v[i];
        solid_voxels += solid.v[i];
        unlabelled += solid.v[i] && !ours.v[i];
      }
      EXPECT_EQ(differ, 0u) << "seed " << seed << ", " << connectivity << "-connected, of " << solid_voxels << " solid voxels";
      EXPECT_EQ(unlabelled, 0u);
    }
}

// Two equal balls whose centres lie 2a apart on x, cut by the plane between two voxel columns:
// by symmetry every voxel belongs to the ball on its side. Pores stay 0; a solid island without
// a marker stays 0 (nothing reaches it through the solid), whatever the connectivity.
TEST(Watershed, EqualBallsPartOnTheirBisectingPlane) {
  Mask solid(Dims{40, 24, 24});
  const double cy = 11.5, cz = 11.5, c1 = 13.5, c2 = 25.5, r = 8;  // mid-plane x = 19.5
  for (std::size_t z = 0; z < 24; ++z)
    for (std::size_t y = 0; y < 24; ++y)
      for (std::size_t x = 0; x < 40; ++x) {
        const double dy = y - cy, dz = z - cz, d1 = x - c1, d2 = x - c2;
        solid.v[solid.index(x, y, z)] = std::min(d1 * d1, d2 * d2) + dy * dy + dz * dz <= r * r;
      }
  solid.v[solid.index(38, 1, 1)] = 1;  // an island, far from both balls
  Labels markers(solid.dims, 0);
  markers.v[markers.index(13, 11, 11)] = 1;
  markers.v[markers.index(26, 12, 12)] = 2;
  for (int connectivity : {26, 6}) {
    GrainOptions go;
    go.connectivity = connectivity;
    const Labels L = watershed_from_markers(solid, markers, go);
    std::size_t wrong = 0, left = 0, right = 0;
    for (std::size_t z = 0; z < 24; ++z)
      for (std::size_t y = 0; y < 24; ++y)
        for (std::size_t x = 0; x < 40; ++x) {
          const std::size_t i = solid.index(x, y, z);
          const int32_t expect = !solid.v[i] || x == 38 ? 0 : x < 20 ? 1 : 2;
          wrong += L.v[i] != expect;
          left += L.v[i] == 1;
          right += L.v[i] == 2;
        }
    EXPECT_EQ(wrong, 0u) << connectivity << "-connected";
    EXPECT_EQ(left, right);
  }
}
