// OpenVDB level sets (tomodem-segment writes them in millimetres, docs/segment.md): read,
// convert the world unit to metres explicitly, sample trilinearly with one accessor per call.
#include <openvdb/openvdb.h>
#include <openvdb/tools/Interpolation.h>

#include <sys/resource.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <csignal>
#include <cstdio>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstring>
#include <fstream>
#include <limits>

#include "tomodem/carve/carve.hpp"
#include "tomodem/core/error.hpp"
#include "tomodem/core/output.hpp"
#include "tomodem/core/tool.hpp"
#include "tomodem/image/outputs.hpp"

namespace tomodem::carve {

namespace {

class LevelSet final : public Macropores {
 public:
  LevelSet(openvdb::FloatGrid::Ptr g, double m_per_unit, std::string file)
      : grid_(std::move(g)), unit_(m_per_unit), file_(std::move(file)) {
    const auto bbox = grid_->evalActiveVoxelBoundingBox();
    const auto& xf = grid_->transform();
    const openvdb::Vec3d a = xf.indexToWorld(bbox.min().asVec3d() - openvdb::Vec3d(0.5));
    const openvdb::Vec3d b = xf.indexToWorld(bbox.max().asVec3d() + openvdb::Vec3d(0.5));
    for (int k = 0; k < 3; ++k) {
      box_.lo[k] = std::min(a[k], b[k]) * unit_;
      box_.hi[k] = std::max(a[k], b[k]) * unit_;
    }
    voxel_ = xf.voxelSize()[0] * unit_;
    band_ = std::abs(double(grid_->background())) * unit_;
    // The active band reaches `band_` beyond the surface: the macropores' box is that much smaller.
    for (int k = 0; k < 3; ++k) {
      const double shrink = std::min(band_, 0.5 * (box_.hi[k] - box_.lo[k]) - 0.5 * voxel_);
      if (shrink > 0) box_.lo[k] += shrink, box_.hi[k] -= shrink;
    }
  }
  double distance(const Vec3& p) const override {
    // Unregistered accessor: the grid is never modified, and registering one per query would
    // serialise the threads on the tree's accessor registry.
    const auto acc = grid_->getConstUnsafeAccessor();
    const openvdb::Vec3d ip = grid_->transform().worldToIndex(openvdb::Vec3d(p.x, p.y, p.z) / unit_);
    return double(openvdb::tools::BoxSampler::sample(acc, ip)) * unit_;
  }
  Box bounds() const override { return box_; }
  double band() const override { return band_; }
  double resolution() const override { return voxel_; }
  std::string describe() const override { return "OpenVDB level set '" + grid_->getName() + "' (" + file_ + ")"; }

