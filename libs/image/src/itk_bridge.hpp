#pragma once
// Private interface to the ITK translation units (io_itk.cpp, filters_itk.cpp, morph_itk.cpp):
// plain tomodem types only, so no other file includes ITK.
#include <functional>
#include <string>
#include <vector>

#include "tomodem/image/volume.hpp"

namespace tomodem::image::itkb {

/// The dimensions a file's header gives (nothing is allocated). A TIFF's page chain is walked
/// first (checks::check_tiff): not a TIFF, truncated, or pages that differ -> InputError.
/// Refuses anything but one grey component in 3-D (or 4-D with one time point).
Dims header_dims(const std::string& path);
/// Reads one file (TIFF single/multi-page, MetaImage, NRRD, NIfTI) as float; spacing/origin in
/// header units. info->pixel_type is set from the file's component type.
Volume read_file(const std::string& path, ReadInfo* info);
/// Reads 2-D slices as z; every slice's size is checked first (InputError naming the slice).
/// `dims` receives nx, ny (from the first slice) and nz (the number of files) before anything is
/// allocated; `before_alloc` runs then (the memory check).
Volume read_series(const std::vector<std::string>& files, ReadInfo* info, const std::function<void(Dims)>& before_alloc);
/// Reads the one DICOM series of `folder` (ITK GDCMSeriesFileNames + GDCMImageIO), slices ordered
/// along their normal; spacing and origin in mm (DICOM's unit). InputError naming the file when
/// the folder holds no or several series, a slice is unreadable, differs in size or pixel spacing,
/// or the slices are not evenly spaced (a missing or doubled slice). `before_alloc` as read_series.
Volume read_dicom(const std::string& folder, ReadInfo* info, const std::function<void(Dims)>& before_alloc);
/// Writes to exactly `path` (the extension picks the ITK ImageIO).
void write_file(const std::string& path, const Volume& v, bool as_uint16);
void write_series(const std::vector<std::string>& files, const Volume& v, bool as_uint16);
void write_file(const std::string& path, const Mask& m);
void write_file(const std::string& path, const Labels& m);

}  // namespace tomodem::image::itkb
