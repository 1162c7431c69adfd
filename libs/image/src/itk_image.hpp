#pragma once
// Conversions between tomodem grids and ITK images (voxel units: spacing 1, origin 0, so radii
// and sigmas passed to ITK filters are in voxels). Included only by the *_itk.cpp files.
#include <itkImage.h>

#include <algorithm>

#include "tomodem/image/volume.hpp"

namespace tomodem::image::itkb {

template <class P, class T>
typename itk::Image<P, 3>::Pointer to_voxel_image(const Grid<T>& g) {
  using Image = itk::Image<P, 3>;
  auto img = Image::New();
  typename Image::SizeType size;
  size[0] = g.dims.nx; size[1] = g.dims.ny; size[2] = g.dims.nz;
  img->SetRegions(typename Image::RegionType(size));
  img->Allocate();
  std::transform(g.v.begin(), g.v.end(), img->GetBufferPointer(), [](T x) { return static_cast<P>(x); });
  return img;
}

template <class T, class Image, class Like>
Grid<T> from_voxel_image(const Image* img, const Grid<Like>& like) {
  Grid<T> g;
  g.copy_geometry(like);
  g.v.resize(like.dims.count());
  const auto* p = img->GetBufferPointer();
  std::transform(p, p + g.v.size(), g.v.begin(), [](auto x) { return static_cast<T>(x); });
  return g;
}

}  // namespace tomodem::image::itkb
