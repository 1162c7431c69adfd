// Out-of-core tomodem-segment (--chunk / --memory, docs/segment.md "Volumes larger than memory"):
// the volume is read block by block (pread of a raw file's rows, or an HDF5 hyperslab), never whole. Held for the whole run:
// the solid and macropore masks as bits (2 bits per voxel, 3 with a second solid phase); every
// other array is one block with its halo. Each stage gives the in-memory path's result exactly:
// - median: a block with a halo of the box radius gives its core exactly (borders are replicated
//   only at the volume's faces, which are the block's faces there);
// - Gaussian: separable, the axes one after the other over the whole block; a halo of the
//   kernel's radius gives its core exactly (each pass reads only values computed exactly);
// - thresholds: the histograms are sums of whole counts, the same chunk by chunk; the filtered
//   values of an integer scan of <= 16 bits are its own values (a median selects one), so one
//   pass counts every value and builds each histogram; other types, and Gaussian-filtered
//   values, take a min/max pass first;
// - macropores: a voxel depends on the pores within 2r + 2 voxels (segment.hpp, macropore_mask);
// - labels: each block's core labelled on its own, the labels joined across block faces by
//   union-find (6-connectivity), numbered by their first voxel in x-fastest order and filtered by
//   size as components()/macropores() do; a second pass writes them;
// - grains (--grains): the distance map of a block is exact in its core when the halo is wider
//   than the largest distance found there (a nearer pore would lie inside the block), so a first
//   pass finds the solid's largest inscribed radius R exactly, widening a block's halo until it
//   holds; the markers (h-maxima of the distance map) are then found per block with a halo of
//   2R + 4, numbered over the whole volume (26-connected, by first voxel, as components()), and
//   each block floods from every marker in its reach, so a grain has one id in every block. The
//   h-maxima and the watershed are not local operations in general (a plateau or a flood can run
//   along a ridge of the distance map farther than any halo): a grain whose id reaches the halo's
//   inner edge is counted in the summary (chunked.grains_reaching_halo_edge), where blocks may
//   disagree. Solid that no marker reaches keeps grain 0 (specks without a marker of their own,
//   or a grain whose marker lies beyond the widest halo; grains.solid_voxels_without_grain).
//   The tests compare the grains with the in-memory path's (tests/e2e/segment).
#include <hdf5.h>
#include <fcntl.h>
#include <omp.h>
#include <unistd.h>

#include <nlohmann/json.hpp>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstring>
#include <exception>
#include <filesystem>
#include <limits>
#include <map>
#include <memory>
#include <numeric>

#include "tomodem/core/error.hpp"
#include "tomodem/core/h5.hpp"
#include "tomodem/core/output.hpp"
#include "tomodem/core/packing_io.hpp"
#include "tomodem/core/summary.hpp"
#include "tomodem/core/tool.hpp"
#include "tomodem/image/segment.hpp"
#include "tomodem/image/tools.hpp"

namespace tomodem::image {
namespace {

using json = nlohmann::json;
namespace fs = std::filesystem;

// A box of voxels [lo, hi) per axis (x, y, z).
struct Box {
  std::array<std::size_t, 3> lo{}, hi{};
  std::size_t n(int a) const { return hi[std::size_t(a)] - lo[std::size_t(a)]; }
  Dims dims() const { return {n(0), n(1), n(2)}; }
  Box grown(const std::array<std::size_t, 3>& h, const Dims& d) const {
    const std::size_t N[3] = {d.nx, d.ny, d.nz};
    Box b;
    for (std::size_t a = 0; a < 3; ++a) {
      b.lo[a] = lo[a] > h[a] ? lo[a] - h[a] : 0;
      b.hi[a] = std::min(N[a], hi[a] + h[a]);
    }
    return b;
  }
};

// One bit per voxel, rows of x padded to 64-bit words.
struct Bits {
  Dims d;
  std::size_t W = 0;
  std::vector<uint64_t> w;
  explicit Bits(Dims dims = {}) : d(dims), W((dims.nx + 63) / 64), w(W * dims.ny * dims.nz, 0) {}
  const uint64_t* row(std::size_t y, std::size_t z) const { return &w[(z * d.ny + y) * W]; }
  uint64_t* row(std::size_t y, std::size_t z) { return &w[(z * d.ny + y) * W]; }
  bool get(std::size_t x, std::size_t y, std::size_t z) const { return (row(y, z)[x >> 6] >> (x & 63)) & 1u; }
  void set(std::size_t x, std::size_t y, std::size_t z) { row(y, z)[x >> 6] |= uint64_t(1) << (x & 63); }
  std::size_t count() const {
    std::size_t n = 0;
    for (auto x : w) n += std::size_t(__builtin_popcountll(x));
    return n;
  }
};

// The input read block by block, never whole: a raw file (RawBlocks) or an HDF5 dataset
// (H5Blocks). Values are converted to float as the in-memory readers convert them.
class BlockSource {
 public:
  virtual ~BlockSource() = default;
  const Dims& dims() const { return d_; }
  RawType type() const { return type_; }  ///< the stored voxel type
  std::size_t type_bytes() const { return type_size(type_); }
  /// Bytes the reader holds while it reads a block, beyond the block itself (an HDF5 chunk).
  virtual double reader_bytes() const { return 0; }
  // Values of <= 16-bit integer types are whole numbers in [offset, offset + 65535].
  bool small_integers() const { return type_ == RawType::uint8 || type_ == RawType::int8 || type_ == RawType::uint16 || type_ == RawType::int16; }
  long offset() const { return (type_ == RawType::int8) ? -128 : (type_ == RawType::int16) ? -32768 : 0; }

  // The block b as floats (x fastest); NaN/Inf refused naming the voxel.
  void read(const Box& b, Volume& out) {
    out.dims = b.dims();
    out.v.resize(out.dims.count());
    largest_read = std::max(largest_read, out.v.size());
    fill(b, out.v.data());
    const std::size_t nx = b.n(0), ny = b.n(1);
    for (std::size_t i = 0; i < out.v.size(); ++i) {
      const float x = out.v[i];
      if (!std::isfinite(x)) {
        const std::size_t X = b.lo[0] + i % nx, Y = b.lo[1] + i / nx % ny, Z = b.lo[2] + i / (nx * ny);
        throw InputError(path_, field_, "voxel (" + std::to_string(X) + ", " + std::to_string(Y) + ", " + std::to_string(Z) + ") (x, y, z)",
                         "is NaN or infinite");
      }
      vmin = std::min(vmin, x);
      vmax = std::max(vmax, x);
    }
  }
  float vmin = std::numeric_limits<float>::max(), vmax = std::numeric_limits<float>::lowest();  ///< values seen
  std::size_t largest_read = 0;  ///< voxels of the largest block read (the tests check it is never the volume)

 protected:
  BlockSource(std::string path, std::string field) : path_(std::move(path)), field_(std::move(field)) {}
  virtual void fill(const Box& b, float* out) = 0;
  std::string path_, field_;
  Dims d_;
  RawType type_ = RawType::uint8;
};

// A raw file: pread per row of the block, converted as read_raw does.
class RawBlocks : public BlockSource {
 public:
  RawBlocks(const std::string& path, const ReadOptions& o) : BlockSource(path, "data"), o_(o) {
    const auto [nx, ny, nz] = o.raw_dims;
    if (nx == 0 || ny == 0 || nz == 0)
      throw InputError(path, "--raw-dims", "", "a raw file needs its dimensions (--raw-dims NX,NY,NZ)");
    d_ = {nx, ny, nz};
    type_ = o.raw_type;
    const std::size_t bytes = type_bytes();
    const std::uintmax_t expected = o.raw_header + nx * ny * nz * bytes;
    std::error_code ec;
    if (fs::is_directory(path)) throw InputError(path, "", "", "is a folder, not a raw file");
    const std::uintmax_t size = fs::file_size(path, ec);
    if (ec) throw InputError(path, "", "", "cannot read file size: " + ec.message());
    const std::string dims = std::to_string(nx) + "x" + std::to_string(ny) + "x" + std::to_string(nz) + " " + to_string(o.raw_type);
    if (size < expected)
      throw InputError(path, "size", std::to_string(size) + " bytes", "truncated: dims " + dims + " need " + std::to_string(expected) + " bytes");
    if (size > expected)
      throw InputError(path, "size", std::to_string(size) + " bytes",
                       "does not match dims " + dims + " (" + std::to_string(expected) + " bytes); check --raw-dims/--raw-type/--raw-header");
    fd_ = ::open(path.c_str(), O_RDONLY);
    if (fd_ < 0) throw InputError(path, "", "", std::string("cannot open: ") + std::strerror(errno));
  }
  ~RawBlocks() override { if (fd_ >= 0) ::close(fd_); }
  RawBlocks(const RawBlocks&) = delete;
  RawBlocks& operator=(const RawBlocks&) = delete;

