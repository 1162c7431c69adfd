// ITK grey-level morphology: hysteresis by reconstruction (the grains are flood.cpp's).
#include <itkReconstructionByDilationImageFilter.h>

#include "itk_image.hpp"
#include "tomodem/core/error.hpp"
#include "tomodem/image/segment.hpp"

namespace tomodem::image {

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

}  // namespace tomodem::image
