// ITK readers and writers: the only I/O translation unit that includes ITK.
// Pixel types instantiated: float (reading, float output), uint16, uint8, int32 (writing).
#include <itkImage.h>
#include <itkImageFileReader.h>
#include <itkImageFileWriter.h>
#include <itkGDCMImageIO.h>
#include <itkGDCMSeriesFileNames.h>
#include <itkImageIOBase.h>
#include <itkImageSeriesReader.h>
#include <itkImageIOFactory.h>
#include <itkImageSeriesWriter.h>
#include <itkImportImageFilter.h>
#include <itkMetaDataObject.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <filesystem>

#include "file_checks.hpp"
#include "itk_bridge.hpp"
#include "tomodem/core/error.hpp"

namespace tomodem::image::itkb {
namespace {

using FloatImage = itk::Image<float, 3>;
// Files written by tomodem carry spacing and origin in metres and say so in a header key "units"
// (MetaImage and NRRD keep unknown keys). NIfTI states its own unit, which ITK writes as mm.
constexpr const char* kUnitKey = "units";
double header_units_per_m(const std::string& path) {
  std::string l = path;
  for (auto& c : l) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  const bool nifti = (l.size() > 4 && l.compare(l.size() - 4, 4, ".nii") == 0) ||
                     (l.size() > 7 && l.compare(l.size() - 7, 7, ".nii.gz") == 0);
  return nifti ? 1e3 : 1.0;
}

itk::ImageIOBase::Pointer probe(const std::string& path) {
  auto io = itk::ImageIOFactory::CreateImageIO(path.c_str(), itk::ImageIOFactory::IOFileModeEnum::ReadMode);
  if (!io) throw InputError(path, "format", "", "no reader recognises this file (corrupt or unknown format)");
  try {
    io->SetFileName(path);
    io->ReadImageInformation();
  } catch (const itk::ExceptionObject& e) {
    throw InputError(path, "header", "", std::string("cannot read: ") + e.GetDescription());
  }
  return io;
}

std::string lower_ext(const std::string& path) {
  std::string e = std::filesystem::path(path).extension().string();
  for (auto& c : e) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return e;
}
bool is_tiff_name(const std::string& path) { const auto e = lower_ext(path); return e == ".tif" || e == ".tiff"; }
bool is_meta_name(const std::string& path) { const auto e = lower_ext(path); return e == ".mha" || e == ".mhd"; }

std::string dims_text(const itk::ImageIOBase* io) {
  std::string s;
  for (unsigned k = 0; k < io->GetNumberOfDimensions(); ++k) s += (k ? "x" : "") + std::to_string(io->GetDimensions(k));
  return s;
}

// One grey component, 3-D (or 4-D with one time point); the checks every volume file passes.
void check_volume_header(const std::string& path, const itk::ImageIOBase* io) {
  if (io->GetNumberOfComponents() != 1)
    throw InputError(path, "pixel", std::to_string(io->GetNumberOfComponents()) + " components", "expected a grey volume");
  const unsigned nd = io->GetNumberOfDimensions();
  if (nd != 3 && !(nd == 4 && io->GetDimensions(3) == 1))
    throw InputError(path, "dimensions", std::to_string(nd) + " (" + dims_text(io) + ")",
                     "expected a 3-D volume (a 2-D image is one slice: give a folder or pattern of slices)");
}

std::string component_name(const itk::ImageIOBase* io) {
  using C = itk::IOComponentEnum;
  switch (io->GetComponentType()) {
    case C::UCHAR: return "uint8";
    case C::CHAR: return "int8";
    case C::USHORT: return "uint16";
    case C::SHORT: return "int16";
    case C::UINT: return "uint32";
    case C::INT: return "int32";
    case C::FLOAT: return "float32";
    case C::DOUBLE: return "float64";
    default: return itk::ImageIOBase::GetComponentTypeAsString(io->GetComponentType());
  }
}

template <class P, class T>
typename itk::Image<P, 3>::Pointer to_itk(const Grid<T>& g, P (*conv)(T), double per_m = 1.0) {
  using Image = itk::Image<P, 3>;
  auto img = Image::New();
  typename Image::SizeType size;
  size[0] = g.dims.nx; size[1] = g.dims.ny; size[2] = g.dims.nz;
  img->SetRegions(typename Image::RegionType(size));
  typename Image::SpacingType sp;
  typename Image::PointType org;
  for (int k = 0; k < 3; ++k) { sp[k] = g.spacing[k] * per_m; org[k] = g.origin[k] * per_m; }
  img->SetSpacing(sp);
  img->SetOrigin(org);
  itk::EncapsulateMetaData<std::string>(img->GetMetaDataDictionary(), kUnitKey, per_m == 1.0 ? "m" : "mm");
  img->Allocate();
  P* out = img->GetBufferPointer();
  for (std::size_t i = 0; i < g.v.size(); ++i) out[i] = conv(g.v[i]);
  return img;
}

uint16_t to_u16(float x) { return static_cast<uint16_t>(std::clamp(std::round(static_cast<double>(x)), 0.0, 65535.0)); }
float to_f(float x) { return x; }
uint8_t to_u8(uint8_t x) { return x; }
int32_t to_i32(int32_t x) { return x; }

template <class Image>
void write_image(const std::string& path, const Image* img) {
  auto w = itk::ImageFileWriter<Image>::New();
  w->SetFileName(path);
  w->SetInput(img);
  w->SetUseCompression(false);
  try {
    w->Update();
  } catch (const itk::ExceptionObject& e) {
    throw RuntimeFailure("cannot write " + path + ": " + e.GetDescription());
  }
}

}  // namespace

Dims header_dims(const std::string& path) {
  std::size_t pages = 0;
  if (is_tiff_name(path)) pages = checks::check_tiff(path).pages;
  auto io = probe(path);
  check_volume_header(path, io);
  const Dims d{io->GetDimensions(0), io->GetDimensions(1), io->GetDimensions(2)};
  if (pages && d.nz != pages)
    throw InputError(path, "pages", std::to_string(d.nz), "the TIFF reader sees " + std::to_string(d.nz) + " of the file's " +
                                                            std::to_string(pages) + " pages");
  return d;
}

Volume read_file(const std::string& path, ReadInfo* info) {
  std::size_t pages = 0;
  if (is_tiff_name(path)) pages = checks::check_tiff(path).pages;
  auto io = probe(path);
  check_volume_header(path, io);
  if (pages && io->GetDimensions(2) != pages)
    throw InputError(path, "pages", std::to_string(io->GetDimensions(2)),
                     "the TIFF reader sees " + std::to_string(io->GetDimensions(2)) + " of the file's " + std::to_string(pages) + " pages");
  // A MetaImage whose data is shorter than its header says is read by ITK without an error.
  if (is_meta_name(path)) checks::check_metaimage(path, io->GetImageSizeInBytes(), dims_text(io));
  {  // and so is a truncated NIfTI
    std::string l = path;
    for (auto& c : l) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
    if (l.size() > 4 && (l.compare(l.size() - 4, 4, ".nii") == 0 || (l.size() > 7 && l.compare(l.size() - 7, 7, ".nii.gz") == 0)))
      checks::check_nifti(path, io->GetImageSizeInBytes(), dims_text(io));
  }
  if (info) info->pixel_type = component_name(io);
  // Read in slabs of about 64 MiB of float straight into the volume: where the ImageIO can stream
  // (uncompressed MetaImage, NRRD, NIfTI, TIFF strips) no second full-size copy is made and the
  // file-type buffer is one slab. Other files are read whole on the first slab and copied.
  auto r = itk::ImageFileReader<FloatImage>::New();
  r->SetFileName(path);
  r->SetImageIO(io);
  const auto fail = [&](const itk::ExceptionObject& e) {
    return InputError(path, "data", "", std::string("cannot read (truncated or corrupt?): ") + e.GetDescription());
  };
  try {
    r->UpdateOutputInformation();
  } catch (const itk::ExceptionObject& e) {
    throw fail(e);
  }
  FloatImage* img = r->GetOutput();
  const auto size = img->GetLargestPossibleRegion().GetSize();
  Volume v(Dims{size[0], size[1], size[2]});
  const std::size_t plane = v.dims.nx * v.dims.ny;
  const std::size_t slab = std::max<std::size_t>(1, (std::size_t(64) << 20) / std::max<std::size_t>(1, plane * sizeof(float)));
  for (std::size_t z0 = 0; z0 < v.dims.nz; z0 += slab) {
    const std::size_t nz = std::min(slab, v.dims.nz - z0);
    FloatImage::RegionType want;
    want.SetIndex({0, 0, itk::IndexValueType(z0)});
    want.SetSize({size[0], size[1], nz});
    img->SetRequestedRegion(want);
    try {
      img->Update();
    } catch (const itk::ExceptionObject& e) {
      throw fail(e);
    }
    const auto have = img->GetBufferedRegion();
    if (!have.IsInside(want) || have.GetSize(0) != size[0] || have.GetSize(1) != size[1])
      throw RuntimeFailure("ITK returned a region other than the slab asked for while reading " + path);
    const std::size_t offset = (z0 - std::size_t(have.GetIndex(2))) * plane;
    std::copy_n(img->GetBufferPointer() + offset, nz * plane, v.v.data() + z0 * plane);
  }
  for (int k = 0; k < 3; ++k) {
    v.spacing[k] = img->GetSpacing()[k];
    v.origin[k] = img->GetOrigin()[k];
  }
  if (info) {
    std::string unit;
    if (itk::ExposeMetaData<std::string>(io->GetMetaDataDictionary(), kUnitKey, unit)) {
      while (!unit.empty() && std::isspace(static_cast<unsigned char>(unit.back()))) unit.pop_back();
      while (!unit.empty() && std::isspace(static_cast<unsigned char>(unit.front()))) unit.erase(unit.begin());
      info->length_unit = unit.empty() ? "(empty)" : unit;
    }
  }
  return v;
}

Volume read_series(const std::vector<std::string>& files, ReadInfo* info, const std::function<void(Dims)>& before_alloc) {
  std::size_t nx = 0, ny = 0;
  for (std::size_t i = 0; i < files.size(); ++i) {
    if (is_tiff_name(files[i])) {
      const auto t = checks::check_tiff(files[i]);
      if (t.pages > 1)
        throw InputError(files[i], "pages", std::to_string(t.pages), "a stack needs single-page slices");
    }
    auto io = probe(files[i]);
    const unsigned nd = io->GetNumberOfDimensions();
    const std::size_t sx = io->GetDimensions(0), sy = nd > 1 ? io->GetDimensions(1) : 1;
    if (nd > 2 && io->GetDimensions(2) > 1)
      throw InputError(files[i], "pages", std::to_string(io->GetDimensions(2)), "a stack needs single-page slices");
    if (io->GetNumberOfComponents() != 1)
      throw InputError(files[i], "pixel", std::to_string(io->GetNumberOfComponents()) + " components", "expected grey slices");
    if (i == 0) {
      nx = sx; ny = sy;
      if (info) info->pixel_type = component_name(io);
    } else if (sx != nx || sy != ny) {
      throw InputError(files[i], "slice size", std::to_string(sx) + "x" + std::to_string(sy),
                       "differs from the first slice " + files[0] + " (" + std::to_string(nx) + "x" + std::to_string(ny) +
                           "): mixed slice sizes");
    }
  }
  // Slice by slice into the volume (no full-size ITK image and copy). The voxel size of a stack
  // comes from --spacing (TIFF resolution tags are not one), so only the values are taken.
  using Slice = itk::Image<float, 2>;
  if (before_alloc) before_alloc(Dims{nx, ny, files.size()});
  Volume v(Dims{nx, ny, files.size()});
  for (std::size_t i = 0; i < files.size(); ++i) {
    auto r = itk::ImageFileReader<Slice>::New();
    r->SetFileName(files[i]);
    try {
      r->Update();
    } catch (const itk::ExceptionObject& e) {
      throw InputError(files[i], "data", "", std::string("cannot read the slice: ") + e.GetDescription());
    }
    const auto got = r->GetOutput()->GetBufferedRegion().GetSize();
    if (got[0] != nx || got[1] != ny)
      throw InputError(files[i], "slice size", std::to_string(got[0]) + "x" + std::to_string(got[1]), "differs from its header");
    std::copy_n(r->GetOutput()->GetBufferPointer(), nx * ny, v.v.data() + i * nx * ny);
  }
  return v;
}

namespace {
// Geometry of one DICOM file of a series, from its header (GDCM), in mm.
struct DicomSlice {
  std::size_t nx = 0, ny = 0, frames = 1;
  double position = 0;  ///< along the slice normal
  double dx = 0, dy = 0;
};
DicomSlice dicom_slice(const std::string& file) {
  auto io = itk::GDCMImageIO::New();
  try {
    io->SetFileName(file);
    io->ReadImageInformation();
  } catch (const itk::ExceptionObject& e) {
    throw InputError(file, "header", "", std::string("not a readable DICOM file: ") + e.GetDescription());
  }
  if (io->GetNumberOfComponents() != 1)
    throw InputError(file, "pixel", std::to_string(io->GetNumberOfComponents()) + " components", "expected grey slices");
  DicomSlice s;
  s.nx = io->GetDimensions(0);
  s.ny = io->GetNumberOfDimensions() > 1 ? io->GetDimensions(1) : 1;
  s.frames = io->GetNumberOfDimensions() > 2 ? io->GetDimensions(2) : 1;
  s.dx = io->GetSpacing(0);
  s.dy = io->GetNumberOfDimensions() > 1 ? io->GetSpacing(1) : 0;
  const auto normal = io->GetDirection(2);
  for (unsigned a = 0; a < 3; ++a) s.position += io->GetOrigin(a) * normal[a];
  return s;
}

// Every slice of the series the same size and pixel spacing, and the slices evenly spaced along
// their normal: a missing, doubled or misplaced slice would otherwise be read as a smooth volume.
void check_dicom_slices(const std::vector<std::string>& files, std::size_t& nx, std::size_t& ny) {
  std::vector<DicomSlice> s;
  for (const auto& f : files) s.push_back(dicom_slice(f));
  nx = s[0].nx;
  ny = s[0].ny;
  for (std::size_t k = 0; k < s.size(); ++k) {
    if (s[k].frames > 1 && files.size() > 1)
      throw InputError(files[k], "frames", std::to_string(s[k].frames), "a multi-frame file among single slices");
    if (s[k].nx != nx || s[k].ny != ny)
      throw InputError(files[k], "Rows/Columns", std::to_string(s[k].nx) + "x" + std::to_string(s[k].ny),
                       "differs from the first slice " + files[0] + " (" + std::to_string(nx) + "x" + std::to_string(ny) + ")");
    if (std::abs(s[k].dx - s[0].dx) > 1e-6 * s[0].dx || std::abs(s[k].dy - s[0].dy) > 1e-6 * s[0].dy)
      throw InputError(files[k], "PixelSpacing", std::to_string(s[k].dx) + "\\" + std::to_string(s[k].dy),
                       "differs from the first slice's " + std::to_string(s[0].dx) + "\\" + std::to_string(s[0].dy) + " mm");
  }
  if (s.size() < 2) return;
  std::vector<double> gaps;
  for (std::size_t k = 0; k + 1 < s.size(); ++k) gaps.push_back(s[k + 1].position - s[k].position);
  std::vector<double> sorted = gaps;
  std::nth_element(sorted.begin(), sorted.begin() + std::ptrdiff_t(sorted.size() / 2), sorted.end());
  const double gap = sorted[sorted.size() / 2];
  // 1 %: scanners write positions to 0.001 mm or better; a missing slice doubles a gap.
  for (std::size_t k = 0; k < gaps.size(); ++k)
    if (!(std::abs(gap) > 0) || std::abs(gaps[k] - gap) > 0.01 * std::abs(gap))
      throw InputError(files[k + 1], "ImagePositionPatient", std::to_string(s[k + 1].position) + " mm along the slice normal",
                       "is " + std::to_string(gaps[k]) + " mm from the previous slice " + files[k] + ", the series' other slices " +
                           std::to_string(gap) + " mm apart: a slice is missing, doubled or out of place");
}
}  // namespace

Volume read_dicom(const std::string& folder, ReadInfo* info, const std::function<void(Dims)>& before_alloc) {
  auto names = itk::GDCMSeriesFileNames::New();
  std::vector<std::string> uids;
  try {
    names->SetUseSeriesDetails(true);
    names->SetDirectory(folder);
    uids = names->GetSeriesUIDs();
  } catch (const itk::ExceptionObject& e) {
    throw InputError(folder, "series", "", std::string("cannot list the DICOM series: ") + e.GetDescription());
  }
  if (uids.empty()) throw InputError(folder, "series", "", "no DICOM series in the folder (no readable .dcm files)");
  if (uids.size() > 1) {
    std::string list;
    for (const auto& u : uids) list += (list.empty() ? "" : ", ") + u + " (" + std::to_string(names->GetFileNames(u).size()) + " files)";
    throw InputError(folder, "series", std::to_string(uids.size()) + " series",
                     "the folder holds several DICOM series: " + list + "; give each series a folder of its own");
  }
  const std::vector<std::string> files = names->GetFileNames(uids[0]);  // ordered along the slice normal by GDCM
  std::size_t nx = 0, ny = 0;
  check_dicom_slices(files, nx, ny);
  auto io = itk::GDCMImageIO::New();
  io->SetFileName(files[0]);
  io->ReadImageInformation();
  const std::size_t nz = files.size() > 1 ? files.size() : std::size_t(io->GetNumberOfDimensions() > 2 ? io->GetDimensions(2) : 1);
  if (before_alloc) before_alloc(Dims{nx, ny, nz});
  auto r = itk::ImageSeriesReader<FloatImage>::New();
  r->SetImageIO(io);
  r->SetFileNames(files);
  try {
    r->Update();
  } catch (const itk::ExceptionObject& e) {
    throw InputError(folder, "data", "", std::string("cannot read the DICOM series (truncated or corrupt slice?): ") + e.GetDescription());
  }
  const FloatImage* img = r->GetOutput();
  const auto size = img->GetLargestPossibleRegion().GetSize();
  Volume v(Dims{size[0], size[1], size[2]});
  std::copy_n(img->GetBufferPointer(), v.v.size(), v.v.data());
  for (unsigned k = 0; k < 3; ++k) {
    v.spacing[k] = img->GetSpacing()[k];  // mm
    v.origin[k] = img->GetOrigin()[k];
  }
  if (info) {
    info->pixel_type = component_name(io);
    info->files = files;
  }
  return v;
}

void write_file(const std::string& path, const Volume& v, bool as_uint16) {
  const double u = header_units_per_m(path);
  if (as_uint16) write_image(path, to_itk<uint16_t, float>(v, to_u16, u).GetPointer());
  else write_image(path, to_itk<float, float>(v, to_f, u).GetPointer());
}

void write_series(const std::vector<std::string>& files, const Volume& v, bool as_uint16) {
  auto run = [&](auto img) {
    using Image = typename decltype(img)::ObjectType;
    using Slice = itk::Image<typename Image::PixelType, 2>;
    auto w = itk::ImageSeriesWriter<Image, Slice>::New();
    w->SetInput(img);
    w->SetFileNames(files);
    try {
      w->Update();
    } catch (const itk::ExceptionObject& e) {
      throw RuntimeFailure("cannot write the TIFF stack: " + std::string(e.GetDescription()));
    }
  };
  if (as_uint16) run(to_itk<uint16_t, float>(v, to_u16));
  else run(to_itk<float, float>(v, to_f));
}

void write_file(const std::string& path, const Mask& m) {
  write_image(path, to_itk<uint8_t, uint8_t>(m, to_u8, header_units_per_m(path)).GetPointer());
}
void write_file(const std::string& path, const Labels& m) {
  write_image(path, to_itk<int32_t, int32_t>(m, to_i32, header_units_per_m(path)).GetPointer());
}

}  // namespace tomodem::image::itkb
