// ITK grey-level morphology: hysteresis by reconstruction, Maurer distance, h-maxima, watershed.
#include <itkHMaximaImageFilter.h>
#include <itkMorphologicalWatershedFromMarkersImageFilter.h>
#include <itkReconstructionByDilationImageFilter.h>
#include <itkRegionalMaximaImageFilter.h>
#include <itkSignedMaurerDistanceMapImageFilter.h>

#include <algorithm>

#include "itk_image.hpp"
#include "tomodem/core/progress.hpp"
#include "tomodem/core/error.hpp"
#include "tomodem/image/segment.hpp"

namespace tomodem::image {

using FI = itk::Image<float, 3>;
using UI = itk::Image<uint8_t, 3>;
using LI = itk::Image<int32_t, 3>;

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

Labels watershed_grains(const Mask& solid, const GrainOptions& opt, int* count) {
  auto dist = itk::SignedMaurerDistanceMapImageFilter<UI, FI>::New();
  // Distances in voxels of the finest axis, each axis weighted by its spacing (anisotropic scans).
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
  auto hmax = itk::HMaximaImageFilter<FI, FI>::New();
  hmax->SetInput(dist->GetOutput());
  hmax->SetHeight(opt.h);
  auto maxima = itk::RegionalMaximaImageFilter<FI, UI>::New();
  maxima->SetInput(hmax->GetOutput());
  maxima->SetFullyConnected(opt.connectivity == 26);
  maxima->SetFlatIsMaxima(true);
  maxima->SetForegroundValue(1);
  maxima->SetBackgroundValue(0);
  // Progress on stderr (unless -q): the distance map and its maxima are the first half of the
  // work, the watershed the second (measured on the demo scan: about equal).
  Progress bar("grain separation", 1.0);
  maxima->AddObserver(itk::ProgressEvent(), [&](const itk::EventObject&) {
    bar.update(0.5 * maxima->GetProgress(), "distance map and maxima");
  });
  maxima->Update();
  Mask peaks = itkb::from_voxel_image<uint8_t>(maxima->GetOutput(), solid);
  for (std::size_t i = 0; i < peaks.v.size(); ++i) peaks.v[i] = peaks.v[i] && solid.v[i];
  int n = 0;
  Labels markers = components(peaks, 26, &n);
  // Watershed of -distance from the markers; the pore space is cut away afterwards.
  const FI* d = dist->GetOutput();
  auto neg = FI::New();
  neg->SetRegions(d->GetLargestPossibleRegion());
  neg->Allocate();
  const std::size_t N = solid.v.size();
  for (std::size_t i = 0; i < N; ++i) neg->GetBufferPointer()[i] = -d->GetBufferPointer()[i];
  auto ws = itk::MorphologicalWatershedFromMarkersImageFilter<FI, LI>::New();
  ws->SetInput(neg);
  ws->SetMarkerImage(itkb::to_voxel_image<int32_t>(markers));
  ws->SetMarkWatershedLine(false);
  ws->SetFullyConnected(opt.connectivity == 26);
  ws->AddObserver(itk::ProgressEvent(), [&](const itk::EventObject&) {
    bar.update(0.5 + 0.5 * ws->GetProgress(), "watershed");
  });
  ws->Update();
  bar.finish(std::to_string(n) + " grains");
  Labels out = itkb::from_voxel_image<int32_t>(ws->GetOutput(), solid);
  for (std::size_t i = 0; i < N; ++i)
    if (!solid.v[i]) out.v[i] = 0;
  if (count) *count = n;
  return out;
}

}  // namespace tomodem::image
