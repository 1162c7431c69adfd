// Format dispatch, bare raw and HDF5 readers, crop and downsampling. No third-party headers.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fnmatch.h>
#include <limits>
#include <fstream>
#include <sstream>

#include "file_checks.hpp"
#include "tomodem/core/units.hpp"
#include "itk_bridge.hpp"
#include "tomodem/core/error.hpp"
#include "tomodem/core/h5.hpp"
#include "tomodem/core/output.hpp"
#include "tomodem/core/packing_io.hpp"
#include "tomodem/core/tool.hpp"
#include "tomodem/image/volume.hpp"

namespace fs = std::filesystem;

namespace tomodem::image {
namespace {
/// A file that ITK wrote under a name of its own (it picks the format by the extension) becomes
/// the output's registered temporary, renamed with the run's other outputs.
void commit_written(const std::string& written, const std::string& final_path) {
  fs::rename(written, temporary_path(final_path));
  commit_output(final_path);
}

std::string lower(std::string s) {
  for (auto& c : s) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return s;
}
bool ends_with(const std::string& s, const std::string& e) {
  return s.size() >= e.size() && s.compare(s.size() - e.size(), e.size(), e) == 0;
}

// A DICOM file: "DICM" after the 128-byte preamble (PS3.10 7.1), or the .dcm extension.
bool is_dicom_file(const fs::path& p) {
  std::string ext = p.extension().string();
  for (auto& c : ext) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  if (ext == ".dcm") return true;
  std::ifstream in(p, std::ios::binary);
  char magic[4] = {};
  in.seekg(128);
  return in.read(magic, 4) && std::memcmp(magic, "DICM", 4) == 0;
}
bool holds_dicom(const std::string& dir) {
  std::error_code ec;
  for (const auto& e : fs::directory_iterator(dir, ec))
    if (e.is_regular_file() && is_dicom_file(e.path())) return true;
  return false;
}

std::string detect_format(const std::string& input) {
  if (input.find_first_of("*?") != std::string::npos) return "tiff-stack";
  if (fs::is_directory(input)) return holds_dicom(input) ? "dicom" : "tiff-stack";
  const std::string l = lower(input);
  if (ends_with(l, ".tif") || ends_with(l, ".tiff")) return "tiff";
  if (ends_with(l, ".mha") || ends_with(l, ".mhd")) return "mha";
  if (ends_with(l, ".nrrd") || ends_with(l, ".nhdr")) return "nrrd";
  if (ends_with(l, ".nii") || ends_with(l, ".nii.gz")) return "nifti";
  if (ends_with(l, ".raw") || ends_with(l, ".bin") || ends_with(l, ".vol")) return "raw";
  if (ends_with(l, ".h5") || ends_with(l, ".hdf5") || ends_with(l, ".nxs")) return "h5";
  if (ends_with(l, ".zarr") || ends_with(l, ".am"))
    throw InputError(input, "format", fs::path(input).extension().string(),
                     "Zarr and AmiraMesh are not supported; convert to MetaImage, TIFF or HDF5");
  throw InputError(input, "format", fs::path(input).extension().string(),
                   "unknown format (known: TIFF stack/folder, .tif, .mha/.mhd, .nrrd, .nii, .raw with --raw-dims, .h5)");
}

std::vector<std::string> stack_files(const std::string& input) {
  std::string dir = input, pattern = "*";
  if (!fs::is_directory(input)) {
    dir = fs::path(input).parent_path().string();
    if (dir.empty()) dir = ".";
    pattern = fs::path(input).filename().string();
  }
  if (!fs::is_directory(dir)) throw InputError(input, "", "", "no such folder");
  std::vector<std::string> files;
  for (const auto& e : fs::directory_iterator(dir)) {
    if (!e.is_regular_file()) continue;
    const std::string name = e.path().filename().string();
    const std::string l = lower(name);
    if (pattern == "*" && !(ends_with(l, ".tif") || ends_with(l, ".tiff"))) continue;
    if (fnmatch(pattern.c_str(), name.c_str(), 0) == 0) files.push_back(e.path().string());
  }
  std::sort(files.begin(), files.end());
  if (files.empty())
    throw InputError(input, "", "", fs::is_directory(input) ? "no TIFF slices (*.tif, *.tiff) in this folder"
                                                            : "no file matches this pattern");
  return files;
}


template <class T>
void convert(const char* p, std::size_t n, bool swap, std::vector<float>& out) {
  for (std::size_t i = 0; i < n; ++i) {
    unsigned char b[sizeof(T)];
    std::memcpy(b, p + i * sizeof(T), sizeof(T));
    if (swap) std::reverse(b, b + sizeof(T));
    T val;
    std::memcpy(&val, b, sizeof(T));
    out[i] = static_cast<float>(val);
  }
}

std::string dims_text(const Dims& d) {
  return std::to_string(d.nx) + "x" + std::to_string(d.ny) + "x" + std::to_string(d.nz);
}

// The memory a read of `full` voxels and the caller's pipeline need, before anything is allocated:
// the float volume and the reader's own buffer (extra_bpv per voxel), the cropped and the
// downsampled copies, and the pipeline on the volume it gets.
void check_read_memory(const std::string& file, const std::string& field, const Dims& full, double extra_bpv,
                       const ReadOptions& o) {
  const double nfull = double(full.nx) * double(full.ny) * double(full.nz);
  double nx = double(full.nx), ny = double(full.ny), nz = double(full.nz);
  if (o.has_roi) {
    nx = std::min(nx, double(o.roi[3]));
    ny = std::min(ny, double(o.roi[4]));
    nz = std::min(nz, double(o.roi[5]));
  }
  const double f = std::max(1, o.downsample);
  const double nfinal = std::floor(nx / f) * std::floor(ny / f) * std::floor(nz / f);
  const double need = std::max({nfull * (4 + extra_bpv), nfull * 4 + nx * ny * nz * 4, nfinal * o.bytes_per_voxel});
  char what[200];
  std::snprintf(what, sizeof what, "a %s volume (%.3g voxels)", dims_text(full).c_str(), nfull);
  std::string w = what;
  if (o.bytes_per_voxel > 0) {
    std::snprintf(what, sizeof what, " with this pipeline (%.0f bytes per voxel", o.bytes_per_voxel);
    w += what;
    w += (o.has_roi || o.downsample > 1) ? " of the " + std::to_string(std::size_t(nfinal)) + " voxels after --roi/--downsample)" : ")";
  }
  check_memory_request(need, file, field, dims_text(full), w);
}

Volume read_raw(const std::string& path, const ReadOptions& o, ReadInfo* info) {
  const auto [nx, ny, nz] = o.raw_dims;
  if (nx == 0 || ny == 0 || nz == 0)
    throw InputError(path, "--raw-dims", "", "a raw file needs its dimensions (--raw-dims NX,NY,NZ)");
  const std::size_t bytes = type_size(o.raw_type);
  check_read_memory(path, "--raw-dims", Dims{nx, ny, nz}, 0, o);
  const std::uintmax_t expected = o.raw_header + nx * ny * nz * bytes;
  std::error_code ec;
  const std::uintmax_t size = fs::file_size(path, ec);
  if (ec) throw InputError(path, "", "", "cannot read file size: " + ec.message());
  if (fs::is_directory(path)) throw InputError(path, "", "", "is a folder, not a raw file");
  if (size < expected)
    throw InputError(path, "size", std::to_string(size) + " bytes",
                     "truncated: dims " + std::to_string(nx) + "x" + std::to_string(ny) + "x" + std::to_string(nz) + " " +
                         to_string(o.raw_type) + " need " + std::to_string(expected) + " bytes");
  if (size > expected)
    throw InputError(path, "size", std::to_string(size) + " bytes",
                     "does not match dims " + std::to_string(nx) + "x" + std::to_string(ny) + "x" + std::to_string(nz) +
                         " " + to_string(o.raw_type) + " (" + std::to_string(expected) + " bytes); check --raw-dims/--raw-type/--raw-header");
  std::ifstream in(path, std::ios::binary);
  in.seekg(static_cast<std::streamoff>(o.raw_header));
  Volume v(Dims{nx, ny, nz});
  const bool swap = (o.byte_order == ByteOrder::big);  // x86: little-endian host
  const std::size_t slab = nx * ny;
  std::vector<char> buf(slab * bytes);
  for (std::size_t z = 0; z < nz; ++z) {
    in.read(buf.data(), static_cast<std::streamsize>(buf.size()));
    if (!in) throw InputError(path, "data", "slice " + std::to_string(z), "read failed (truncated?)");
    std::vector<float> out(slab);
    switch (o.raw_type) {
      case RawType::uint8: convert<uint8_t>(buf.data(), slab, false, out); break;
      case RawType::int8: convert<int8_t>(buf.data(), slab, false, out); break;
      case RawType::uint16: convert<uint16_t>(buf.data(), slab, swap, out); break;
      case RawType::int16: convert<int16_t>(buf.data(), slab, swap, out); break;
      case RawType::uint32: convert<uint32_t>(buf.data(), slab, swap, out); break;
      case RawType::int32: convert<int32_t>(buf.data(), slab, swap, out); break;
      case RawType::float32: convert<float>(buf.data(), slab, swap, out); break;
      case RawType::float64: convert<double>(buf.data(), slab, swap, out); break;
    }
    std::copy(out.begin(), out.end(), v.v.begin() + static_cast<std::ptrdiff_t>(z * slab));
  }
  if (info) info->pixel_type = to_string(o.raw_type);
  return v;
}

// The dataset's spacing and origin attributes in m (the root attribute `units`; metres when
// absent); returns whether it has a spacing.
bool h5_attributes(const h5::File& f, const std::string& path, const ReadOptions& o, VolumeGeometry& g) {
  const bool has_geometry = f.has_attr(o.h5_dataset, "spacing") || f.has_attr(o.h5_dataset, "origin");
  // Lengths in the file's unit (root attribute `units`); files without it were written in metres.
  const double u = has_geometry ? h5_length_unit(f, o.spacing[0] == 0) : 1.0;
  if (f.has_attr("/", "units")) g.length_unit = f.attr_string("/", "units");
  bool has_spacing = false;
  if (f.has_attr(o.h5_dataset, "spacing")) {
    const auto s = f.attr_doubles(o.h5_dataset, "spacing");
    if (s.size() != 3) throw InputError(path, o.h5_dataset + "@spacing", "", "expected 3 values (x, y, z) in m");
    g.spacing = {s[0] * u, s[1] * u, s[2] * u};
    has_spacing = true;
  }
  if (f.has_attr(o.h5_dataset, "origin")) {
    const auto s = f.attr_doubles(o.h5_dataset, "origin");
    if (s.size() == 3) g.origin = {s[0] * u, s[1] * u, s[2] * u};
  }
  return has_spacing;
}

Volume read_h5(const std::string& path, const ReadOptions& o, bool* has_spacing, std::string* unit) {
  h5::File f(path, h5::File::Mode::read);
  std::vector<std::size_t> d = f.shape(o.h5_dataset);  // InputError naming the dataset when missing
  if (d.size() != 3)
    throw InputError(path, o.h5_dataset, std::to_string(d.size()) + "-D", "expected a 3-D dataset (z, y, x)");
  // The dataset is read as double, then converted: 8 bytes per voxel on top of the volume.
  check_read_memory(path, o.h5_dataset, Dims{d[2], d[1], d[0]}, 8, o);
  const auto data = f.read_double(o.h5_dataset, &d);
  if (d.size() != 3 || data.size() != d[0] * d[1] * d[2])
    throw InputError(path, o.h5_dataset, std::to_string(data.size()) + " values", "does not match its shape");
  Volume v(Dims{d[2], d[1], d[0]});
  for (std::size_t i = 0; i < data.size(); ++i) v.v[i] = static_cast<float>(data[i]);
  VolumeGeometry g;
  *has_spacing = h5_attributes(f, path, o, g);
  v.spacing = g.spacing;
  v.origin = g.origin;
  *unit = g.length_unit;
  return v;
}

}  // namespace

std::size_t type_size(RawType t) {
  switch (t) {
    case RawType::uint8: case RawType::int8: return 1;
    case RawType::uint16: case RawType::int16: return 2;
    case RawType::uint32: case RawType::int32: case RawType::float32: return 4;
    case RawType::float64: return 8;
  }
  return 1;
}

std::array<double, 2> type_range(const std::string& t) {
  if (t == "uint8") return {0, 255};
  if (t == "int8") return {-128, 127};
  if (t == "uint16") return {0, 65535};
  if (t == "int16") return {-32768, 32767};
  if (t == "uint32") return {0, 4294967295.0};
  if (t == "int32") return {-2147483648.0, 2147483647.0};
  if (t == "float32") return {-double(std::numeric_limits<float>::max()), double(std::numeric_limits<float>::max())};
  if (t == "float64") return {-std::numeric_limits<double>::max(), std::numeric_limits<double>::max()};
  const double nan = std::numeric_limits<double>::quiet_NaN();
  return {nan, nan};
}

double parse_length(const std::string& option, const std::string& text) {
  // Voxels are the image tools' own unit; physical lengths go through core's one parser.
  double x = 0;
  std::string unit;
  const bool number = split_number_unit(text, x, unit);
  unit = lower(unit);
  const bool voxels = number && (unit == "vox" || unit == "voxel" || unit == "voxels");
  const double v = voxels ? x : tomodem::parse_length(option, text);
  if (!(v > 0) || !std::isfinite(v))
    throw InputError("", option, text, "must be finite and > 0 (a length such as 60.7um, or voxels such as 3vox)");
  return voxels ? -v : v;
}

Volume crop(const Volume& v, const std::array<std::size_t, 6>& r) {
  const Dims& d = v.dims;
  if (r[3] == 0 || r[4] == 0 || r[5] == 0 || r[0] + r[3] > d.nx || r[1] + r[4] > d.ny || r[2] + r[5] > d.nz)
    throw InputError("", "--roi",
                     std::to_string(r[0]) + "," + std::to_string(r[1]) + "," + std::to_string(r[2]) + "," +
                         std::to_string(r[3]) + "," + std::to_string(r[4]) + "," + std::to_string(r[5]),
                     "region outside the volume (" + std::to_string(d.nx) + "x" + std::to_string(d.ny) + "x" +
                         std::to_string(d.nz) + ") or empty");
  Volume out(Dims{r[3], r[4], r[5]});
  out.spacing = v.spacing;
  for (int k = 0; k < 3; ++k) out.origin[k] = v.origin[k] + static_cast<double>(r[k]) * v.spacing[k];
  for (std::size_t z = 0; z < r[5]; ++z)
    for (std::size_t y = 0; y < r[4]; ++y)
      std::copy_n(&v.at(r[0], r[1] + y, r[2] + z), r[3], &out.at(0, y, z));
  return out;
}

Volume downsample(const Volume& v, int f) {
  if (f <= 1) return v;
  const std::size_t F = static_cast<std::size_t>(f);
  Dims d{v.dims.nx / F, v.dims.ny / F, v.dims.nz / F};
  if (d.count() == 0) throw InputError("", "--downsample", std::to_string(f), "larger than the volume");
  Volume out(d);
  for (int k = 0; k < 3; ++k) {
    out.spacing[k] = v.spacing[k] * f;
    out.origin[k] = v.origin[k] + 0.5 * (f - 1) * v.spacing[k];  // centre of the first block
  }
  const double inv = 1.0 / static_cast<double>(F * F * F);
#pragma omp parallel for schedule(static)
  for (std::ptrdiff_t z = 0; z < static_cast<std::ptrdiff_t>(d.nz); ++z)
    for (std::size_t y = 0; y < d.ny; ++y)
      for (std::size_t x = 0; x < d.nx; ++x) {
        double s = 0;
        for (std::size_t c = 0; c < F; ++c)
          for (std::size_t b = 0; b < F; ++b)
            for (std::size_t a = 0; a < F; ++a) s += v.at(x * F + a, y * F + b, z * F + c);
        out.at(x, y, static_cast<std::size_t>(z)) = static_cast<float>(s * inv);
      }
  return out;
}

void check_read_options(const ReadOptions& o) {
  if (o.downsample < 1) throw InputError("", "--downsample", std::to_string(o.downsample), "must be an integer >= 1");
  if (!(o.header_unit > 0) || !std::isfinite(o.header_unit))
    throw InputError("", "--header-unit", std::to_string(o.header_unit), "must be finite and > 0 (metres per header unit, e.g. 0.001)");
  for (double s : o.spacing)
    if (!(s >= 0) || !std::isfinite(s)) throw InputError("", "--spacing", value_text(s), "must be finite and > 0");
  if (o.has_roi && (o.roi[3] == 0 || o.roi[4] == 0 || o.roi[5] == 0))
    throw InputError("", "--roi", std::to_string(o.roi[3]) + "x" + std::to_string(o.roi[4]) + "x" + std::to_string(o.roi[5]),
                     "an empty region: NX, NY and NZ must be >= 1");
  if (o.h5_dataset.empty() || o.h5_dataset[0] != '/')
    throw InputError("", "--dataset", o.h5_dataset, "an HDF5 dataset path starts with '/' (e.g. /volume)");
}

std::vector<std::string> input_files(const std::string& input, const ReadOptions& o) {
  const std::string format = input_format(input, o);
  if (format == "tiff-stack") return stack_files(input);
  if (format == "dicom") {  // every file of the folder (the series is found when it is read)
    std::vector<std::string> files;
    std::error_code ec;
    for (const auto& e : fs::directory_iterator(input, ec))
      if (e.is_regular_file()) files.push_back(e.path().string());
    return files;
  }
  std::vector<std::string> files{input};
  if (format == "mha" && fs::is_regular_file(input)) {
    const std::string data = checks::metaimage_data_file(input);
    if (!data.empty()) files.push_back(data);
  }
  return files;
}

namespace {
// NaN or infinite grey values break every threshold and histogram: refused with the first voxel.
void check_finite(const Volume& v, const std::string& file, const std::string& field, bool zyx) {
  const auto it = std::find_if(v.v.begin(), v.v.end(), [](float x) { return !std::isfinite(x); });
  if (it == v.v.end()) return;
  const std::size_t i = std::size_t(it - v.v.begin()), x = i % v.dims.nx, y = (i / v.dims.nx) % v.dims.ny,
                    z = i / (v.dims.nx * v.dims.ny);
  const std::size_t bad = std::size_t(std::count_if(v.v.begin(), v.v.end(), [](float q) { return !std::isfinite(q); }));
  const std::string where = zyx ? "[" + std::to_string(z) + "," + std::to_string(y) + "," + std::to_string(x) + "] (z,y,x)"
                                : "(" + std::to_string(x) + "," + std::to_string(y) + "," + std::to_string(z) + ") (x,y,z)";
  throw InputError(file, field, std::isnan(*it) ? "NaN" : (*it > 0 ? "inf" : "-inf"),
                   "voxel " + where + " is not a finite number (" + std::to_string(bad) +
                       " such voxels); a grey volume must hold finite values: fill or mask them first");
}
}  // namespace

std::string input_format(const std::string& input, const ReadOptions& o) {
  const std::string format = (o.format == VolumeFormat::automatic) ? detect_format(input) : to_string(o.format);
  if (format == "tiff" && (input.find_first_of("*?") != std::string::npos || fs::is_directory(input))) return "tiff-stack";
  return format;
}

VolumeGeometry h5_geometry(const std::string& path, const ReadOptions& o) {
  h5::File f(path, h5::File::Mode::read);
  VolumeGeometry g;
  const bool header_spacing = h5_attributes(f, path, o, g);
  if (o.spacing[0] > 0) {  // as read_volume: --spacing wins; the origin stays only with a header spacing
    g.spacing = o.spacing;
    if (!header_spacing) g.origin = {0, 0, 0};
    g.spacing_source = "--spacing";
  } else if (header_spacing) {
    for (double s : g.spacing)
      if (!(s > 0) || !std::isfinite(s)) throw InputError(path, "spacing", value_text(s), "invalid voxel size in header");
    g.spacing_source = "header";
  } else {
    throw InputError(path, "spacing", "", "h5 carries no voxel size; give --spacing (e.g. 60.7um)");
  }
  return g;
}

Volume read_volume(const std::string& input, const ReadOptions& o, ReadInfo* info_out) {
  check_read_options(o);
  ReadInfo info;
  info.format = input_format(input, o);
  const bool folder_format = info.format == "tiff-stack" || info.format == "dicom";
  if (info.format == "dicom" && !fs::is_directory(input))
    throw InputError(input, "", "", "a DICOM series is read from its folder: give the folder that holds the slices");
  if (!folder_format && !fs::exists(input)) throw InputError(input, "", "", "no such file");
  if (!folder_format && fs::is_directory(input))
    throw InputError(input, "", "", "is a folder; a folder is read as a stack of TIFF slices or a DICOM series only (--format tiff, dicom or auto)");
  if (!folder_format) {
    std::ifstream probe(input, std::ios::binary);
    if (!probe) throw InputError(input, "", "", "cannot open the file for reading (permissions?)");
    std::error_code ec;
    if (fs::file_size(input, ec) == 0) throw InputError(input, "size", "0 bytes", "the file is empty");
  }
  Volume v;
  bool header_spacing = false;  // spacing present in the file, in header units (ITK) or m (h5)
  std::string field = "data";
  if (info.format == "tiff-stack") {
    info.files = stack_files(input);
    v = itkb::read_series(info.files, &info, [&](Dims d) { check_read_memory(input, "slices", d, 0, o); });
  } else if (info.format == "tiff" || info.format == "mha" || info.format == "nrrd" || info.format == "nifti") {
    info.files = {input};
    check_read_memory(input, info.format == "mha" ? "DimSize" : "dims", itkb::header_dims(input), 0, o);
    v = itkb::read_file(input, &info);
    header_spacing = info.format != "tiff";  // TIFF resolution tags are not a voxel size
    if (header_spacing) {
      // The unit the header states wins (tomodem writes "m"); a file that states none is read in
      // --header-unit (mm by default: the ITK convention, and tomodem's own files before).
      double unit = o.header_unit;
      if (!info.length_unit.empty()) {
        unit = metres_per_unit(info.length_unit);
        if (!(unit > 0)) throw InputError(input, "units", info.length_unit, "unknown length unit in the header (m, mm, um, nm)");
      } else if (info.format != "nifti" && o.spacing[0] == 0) {  // NIfTI states its unit itself (ITK gives mm)
        char u[32];
        std::snprintf(u, sizeof u, "%g", o.header_unit);
        warn(input + ": the header states no length unit (key 'units'): spacing and origin read as " + u +
             " m per unit (--header-unit; the ITK convention, and how tomodem wrote files before they stated the unit)");
      }
      for (int k = 0; k < 3; ++k) { v.spacing[k] *= unit; v.origin[k] *= unit; }
    }
  } else if (info.format == "dicom") {
    v = itkb::read_dicom(input, &info, [&](Dims d) { check_read_memory(input, "slices", d, 0, o); });
    header_spacing = true;
    info.length_unit = "mm";  // DICOM states every length in mm (PS3.3 C.7.6.2)
    for (int k = 0; k < 3; ++k) { v.spacing[k] *= 1e-3; v.origin[k] *= 1e-3; }
  } else if (info.format == "raw") {
    info.files = {input};
    v = read_raw(input, o, &info);
  } else if (info.format == "h5") {
    info.files = {input};
    v = read_h5(input, o, &header_spacing, &info.length_unit);
    info.pixel_type = "float64 (as read)";
    field = o.h5_dataset;
  } else {
    throw InputError(input, "--format", to_string(o.format), "unknown format (" + names_of(kVolumeFormatNames) + ")");
  }
  if (v.dims.count() == 0) throw InputError(input, "dims", "0", "empty volume");
  check_finite(v, input, field, info.format == "h5");
  {  // the values as read and the stored type's range (16- and 32-bit scans use a part of it)
    const auto [lo, hi] = std::minmax_element(v.v.begin(), v.v.end());
    info.value_min = *lo;
    info.value_max = *hi;
    const auto range = type_range(info.pixel_type);
    info.type_min = range[0];
    info.type_max = range[1];
    if ((info.pixel_type == "uint32" || info.pixel_type == "int32") && std::max(std::abs(info.value_min), std::abs(info.value_max)) > 16777216.0)
      warn(input + ": 32-bit integer values beyond 2^24 = 16777216 are rounded to float32 (24-bit mantissa)");
  }
  if (o.spacing[0] > 0) {
    v.spacing = o.spacing;
    if (!header_spacing) v.origin = {0, 0, 0};
    info.spacing_source = "--spacing";
  } else if (header_spacing) {
    for (double s : v.spacing)
      if (!(s > 0) || !std::isfinite(s)) throw InputError(input, "spacing", value_text(s), "invalid voxel size in header");
    info.spacing_source = "header";
  } else {
    throw InputError(input, "spacing", "", info.format + " carries no voxel size; give --spacing (e.g. 60.7um)");
  }
  if (o.has_roi) v = crop(v, o.roi);
  v = downsample(v, o.downsample);
  if (info_out) *info_out = info;
  return v;
}

void write_volume(const std::string& path, const Volume& v, bool as_uint16) {
  const std::string l = lower(path);
  if (!path.empty() && path.back() == '/') {  // TIFF stack: write a folder under a temporary name, then rename
    const std::string dir = path.substr(0, path.size() - 1);
    // The stack replaces the folder: only an earlier stack's slices may be in it (never a user's files).
    if (fs::exists(dir)) {
      if (!fs::is_directory(dir)) throw InputError("", "-o", path, "is a file, not a folder");
      for (const auto& e : fs::directory_iterator(dir)) {
        const std::string name = e.path().filename().string();
        if (!(e.is_regular_file() && name.size() == 14 && name.rfind("slice", 0) == 0 && ends_with(name, ".tif")))
          throw InputError("", "-o", path, "the folder holds " + name + ", which is not a slice of an earlier stack: "
                                           "choose a new or empty folder");
      }
    }
    const std::string tmp = temporary_path(dir);
    fs::remove_all(tmp);
    fs::create_directories(tmp);
    std::vector<std::string> files;
    for (std::size_t z = 0; z < v.dims.nz; ++z) {
      char name[32];
      std::snprintf(name, sizeof name, "/slice%05zu.tif", z);
      files.push_back(tmp + name);
    }
    try {
      itkb::write_series(files, v, as_uint16);
    } catch (...) {
      fs::remove_all(tmp);
      throw;
    }
    // A folder is renamed at once (the old stack goes first, and a folder cannot wait among the
    // run's file temporaries, which are removed with unlink).
    fs::remove_all(dir);  // checked above: only slices of an earlier stack
    commit_output(dir, Commit::now);
    return;
  }
  if (ends_with(l, ".h5")) {
    const std::string tmp = temporary_path(path);
    {
      h5::File f(tmp, h5::File::Mode::create);
      std::vector<double> d(v.v.size());
      for (std::size_t i = 0; i < d.size(); ++i)
        d[i] = as_uint16 ? std::clamp(std::round(static_cast<double>(v.v[i])), 0.0, 65535.0) : v.v[i];
      f.write("/volume", d, {v.dims.nz, v.dims.ny, v.dims.nx});
      f.set_attr("/volume", "spacing", std::vector<double>(v.spacing.begin(), v.spacing.end()));
      f.set_attr("/volume", "origin", std::vector<double>(v.origin.begin(), v.origin.end()));
      write_provenance(f);
      f.close();  // a full disk is found here, before the rename
    }
    commit_output(path);
    return;
  }
  if (ends_with(l, ".raw")) {  // bare little-endian, no header: read back with --raw-dims/--raw-type
    const std::string tmp = temporary_path(path);
    {
      std::ofstream out(tmp, std::ios::binary);
      for (float x : v.v) {
        if (as_uint16) {
          const auto u = static_cast<uint16_t>(std::clamp(std::round(static_cast<double>(x)), 0.0, 65535.0));
          out.write(reinterpret_cast<const char*>(&u), 2);
        } else {
          out.write(reinterpret_cast<const char*>(&x), 4);
        }
      }
      out.close();  // the last buffer is written here: a full disk shows now, before the rename
      if (!out) throw RuntimeFailure("cannot write " + path + " (disk full or a file-size limit?)");
    }
    commit_output(path);
    return;
  }
  // ITK formats: the temporary name keeps the extension so ITK picks the right ImageIO.
  const fs::path p(path);
  std::string ext = p.extension().string();
  if (ends_with(l, ".nii.gz")) ext = ".nii.gz";
  if (ext == ".mhd") {  // header + .raw pair: write both in a temporary folder, then move the pair
    const std::string tmpdir = temporary_path(path) + ".d";
    fs::create_directories(tmpdir);
    const std::string stem = p.stem().string();
    try {
      itkb::write_file(tmpdir + "/" + stem + ".mhd", v, as_uint16);
    } catch (...) {
      std::error_code ec;
      fs::remove_all(tmpdir, ec);
      throw;
    }
    const fs::path dir = p.parent_path().empty() ? fs::path(".") : p.parent_path();
    commit_written(tmpdir + "/" + stem + ".raw", (dir / (stem + ".raw")).string());
    commit_written(tmpdir + "/" + stem + ".mhd", path);
    fs::remove_all(tmpdir);
    return;
  }
  const std::string tmp = temporary_path(path) + ext;
  try {
    itkb::write_file(tmp, v, as_uint16);
    commit_written(tmp, path);
  } catch (...) {
    std::error_code ec;
    fs::remove(tmp, ec);
    throw;
  }
}

namespace {
template <class G>
void write_meta(const std::string& path, const G& m) {
  const std::string l = lower(path);
  if (!ends_with(l, ".mha") && !ends_with(l, ".mhd"))
    throw InputError("", "--mha", path, "MetaImage output needs a .mha or .mhd name");
  const fs::path p(path);
  if (ends_with(l, ".mhd")) {
    const std::string tmpdir = temporary_path(path) + ".d";
    fs::create_directories(tmpdir);
    const std::string stem = p.stem().string();
    try {
      itkb::write_file(tmpdir + "/" + stem + ".mhd", m);
    } catch (...) {
      std::error_code ec;
      fs::remove_all(tmpdir, ec);
      throw;
    }
    const fs::path dir = p.parent_path().empty() ? fs::path(".") : p.parent_path();
    commit_written(tmpdir + "/" + stem + ".raw", (dir / (stem + ".raw")).string());
    commit_written(tmpdir + "/" + stem + ".mhd", path);
    fs::remove_all(tmpdir);
    return;
  }
  const std::string tmp = temporary_path(path) + ".mha";
  try {
    itkb::write_file(tmp, m);
    commit_written(tmp, path);
  } catch (...) {
    std::error_code ec;
    fs::remove(tmp, ec);
    throw;
  }
}
}  // namespace

void write_metaimage(const std::string& path, const Mask& m) { write_meta(path, m); }
void write_metaimage(const std::string& path, const Labels& m) { write_meta(path, m); }

}  // namespace tomodem::image