 private:
  openvdb::FloatGrid::Ptr grid_;
  double unit_;
  std::string file_;
  Box box_;
  double voxel_ = 0, band_ = 0;
};

// A grid whose bytes are damaged (not cut: the table of contents is intact) can crash OpenVDB
// while it reads the tree (SIGSEGV, a failed free) or make it allocate without bound. So the grid
// is read once in a child process, with the machine's memory as its address-space limit and a
// time limit; only when the child read it cleanly does this process read it. OpenVDB's own
// exceptions are left to the real read, which reports them.
void trial_read(const std::string& path, const std::string& name) {
  std::fflush(nullptr);
  const pid_t pid = ::fork();
  if (pid < 0) return;  // no child: read as before
  if (pid == 0) {
    rlimit lim{};
    lim.rlim_cur = lim.rlim_max = rlim_t(usable_memory_bytes());
    ::setrlimit(RLIMIT_AS, &lim);
    ::alarm(300);
    int code = 0;
    try {
      openvdb::io::File f(path);
      f.open(false);  // no delayed loading: every leaf buffer is read now
      f.readGrid(name);
      f.close();
    } catch (const std::bad_alloc&) {
      code = 4;
    } catch (...) {
    }
    ::_exit(code);
  }
  int status = 0;
  while (::waitpid(pid, &status, 0) < 0 && errno == EINTR) {
  }
  const std::string grid = "grid '" + name + "'";
  if (WIFSIGNALED(status)) {
    const int sig = WTERMSIG(status);
    throw InputError(path, grid, "", sig == SIGALRM ? "reading the grid did not finish within 300 s: the file is corrupt"
                                                    : "the grid is corrupt: reading it crashed OpenVDB (" +
                                                          std::string(::strsignal(sig)) + ")");
  }
  if (WIFEXITED(status) && WEXITSTATUS(status) == 4)
    throw InputError(path, grid, "", "the grid is corrupt: reading it would need more memory than this machine has (" +
                                         bytes_text(double(usable_memory_bytes())) + ")");
}

double unit_from_metadata(const openvdb::GridBase& g, const std::string& path) {
  if (auto m = g.getMetadata<openvdb::DoubleMetadata>("metres_per_unit")) return m->value();
  if (auto m = g.getMetadata<openvdb::FloatMetadata>("metres_per_unit")) return double(m->value());
  if (auto s = g.getMetadata<openvdb::StringMetadata>("units")) {
    const std::string u = s->value();
    if (u == "m") return 1;
    if (u == "mm") return 1e-3;
    if (u == "um" || u == "µm") return 1e-6;
    throw InputError(path, "units", u, "unknown length unit in the grid metadata; give --image-unit");
  }
  warn(path + ": the level set carries no unit metadata; its world coordinates are taken as metres (--image-unit to override)");
  return 1;
}

}  // namespace

double Macropores::band() const { return std::numeric_limits<double>::infinity(); }

std::unique_ptr<Macropores> load_level_set(const std::string& path, const std::string& name, double metres_per_unit) {
  openvdb::initialize();
  image::check_vdb_file(path);
  openvdb::io::File file(path);
  try {
    file.open(false);  // no delayed loading: the whole grid is read (and checked) here, not while sampling
  } catch (const std::exception& e) {
    throw InputError(path, "", "", std::string("cannot open as an OpenVDB file: ") + e.what());
  }
  openvdb::FloatGrid::Ptr grid;
  std::vector<std::string> names;
  for (auto it = file.beginName(); it != file.endName(); ++it) names.push_back(it.gridName());
  const auto pick = [&](const std::string& n) {
    // The grid's own statistics (written by OpenVDB with every grid) say what it needs in memory:
    // refuse before the tree is read rather than after the machine runs out.
    const openvdb::GridBase::Ptr head = file.readGridMetadata(n);
    if (const auto bytes = head->getMetadata<openvdb::Int64Metadata>(openvdb::GridBase::META_FILE_MEM_BYTES))
      check_memory_request(double(bytes->value()), path, "grid '" + n + "'", std::to_string(bytes->value()) + " bytes",
                           "the level set '" + n + "' (its file_mem_bytes metadata)");
    trial_read(path, n);
    try {
      return openvdb::gridPtrCast<openvdb::FloatGrid>(file.readGrid(n));
    } catch (const openvdb::Exception& e) {
      throw InputError(path, "grid '" + n + "'", "", std::string("cannot read the grid (corrupt file?): ") + e.what());
    }
  };
  if (!name.empty()) {
    if (std::find(names.begin(), names.end(), name) == names.end())
      throw InputError(path, "grid", name, "no grid of that name in the file");
    grid = pick(name);
    if (!grid) throw InputError(path, "grid", name, "not a float grid");
  } else {
    if (std::find(names.begin(), names.end(), "macropores") != names.end()) grid = pick("macropores");
    for (std::size_t k = 0; !grid && k < names.size(); ++k) grid = pick(names[k]);
    if (!grid) throw InputError(path, "grid", "", "the file holds no float grid");
  }
  file.close();
  const double unit = metres_per_unit > 0 ? metres_per_unit : unit_from_metadata(*grid, path);
  if (!grid->transform().isLinear()) throw InputError(path, "transform", "", "only linear (voxel) transforms are supported");
  const auto vs = grid->transform().voxelSize();
  if (std::abs(vs[0] - vs[1]) > 1e-9 * vs[0] || std::abs(vs[0] - vs[2]) > 1e-9 * vs[0])
    throw InputError(path, "transform", "", "anisotropic voxels are not supported");
  // A level set has negative values inside; a narrow band without any is a set with no interior.
  float vmin = std::numeric_limits<float>::max();
  for (auto it = grid->cbeginValueOn(); it; ++it) vmin = std::min(vmin, *it);
  if (grid->activeVoxelCount() == 0 || !(vmin < 0))
    throw InputError(path, grid->getName(), "", "the level set has no interior (no negative value): no macropore to carve");
  return std::make_unique<LevelSet>(grid, unit, path);
}

}  // namespace tomodem::carve