 private:
  void fill(const Box& b, float* out) override {
    const std::size_t nxb = b.n(0), bytes = type_bytes();
    std::vector<char> buf(nxb * bytes);
    const bool swap = o_.byte_order == ByteOrder::big;
    for (std::size_t z = b.lo[2]; z < b.hi[2]; ++z)
      for (std::size_t y = b.lo[1]; y < b.hi[1]; ++y) {
        const off_t at = off_t(o_.raw_header + ((z * d_.ny + y) * d_.nx + b.lo[0]) * bytes);
        std::size_t got = 0;
        while (got < buf.size()) {
          const ssize_t r = ::pread(fd_, buf.data() + got, buf.size() - got, at + off_t(got));
          if (r <= 0) throw InputError(path_, "data", "row y " + std::to_string(y) + ", z " + std::to_string(z), "read failed (truncated?)");
          got += std::size_t(r);
        }
        convert_row(buf.data(), nxb, swap, out + ((z - b.lo[2]) * b.n(1) + (y - b.lo[1])) * nxb);
      }
  }
  template <class T>
  static void conv(const char* p, std::size_t n, bool swap, float* out) {
    for (std::size_t i = 0; i < n; ++i) {
      unsigned char b[sizeof(T)];
      std::memcpy(b, p + i * sizeof(T), sizeof(T));
      if (swap) std::reverse(b, b + sizeof(T));
      T val;
      std::memcpy(&val, b, sizeof(T));
      out[i] = static_cast<float>(val);
    }
  }
  void convert_row(const char* p, std::size_t n, bool swap, float* out) const {
    switch (o_.raw_type) {
      case RawType::uint8: conv<uint8_t>(p, n, false, out); break;
      case RawType::int8: conv<int8_t>(p, n, false, out); break;
      case RawType::uint16: conv<uint16_t>(p, n, swap, out); break;
      case RawType::int16: conv<int16_t>(p, n, swap, out); break;
      case RawType::uint32: conv<uint32_t>(p, n, swap, out); break;
      case RawType::int32: conv<int32_t>(p, n, swap, out); break;
      case RawType::float32: conv<float>(p, n, swap, out); break;
      case RawType::float64: conv<double>(p, n, swap, out); break;
    }
  }
  ReadOptions o_;
  int fd_ = -1;
};

/// The file and memory dataspaces of one block of a (z, y, x) dataset, for H5Dread and H5Dwrite:
/// the block's hyperslab selected in the file, a memory space of its size.
struct BlockSpaces {
  hid_t file, memory;
  BlockSpaces(hid_t ds, const Box& b) {
    const hsize_t start[3] = {b.lo[2], b.lo[1], b.lo[0]}, count[3] = {b.n(2), b.n(1), b.n(0)};
    file = H5Dget_space(ds);
    H5Sselect_hyperslab(file, H5S_SELECT_SET, start, nullptr, count, nullptr);
    memory = H5Screate_simple(3, count, nullptr);
  }
  ~BlockSpaces() {
    H5Sclose(memory);
    H5Sclose(file);
  }
  BlockSpaces(const BlockSpaces&) = delete;
  BlockSpaces& operator=(const BlockSpaces&) = delete;
};

// An HDF5 dataset (z, y, x), contiguous or chunked: one hyperslab per block, converted to float
// by HDF5 (a C cast, as read_h5's double -> float; exact for <= 16-bit integers and float32).
// A chunked dataset is decompressed chunk by chunk: one chunk is held while a block is read.
class H5Blocks : public BlockSource {
 public:
  H5Blocks(const std::string& path, const std::string& dataset) : BlockSource(path, dataset) {
    H5Eset_auto2(H5E_DEFAULT, nullptr, nullptr);  // errors are InputErrors naming the file, not HDF5's stack
    file_ = H5Fopen(path.c_str(), H5F_ACC_RDONLY, H5P_DEFAULT);
    if (file_ < 0) throw InputError(path, "", "", "cannot open as HDF5");
    if (H5Lexists(file_, dataset.c_str(), H5P_DEFAULT) <= 0 || (ds_ = H5Dopen2(file_, dataset.c_str(), H5P_DEFAULT)) < 0)
      throw InputError(path, dataset, "", "no such dataset (give --dataset)");
    const hid_t space = H5Dget_space(ds_);
    const int rank = H5Sget_simple_extent_ndims(space);
    hsize_t n[3] = {0, 0, 0};
    if (rank == 3) H5Sget_simple_extent_dims(space, n, nullptr);
    H5Sclose(space);
    if (rank != 3) throw InputError(path, dataset, std::to_string(rank) + "-D", "expected a 3-D dataset (z, y, x)");
    d_ = {std::size_t(n[2]), std::size_t(n[1]), std::size_t(n[0])};
    const hid_t t = H5Dget_type(ds_);
    const H5T_class_t cls = H5Tget_class(t);
    const std::size_t size = H5Tget_size(t);
    const bool sign = cls == H5T_INTEGER && H5Tget_sign(t) == H5T_SGN_2;
    H5Tclose(t);
    const std::map<std::pair<std::size_t, bool>, RawType> ints{{{1, false}, RawType::uint8}, {{1, true}, RawType::int8},
                                                               {{2, false}, RawType::uint16}, {{2, true}, RawType::int16},
                                                               {{4, false}, RawType::uint32}, {{4, true}, RawType::int32}};
    if (cls == H5T_INTEGER && ints.count({size, sign})) type_ = ints.at({size, sign});
    else if (cls == H5T_FLOAT && (size == 4 || size == 8)) type_ = size == 4 ? RawType::float32 : RawType::float64;
    else
      throw InputError(path, dataset, std::to_string(size * 8) + "-bit " + (cls == H5T_INTEGER ? "integer" : cls == H5T_FLOAT ? "float" : "non-numeric"),
                       "the chunked path reads 8-, 16- and 32-bit integers and 32- and 64-bit floats; convert the dataset or read it in memory");
    const hid_t dcpl = H5Dget_create_plist(ds_);
    if (H5Pget_layout(dcpl) == H5D_CHUNKED) {
      hsize_t c[3] = {0, 0, 0};
      H5Pget_chunk(dcpl, 3, c);
      chunk_ = {std::size_t(c[2]), std::size_t(c[1]), std::size_t(c[0])};
    }
    H5Pclose(dcpl);
  }
  ~H5Blocks() override {
    if (ds_ >= 0) H5Dclose(ds_);
    if (file_ >= 0) H5Fclose(file_);
  }
  H5Blocks(const H5Blocks&) = delete;
  H5Blocks& operator=(const H5Blocks&) = delete;
  /// The dataset's HDF5 chunk (x, y, z voxels); zeros when contiguous.
  const std::array<std::size_t, 3>& chunk() const { return chunk_; }
  // One decompressed chunk and its compressed bytes (at most as many), plus HDF5's 1 MiB
  // conversion buffer and 1 MiB chunk cache.
  double reader_bytes() const override {
    return 2.0 * double(chunk_[0]) * double(chunk_[1]) * double(chunk_[2]) * double(type_bytes()) + 2 * 1048576.0;
  }

