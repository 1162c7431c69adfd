// DICOM series input (issue 21 item 7): a small series written here with ITK's GDCM writer, read by
// tomodem and compared with the same volume written and read as raw; malformed series are refused
// with the file and what is wrong (InputError, exit 2 in the tools).
#include <gtest/gtest.h>

#include <itkGDCMImageIO.h>
#include <itkImage.h>
#include <itkImageFileWriter.h>
#include <itkMetaDataObject.h>

#include <nlohmann/json.hpp>

#include <filesystem>
#include <fstream>

#include "tomodem/core/error.hpp"
#include "tomodem/image/tools.hpp"
#include "tomodem/image/volume.hpp"

namespace fs = std::filesystem;
using namespace tomodem::image;

namespace {
constexpr std::size_t NX = 16, NY = 12, NZ = 6;
constexpr double kPixelMm = 0.5, kSliceMm = 1.25;

fs::path tmpdir(const std::string& name) {
  const fs::path p = fs::temp_directory_path() / ("tomodem_dicom_" + name);
  fs::remove_all(p);
  fs::create_directories(p);
  return p;
}

// 16-bit values that differ in every voxel, so a reordered or shifted slice cannot go unseen.
uint16_t value(std::size_t x, std::size_t y, std::size_t z) { return uint16_t(1000 + x + 20 * y + 300 * z); }

// One file per slice, each a 1-slice image at its own position (ImagePositionPatient), sharing
// the study and series UIDs, the way a scanner writes a series.
void write_series(const fs::path& dir, const std::string& series_uid, std::size_t first = 0, std::size_t count = NZ) {
  using Image = itk::Image<uint16_t, 3>;
  for (std::size_t z = first; z < first + count; ++z) {
    auto img = Image::New();
    Image::SizeType size;
    size[0] = NX; size[1] = NY; size[2] = 1;
    img->SetRegions(Image::RegionType(size));
    img->Allocate();
    for (std::size_t y = 0; y < NY; ++y)
      for (std::size_t x = 0; x < NX; ++x) img->GetBufferPointer()[y * NX + x] = value(x, y, z);
    Image::SpacingType sp;
    sp[0] = kPixelMm; sp[1] = kPixelMm; sp[2] = kSliceMm;
    img->SetSpacing(sp);
    Image::PointType org;
    org[0] = -4.0; org[1] = 2.0; org[2] = 10.0 + double(z) * kSliceMm;
    img->SetOrigin(org);
    auto io = itk::GDCMImageIO::New();
    io->KeepOriginalUIDOn();
    auto& dict = img->GetMetaDataDictionary();
    itk::EncapsulateMetaData<std::string>(dict, "0008|0060", "CT");
    itk::EncapsulateMetaData<std::string>(dict, "0028|0004", "MONOCHROME2");
    itk::EncapsulateMetaData<std::string>(dict, "0020|000d", "1.2.826.0.1.3680043.9.7133.1");
    itk::EncapsulateMetaData<std::string>(dict, "0020|000e", series_uid);
    itk::EncapsulateMetaData<std::string>(dict, "0008|0018", series_uid + "." + std::to_string(z + 1));
    itk::EncapsulateMetaData<std::string>(dict, "0020|0013", std::to_string(z + 1));
    itk::EncapsulateMetaData<std::string>(dict, "0018|0050", std::to_string(kSliceMm));
    io->SetMetaDataDictionary(dict);
    auto w = itk::ImageFileWriter<Image>::New();
    char name[32];
    std::snprintf(name, sizeof name, "slice%03zu_%s.dcm", z, series_uid.substr(series_uid.size() - 1).c_str());
    w->SetFileName((dir / name).string());
    w->SetInput(img);
    w->SetImageIO(io);
    w->Update();
  }
}
const std::string kSeries = "1.2.826.0.1.3680043.9.7133.2";
}  // namespace

