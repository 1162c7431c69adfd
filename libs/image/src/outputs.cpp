// HDF5 labels (core h5), the OpenVDB level set and OpenCV overlays (drawn by imgproc, written as
// PNG by zlib: OpenCV's imgcodecs loads GDAL, poppler and ~140 libraries at every start of the tools).
#include <openvdb/openvdb.h>
#include <openvdb/io/Archive.h>
#include <openvdb/io/GridDescriptor.h>
#include <openvdb/io/io.h>
#include <openvdb/tools/Interpolation.h>
#include <openvdb/tools/ChangeBackground.h>
#include <openvdb/tools/LevelSetRebuild.h>
#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

#include <sys/stat.h>
#include <zlib.h>
#include <cerrno>
#include <cstring>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>

#include "tomodem/core/error.hpp"
#include "tomodem/core/h5.hpp"
#include "tomodem/core/output.hpp"
#include "tomodem/core/packing_io.hpp"
#include "tomodem/core/tool.hpp"
#include "tomodem/image/outputs.hpp"
#include "tomodem/image/segment.hpp"

namespace tomodem::image {

void write_labels_h5(const std::string& path, const Mask& phases, const Labels& macro, const Labels* grains,
                     const std::vector<std::string>& inputs) {
  const std::string tmp = temporary_path(path);
  try {
    h5::File f(tmp, h5::File::Mode::create);
    const std::vector<std::size_t> dims{phases.dims.nz, phases.dims.ny, phases.dims.nx};
    const std::vector<double> sp(phases.spacing.begin(), phases.spacing.end()), org(phases.origin.begin(), phases.origin.end());
    auto geom = [&](const std::string& ds) {
      f.set_attr(ds, "spacing", sp);
      f.set_attr(ds, "origin", org);
      f.set_attr(ds, "axes", std::string("z,y,x (spacing and origin listed x,y,z, m)"));
      f.set_attr(ds, "units", std::string("1"));  // labels and ids; lengths are in the root's units (m)
    };
    f.write("/labels", phases.v, dims);
    f.set_attr("/labels", "legend", std::string(kLegend));
    geom("/labels");
    f.write("/macropores", macro.v, dims);
    geom("/macropores");
    if (grains) {
      f.write("/grains", grains->v, dims);
      geom("/grains");
    }
    write_provenance(f, inputs);
    f.close();  // a full disk is found here, before the rename
  } catch (...) {
    std::remove(tmp.c_str());
    throw;
  }
  commit_output(path);
  // The sidecar follows the data (ParaView opens the labels in metres beside the packings).
  std::vector<XdmfField> fields{{"labels", "/labels", "UChar", 1}, {"macropores", "/macropores", "Int", 4}};
  if (grains) fields.push_back({"grains", "/grains", "Int", 4});
  try {
    write_volume_xdmf(path, {phases.dims.nx, phases.dims.ny, phases.dims.nz}, phases.origin, phases.spacing, fields);
  } catch (...) {
    std::remove(xdmf_sidecar_of(path).c_str());
    throw;
  }
}

namespace {
constexpr double kMmPerM = 1e3;
// A level set needs cubic voxels (its values are distances in world units): a mask with coarser
// axes is resampled to the finest voxel size, each new voxel taking the mask value of the old
// voxel that holds its centre. The box (origin - s/2 .. + n s) is kept where n s is a whole
// number of finest voxels; otherwise it grows by less than one finest voxel.
Mask cubic_voxels(const Mask& m) {
  const double h = std::min({m.spacing[0], m.spacing[1], m.spacing[2]});
  if (std::max({m.spacing[0], m.spacing[1], m.spacing[2]}) <= h * (1 + 1e-9)) return m;
  const std::size_t n_old[3] = {m.dims.nx, m.dims.ny, m.dims.nz};
  std::size_t n[3];
  for (int a = 0; a < 3; ++a) n[a] = std::size_t(std::ceil(double(n_old[a]) * m.spacing[a] / h - 1e-9));
  Mask c(Dims{n[0], n[1], n[2]});
  c.spacing = {h, h, h};
  std::vector<std::size_t> map[3];
  for (int a = 0; a < 3; ++a) {
    const double lo = m.origin[a] - 0.5 * m.spacing[a];
    c.origin[a] = lo + 0.5 * h;
    for (std::size_t i = 0; i < n[a]; ++i)
      map[a].push_back(std::min(n_old[a] - 1, std::size_t((double(i) + 0.5) * h / m.spacing[a])));
  }
  for (std::size_t z = 0; z < n[2]; ++z)
    for (std::size_t y = 0; y < n[1]; ++y)
      for (std::size_t x = 0; x < n[0]; ++x) c.at(x, y, z) = m.at(map[0][x], map[1][y], map[2][z]);
  return c;
}
}  // namespace

void write_level_set(const std::string& path, const Mask& mask, double half_width_vox) {
  openvdb::initialize();
  const Mask m = cubic_voxels(mask);
  Volume f;
  f.copy_geometry(m);
  f.v.resize(m.v.size());
  for (std::size_t i = 0; i < m.v.size(); ++i) f.v[i] = m.v[i] ? 1.0f : 0.0f;
  const Volume s = gaussian(f, 1.0);
  // phi = 0.5 - smoothed indicator: negative inside; background +0.5 (outside).
  // Built in voxel units (OpenVDB's mesher rejects voxel sizes of ~1e-5 as zero scale), then
  // values and transform are scaled to metres.
  const double h = m.spacing[0] * kMmPerM;  // OpenVDB refuses scale maps with |det| < 3e-15: store mm
  auto fog = openvdb::FloatGrid::create(0.5f);
  auto acc = fog->getAccessor();
  for (std::size_t z = 0; z < m.dims.nz; ++z)
    for (std::size_t y = 0; y < m.dims.ny; ++y)
      for (std::size_t x = 0; x < m.dims.nx; ++x) {
        const float v = s.at(x, y, z);
        if (v > 1e-4f) acc.setValue(openvdb::Coord(int(x), int(y), int(z)), 0.5f - v);
      }
  auto ls = openvdb::tools::levelSetRebuild(*fog, 0.0f, float(half_width_vox));
  for (auto it = ls->beginValueOn(); it; ++it) it.setValue(float(*it * h));
  openvdb::tools::changeLevelSetBackground(ls->tree(), float(ls->background() * h));
  auto xf = openvdb::math::Transform::createLinearTransform(h);
  xf->postTranslate(openvdb::Vec3d(m.origin[0], m.origin[1], m.origin[2]) * kMmPerM);
  ls->setTransform(xf);
  ls->setName("macropores");
  ls->setGridClass(openvdb::GRID_LEVEL_SET);
  ls->insertMeta("units", openvdb::StringMetadata("mm"));
  ls->insertMeta("metres_per_unit", openvdb::DoubleMetadata(1e-3));
  const std::string tmp = temporary_path(path);
  try {
    openvdb::io::File file(tmp);
    openvdb::GridPtrVec grids{ls};
    file.write(grids);
    file.close();
  } catch (const std::exception& e) {
    std::remove(tmp.c_str());
    throw RuntimeFailure("cannot write " + path + ": " + e.what());
  }
  commit_output(path);
}

namespace {
// OpenVDB reads a truncated file past its end without noticing: counts read from the failed
// stream are garbage, and it loops and allocates without bound (a cut 60 kB level set grew to
// 1.8 GB). So the file's own table of contents is walked first, with OpenVDB's readers for the
// header, the file metadata and each grid descriptor: every grid must end inside the file.
class TableOfContents final : public openvdb::io::Archive {
 public:
  explicit TableOfContents(std::string path) : path_(std::move(path)) {}

