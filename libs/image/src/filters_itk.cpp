// ITK smoothing and denoising (float images only).
#include <itkCurvatureAnisotropicDiffusionImageFilter.h>
#include <itkMultiThreaderBase.h>
#include <itkPatchBasedDenoisingImageFilter.h>
#include <itkSmoothingRecursiveGaussianImageFilter.h>

#include <omp.h>

#include <algorithm>

#include "itk_image.hpp"
#include "tomodem/core/error.hpp"
#include "tomodem/image/segment.hpp"

namespace tomodem::image {

using FI = itk::Image<float, 3>;

void set_threads(int n) {
  if (n <= 0) return;
  omp_set_num_threads(n);
  itk::MultiThreaderBase::SetGlobalDefaultNumberOfThreads(n);
  itk::MultiThreaderBase::SetGlobalMaximumNumberOfThreads(n);
}

// Voxel spacing relative to the finest axis (1 on it): the filters that use image spacing then
// see anisotropic voxels while their parameters stay in voxels of the finest axis.
template <class Image>
static void set_relative_spacing(Image* img, const Volume& v) {
  const double finest = std::min({v.spacing[0], v.spacing[1], v.spacing[2]});
  typename Image::SpacingType sp;
  for (unsigned a = 0; a < 3; ++a) sp[a] = v.spacing[a] / finest;
  img->SetSpacing(sp);
}

template <class Filter>
static Volume run_filter(const Volume& v, Filter* f) {
  auto in = itkb::to_voxel_image<float>(v);
  set_relative_spacing(in.GetPointer(), v);
  f->SetInput(in);
  try {
    f->Update();
  } catch (const itk::ExceptionObject& e) {
    throw RuntimeFailure(std::string("ITK filter failed: ") + e.GetDescription());
  }
  return itkb::from_voxel_image<float>(f->GetOutput(), v);
}

Volume gaussian(const Volume& v, double sigma) {
  if (!(sigma > 0)) throw InputError("", "--sigma", value_text(sigma), "must be > 0 (voxels)");
  using Filter = itk::SmoothingRecursiveGaussianImageFilter<FI, FI>;
  auto f = Filter::New();
  // sigma in voxels of the finest axis, the same length on each axis (image spacing is relative, so
  // ITK's physical sigma is this length; on an axis twice as coarse it spans half the voxels).
  typename Filter::SigmaArrayType sigmas;
  sigmas.Fill(sigma);
  f->SetSigmaArray(sigmas);
  return run_filter(v, f.GetPointer());
}

Volume anisotropic_diffusion(const Volume& v, int iterations, double conductance, double time_step) {
  if (iterations < 1) throw InputError("", "--iterations", std::to_string(iterations), "must be >= 1");
  auto f = itk::CurvatureAnisotropicDiffusionImageFilter<FI, FI>::New();
  f->SetNumberOfIterations(static_cast<unsigned>(iterations));
  f->SetTimeStep(time_step);
  f->SetConductanceParameter(conductance);
  return run_filter(v, f.GetPointer());
}

Volume nlm(const Volume& v, int patch_radius, int iterations) {
  if (patch_radius < 1) throw InputError("", "--filter-radius", std::to_string(patch_radius), "must be >= 1");
  auto f = itk::PatchBasedDenoisingImageFilter<FI, FI>::New();
  f->SetPatchRadius(static_cast<unsigned>(patch_radius));
  f->SetNumberOfIterations(static_cast<unsigned>(std::max(1, iterations)));
  f->SetNoiseModel(itk::PatchBasedDenoisingImageFilter<FI, FI>::NoiseModelEnum::GAUSSIAN);
  f->SetNoiseModelFidelityWeight(0.0);
  f->SetKernelBandwidthEstimation(true);
  return run_filter(v, f.GetPointer());
}

}  // namespace tomodem::image
