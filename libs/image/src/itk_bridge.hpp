#pragma once
// Private interface to the ITK translation units (io_itk.cpp, filters_itk.cpp, morph_itk.cpp):
// plain tomodem types only, so no other file includes ITK.
#include <string>
#include <vector>

#include "tomodem/image/volume.hpp"

namespace tomodem::image::itkb {

/// Reads one file (TIFF single/multi-page, MetaImage, NRRD, NIfTI) as float; spacing/origin in
/// header units. info->pixel_type is set from the file's component type.
Volume read_file(const std::string& path, ReadInfo* info);
/// Reads 2-D slices as z; every slice's size is checked first (InputError naming the slice).
Volume read_series(const std::vector<std::string>& files, ReadInfo* info);
/// Writes to exactly `path` (the extension picks the ITK ImageIO).
void write_file(const std::string& path, const Volume& v, bool as_uint16);
void write_series(const std::vector<std::string>& files, const Volume& v, bool as_uint16);
void write_file(const std::string& path, const Mask& m);
void write_file(const std::string& path, const Labels& m);

}  // namespace tomodem::image::itkb