  void check() {
    struct stat st {};
    if (::stat(path_.c_str(), &st) != 0) throw InputError(path_, "", "", std::string("cannot open: ") + std::strerror(errno));
    if (S_ISDIR(st.st_mode)) throw InputError(path_, "", "", "is a folder, not an OpenVDB level set (.vdb)");
    std::ifstream is(path_, std::ios::binary);
    if (!is) throw InputError(path_, "", "", std::string("cannot open: ") + std::strerror(errno));
    is.seekg(0, std::ios::end);
    const std::int64_t size = std::int64_t(is.tellg());
    is.seekg(0);
    if (size <= 0) throw InputError(path_, "", "0 bytes", "empty file, not an OpenVDB level set");
    try {
      readHeader(is);
    } catch (const std::exception& e) {
      throw InputError(path_, "header", "", std::string("not an OpenVDB file: ") + e.what());
    }
    if (!is) truncated("header", size);
    try {
      openvdb::io::StreamMetadata::Ptr meta(new openvdb::io::StreamMetadata);
      meta->setSeekable(true);
      openvdb::io::setStreamMetadataPtr(is, meta, /*transfer=*/false);
      setFormatVersion(is);
      setLibraryVersion(is);
      setDataCompression(is);
      openvdb::MetaMap file_meta;
      file_meta.readMeta(is);
      if (!is) truncated("file metadata", size);
      if (!inputHasGridOffsets()) return;  // very old files: no offsets to check
      const int32_t n = readGridCount(is);
      if (!is || n < 0) truncated("grid count", size);
      for (int32_t k = 0; k < n; ++k) {
        const std::int64_t here = std::int64_t(is.tellg());
        if (!is || here < 0 || here + 12 > size) truncated("grid " + std::to_string(k) + " descriptor", size);
        openvdb::io::GridDescriptor gd;
        gd.read(is);
        const std::string name = "grid '" + openvdb::io::GridDescriptor::nameAsString(gd.uniqueName()) + "'";
        if (!is) truncated(name, size);
        if (gd.getGridPos() < here || gd.getBlockPos() < gd.getGridPos() || gd.getEndPos() < gd.getBlockPos())
          throw InputError(path_, name, "offsets " + std::to_string(gd.getGridPos()) + ", " +
                                            std::to_string(gd.getBlockPos()) + ", " + std::to_string(gd.getEndPos()),
                           "corrupt grid descriptor (offsets out of order)");
        if (gd.getEndPos() > size)
          throw InputError(path_, name, "ends at byte " + std::to_string(gd.getEndPos()),
                           "the file has only " + std::to_string(size) +
                               " bytes: it is truncated (an interrupted copy or write?)");
        is.seekg(gd.getEndPos());
      }
    } catch (const InputError&) {
      throw;
    } catch (const std::exception& e) {
      throw InputError(path_, "", "", std::string("corrupt OpenVDB file: ") + e.what());
    }
  }