// The series read through GDCM equals the raw copy voxel for voxel (16-bit integers are exact in
// float), with the pixel spacing and slice distance converted from mm (DICOM's unit) to metres.
// The summary reports the stored type and the value range of the scan within it.
TEST(Dicom, SeriesReadsLikeTheSameVolumeAsRaw) {
  const fs::path d = tmpdir("ok");
  fs::create_directories(d / "series");
  write_series(d / "series", kSeries);
  {
    std::ofstream raw(d / "same.raw", std::ios::binary);
    for (std::size_t z = 0; z < NZ; ++z)
      for (std::size_t y = 0; y < NY; ++y)
        for (std::size_t x = 0; x < NX; ++x) {
          const uint16_t q = value(x, y, z);
          raw.write(reinterpret_cast<const char*>(&q), 2);
        }
  }
  ReadInfo info;
  const Volume dicom = read_volume((d / "series").string(), ReadOptions{}, &info);
  EXPECT_EQ(info.format, "dicom");
  EXPECT_EQ(info.pixel_type, "uint16");
  EXPECT_EQ(info.files.size(), NZ);
  ReadOptions ro;
  ro.raw_dims = {NX, NY, NZ};
  ro.raw_type = RawType::uint16;
  ro.spacing = {kPixelMm * 1e-3, kPixelMm * 1e-3, kSliceMm * 1e-3};
  const Volume raw = read_volume((d / "same.raw").string(), ro);
  ASSERT_EQ(dicom.dims, raw.dims);
  for (std::size_t i = 0; i < raw.v.size(); ++i) ASSERT_EQ(dicom.v[i], raw.v[i]) << "voxel " << i;
  for (int a = 0; a < 3; ++a) EXPECT_NEAR(dicom.spacing[a] / raw.spacing[a], 1.0, 1e-9) << a;
  EXPECT_NEAR(dicom.origin[2], 10.0e-3, 1e-12);
  EXPECT_EQ(info.value_min, double(value(0, 0, 0)));
  EXPECT_EQ(info.value_max, double(value(NX - 1, NY - 1, NZ - 1)));
  EXPECT_EQ(info.type_min, 0.0);
  EXPECT_EQ(info.type_max, 65535.0);

  // Through the whole tool: the summary names the format, the type and both ranges.
  SegmentConfig cfg;
  cfg.input = (d / "series").string();
  cfg.macro_radius_text = "1vox";
  const auto s = nlohmann::json::parse(run_segment(cfg));
  EXPECT_EQ(s["input"]["format"], "dicom");
  EXPECT_EQ(s["input"]["pixel_type"], "uint16");
  EXPECT_EQ(s["input"]["value_range"], nlohmann::json({double(value(0, 0, 0)), double(value(NX - 1, NY - 1, NZ - 1))}));
  EXPECT_EQ(s["input"]["type_range"], nlohmann::json({0.0, 65535.0}));
}

namespace {
std::string refusal(const fs::path& dir) {
  try {
    read_volume(dir.string(), ReadOptions{});
  } catch (const tomodem::InputError& e) {
    return e.what();
  }
  return "accepted";
}
}  // namespace

// A missing slice (the gap doubles), two series in one folder, and a folder with no DICOM at all.
TEST(Dicom, MalformedSeriesIsRefusedNamingTheProblem) {
  const fs::path gap = tmpdir("gap");
  write_series(gap, kSeries);
  fs::remove(gap / "slice003_2.dcm");
  const std::string g = refusal(gap);
  EXPECT_NE(g.find("slice004_2.dcm"), std::string::npos) << g;
  EXPECT_NE(g.find("missing"), std::string::npos) << g;

  const fs::path two = tmpdir("two");
  write_series(two, kSeries, 0, 3);
  write_series(two, "1.2.826.0.1.3680043.9.7133.3", 3, 3);
  const std::string t = refusal(two);
  EXPECT_NE(t.find("several DICOM series"), std::string::npos) << t;

  const fs::path none = tmpdir("none");
  std::ofstream(none / "junk.dcm") << "not a DICOM file";
  const std::string n = refusal(none);
  EXPECT_NE(n.find(none.string()), std::string::npos) << n;
  EXPECT_NE(n, "accepted");
}

// 32-bit integers: the summary's range is the values as stored and the type's full range.
TEST(ValueRange, ThirtyTwoBitRawReportsValuesAndTypeRange) {
  const fs::path d = tmpdir("int32");
  {
    std::ofstream raw(d / "v.raw", std::ios::binary);
    for (int32_t k = 0; k < 64; ++k) {
      const int32_t q = -70000 + 5000 * k;  // -70000 .. 245000: beyond 16 bits both ways
      raw.write(reinterpret_cast<const char*>(&q), 4);
    }
  }
  ReadOptions ro;
  ro.raw_dims = {4, 4, 4};
  ro.raw_type = RawType::int32;
  ro.spacing = {1e-6, 1e-6, 1e-6};
  ReadInfo info;
  read_volume((d / "v.raw").string(), ro, &info);
  EXPECT_EQ(info.pixel_type, "int32");
  EXPECT_EQ(info.value_min, -70000.0);
  EXPECT_EQ(info.value_max, 245000.0);
  EXPECT_EQ(info.type_min, -2147483648.0);
  EXPECT_EQ(info.type_max, 2147483647.0);
}