 private:
  void fill(const Box& b, float* out) override {
    const BlockSpaces spaces(ds_, b);
    if (H5Dread(ds_, H5T_NATIVE_FLOAT, spaces.memory, spaces.file, H5P_DEFAULT, out) < 0)
      throw InputError(path_, field_, "block x " + std::to_string(b.lo[0]) + ", y " + std::to_string(b.lo[1]) + ", z " + std::to_string(b.lo[2]),
                       "read failed (a damaged or truncated file?)");
  }
  hid_t file_ = -1, ds_ = -1;
  std::array<std::size_t, 3> chunk_{0, 0, 0};
};

// The block grid: cores of `chunk` voxels per side (the last ones shorter), in x-fastest order.
struct Grid3 {
  Dims d;
  std::size_t c = 0, n[3] = {0, 0, 0};
  Grid3(Dims dims, std::size_t chunk) : d(dims), c(chunk) {
    n[0] = (d.nx + c - 1) / c;
    n[1] = (d.ny + c - 1) / c;
    n[2] = (d.nz + c - 1) / c;
  }
  std::size_t count() const { return n[0] * n[1] * n[2]; }
  Box core(std::size_t k) const {
    const std::size_t i[3] = {k % n[0], (k / n[0]) % n[1], k / (n[0] * n[1])};
    const std::size_t N[3] = {d.nx, d.ny, d.nz};
    Box b;
    for (std::size_t a = 0; a < 3; ++a) {
      b.lo[a] = i[a] * c;
      b.hi[a] = std::min(N[a], b.lo[a] + c);
    }
    return b;
  }
};

// Parses a memory size: 8GB, 512MB (decimal), 8GiB (binary), or bytes.
double parse_bytes(const std::string& text) {
  std::size_t pos = 0;
  double x = 0;
  try {
    x = std::stod(text, &pos);
  } catch (const std::exception&) {
    throw InputError("", "--memory", text, "expected a size such as 8GB, 512MB or 8GiB");
  }
  std::string u = text.substr(pos);
  for (auto& ch : u) ch = char(std::toupper(static_cast<unsigned char>(ch)));
  const std::map<std::string, double> units{{"", 1}, {"B", 1}, {"KB", 1e3}, {"MB", 1e6}, {"GB", 1e9}, {"TB", 1e12},
                                            {"KIB", 1024.0}, {"MIB", 1048576.0}, {"GIB", 1073741824.0}, {"TIB", 1099511627776.0}};
  const auto it = units.find(u);
  if (it == units.end() || !std::isfinite(x) || !(x > 0))
    throw InputError("", "--memory", text, "expected a size > 0 such as 8GB, 512MB or 8GiB");
  return x * it->second;
}

// What the chunked run holds (bytes): the whole-volume bit masks and face planes, the process
// itself (88 MB: 70 MB measured before the first block, and the output writer's buffers that do
// not grow with the block), and one block of the pass that holds the most. The passes run one
// after another and each frees its block: per block voxel (side chunk + 2 halo) the filter's
// float block and raw rows or the macropores' mask, distance and result, 6 bytes, 8 with a raw
// type of 4 bytes or more (5.5 measured for uint16); per core voxel the outputs' uint8 and int32
// blocks and HDF5's compression buffers, 12 (9.0-9.6 measured, the run's peak). Measured per
// stage at 512^3 (peak_rss_after_stage_bytes, docs/segment.md).
struct MemoryModel {
  double fixed = 0, per_block = 0;
  double total() const { return fixed + per_block; }
};
// Grains (grains_halo > 0): the distance map, markers and watershed of one block with its halo,
// 24 bytes per voxel (15-17 measured at 512^3 with one and two blocks at once, docs/segment.md:
// the block, its distance, markers, labels and the flood's queues); `grain_blocks` blocks are
// worked on at once (one per thread).
constexpr double kGrainsBytesPerBlockVoxel = 24;
MemoryModel memory_model(const Dims& d, std::size_t chunk, std::size_t halo, bool phase2, const BlockSource& src,
                         std::size_t grains_halo = 0, std::size_t grain_blocks = 1) {
  const std::size_t type_bytes = src.type_bytes();
  const double words = double((d.nx + 63) / 64) * double(d.ny) * double(d.nz) * 8;
  MemoryModel m;
  m.fixed = words * (phase2 ? 3 : 2) + 2.0 * 4 * double(d.nx) * double(d.ny) + 88e6;  // bits, faces, process
  const double s = double(chunk + 2 * halo), c = double(chunk);
  m.per_block = std::max(s * s * s * (6 + double(std::min<std::size_t>(type_bytes, 8)) / 2), c * c * c * 12) + src.reader_bytes();
  if (grains_halo > 0) {
    const double g = double(chunk + 2 * grains_halo);
    m.per_block = std::max(m.per_block, double(grain_blocks) * (g * g * g * kGrainsBytesPerBlockVoxel + c * c * c * 19));
  }
  return m;
}

// Runs f(k) for the blocks k = 0..count-1, `workers` of them at once; the first exception one
// throws is rethrown after the loop (none may leave an OpenMP region).
template <class F>
void each_block(std::size_t count, std::size_t workers, F&& f) {
  std::exception_ptr error;
  std::atomic<bool> failed{false};
#pragma omp parallel for schedule(dynamic, 1) num_threads(int(workers))
  for (std::ptrdiff_t k = 0; k < std::ptrdiff_t(count); ++k) {
    if (failed) continue;
    try {
      f(std::size_t(k));
    } catch (...) {
#pragma omp critical(tomodem_block_error)
      if (!error) error = std::current_exception();
      failed = true;
    }
  }
  if (error) std::rethrow_exception(error);
}

/// The largest block edge, a multiple of 32 below `below`, whose plan fits `budget`; 0 if none.
std::size_t largest_block(const Dims& d, std::size_t halo, bool phase2, const BlockSource& src, std::size_t grains_halo,
                          std::size_t grain_blocks, double budget, std::size_t below) {
  std::size_t best = 0;
  for (std::size_t c = 32; c < below; c += 32)
    if (memory_model(d, c, halo, phase2, src, grains_halo, grain_blocks).total() <= budget) best = c;
  return best;
}

// The union-find of block-local labels (global id = the block's offset + local label).
struct Joins {
  std::vector<int64_t> parent;
  std::vector<uint64_t> first, size;  ///< first voxel (x-fastest global index), voxel count
  int64_t find(int64_t a) {
    while (parent[std::size_t(a)] != a) {
      parent[std::size_t(a)] = parent[std::size_t(parent[std::size_t(a)])];
      a = parent[std::size_t(a)];
    }
    return a;
  }
  void unite(int64_t a, int64_t b) {
    a = find(a);
    b = find(b);
    if (a == b) return;
    if (first[std::size_t(b)] < first[std::size_t(a)]) std::swap(a, b);
    parent[std::size_t(b)] = a;  // the root keeps the smaller first voxel
  }
};

// HDF5 output written block by block: chunked, deflate-compressed datasets in a file whose root
// carries tomodem's provenance (written first with h5::File).
class LabelsWriter {
 public:
  LabelsWriter(const std::string& tmp, const Dims& d, std::size_t chunk, const std::vector<std::string>& inputs, bool grains)
      : d_(d) {
    {
      h5::File f(tmp, h5::File::Mode::create);
      write_provenance(f, inputs);
      f.close();
    }
    file_ = H5Fopen(tmp.c_str(), H5F_ACC_RDWR, H5P_DEFAULT);
    if (file_ < 0) throw RuntimeFailure(tmp + ": cannot reopen the labels file");
    // HDF5 chunks that tile the blocks: 64 when the block is a multiple of it, else the block (<= 128).
    std::size_t hc = chunk % 64 == 0 ? 64 : (chunk <= 128 ? chunk : std::gcd(chunk, std::size_t(64)));
    hc = std::max<std::size_t>(hc, 8);
    const hsize_t dims[3] = {d.nz, d.ny, d.nx};
    const hsize_t cd[3] = {std::min<hsize_t>(hc, d.nz), std::min<hsize_t>(hc, d.ny), std::min<hsize_t>(hc, d.nx)};
    labels_ = make(tmp, "labels", H5T_STD_U8LE, dims, cd);
    macro_ = make(tmp, "macropores", H5T_STD_I32LE, dims, cd);
    if (grains) grains_ = make(tmp, "grains", H5T_STD_I32LE, dims, cd);
    path_ = tmp;
  }
  ~LabelsWriter() {
    if (labels_ >= 0) H5Dclose(labels_);
    if (macro_ >= 0) H5Dclose(macro_);
    if (grains_ >= 0) H5Dclose(grains_);
    if (file_ >= 0) H5Fclose(file_);
  }
  void write(const Box& b, const std::vector<uint8_t>& phases, const std::vector<int32_t>& ids) {
    put(labels_, b, H5T_NATIVE_UINT8, phases.data());
    put(macro_, b, H5T_NATIVE_INT32, ids.data());
  }
  void write_grains(const Box& b, const std::vector<int32_t>& ids) { put(grains_, b, H5T_NATIVE_INT32, ids.data()); }
  void finish(const std::array<double, 3>& spacing, const std::array<double, 3>& origin, const std::string& legend) {
    for (hid_t ds : {labels_, macro_, grains_}) {
      if (ds < 0) continue;
      attr_doubles(ds, "spacing", spacing);
      attr_doubles(ds, "origin", origin);
      attr_string(ds, "axes", "z,y,x (spacing and origin listed x,y,z, m)");
      attr_string(ds, "units", "1");
    }
    attr_string(labels_, "legend", legend);
    H5Dclose(labels_);
    H5Dclose(macro_);
    if (grains_ >= 0) H5Dclose(grains_);
    labels_ = macro_ = grains_ = -1;
    const herr_t e = H5Fclose(file_);
    file_ = -1;
    if (e < 0) throw RuntimeFailure(path_ + ": closing the labels file failed (disk full?)");
  }

