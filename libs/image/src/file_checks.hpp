#pragma once
// Checks of a file's structure before a library reads it, so a truncated or inconsistent file is
// refused (InputError naming the file, the field and the value) instead of being read in part:
// ITK reads a truncated MetaImage, NIfTI or multi-page TIFF without an error (OpenVDB files:
// check_vdb_file in outputs.hpp). No third-party headers.
#include <cstddef>
#include <cstdint>
#include <string>

namespace tomodem::image::checks {

/// What a TIFF's pages hold (all pages equal, else InputError).
struct TiffPages {
  std::size_t pages = 0, width = 0, height = 0;
};
/// Walks the IFD chain of a TIFF (classic or BigTIFF): refuses a file that is not a TIFF, an IFD
/// or a strip/tile outside the file (truncated), and pages that differ in size or sample type.
TiffPages check_tiff(const std::string& path);

/// MetaImage (.mha with LOCAL data, or .mhd + .raw/.zraw): refuses data holding fewer bytes than
/// DimSize x element size x channels, and compressed data that does not inflate to that size.
/// `needed`: the bytes of data the header describes (ITK's image size in bytes), `dims_text` its
/// DimSize for the message. Returns the data file ("" when it is the header itself).
std::string check_metaimage(const std::string& path, std::uint64_t needed, const std::string& dims_text);
/// The data file a MetaImage header names ("" for LOCAL, LIST or a pattern).
std::string metaimage_data_file(const std::string& path);

/// NIfTI-1/2 (.nii, .nii.gz): refuses data shorter than vox_offset + `needed` bytes (ITK reads a
/// truncated NIfTI without an error), and a gzip stream that is cut short or corrupt.
void check_nifti(const std::string& path, std::uint64_t needed, const std::string& dims_text);

}  // namespace tomodem::image::checks
