// ITK grey-level morphology: hysteresis by reconstruction, the Maurer distance of the grains
// (their markers and watershed are flood.cpp's).
#include <itkReconstructionByDilationImageFilter.h>
#include <itkSignedMaurerDistanceMapImageFilter.h>

#include <algorithm>

#include "flood.hpp"
#include "itk_image.hpp"
#include "tomodem/core/progress.hpp"
#include "tomodem/core/error.hpp"
#include "tomodem/image/segment.hpp"

namespace tomodem::image {

using FI = itk::Image<float, 3>;
using UI = itk::Image<uint8_t, 3>;

Mask hysteresis(const Volume& v, double low, double high) {
  if (!(low <= high)) throw InputError("", "--levels", std::to_string(low) + "," + std::to_string(high), "need low <= high");
  Mask marker = threshold(v, high), mask = threshold(v, low);
  auto f = itk::ReconstructionByDilationImageFilter<UI, UI>::New();
  f->SetMarkerImage(itkb::to_voxel_image<uint8_t>(marker));
  f->SetMaskImage(itkb::to_voxel_image<uint8_t>(mask));
  f->SetFullyConnected(true);
  f->Update();
  return itkb::from_voxel_image<uint8_t>(f->GetOutput(), v);
}

namespace {

// The signed Maurer distance of the solid (inside positive), in voxels of the finest axis, each
// axis weighted by its spacing (anisotropic scans).
FI::Pointer solid_distance(const Mask& solid) {
  auto dist = itk::SignedMaurerDistanceMapImageFilter<UI, FI>::New();
  auto in = itkb::to_voxel_image<uint8_t>(solid);
  const double finest = std::min({solid.spacing[0], solid.spacing[1], solid.spacing[2]});
  UI::SpacingType sp;
  for (unsigned a = 0; a < 3; ++a) sp[a] = solid.spacing[a] / finest;
  in->SetSpacing(sp);
  dist->SetInput(in);
  dist->SetInsideIsPositive(true);
  dist->SetSquaredDistance(false);
  dist->SetUseImageSpacing(true);
  dist->SetBackgroundValue(0);
  dist->Update();
  FI::Pointer d = dist->GetOutput();
  d->DisconnectPipeline();
  return d;
}

// The h-maxima's regional maxima of the distance, inside the solid (0/1; flood.cpp).
Mask peaks_of(FI* d, const Mask& solid, const GrainOptions& opt, Progress* bar) {
  if (bar) bar->update(0.25, "maxima");
  return grain_markers(d->GetBufferPointer(), solid, opt.h, opt.connectivity);
}

// Watershed of -distance from the markers, restricted to the solid (flood.cpp).
Labels flood(const FI* d, const Mask& solid, const Labels& markers, const GrainOptions& opt, Progress* bar) {
  if (bar) bar->update(0.5, "watershed");
  return flood_from_markers(d->GetBufferPointer(), solid, markers, opt.connectivity);
}

}  // namespace

Labels watershed_grains(const Mask& solid, const GrainOptions& opt, int* count) {
  // Progress on stderr (unless -q): the distance map and its maxima are the first half of the
  // work, the watershed the second (measured on the demo scan: about equal).
  Progress bar("grain separation", 1.0);
  const FI::Pointer d = solid_distance(solid);
  int n = 0;
  const Labels markers = components(peaks_of(d, solid, opt, &bar), 26, &n);
  Labels out = flood(d, solid, markers, opt, &bar);
  bar.finish(std::to_string(n) + " grains");
  if (count) *count = n;
  return out;
}

Mask grain_peaks(const Mask& solid, const GrainOptions& opt) { return peaks_of(solid_distance(solid), solid, opt, nullptr); }

Labels watershed_from_markers(const Mask& solid, const Labels& markers, const GrainOptions& opt) {
  return flood(solid_distance(solid), solid, markers, opt, nullptr);
}

}  // namespace tomodem::image