 private:
  hid_t make(const std::string& tmp, const char* name, hid_t type, const hsize_t* dims, const hsize_t* cd) {
    const hid_t space = H5Screate_simple(3, dims, nullptr);
    const hid_t dcpl = H5Pcreate(H5P_DATASET_CREATE);
    H5Pset_chunk(dcpl, 3, cd);
    H5Pset_shuffle(dcpl);
    H5Pset_deflate(dcpl, 1);  // mostly zeros and long runs: level 1 is as small as 6 within a few percent, and faster
    const hid_t ds = H5Dcreate2(file_, name, type, space, H5P_DEFAULT, dcpl, H5P_DEFAULT);
    H5Pclose(dcpl);
    H5Sclose(space);
    if (ds < 0) throw RuntimeFailure(tmp + ": cannot create dataset /" + name);
    return ds;
  }
  void put(hid_t ds, const Box& b, hid_t mem_type, const void* data) {
    const BlockSpaces spaces(ds, b);
    if (H5Dwrite(ds, mem_type, spaces.memory, spaces.file, H5P_DEFAULT, data) < 0)
      throw RuntimeFailure(path_ + ": writing a block of labels failed (disk full?)");
  }
  void attr_doubles(hid_t ds, const char* name, const std::array<double, 3>& v) {
    const hsize_t n = 3;
    const hid_t sp = H5Screate_simple(1, &n, nullptr);
    const hid_t a = H5Acreate2(ds, name, H5T_IEEE_F64LE, sp, H5P_DEFAULT, H5P_DEFAULT);
    H5Awrite(a, H5T_NATIVE_DOUBLE, v.data());
    H5Aclose(a);
    H5Sclose(sp);
  }
  void attr_string(hid_t ds, const char* name, const std::string& s) {
    const hid_t t = H5Tcopy(H5T_C_S1);  // variable-length UTF-8, as h5::File writes them
    H5Tset_size(t, H5T_VARIABLE);
    H5Tset_cset(t, H5T_CSET_UTF8);
    const hid_t sp = H5Screate(H5S_SCALAR);
    const hid_t a = H5Acreate2(ds, name, t, sp, H5P_DEFAULT, H5P_DEFAULT);
    const char* p = s.c_str();
    H5Awrite(a, t, &p);
    H5Aclose(a);
    H5Sclose(sp);
    H5Tclose(t);
  }
  Dims d_;
  std::string path_;
  hid_t file_ = -1, labels_ = -1, macro_ = -1, grains_ = -1;
};

// What the chunked path does not do (yet): refused before any work, naming the option.
void refuse_unsupported(const SegmentConfig& c, const std::string& format) {
  const std::string why = "is not available with --chunk/--memory (the chunked path, docs/segment.md \"Volumes larger than memory\")";
  if (format != "raw" && format != "h5")
    throw InputError(c.input, "format", format, "the chunked path reads raw files only (--raw-dims) or HDF5 datasets (--dataset), by block; " + why);
  if (c.filter != ImageFilter::median && c.filter != ImageFilter::gaussian && c.filter != ImageFilter::none)
    throw InputError("", "--filter", to_string(c.filter), why + "; use median, gaussian or none");
  if (c.method == ThresholdMethod::hysteresis) throw InputError("", "--method", "hysteresis", why);
  if (c.open_r > 0) throw InputError("", "--open", value_text(c.open_r), why);
  if (c.close_r > 0) throw InputError("", "--close", value_text(c.close_r), why);
  if (c.min_island > 1) throw InputError("", "--min-island", std::to_string(c.min_island), why);
  if (!c.mha.empty()) throw InputError("", "--mha", c.mha, why + "; -o labels.h5 is written block by block");
  if (!c.vdb.empty()) throw InputError("", "--vdb", c.vdb, why);
  if (!c.overlay.empty()) throw InputError("", "--overlay", c.overlay, why);
  if (c.read.has_roi || !c.roi_text.empty()) throw InputError("", "--roi", c.roi_text, why);
  if (c.read.downsample != 1) throw InputError("", "--downsample", std::to_string(c.read.downsample), why);
}

}  // namespace

std::string run_segment_chunked(const SegmentConfig& cfg, const ReadOptions& ro) {
  using clk = std::chrono::steady_clock;
  auto last = clk::now();
  json times = json::object();
  // The process's peak memory so far after each stage: the stage where it rises is the one whose
  // buffers set the run's peak (what --memory has to hold).
  json peaks = json::object();
  const auto done = [&](const char* stage) {
    const auto t = clk::now();
    times[stage] = std::chrono::duration<double>(t - last).count();
    peaks[stage] = peak_rss_bytes();
    last = t;
  };
  const std::string format = input_format(cfg.input, ro);
  refuse_unsupported(cfg, format);
  // The voxel size and origin: --spacing for raw; an HDF5 dataset's attributes or --spacing.
  VolumeGeometry vg{ro.spacing, {0, 0, 0}, "--spacing", ""};
  std::unique_ptr<BlockSource> source;
  if (format == "h5") {
    if (!fs::is_regular_file(cfg.input)) throw InputError(cfg.input, "", "", "no such file");
    source = std::make_unique<H5Blocks>(cfg.input, ro.h5_dataset);
    vg = h5_geometry(cfg.input, ro);
  } else {
    if (!(ro.spacing[0] > 0)) throw InputError(cfg.input, "spacing", "", "raw carries no voxel size; give --spacing (e.g. 60.7um)");
    source = std::make_unique<RawBlocks>(cfg.input, ro);
  }
  BlockSource& src = *source;
  const Dims D = src.dims();
  Volume geom;  // geometry only (spacing, origin) for the helpers that take a volume
  geom.dims = D;
  geom.spacing = vg.spacing;
  const auto& sp = vg.spacing;
  const double finest = std::min({sp[0], sp[1], sp[2]});

  // Halos: the median's box or the Gaussian's kernel, and 2r + 2 for the macropores (segment.hpp,
  // macropore_mask).
  std::array<int, 3> fr{0, 0, 0};
  double radius = 0, sigma = 0;
  if (cfg.filter == ImageFilter::gaussian) {
    const double L = parse_length("--sigma", cfg.sigma_text);
    sigma = L < 0 ? -L : L / finest;
    fr = gaussian_radii(geom, sigma);
  }
  if (cfg.filter == ImageFilter::median) {
    const double L = parse_length("--filter-radius", cfg.filter_radius_text);
    radius = L < 0 ? -L : L / finest;
    if (!(radius >= 1 && radius <= 10))
      throw InputError("", "--filter-radius", cfg.filter_radius_text, "is " + value_text(radius) + " voxels of the finest axis here; must be in [1, 10]");
    fr = radii_for_length(geom, radius);
  }
  const double Lm = parse_length("--macropore-radius", cfg.macro_radius_text);
  const double macro_r = Lm < 0 ? -Lm : Lm / finest;
  const std::size_t mhalo = std::size_t(std::ceil(2 * macro_r + 2));
  const std::size_t fhalo = std::size_t(*std::max_element(fr.begin(), fr.end()));
  const std::size_t halo = std::max(mhalo, fhalo);
  const bool phase2 = cfg.method == ThresholdMethod::multiotsu3 || (cfg.method == ThresholdMethod::manual && cfg.levels.size() == 2);
  // Grains: the halo is known once the largest inscribed radius is (below); the block size from
  // --memory plans for grains up to 10 voxels in radius (a halo of 24) and is checked again then.
  const std::size_t grains_guess = cfg.grains ? std::max<std::size_t>(halo, 24) : 0;
  // The grains' markers and watershed are serial within a block: one block per thread at once.
  const std::size_t workers = cfg.grains ? std::size_t(std::max(1, omp_get_max_threads())) : 1;

  // The block size: given (--chunk), or the largest multiple of 32 the budget (--memory) allows.
  const double budget = cfg.memory_text.empty() ? 0 : parse_bytes(cfg.memory_text);
  std::size_t chunk = cfg.chunk;
  const std::size_t biggest = std::max({D.nx, D.ny, D.nz});
  if (chunk == 0) {
    chunk = largest_block(D, halo, phase2, src, grains_guess, workers, budget, biggest + 32);
    if (chunk == 0) {
      const MemoryModel m = memory_model(D, std::max<std::size_t>(halo, 32), halo, phase2, src, grains_guess, workers);
      throw InputError("", "--memory", cfg.as_written.count("--memory") ? cfg.as_written.at("--memory") : cfg.memory_text,
                       "is below what one block needs: " + bytes_text(m.total()) + " for the smallest block (" +
                           std::to_string(std::max<std::size_t>(halo, 32)) + " voxels per side with a halo of " +
                           std::to_string(halo) + "): " + bytes_text(m.fixed) + " held for the whole run (bit masks of the " +
                           std::to_string(D.nx) + "x" + std::to_string(D.ny) + "x" + std::to_string(D.nz) +
                           " volume, block faces, 88 MB for the process) plus " + bytes_text(m.per_block) + " for the block");
    }
  }
  if (chunk < halo)
    throw InputError("", "--chunk", std::to_string(chunk),
                     "is below the halo of " + std::to_string(halo) + " voxels (" +
                         (cfg.filter == ImageFilter::gaussian ? "Gaussian kernel radius " : "median box radius ") + std::to_string(fhalo) +
                         ", macropores 2r + 2 = " + std::to_string(mhalo) + " at r = " + value_text(macro_r) +
                         " voxels): a block would be mostly halo; give --chunk >= " + std::to_string(halo));
  chunk = std::min(chunk, biggest);
  MemoryModel mem = memory_model(D, chunk, halo, phase2, src, grains_guess, workers);
  if (budget > 0 && mem.total() > budget)
    throw InputError("", "--memory", cfg.as_written.count("--memory") ? cfg.as_written.at("--memory") : cfg.memory_text,
                     "is below what --chunk " + std::to_string(chunk) + " needs: " + bytes_text(mem.total()) + " (" +
                         bytes_text(mem.fixed) + " held for the whole run + " + bytes_text(mem.per_block) +
                         " for one block with its halo of " + std::to_string(halo) + "); give a smaller --chunk or more --memory");
  check_memory_request(mem.total(), cfg.input, "--chunk", std::to_string(chunk),
                       "a chunked run of a " + std::to_string(D.nx) + "x" + std::to_string(D.ny) + "x" + std::to_string(D.nz) + " volume");
  Grid3 G(D, chunk);  // re-planned once the grains halo is measured (2b)
  std::size_t replanned_from = 0;
  info("chunked: " + std::to_string(G.count()) + " blocks of " + std::to_string(chunk) + " voxels per side, halo " +
       std::to_string(halo) + ", planned memory " + bytes_text(mem.total()));

  const std::array<std::size_t, 3> fh{std::size_t(fr[0]), std::size_t(fr[1]), std::size_t(fr[2])};
  // Filters block k: calls f(block volume, its box, the core box) for the core's filtered values.
  const auto filtered = [&](auto&& f) {
    Volume b;
    b.spacing = sp;
    for (std::size_t k = 0; k < G.count(); ++k) {
      const Box core = G.core(k), outer = core.grown(fh, D);
      src.read(outer, b);
      if (cfg.filter == ImageFilter::median) median_inplace(b, fr);
      if (cfg.filter == ImageFilter::gaussian) gaussian_inplace(b, sigma);
      f(b, outer, core);
    }
  };
  const auto for_core = [](const Box& outer, const Box& core, auto&& g) {  // g(index in block, x, y, z)
    for (std::size_t z = core.lo[2]; z < core.hi[2]; ++z)
      for (std::size_t y = core.lo[1]; y < core.hi[1]; ++y) {
        const std::size_t row = ((z - outer.lo[2]) * outer.n(1) + (y - outer.lo[1])) * outer.n(0) - outer.lo[0];
        for (std::size_t x = core.lo[0]; x < core.hi[0]; ++x) g(row + x, x, y, z);
      }
  };

  // 1. Histograms of the filtered values (one pass for <= 16-bit integers, whose median or
  // unfiltered values are their own; else, and after a Gaussian, min/max first).
  float lo = std::numeric_limits<float>::max(), hi = std::numeric_limits<float>::lowest();
  std::vector<uint64_t> counts;
  const bool exact = src.small_integers() && cfg.filter != ImageFilter::gaussian;
  if (exact) counts.assign(65536, 0);
  const long off = src.offset();
  filtered([&](const Volume& b, const Box& outer, const Box& core) {
    for_core(outer, core, [&](std::size_t i, std::size_t, std::size_t, std::size_t) {
      const float x = b.v[i];
      lo = std::min(lo, x);
      hi = std::max(hi, x);
      if (exact) ++counts[std::size_t(long(x) - off)];
    });
  });
  if (!(src.vmax > src.vmin))
    throw InputError(cfg.input, "volume", value_text(src.vmin), "constant volume (every voxel has this value): nothing to segment");
  GreyHistogram h256 = empty_histogram(lo, hi, 256), h1024 = empty_histogram(lo, hi, 1024), h4096 = empty_histogram(lo, hi, 4096);
  const auto add = [&](float x, double n) {
    h256.h[std::size_t(h256.bin(x))] += n;
    h1024.h[std::size_t(h1024.bin(x))] += n;
    h4096.h[std::size_t(h4096.bin(x))] += n;
  };
  if (exact) {
    for (std::size_t k = 0; k < counts.size(); ++k)
      if (counts[k]) add(float(long(k) + off), double(counts[k]));
  } else {
    filtered([&](const Volume& b, const Box& outer, const Box& core) {
      for_core(outer, core, [&](std::size_t i, std::size_t, std::size_t, std::size_t) { add(b.v[i], 1.0); });
    });
  }
  done("filter_histogram");

  Summary summary("tomodem-segment");
  const auto range = type_range(to_string(src.type()));
  summary.input(cfg.input, {{"format", format}, {"pixel_type", to_string(src.type())}, {"files", 1},
                            {"dims", {D.nx, D.ny, D.nz}}, {"spacing_m", sp}, {"origin_m", vg.origin},
                            {"spacing_source", vg.spacing_source}, {"value_range", {src.vmin, src.vmax}}, {"type_range", {range[0], range[1]}}});
  json filt{{"name", to_string(cfg.filter)}};
  if (cfg.filter == ImageFilter::median) {
    filt["radius_vox"] = radius;
    filt["radius_m"] = radius * finest;
    filt["box_radii_vox"] = fr;
  }
  if (cfg.filter == ImageFilter::gaussian) {
    filt["sigma_vox"] = sigma;
    filt["sigma_m"] = sigma * finest;
  }
  summary["filter"] = filt;
  std::vector<double> t;
  switch (cfg.method) {
    case ThresholdMethod::otsu: case ThresholdMethod::multiotsu2: t = {multi_otsu_thresholds(h256, 2).front()}; break;
    case ThresholdMethod::peaks: case ThresholdMethod::intermeans: {
      const double t_otsu = multi_otsu_thresholds(h256, 2).front();
      t = {cfg.method == ThresholdMethod::peaks ? peaks_threshold(h1024, t_otsu) : intermeans_threshold(h4096, t_otsu)};
      summary["otsu_threshold"] = t_otsu;
      break;
    }
    case ThresholdMethod::multiotsu3: t = multi_otsu_thresholds(h256, 3); break;
    case ThresholdMethod::manual: t = cfg.levels; std::sort(t.begin(), t.end()); break;
    case ThresholdMethod::hysteresis: break;  // refused above
  }

  // 2. The solid (and a second solid phase) as bits; the filter runs again.
  Bits solid(D), second(phase2 ? D : Dims{});
  const bool dark = !cfg.pores_bright;
  filtered([&](const Volume& b, const Box& outer, const Box& core) {
    for_core(outer, core, [&](std::size_t i, std::size_t x, std::size_t y, std::size_t z) {
      const float v = b.v[i];
      if (dark ? v >= t.front() : v < t.back()) solid.set(x, y, z);
      if (phase2 && (dark ? v >= t[1] : v < t[0])) second.set(x, y, z);
    });
  });
  std::size_t n_pore = D.count() - solid.count();
  done("threshold");

  // 2b. Grains (--grains): the largest inscribed radius, right after the solid is known, so that
  // a block planned from --memory alone can be re-planned for the measured halo before any
  // stage runs on the block grid (the bits do not depend on it).
  GrainOptions go;
  go.h = cfg.h;
  const auto solid_block = [&](const Box& outer, Mask& m) {
    m.dims = outer.dims();
    m.spacing = sp;
    m.origin = {0, 0, 0};
    m.v.resize(m.dims.count());
    std::size_t i = 0;
    for (std::size_t z = outer.lo[2]; z < outer.hi[2]; ++z)
      for (std::size_t y = outer.lo[1]; y < outer.hi[1]; ++y)
        for (std::size_t x = outer.lo[0]; x < outer.hi[0]; ++x, ++i) m.v[i] = solid.get(x, y, z);
  };
  const auto whole = [&](const Box& b) { return b.n(0) == D.nx && b.n(1) == D.ny && b.n(2) == D.nz; };
  double inscribed_max = 0;  // the largest distance to a pore (finest voxels)
  std::size_t ghalo = 0;
  std::vector<uint64_t> peak_at;   // marker voxels (x-fastest global index), ascending
  std::vector<int32_t> peak_id;    // their marker ids, 1..n by first voxel
  int n_grains = 0;
  if (cfg.grains) {
    Mask m;
    for (std::size_t k = 0; k < G.count(); ++k) {
      const Box core = G.core(k);
      // A core voxel's distance d found in the block is at least the true one, and exact when
      // the ball of radius d fits in the block (its nearest pore is then inside).
      for (std::size_t H = std::max<std::size_t>(halo, 8);; H *= 2) {
        const Box outer = core.grown({H, H, H}, D);
        solid_block(outer, m);
        const auto d2 = distance_squared(m);
        float mx = 0;
        for_core(outer, core, [&](std::size_t i, std::size_t, std::size_t, std::size_t) { mx = std::max(mx, d2[i]); });
        if (whole(outer) || std::sqrt(double(mx)) + 1 <= double(H)) {
          inscribed_max = std::max(inscribed_max, std::sqrt(double(mx)));
          break;
        }
        if (H > 2 * chunk)
          throw InputError("", "--chunk", std::to_string(chunk),
                           "is too small for grain separation: the solid holds a ball of radius above " + std::to_string(H - 1) +
                               " voxels, and the distance map needs a halo wider than that; give a larger --chunk");
      }
    }
    ghalo = std::size_t(std::ceil(2 * inscribed_max)) + 4;
    done("grains_radius");
    mem = memory_model(D, chunk, halo, phase2, src, ghalo, workers);
    if (budget > 0 && mem.total() > budget) {
      // The block the budget holds with this halo (a multiple of 32, at least the halo): the
      // tool's own choice is re-planned with it; a --chunk the user gave is refused, naming it.
      std::size_t fits = largest_block(D, halo, phase2, src, ghalo, workers, budget, chunk);
      if (fits < halo) fits = 0;  // a block must be at least its halo
      if (fits && cfg.chunk == 0) {
        info("grains: a halo of " + std::to_string(ghalo) + " (largest inscribed radius " + value_text(inscribed_max) + " voxels) needs " +
             bytes_text(mem.total()) + " in blocks of " + std::to_string(chunk) + ", above --memory; blocks of " +
             std::to_string(fits) + " from here on");
        replanned_from = chunk;
        chunk = fits;
        G = Grid3(D, chunk);
        mem = memory_model(D, chunk, halo, phase2, src, ghalo, workers);
      } else {
        // The tool's own block is refused only when the smallest block does not fit either.
        const std::size_t smallest = std::min(std::max<std::size_t>(halo, 32), chunk);
        const std::string block = cfg.chunk ? "--chunk " + std::to_string(chunk) : "the smallest block (" + std::to_string(smallest) + " voxels per side)";
        if (!cfg.chunk) mem = memory_model(D, smallest, halo, phase2, src, ghalo, workers);
        throw InputError("", "--memory", cfg.as_written.count("--memory") ? cfg.as_written.at("--memory") : cfg.memory_text,
                         "is below what grain separation needs with " + block + ": " + bytes_text(mem.total()) +
                             " (the solid's largest inscribed radius is " + value_text(inscribed_max) + " voxels, so a grains halo of " +
                             std::to_string(ghalo) + "); " +
                             (fits ? "give --chunk " + std::to_string(fits) + " (the largest block this budget holds with that halo) or more --memory"
                                   : "give more --memory"));
      }
    }
    check_memory_request(mem.total(), cfg.input, "--chunk", std::to_string(chunk), "chunked grain separation");
    info("grains: largest inscribed radius " + value_text(inscribed_max) + " voxels, halo " + std::to_string(ghalo) +
         ", planned memory " + bytes_text(mem.total()));
  }

  // Specific surface of the solid: faces between unlike neighbours, counted by words.
  double fx = 0, fy = 0, fz = 0;
  {
    const std::size_t W = solid.W, tail = D.nx % 64;
    const uint64_t last = tail ? (uint64_t(1) << tail) - 1 : ~uint64_t(0);
    for (std::size_t z = 0; z < D.nz; ++z)
      for (std::size_t y = 0; y < D.ny; ++y) {
        const uint64_t* r = solid.row(y, z);
        for (std::size_t w = 0; w < W; ++w) {
          const uint64_t m = w + 1 == W ? last : ~uint64_t(0);
          // x: bit i against bit i + 1 (the next word's bit 0 for bit 63), pairs inside the row only
          uint64_t nxt = r[w] >> 1;
          if (w + 1 < W) nxt |= r[w + 1] << 63;
          uint64_t pm = m;
          if (w + 1 == W) pm = tail ? (last >> 1) : (~uint64_t(0) >> 1);
          fx += double(__builtin_popcountll((r[w] ^ nxt) & pm));
          if (y + 1 < D.ny) fy += double(__builtin_popcountll((r[w] ^ solid.row(y + 1, z)[w]) & m));
          if (z + 1 < D.nz) fz += double(__builtin_popcountll((r[w] ^ solid.row(y, z + 1)[w]) & m));
        }
      }
  }
  const double surface = specific_surface(fx, fy, fz, D, sp);

  // 3. Macropore voxels, block by block with the 2r + 2 halo.
  Bits macro(D);
  {
    const std::array<std::size_t, 3> mh{mhalo, mhalo, mhalo};
    Mask pores;
    pores.spacing = sp;
    for (std::size_t k = 0; k < G.count(); ++k) {
      const Box core = G.core(k), outer = core.grown(mh, D);
      pores.dims = outer.dims();
      pores.v.resize(pores.dims.count());
      for (std::size_t z = outer.lo[2]; z < outer.hi[2]; ++z)
        for (std::size_t y = outer.lo[1]; y < outer.hi[1]; ++y) {
          uint8_t* o = &pores.v[((z - outer.lo[2]) * outer.n(1) + (y - outer.lo[1])) * outer.n(0)];
          for (std::size_t x = outer.lo[0]; x < outer.hi[0]; ++x) o[x - outer.lo[0]] = !solid.get(x, y, z);
        }
      const Mask opened = macropore_mask(pores, macro_r);
      for_core(outer, core, [&](std::size_t i, std::size_t x, std::size_t y, std::size_t z) {
        if (opened.v[i]) macro.set(x, y, z);
      });
    }
  }
  done("macropores");

  // 4. Labels: each core on its own, joined across faces (6-connectivity) by union-find.
  const auto core_labels = [&](const Box& core, int* n) {
    Mask m(core.dims());
    for (std::size_t z = core.lo[2]; z < core.hi[2]; ++z)
      for (std::size_t y = core.lo[1]; y < core.hi[1]; ++y)
        for (std::size_t x = core.lo[0]; x < core.hi[0]; ++x)
          m.v[((z - core.lo[2]) * core.n(1) + (y - core.lo[1])) * core.n(0) + (x - core.lo[0])] = macro.get(x, y, z);
    return components(m, 6, n);
  };
  Joins J;
  J.parent.push_back(0);
  J.first.push_back(0);
  J.size.push_back(0);
  std::vector<int64_t> offset(G.count(), 0);
  std::map<std::size_t, std::vector<int64_t>> face[3];  // a block's high faces (global ids), until its neighbour reads them
  for (std::size_t k = 0; k < G.count(); ++k) {
    const Box core = G.core(k);
    int n = 0;
    const Labels L = core_labels(core, &n);
    const int64_t base = int64_t(J.parent.size()) - 1;
    offset[k] = base;
    for (int a = 1; a <= n; ++a) {
      J.parent.push_back(base + a);
      J.first.push_back(std::numeric_limits<uint64_t>::max());
      J.size.push_back(0);
    }
    const std::size_t nx = core.n(0), ny = core.n(1), nz = core.n(2);
    for (std::size_t z = 0; z < nz; ++z)
      for (std::size_t y = 0; y < ny; ++y)
        for (std::size_t x = 0; x < nx; ++x) {
          const int32_t l = L.v[(z * ny + y) * nx + x];
          if (!l) continue;
          const auto g = std::size_t(base + l);
          if (J.first[g] == std::numeric_limits<uint64_t>::max())
            J.first[g] = ((core.lo[2] + z) * D.ny + core.lo[1] + y) * D.nx + core.lo[0] + x;
          ++J.size[g];
        }
    const std::size_t ci[3] = {k % G.n[0], (k / G.n[0]) % G.n[1], k / (G.n[0] * G.n[1])};
    const std::size_t stride[3] = {1, G.n[0], G.n[0] * G.n[1]};
    const std::size_t n3[3] = {nx, ny, nz};
    for (int a = 0; a < 3; ++a) {
      // The plane of this core at index p along axis a, as (u, v) with u the faster remaining axis.
      const int ua = a == 0 ? 1 : 0, va = a == 2 ? 1 : 2;
      const auto at = [&](std::size_t p, std::size_t u, std::size_t v) {
        std::size_t c[3];
        c[a] = p;
        c[ua] = u;
        c[va] = v;
        return L.v[(c[2] * ny + c[1]) * nx + c[0]];
      };
      if (ci[a] > 0) {  // join with the lower neighbour's high face
        auto it = face[a].find(k - stride[a]);
        const auto& pl = it->second;
        for (std::size_t v = 0; v < n3[va]; ++v)
          for (std::size_t u = 0; u < n3[ua]; ++u) {
            const int32_t l = at(0, u, v);
            const int64_t q = pl[v * n3[ua] + u];
            if (l && q) J.unite(base + l, q);
          }
        face[a].erase(it);
      }
      if (ci[a] + 1 < G.n[a]) {
        std::vector<int64_t> pl(n3[ua] * n3[va], 0);
        for (std::size_t v = 0; v < n3[va]; ++v)
          for (std::size_t u = 0; u < n3[ua]; ++u) {
            const int32_t l = at(n3[a] - 1, u, v);
            if (l) pl[v * n3[ua] + u] = base + l;
          }
        face[a][k] = std::move(pl);
      }
    }
  }
  // Roots: their total size and first voxel; kept ones numbered by first voxel (components()
  // order), then the size filter's renumbering (macropores()) keeps that order.
  std::vector<uint64_t> total(J.parent.size(), 0);
  for (std::size_t g = 1; g < J.parent.size(); ++g) total[std::size_t(J.find(int64_t(g)))] += J.size[g];
  std::vector<int64_t> kept;
  for (std::size_t g = 1; g < J.parent.size(); ++g)
    if (J.parent[g] == int64_t(g) && total[g] >= std::max<std::size_t>(cfg.macro_min_voxels, 1)) kept.push_back(int64_t(g));
  std::sort(kept.begin(), kept.end(), [&](int64_t a, int64_t b) { return J.first[std::size_t(a)] < J.first[std::size_t(b)]; });
  if (kept.size() > std::size_t(std::numeric_limits<int32_t>::max()))
    throw RuntimeFailure(cfg.input + ": more than 2^31 - 1 macropores: int32 ids cannot hold them");
  std::vector<int32_t> final_id(J.parent.size(), 0);
  for (std::size_t r = 0; r < kept.size(); ++r) final_id[std::size_t(kept[r])] = int32_t(r + 1);
  for (std::size_t g = 1; g < J.parent.size(); ++g) final_id[g] = final_id[std::size_t(J.find(int64_t(g)))];
  std::vector<uint64_t>().swap(total);
  done("labels");

  // 4b. Grains (--grains): the markers, numbered over the volume; the watershed runs block by
  // block with the outputs (5).
  if (cfg.grains) {
    // Marker voxels of each core, from its block with the grains halo.
    const std::array<std::size_t, 3> gh{ghalo, ghalo, ghalo};
    std::vector<std::vector<uint64_t>> found(G.count());
    each_block(G.count(), workers, [&](std::size_t k) {
      const Box core = G.core(k), outer = core.grown(gh, D);
      Mask m;
      solid_block(outer, m);
      const Mask peaks = grain_peaks(m, go);
      for_core(outer, core, [&](std::size_t i, std::size_t x, std::size_t y, std::size_t z) {
        if (peaks.v[i]) found[k].push_back((z * D.ny + y) * D.nx + x);
      });
    });
    for (auto& f : found) peak_at.insert(peak_at.end(), f.begin(), f.end());
    std::vector<std::vector<uint64_t>>().swap(found);
    // 26-connected marker components over the whole volume, numbered by first voxel.
    std::sort(peak_at.begin(), peak_at.end());
    std::vector<std::size_t> up(peak_at.size());
    std::iota(up.begin(), up.end(), std::size_t(0));
    const auto root = [&](std::size_t a) {
      while (up[a] != a) a = up[a] = up[up[a]];
      return a;
    };
    for (std::size_t i = 0; i < peak_at.size(); ++i) {
      const uint64_t g = peak_at[i];
      const long x = long(g % D.nx), y = long(g / D.nx % D.ny), z = long(g / (D.nx * D.ny));
      for (long dz = 0; dz <= 1; ++dz)
        for (long dy = dz ? -1 : 0; dy <= 1; ++dy)
          for (long dx = (dz || dy) ? -1 : 1; dx <= 1; ++dx) {  // the 13 neighbours after this voxel
            const long X = x + dx, Y = y + dy, Z = z + dz;
            if (X < 0 || Y < 0 || X >= long(D.nx) || Y >= long(D.ny) || Z >= long(D.nz)) continue;
            const uint64_t q = (uint64_t(Z) * D.ny + uint64_t(Y)) * D.nx + uint64_t(X);
            const auto it = std::lower_bound(peak_at.begin() + std::ptrdiff_t(i), peak_at.end(), q);
            if (it == peak_at.end() || *it != q) continue;
            const std::size_t a = root(i), b = root(std::size_t(it - peak_at.begin()));
            if (a != b) up[std::max(a, b)] = std::min(a, b);  // the root is the component's first voxel
          }
    }
    peak_id.assign(peak_at.size(), 0);
    for (std::size_t i = 0; i < peak_at.size(); ++i) {
      const std::size_t r = root(i);
      peak_id[i] = r == i ? ++n_grains : peak_id[r];
    }
    done("grains_markers");
    info("grains: " + std::to_string(n_grains) + " markers");
  }

  // 5. Outputs block by block; each macropore's statistics summed as regions() sums them
  // (RegionSums: the same in any block order).
  const int n_macro = int(kept.size());
  RegionSums macro_sums(kept.size());
  std::size_t n_macro_vox = 0;
  const std::string legend = "0:solid,1:fine_pore,2:macropore,3:solid_phase_2";
  std::string tmp;
  std::unique_ptr<LabelsWriter> out;
  if (!cfg.output.empty()) {
    tmp = temporary_path(cfg.output);
    // No input hashes, as the in-memory writer (hashing a 16 GiB scan would read it once more).
    out = std::make_unique<LabelsWriter>(tmp, D, chunk, std::vector<std::string>{}, cfg.grains);
  }
  // Grains: each block floods from the markers in its reach; statistics as for the macropores.
  RegionSums grain_sums(static_cast<std::size_t>(n_grains));
  std::vector<float> inscribed(std::size_t(n_grains) + 1, 0.0f);
  std::vector<std::size_t> n_phase2(std::size_t(n_grains) + 1, 0);
  std::vector<char> at_edge(std::size_t(n_grains) + 1, 0);
  // A grain of the core whose voxels reach the block's outer edge (a face that is not the
  // volume's) through voxels of the same id may be cut otherwise with more of the volume in view:
  // its id in the core is not certain. Returns those ids, and 0 when solid of the core that no
  // marker reached (label 0) reaches the edge the same way: its marker may lie beyond.
  const auto reaching_edge = [&](const Box& outer, const Box& core, const Mask& m, const Labels& L) {
    const std::size_t nx = outer.n(0), ny = outer.n(1), nz = outer.n(2);
    std::vector<uint8_t> seen(L.v.size(), 0);
    std::vector<std::size_t> stack;
    std::vector<int32_t> found;
    for_core(outer, core, [&](std::size_t i, std::size_t, std::size_t, std::size_t) {
      if ((L.v[i] || m.v[i]) && !seen[i]) {
        seen[i] = 1;
        stack.push_back(i);
      }
    });
    while (!stack.empty()) {
      const std::size_t i = stack.back();
      stack.pop_back();
      const std::size_t x = i % nx, y = i / nx % ny, z = i / (nx * ny);
      if ((x == 0 && outer.lo[0] > 0) || (x + 1 == nx && outer.hi[0] < D.nx) || (y == 0 && outer.lo[1] > 0) ||
          (y + 1 == ny && outer.hi[1] < D.ny) || (z == 0 && outer.lo[2] > 0) || (z + 1 == nz && outer.hi[2] < D.nz))
        found.push_back(L.v[i]);
      for (std::size_t c = z ? z - 1 : 0; c <= std::min(z + 1, nz - 1); ++c)
        for (std::size_t b = y ? y - 1 : 0; b <= std::min(y + 1, ny - 1); ++b)
          for (std::size_t a = x ? x - 1 : 0; a <= std::min(x + 1, nx - 1); ++a) {
            const std::size_t q = (c * ny + b) * nx + a;
            if (!seen[q] && L.v[q] == L.v[i] && (L.v[i] || m.v[q])) {
              seen[q] = 1;
              stack.push_back(q);
            }
          }
    }
    std::sort(found.begin(), found.end());
    found.erase(std::unique(found.begin(), found.end()), found.end());
    return found;
  };
  std::size_t widened = 0, widest = ghalo, solid_without_grain = 0;
  const auto grains_pass = [&] {
    // The widest halo a block may take: what the budget (or twice the plan) allows.
    const double limit = budget > 0 ? budget : 2 * mem.total();
    std::size_t cap = ghalo;
    while (memory_model(D, chunk, halo, phase2, src, 2 * cap, workers).total() <= limit) cap *= 2;
    each_block(G.count(), workers, [&](std::size_t k) {
      const Box core = G.core(k);
      Box outer;
      Mask m;
      Labels markers, L;
      std::vector<int32_t> far;
      std::size_t H = ghalo, times_widened = 0;
      // The block's watershed with the grains halo; twice as wide while a grain of the core
      // reaches its edge (a grain longer than the halo), up to the cap.
      for (;; H *= 2) {
        outer = core.grown({H, H, H}, D);
        solid_block(outer, m);
        markers.copy_geometry(m);
        markers.v.assign(m.v.size(), 0);
        for (std::size_t z = outer.lo[2]; z < outer.hi[2]; ++z)
          for (std::size_t y = outer.lo[1]; y < outer.hi[1]; ++y) {
            const uint64_t row = (z * D.ny + y) * D.nx;
            auto it = std::lower_bound(peak_at.begin(), peak_at.end(), row + outer.lo[0]);
            for (; it != peak_at.end() && *it < row + outer.hi[0]; ++it)
              markers.v[((z - outer.lo[2]) * outer.n(1) + (y - outer.lo[1])) * outer.n(0) + (*it - row - outer.lo[0])] =
                  peak_id[std::size_t(it - peak_at.begin())];
          }
        L = watershed_from_markers(m, markers, go);
        far = reaching_edge(outer, core, m, L);
        if (far.empty() || whole(outer) || 2 * H > cap) break;
        ++times_widened;
      }
      const auto d2 = distance_squared(m);  // exact in the core: the halo passes the largest distance
      std::vector<int32_t> ids(core.dims().count(), 0);
      // The sums are whole numbers in doubles (the same in any block order); one block at a time.
      // An exception (the write: a full disk) may not leave the critical section: kept, rethrown.
      std::exception_ptr error;
#pragma omp critical(tomodem_grains_sums)
      try {
        widened += times_widened;
        widest = std::max(widest, H);
        for (auto id : far)
          if (id > 0) at_edge[std::size_t(id)] = 1;
        std::size_t j = 0;
        for_core(outer, core, [&](std::size_t i, std::size_t x, std::size_t y, std::size_t z) {
          const int32_t id = L.v[i];
          ids[j++] = id;
          if (!id) {
            solid_without_grain += m.v[i];
            return;
          }
          grain_sums.add(id, x, y, z, D);
          inscribed[std::size_t(id)] = std::max(inscribed[std::size_t(id)], d2[i]);
          if (phase2 && second.get(x, y, z)) ++n_phase2[std::size_t(id)];
        });
        if (out) out->write_grains(core, ids);
      } catch (...) {
        error = std::current_exception();
      }
      if (error) std::rethrow_exception(error);
    });
    done("grains_watershed");
  };
  try {
    if (cfg.grains) grains_pass();
    std::vector<uint8_t> phases;
    std::vector<int32_t> ids;
    for (std::size_t k = 0; k < G.count(); ++k) {
      const Box core = G.core(k);
      int n = 0;
      const Labels L = core_labels(core, &n);
      phases.assign(L.v.size(), 0);
      ids.assign(L.v.size(), 0);
      std::size_t i = 0;
      for (std::size_t z = core.lo[2]; z < core.hi[2]; ++z)
        for (std::size_t y = core.lo[1]; y < core.hi[1]; ++y)
          for (std::size_t x = core.lo[0]; x < core.hi[0]; ++x, ++i) {
            const int32_t id = L.v[i] ? final_id[std::size_t(offset[k] + L.v[i])] : 0;
            ids[i] = id;
            uint8_t p = 0;
            if (id) {
              p = 2;
              ++n_macro_vox;
              macro_sums.add(id, x, y, z, D);
            } else if (!solid.get(x, y, z)) p = 1;
            else if (phase2 && second.get(x, y, z)) p = 3;
            phases[i] = p;
          }
      if (out) out->write(core, phases, ids);
    }
    done("outputs_blocks");
    if (out) {
      out->finish(sp, vg.origin, legend);
      out.reset();
      commit_output(cfg.output);
      std::vector<XdmfField> fields{{"labels", "/labels", "UChar", 1}, {"macropores", "/macropores", "Int", 4}};
      if (cfg.grains) fields.push_back({"grains", "/grains", "Int", 4});
      write_volume_xdmf(cfg.output, {D.nx, D.ny, D.nz}, vg.origin, sp, fields);
    }
  } catch (...) {
    out.reset();
    if (!tmp.empty()) std::remove(tmp.c_str());
    throw;
  }
  summary.output("labels_h5", cfg.output);

  const double N = double(D.count());
  summary["porosity"] = double(n_pore) / N;
  summary["macroporosity"] = double(n_macro_vox) / N;
  summary["fine_porosity"] = double(n_pore - n_macro_vox) / N;
  summary["n_macropores"] = n_macro;
  summary["thresholds"] = t;
  summary["threshold_rule"] = std::string(cfg.pores_bright ? "pores above the threshold" : "pores below the threshold") +
                              " (value >= t is the brighter class)";
  summary["method"] = to_string(cfg.method);
  summary["macropore_radius_m"] = macro_r * finest;
  summary["macropore_radius_vox"] = macro_r;
  summary["specific_surface_per_m"] = surface;
  summary["cleaning"] = {{"open_radius_vox", 0}, {"close_radius_vox", 0}, {"min_island_vox", cfg.min_island},
                         {"solid_islands_removed", 0}, {"pore_islands_removed", 0}, {"connectivity", cfg.connectivity}};
  macropore_summary(macro_sums.regions(vg.origin, sp), summary);
  if (cfg.grains) {
    Packing packing = grains_packing(grain_sums.regions(vg.origin, sp), inscribed, n_phase2, D, sp, vg.origin, phase2, cfg.h, solid_without_grain, summary);
    summary.n_particles(packing.particles.size());
    write_grains_packing(cfg, packing, summary);
  }
  summary["chunked"] = {{"chunk_vox", chunk}, {"halo_vox", halo}, {"blocks", G.count()},
                        {"memory_budget_bytes", budget > 0 ? json(budget) : json(nullptr)},
                        {"planned_memory_bytes", mem.total()}, {"histogram_passes", exact ? 1 : 2},
                        {"largest_read_voxels", src.largest_read}};
  if (const auto* h5 = dynamic_cast<const H5Blocks*>(&src)) summary["chunked"]["input_h5_chunk_vox"] = h5->chunk();
  if (cfg.grains) {
    summary["chunked"]["grains_halo_vox"] = ghalo;
    summary["chunked"]["largest_inscribed_radius_vox"] = inscribed_max;
    summary["chunked"]["grains_blocks_widened"] = widened;
    summary["chunked"]["grains_widest_halo_vox"] = widest;
    summary["chunked"]["grains_reaching_halo_edge"] = std::count(at_edge.begin(), at_edge.end(), char(1));
    // The block --memory gave before the grains halo was measured (null: it held the halo).
    summary["chunked"]["grains_replanned_from_chunk_vox"] = replanned_from ? json(replanned_from) : json(nullptr);
  }
  summary["stage_times_s"] = times;
  summary.unit("stage_times_s", "s");
  summary["peak_rss_after_stage_bytes"] = peaks;
  summary.unit("peak_rss_after_stage_bytes", "B");
  return summary.text();
}

}  // namespace tomodem::image
