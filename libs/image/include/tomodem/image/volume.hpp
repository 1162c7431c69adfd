#pragma once
// Volumes as plain tomodem types (no ITK/OpenCV/OpenVDB here: docs/architecture.md#code-conventions, P7).
// Index order: x fastest, then y, then z (ITK, MetaImage, TIFF stacks with z = slice);
// HDF5 datasets are (z, y, x). Physical position of voxel (i,j,k) = origin + (i,j,k)*spacing,
// in metres (ITK convention: the origin is the centre of the first voxel).
#include <array>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <string>
#include <vector>

#include "tomodem/core/names.hpp"

namespace tomodem::image {

struct Dims {
  std::size_t nx = 0, ny = 0, nz = 0;
  std::size_t count() const { return nx * ny * nz; }
  bool operator==(const Dims& o) const { return nx == o.nx && ny == o.ny && nz == o.nz; }
};

template <class T>
struct Grid {
  Dims dims;
  std::array<double, 3> spacing{1, 1, 1};  ///< m, per axis (x, y, z)
  std::array<double, 3> origin{0, 0, 0};   ///< m, centre of voxel (0,0,0)
  std::vector<T> v;
  Grid() = default;
  Grid(Dims d, T fill = T{}) : dims(d), v(d.count(), fill) {}
  std::size_t index(std::size_t x, std::size_t y, std::size_t z) const { return (z * dims.ny + y) * dims.nx + x; }
  T& at(std::size_t x, std::size_t y, std::size_t z) { return v[index(x, y, z)]; }
  const T& at(std::size_t x, std::size_t y, std::size_t z) const { return v[index(x, y, z)]; }
  template <class U> void copy_geometry(const Grid<U>& o) { dims = o.dims; spacing = o.spacing; origin = o.origin; }
};

using Volume = Grid<float>;     ///< grey values (any input type is converted to float on read)
using Mask = Grid<uint8_t>;     ///< 0/1, or small phase labels
using Labels = Grid<int32_t>;   ///< component or grain ids, 0 = background

/// An input's file format; automatic: from the extension (a pattern: a TIFF stack; a folder: a
/// DICOM series when it holds DICOM files, else a TIFF stack).
enum class VolumeFormat : uint8_t { automatic, tiff, mha, nrrd, nifti, raw, h5, dicom };
inline constexpr NameTable<VolumeFormat, 8> kVolumeFormatNames = {{{VolumeFormat::automatic, "auto"},
                                                                   {VolumeFormat::tiff, "tiff"},
                                                                   {VolumeFormat::mha, "mha"},
                                                                   {VolumeFormat::nrrd, "nrrd"},
                                                                   {VolumeFormat::nifti, "nifti"},
                                                                   {VolumeFormat::raw, "raw"},
                                                                   {VolumeFormat::h5, "h5"},
                                                                   {VolumeFormat::dicom, "dicom"}}};
inline const char* to_string(VolumeFormat f) { return name_of(kVolumeFormatNames, f); }

/// The voxel type of a raw file.
enum class RawType : uint8_t { uint8, int8, uint16, int16, uint32, int32, float32, float64 };
inline constexpr NameTable<RawType, 8> kRawTypeNames = {{{RawType::uint8, "uint8"},
                                                         {RawType::int8, "int8"},
                                                         {RawType::uint16, "uint16"},
                                                         {RawType::int16, "int16"},
                                                         {RawType::uint32, "uint32"},
                                                         {RawType::int32, "int32"},
                                                         {RawType::float32, "float32"},
                                                         {RawType::float64, "float64"}}};
inline const char* to_string(RawType t) { return name_of(kRawTypeNames, t); }
/// Bytes per voxel of a raw type.
std::size_t type_size(RawType t);

/// The byte order of a raw file's voxels.
enum class ByteOrder : uint8_t { little, big };
inline constexpr NameTable<ByteOrder, 2> kByteOrderNames = {{{ByteOrder::little, "little"}, {ByteOrder::big, "big"}}};
inline const char* to_string(ByteOrder b) { return name_of(kByteOrderNames, b); }

/// How to read an input (docs/segment.md, "Inputs").
struct ReadOptions {
  VolumeFormat format = VolumeFormat::automatic;
  // raw binary
  std::array<std::size_t, 3> raw_dims{0, 0, 0};  ///< nx, ny, nz
  RawType raw_type = RawType::uint8;
  ByteOrder byte_order = ByteOrder::little;
  std::size_t raw_header = 0;           ///< bytes to skip
  // HDF5
  std::string h5_dataset = "/volume";   ///< (z, y, x); spacing from its attribute "spacing" (x y z) if present,
                                        ///< in the file's root attribute `units` (m when absent)
  // voxel size
  std::array<double, 3> spacing{0, 0, 0};  ///< m; 0 = take from the header
  /// Metres per header length unit of a MetaImage/NRRD/NIfTI file that does not state its unit
  /// (header key `units`; tomodem writes "m"): 1e-3, the ITK/medical convention and what tomodem
  /// wrote before it stated the unit. A file that states its unit is read in that unit.
  double header_unit = 1e-3;
  // region of interest (voxels, after reading) and block-average downsampling
  bool has_roi = false;
  std::array<std::size_t, 6> roi{0, 0, 0, 0, 0, 0};  ///< x0, y0, z0, nx, ny, nz
  int downsample = 1;
  /// Memory the caller's pipeline needs per voxel of the volume it gets (after --roi and
  /// --downsample), the grey volume included; 0: only the reader's own. Checked against the
  /// machine's memory from the header's dimensions, before anything is allocated.
  double bytes_per_voxel = 0;
};

/// What the reader found, for the summary's provenance.
struct ReadInfo {
  std::string format;          ///< tiff-stack | tiff | mha | nrrd | nifti | raw | h5 | dicom
  std::string pixel_type;      ///< as stored: uint8, uint16, int16, float32, ...
  std::string spacing_source;  ///< header | --spacing
  std::string length_unit;     ///< the unit the file states (header key or HDF5 attribute `units`); "" = none
  std::vector<std::string> files;
  /// Grey values as read (before --roi and --downsample) and the range of the stored type
  /// (uint16: 0..65535); the type range is NaN where the file's type is not known (HDF5).
  double value_min = 0, value_max = 0;
  double type_min = std::numeric_limits<double>::quiet_NaN(), type_max = std::numeric_limits<double>::quiet_NaN();
};

/// The value range of a stored voxel type ("uint16" -> 0, 65535); NaNs for an unknown name.
std::array<double, 2> type_range(const std::string& pixel_type);

/// Reads a volume. `input` is a file, a folder of TIFF slices, or a pattern with * or ?
/// (slices sorted by name). InputError (exit 2) names the file and what is wrong: unknown
/// format, truncated or mis-sized raw, truncated MetaImage or multi-page TIFF, mixed slice
/// sizes or page types, a NaN or infinite voxel (with its index), missing voxel size, empty
/// volume, or dimensions whose memory (opt.bytes_per_voxel) the machine does not have.
Volume read_volume(const std::string& input, const ReadOptions& opt, ReadInfo* info = nullptr);

/// The files read_volume would read for `input` (a stack's slices, a .mhd and its data file), for
/// refusing outputs that would overwrite them. Nothing is read but headers and folder listings.
std::vector<std::string> input_files(const std::string& input, const ReadOptions& opt);

/// Refuses (InputError naming the option and the value) read options that are nonsense on their
/// own: --downsample < 1, a --header-unit or
/// spacing that is not finite and > 0, an empty --roi region, a --dataset not starting with '/'.
void check_read_options(const ReadOptions& opt);

/// The format read_volume reads `input` as: tiff-stack | tiff | mha | nrrd | nifti | raw | h5 | dicom.
std::string input_format(const std::string& input, const ReadOptions& opt);

/// An HDF5 input's voxel size and origin (m) as read_volume gives them: the dataset's `spacing`
/// and `origin` attributes (x y z) in the file's root attribute `units`, or opt.spacing, which
/// overrides them. InputError when neither gives a voxel size.
struct VolumeGeometry {
  std::array<double, 3> spacing{0, 0, 0}, origin{0, 0, 0};
  std::string spacing_source;  ///< header | --spacing
  std::string length_unit;     ///< the file's root attribute `units`; "" = none
};
VolumeGeometry h5_geometry(const std::string& path, const ReadOptions& opt);

/// Crop to [x0, x0+nx) × … and block-average by `factor` (origin and spacing follow).
Volume crop(const Volume& v, const std::array<std::size_t, 6>& roi);
Volume downsample(const Volume& v, int factor);

/// Parses a length with an optional unit: "60.7um", "0.06mm", "6e-5" (m), "3vox" (returns
/// -3: voxels, negative by convention). Throws InputError naming `option` on nonsense.
double parse_length(const std::string& option, const std::string& text);

// Writers used by the tools and tests (atomic: temporary name, then rename).
/// Grey volume in the format given by the extension: .mha .mhd .nrrd .nii .nii.gz .tif (multi-page),
/// .h5 (dataset /volume), .raw (bare little-endian), or a folder path ending in '/' (TIFF stack).
/// `as_uint16`: values are rounded and clamped to [0, 65535] first (else float32 where the format allows).
void write_volume(const std::string& path, const Volume& v, bool as_uint16);
void write_metaimage(const std::string& path, const Mask& m);    ///< .mha/.mhd (ITK), uint8
void write_metaimage(const std::string& path, const Labels& m);  ///< .mha/.mhd (ITK), int32

}  // namespace tomodem::image