 private:
  [[noreturn]] void truncated(const std::string& where, std::int64_t size) const {
    throw InputError(path_, where, std::to_string(size) + " bytes",
                     "the file ends inside its " + where + ": truncated or not an OpenVDB file");
  }
  std::string path_;
};

}  // namespace

void check_vdb_file(const std::string& path) { TableOfContents(path).check(); }

std::vector<double> sample_level_set(const std::string& path, const std::vector<Vec3>& pts) {
  openvdb::initialize();
  check_vdb_file(path);
  openvdb::io::File file(path);
  try {
    file.open();
  } catch (const std::exception& e) {
    throw InputError(path, "", "", std::string("cannot open: ") + e.what());
  }
  openvdb::GridBase::Ptr base;
  try {
    base = file.readGrid("macropores");
  } catch (const std::exception& e) {
    throw InputError(path, "macropores", "", std::string("cannot read the grid: ") + e.what());
  }
  file.close();
  auto grid = openvdb::gridPtrCast<openvdb::FloatGrid>(base);
  if (!grid) throw InputError(path, "macropores", "", "not a float grid");
  // The grid's own unit (write_level_set states mm); a grid that states none is taken in metres,
  // as tomodem-carve does.
  double unit = 1;
  if (auto m = grid->getMetadata<openvdb::DoubleMetadata>("metres_per_unit")) {
    unit = m->value();
  } else if (auto u = grid->getMetadata<openvdb::StringMetadata>("units")) {
    unit = metres_per_unit(u->value());
    if (!(unit > 0)) throw InputError(path, "units", u->value(), "unknown length unit in the grid metadata (m, mm, um, nm)");
  } else {
    warn(path + ": the level set states no unit (metadata metres_per_unit or units): taken in metres");
  }
  if (!(unit > 0) || !std::isfinite(unit))
    throw InputError(path, "metres_per_unit", value_text(unit), "must be finite and > 0");
  openvdb::tools::GridSampler<openvdb::FloatGrid, openvdb::tools::BoxSampler> sampler(*grid);
  std::vector<double> out;
  for (const auto& p : pts) out.push_back(sampler.wsSample(openvdb::Vec3d(p.x, p.y, p.z) / unit) * unit);
  return out;
}

OverlayPlanes overlay_planes(const Volume& grey) {
  // Grey window from a subsample of the volume.
  std::vector<float> sample;
  const std::size_t step = std::max<std::size_t>(1, grey.v.size() / 200000);
  for (std::size_t i = 0; i < grey.v.size(); i += step) sample.push_back(grey.v[i]);
  std::sort(sample.begin(), sample.end());
  OverlayPlanes o;
  const auto& d = o.dims = grey.dims;
  o.lo = sample[std::size_t(0.005 * double(sample.size() - 1))];
  o.hi = std::max(o.lo + 1e-12, double(sample[std::size_t(0.995 * double(sample.size() - 1))]));
  for (std::size_t y = 0; y < d.ny; ++y)
    for (std::size_t x = 0; x < d.nx; ++x) o.xy.push_back(grey.at(x, y, d.nz / 2));
  for (std::size_t z = 0; z < d.nz; ++z)
    for (std::size_t x = 0; x < d.nx; ++x) o.xz.push_back(grey.at(x, d.ny / 2, z));
  for (std::size_t z = 0; z < d.nz; ++z)
    for (std::size_t y = 0; y < d.ny; ++y) o.yz.push_back(grey.at(d.nx / 2, y, z));
  return o;
}

ScaleBar scale_bar(double metres_per_pixel, int width_px) {
  if (!(metres_per_pixel > 0) || width_px < 4) throw RuntimeFailure("scale bar: no picture to measure");
  const double room = 0.25 * width_px * metres_per_pixel;
  const double decade = std::pow(10.0, std::floor(std::log10(room)));
  ScaleBar b;
  for (double m : {5.0, 2.0, 1.0})
    if (m * decade <= room * (1 + 1e-12)) {
      b.length_m = m * decade;
      break;
    }
  b.pixels = int(std::lround(b.length_m / metres_per_pixel));
  // The unit that shows the length as 1 to 999 of it.
  struct Unit { double m; const char* name; };
  const Unit units[] = {{1, "m"}, {1e-3, "mm"}, {1e-6, "um"}, {1e-9, "nm"}};
  Unit u = units[3];
  for (const Unit& c : units)
    if (b.length_m >= c.m * (1 - 1e-9)) {
      u = c;
      break;
    }
  char text[32];
  std::snprintf(text, sizeof text, "%.0f %s", b.length_m / u.m, u.name);
  b.label = text;
  return b;
}

namespace {
void put_be32(std::string& s, uint32_t v) {
  for (int shift = 24; shift >= 0; shift -= 8) s += char((v >> shift) & 0xff);
}
// One PNG chunk: length, type, data, CRC-32 of type and data (PNG spec, section 5.3).
void put_chunk(std::string& png, const char* type, const std::string& data) {
  put_be32(png, uint32_t(data.size()));
  const std::size_t from = png.size();
  png.append(type, 4);
  png += data;
  put_be32(png, uint32_t(crc32(0, reinterpret_cast<const Bytef*>(png.data() + from), uInt(png.size() - from))));
}
}  // namespace

std::string png_from_bgr(const uint8_t* bgr, int width, int height, std::size_t row_bytes) {
  // Each row: filter type 0 (none), then R G B.
  std::string raw;
  raw.reserve(std::size_t(height) * (1 + 3 * std::size_t(width)));
  for (int y = 0; y < height; ++y) {
    raw += '\0';
    const uint8_t* row = bgr + std::size_t(y) * row_bytes;
    for (int x = 0; x < width; ++x) raw += {char(row[3 * x + 2]), char(row[3 * x + 1]), char(row[3 * x])};
  }
  uLongf packed_size = compressBound(uLong(raw.size()));
  std::string packed(packed_size, '\0');
  if (compress2(reinterpret_cast<Bytef*>(packed.data()), &packed_size, reinterpret_cast<const Bytef*>(raw.data()),
                uLong(raw.size()), Z_DEFAULT_COMPRESSION) != Z_OK)
    throw RuntimeFailure("PNG encoding failed (zlib)");
  packed.resize(packed_size);
  std::string header;  // IHDR: width, height, 8 bits, colour type 2 (RGB), deflate, no interlace
  put_be32(header, uint32_t(width));
  put_be32(header, uint32_t(height));
  header += {char(8), char(2), char(0), char(0), char(0)};
  std::string png("\x89PNG\r\n\x1a\n", 8);
  put_chunk(png, "IHDR", header);
  put_chunk(png, "IDAT", packed);
  put_chunk(png, "IEND", "");
  return png;
}

namespace {
// The white strip under an overlay: the scale bar on the first row, then one swatch and name per
// phase present, wrapped to the picture's width.
cv::Mat with_footer(const cv::Mat& img, double metres_per_pixel, const std::vector<std::pair<cv::Scalar, std::string>>& legend) {
  const int font = cv::FONT_HERSHEY_SIMPLEX, thick = 1, pad = 6, row = 18, swatch = 10;
  const double fs = 0.4;
  const ScaleBar bar = scale_bar(metres_per_pixel, img.cols);
  // Lay the legend out first to know how many rows it takes.
  std::vector<cv::Point> at;
  int x = pad, y = 2 * row;
  for (const auto& [colour, name] : legend) {
    int base = 0;
    const int w = swatch + 4 + cv::getTextSize(name, font, fs, thick, &base).width + 2 * pad;
    if (x > pad && x + w > img.cols) x = pad, y += row;
    at.push_back({x, y});
    x += w;
  }
  cv::Mat out(img.rows + y + pad, img.cols, img.type(), cv::Scalar(255, 255, 255));
  img.copyTo(out(cv::Rect(0, 0, img.cols, img.rows)));
  const int y0 = img.rows;
  cv::rectangle(out, cv::Rect(pad, y0 + row - 8, bar.pixels, 5), cv::Scalar(0, 0, 0), cv::FILLED);
  cv::putText(out, bar.label, cv::Point(pad + bar.pixels + 6, y0 + row - 2), font, fs, cv::Scalar(0, 0, 0), thick, cv::LINE_AA);
  for (std::size_t k = 0; k < legend.size(); ++k) {
    const cv::Point p(at[k].x, y0 + at[k].y);
    cv::rectangle(out, cv::Rect(p.x, p.y - swatch, swatch, swatch), legend[k].first, cv::FILLED);
    cv::putText(out, legend[k].second, cv::Point(p.x + swatch + 4, p.y), font, fs, cv::Scalar(0, 0, 0), thick, cv::LINE_AA);
  }
  return out;
}
}  // namespace

std::vector<std::string> write_overlays(const std::string& prefix, const OverlayPlanes& grey, const Mask& phases) {
  const auto& d = grey.dims;
  if (!(phases.dims == d)) throw RuntimeFailure("overlay: grey planes and labels differ in size");
  std::vector<std::string> written;
  // The legend names what the volume has: grey is the scan, tints the phases (blended 45 %).
  bool present[4] = {};
  for (const uint8_t v : phases.v) present[std::min<uint8_t>(v, 3)] = true;
  const cv::Vec3d tints[4] = {{0, 0, 0}, {255, 80, 0}, {0, 0, 255}, {0, 200, 0}};  // BGR
  const char* names[4] = {"", "fine pore", "macropore", "solid phase 2"};
  std::vector<std::pair<cv::Scalar, std::string>> legend;
  for (int k = 1; k < 4; ++k)
    if (present[k]) {
      const cv::Vec3d c = 0.55 * cv::Vec3d(128, 128, 128) + 0.45 * tints[k];
      legend.push_back({cv::Scalar(c[0], c[1], c[2]), names[k]});
    }
  legend.push_back({cv::Scalar(128, 128, 128), "solid (grey: scan)"});
  struct Plane { const char* name; std::size_t w, h; const std::vector<float>* grey; };
  const Plane planes[3] = {{"xy", d.nx, d.ny, &grey.xy}, {"xz", d.nx, d.nz, &grey.xz}, {"yz", d.ny, d.nz, &grey.yz}};
  for (int p = 0; p < 3; ++p) {
    cv::Mat img(int(planes[p].h), int(planes[p].w), CV_8UC3);
    for (std::size_t b = 0; b < planes[p].h; ++b)
      for (std::size_t a = 0; a < planes[p].w; ++a) {
        std::size_t x, y, z;
        if (p == 0) { x = a; y = b; z = d.nz / 2; }
        else if (p == 1) { x = a; y = d.ny / 2; z = b; }
        else { x = d.nx / 2; y = a; z = b; }
        const double gv = (*planes[p].grey)[b * planes[p].w + a];
        const double g = std::clamp((gv - grey.lo) / (grey.hi - grey.lo), 0.0, 1.0) * 255.0;
        cv::Vec3d c(g, g, g);  // BGR
        const uint8_t ph = phases.at(x, y, z);
        if (ph != 0) c = 0.55 * c + 0.45 * tints[std::min<uint8_t>(ph, 3)];
        img.at<cv::Vec3b>(int(b), int(a)) = cv::Vec3b(cv::saturate_cast<uint8_t>(c[0]), cv::saturate_cast<uint8_t>(c[1]),
                                                      cv::saturate_cast<uint8_t>(c[2]));
      }
    // Pixels as long as the voxels are (anisotropic scans): a plane through a coarser z is
    // stretched along z by s_z / s_finest, so shapes look as they are in metres.
    const double finest = std::min({phases.spacing[0], phases.spacing[1], phases.spacing[2]});
    const double sa = phases.spacing[p == 2 ? 1 : 0] / finest, sb = phases.spacing[p == 0 ? 1 : 2] / finest;
    const double wa = double(planes[p].w) * sa, hb = double(planes[p].h) * sb;
    const double scale = std::max(1.0, std::ceil(256.0 / std::max(wa, hb)));
    const cv::Size size(int(std::lround(wa * scale)), int(std::lround(hb * scale)));
    if (size != img.size()) cv::resize(img, img, size, 0, 0, cv::INTER_NEAREST);
    const double metres_per_pixel = phases.spacing[p == 2 ? 1 : 0] * double(planes[p].w) / double(size.width);
    img = with_footer(img, metres_per_pixel, legend);
    const std::string path = prefix + "_" + planes[p].name + ".png";
    write_text_atomic(path, png_from_bgr(img.ptr(), img.cols, img.rows, img.step));
    written.push_back(path);
  }
  return written;
}

}  // namespace tomodem::image
