// Checkpoints of a decomposed run (docs/dem.md, "Checkpoints").
//
// Writing: the file has the serial layout (checkpoint.cpp), so the serial build and any rank
// count read it. Each rank sends its owned particles, with their neighbour-list rows (contact
// history), to the rank that holds their block of ids (rank r: ids [N r/P, N (r+1)/P)); each
// rank then writes its block of every per-particle dataset, and its rows at the offset an
// exclusive prefix sum of the row lengths gives, with collective hyperslab writes through HDF5's
// MPI-IO driver. The file is therefore the same bytes of data whatever the rank count. The small
// datasets (cell, walls, clocks, series) and the bond set (gathered: it is a list of its own, by
// bond index) are written by rank 0 in the same collective calls. Under a temporary name that
// rank 0 renames once every rank has closed the file: a killed run leaves no half checkpoint.
//
// Restarting: every rank reads the whole file into the whole sample (each rank holds the whole
// sample before decompose() anyway) and keeps its own particles (decompose_restored).
#include <hdf5.h>
#include <mpi.h>

#include <algorithm>
#include <cstring>
#include <numeric>

#include "../checkpoint_format.hpp"
#include "checkpoint_mpi.hpp"
#include "tomodem/core/error.hpp"
#include "tomodem/core/output.hpp"
#include "tomodem/core/tool.hpp"
#include "tomodem/dem/checkpoint_ranks.hpp"
#include "tomodem/dem/scene.hpp"
#include "tomodem/dem/simulation.hpp"
#include "tomodem/spatial/grid.hpp"

namespace tomodem::dem {
namespace {

struct Bytes {
  std::vector<char>& b;
  template <class T>
  void put(const T& v) {
    const std::size_t o = b.size();
    b.resize(o + sizeof(T));
    std::memcpy(b.data() + o, &v, sizeof(T));
  }
  void put(const double* v, std::size_t n) {
    const std::size_t o = b.size();
    b.resize(o + sizeof(double) * n);
    if (n) std::memcpy(b.data() + o, v, sizeof(double) * n);
  }
};
struct Cursor {
  const char* p;
  const char* end;
  template <class T>
  T get() {
    T v;
    std::memcpy(&v, p, sizeof(T));
    p += sizeof(T);
    return v;
  }
  void get(double* v, std::size_t n) {
    if (n) std::memcpy(v, p, sizeof(double) * n);
    p += sizeof(double) * n;
  }
  bool done() const { return p >= end; }
};

/// One particle as it travels to the writer of its id block.
struct Row {
  int64_t id = 0;
  Vec3 x, v, omega, x_build, f, torque;
  double r = 0, m = 0;
  int32_t phase = 0;
  uint8_t motion = 0;
  uint32_t pairs = 0;
};

/// First id of rank r's block.
int64_t block_start(int64_t n, int ranks, int r) { return n * r / ranks; }
int block_owner(int64_t id, int64_t n, int ranks) {
  int r = int(std::min<int64_t>(ranks - 1, n > 0 ? id * ranks / n : 0));
  while (r > 0 && block_start(n, ranks, r) > id) --r;
  while (r + 1 < ranks && block_start(n, ranks, r + 1) <= id) ++r;
  return r;
}

/// A file every rank of `comm` writes at once (MPI-IO driver). Every call is collective: the
/// same datasets and attributes, in the same order, on every rank; each rank gives its rows.
class ParallelFile {
 public:
  ParallelFile(const std::string& path, MPI_Comm comm) : path_(path), comm_(comm) {
    H5Eset_auto2(H5E_DEFAULT, nullptr, nullptr);
    MPI_Comm_rank(comm, &rank_);
    const hid_t fapl = H5Pcreate(H5P_FILE_ACCESS);
    H5Pset_fapl_mpio(fapl, comm, MPI_INFO_NULL);
    file_ = H5Fcreate(path.c_str(), H5F_ACC_TRUNC, H5P_DEFAULT, fapl);
    H5Pclose(fapl);
    check(file_, "create the file");
    xfer_ = H5Pcreate(H5P_DATASET_XFER);
    H5Pset_dxpl_mpio(xfer_, H5FD_MPIO_COLLECTIVE);
    lcpl_ = H5Pcreate(H5P_LINK_CREATE);
    H5Pset_create_intermediate_group(lcpl_, 1);
  }
  ~ParallelFile() {
    if (file_ >= 0) H5Fclose(file_);
    H5Pclose(xfer_);
    H5Pclose(lcpl_);
  }
  void close() {
    const herr_t e = H5Fclose(file_);
    file_ = -1;
    check(e, "close the file (flush)");
  }

  /// Dataset `name` of rows × cols values; this rank writes `count` rows from row `first`.
  template <class T>
  void write(const std::string& name, hid_t type, const T* data, hsize_t rows, hsize_t cols, hsize_t first,
             hsize_t count, const std::string& units = "") {
    const hsize_t dims[2] = {rows, cols};
    const int rank = cols > 0 ? 2 : 1;
    const hid_t fspace = H5Screate_simple(rank, dims, nullptr);
    const hid_t dset = H5Dcreate2(file_, name.c_str(), type, fspace, lcpl_, H5P_DEFAULT, H5P_DEFAULT);
    check(dset, "create " + name);
    const hsize_t width = cols > 0 ? cols : 1;
    const hsize_t mdim = std::max<hsize_t>(count * width, 1);
    const hid_t mspace = H5Screate_simple(1, &mdim, nullptr);
    if (count > 0) {
      const hsize_t start[2] = {first, 0}, cnt[2] = {count, width};
      H5Sselect_hyperslab(fspace, H5S_SELECT_SET, start, nullptr, cnt, nullptr);
    } else {
      H5Sselect_none(fspace);
      H5Sselect_none(mspace);
    }
    static const T dummy{};
    // An empty dataset (no walls, no rotation) is created, not written.
    const herr_t e = rows == 0 ? 0 : H5Dwrite(dset, type, mspace, fspace, xfer_, count > 0 ? static_cast<const void*>(data) : &dummy);
    if (!units.empty()) string_attr(dset, "units", units);
    H5Sclose(mspace);
    H5Sclose(fspace);
    H5Dclose(dset);
    check(e, "write " + name);
  }
  /// A small dataset of the whole sample, written by rank 0 (every rank calls it).
  template <class T>
  void write_root(const std::string& name, hid_t type, const std::vector<T>& data, hsize_t cols,
                  const std::string& units = "") {
    // The shape is rank 0's (the gathered bond set is on rank 0 only).
    unsigned long long rows = cols > 0 ? data.size() / cols : data.size();
    MPI_Bcast(&rows, 1, MPI_UNSIGNED_LONG_LONG, 0, comm_);
    write(name, type, data.data(), rows, cols, 0, rank_ == 0 ? rows : 0, units);
  }
  void string_attr(hid_t on, const std::string& name, const std::string& value) {
    const hid_t t = H5Tcopy(H5T_C_S1);
    H5Tset_size(t, H5T_VARIABLE);
    H5Tset_cset(t, H5T_CSET_UTF8);
    const hid_t sp = H5Screate(H5S_SCALAR);
    const hid_t a = H5Acreate2(on, name.c_str(), t, sp, H5P_DEFAULT, H5P_DEFAULT);
    const char* s = value.c_str();
    const herr_t e = a >= 0 ? H5Awrite(a, t, &s) : -1;
    if (a >= 0) H5Aclose(a);
    H5Sclose(sp);
    H5Tclose(t);
    check(e, "write the attribute " + name);
  }
  void double_attr(const std::string& name, double value) {
    const hid_t sp = H5Screate(H5S_SCALAR);
    const hid_t a = H5Acreate2(file_, name.c_str(), H5T_NATIVE_DOUBLE, sp, H5P_DEFAULT, H5P_DEFAULT);
    const herr_t e = a >= 0 ? H5Awrite(a, H5T_NATIVE_DOUBLE, &value) : -1;
    if (a >= 0) H5Aclose(a);
    H5Sclose(sp);
    check(e, "write the attribute " + name);
  }
  hid_t root() const { return file_; }

 private:
  void check(long long status, const std::string& what) const {
    if (status < 0) throw RuntimeFailure("cannot " + what + " in the checkpoint " + path_ + " (parallel HDF5)");
  }
  std::string path_;
  MPI_Comm comm_;
  int rank_ = 0;
  hid_t file_ = -1, xfer_ = -1, lcpl_ = -1;
};

std::vector<double> flat(const std::vector<Vec3>& v) {
  std::vector<double> out;
  out.reserve(v.size() * 3);
  for (const Vec3& x : v) out.insert(out.end(), {x.x, x.y, x.z});
  return out;
}
std::vector<double> mat(const Mat3& m) { return std::vector<double>(&m.a[0][0], &m.a[0][0] + 9); }

}  // namespace

void write_checkpoint_ranks(const std::string& path, const Simulation& sim, const std::string& scene_text,
                            const std::vector<std::vector<double>>& series) {
  const MPI_Comm comm = MPI_COMM_WORLD;
  int rank = 0, ranks = 1;
  MPI_Comm_rank(comm, &rank);
  MPI_Comm_size(comm, &ranks);
  const DomainHooks& d = *sim.domain();
  const Particles& p = sim.particles();
  const Simulation::EngineState e = sim.engine_state();
  const bool rot = p.has_rotation();
  const std::size_t nw = sim.walls().size();  // the same on every rank

  // The history's width and contact flag are the engine's (the same on every rank, pairs and
  // walls alike); a rank without pairs or particles learns them from the others.
  long shape[3] = {e.j.empty() ? 0L : long(e.history.size() / e.j.size()), e.touching.empty() ? 0L : 1L,
                   nw == 0 || p.size() == 0 ? 0L : long(e.wall_history[0].size() / p.size())};
  if (nw > 0 && !e.wall_touching[0].empty()) shape[1] = 1;
  MPI_Allreduce(MPI_IN_PLACE, shape, 3, MPI_LONG, MPI_MAX, comm);
  const std::size_t stride = std::size_t(std::max(shape[0], shape[2]));
  const bool touch = shape[1] != 0;
  // Per wall, whether each local particle is one of its candidates (the list holds owned ones).
  std::vector<std::vector<uint8_t>> candidate(nw, std::vector<uint8_t>(p.size(), 0));
  for (std::size_t w = 0; w < nw; ++w)
    for (const int32_t i : e.wall_candidates[w]) candidate[w][std::size_t(i)] = 1;
  long owned = 0;
  for (std::size_t i = 0; i < p.size(); ++i) owned += !d.ghost[i];
  int64_t n = owned;
  MPI_Allreduce(MPI_IN_PLACE, &n, 1, MPI_INT64_T, MPI_SUM, comm);

  // Owned particles and their rows to the writers of their id blocks.
  const std::size_t nr = static_cast<std::size_t>(ranks);
  std::vector<std::vector<char>> out(nr);
  for (std::size_t i = 0; i < p.size(); ++i) {
    if (d.ghost[i]) continue;
    if (p.id[i] < 0 || p.id[i] >= n) throw RuntimeFailure("checkpoint: particle id " + std::to_string(p.id[i]) + " outside 0.." + std::to_string(n - 1));
    Bytes w{out[std::size_t(block_owner(p.id[i], n, ranks))]};
    Row r;
    r.id = p.id[i], r.x = p.x[i], r.v = p.v[i], r.r = p.r[i], r.m = p.m[i], r.phase = p.phase[i];
    r.motion = uint8_t(p.motion[i]);
    if (rot) r.omega = p.omega[i], r.torque = e.torque[i];
    r.x_build = e.x_at_build[i], r.f = e.force[i];
    const int32_t a = e.start.empty() ? 0 : e.start[i], b = e.start.empty() ? 0 : e.start[i + 1];
    r.pairs = uint32_t(b - a);
    w.put(r);
    for (int32_t q = a; q < b; ++q) {
      w.put(int64_t(p.id[std::size_t(e.j[std::size_t(q)])]));
      w.put(e.image[std::size_t(q)]);
      w.put(touch ? e.touching[std::size_t(q)] : uint8_t(0));
      w.put(&e.history[std::size_t(q) * stride], stride);
    }
    // Its wall state: per wall, candidate and contact flags and the history.
    for (std::size_t wl = 0; wl < nw; ++wl) {
      w.put(candidate[wl][i]);
      w.put(touch ? e.wall_touching[wl][i] : uint8_t(0));
      w.put(&e.wall_history[wl][i * stride], stride);
    }
  }
  std::vector<int> scount(nr), rcount(nr), sdis(nr, 0), rdis(nr, 0);
  for (int r = 0; r < ranks; ++r) scount[std::size_t(r)] = int(out[std::size_t(r)].size());
  MPI_Alltoall(scount.data(), 1, MPI_INT, rcount.data(), 1, MPI_INT, comm);
  std::partial_sum(scount.begin(), scount.end() - 1, sdis.begin() + 1);
  std::partial_sum(rcount.begin(), rcount.end() - 1, rdis.begin() + 1);
  std::vector<char> sendbuf, recvbuf(std::size_t(rdis.back() + rcount.back()));
  for (const auto& o : out) sendbuf.insert(sendbuf.end(), o.begin(), o.end());
  out.clear();
  MPI_Alltoallv(sendbuf.data(), scount.data(), sdis.data(), MPI_BYTE, recvbuf.data(), rcount.data(), rdis.data(),
                MPI_BYTE, comm);
  std::vector<char>().swap(sendbuf);

  // This rank's block, in id order.
  const int64_t lo = block_start(n, ranks, rank), hi = block_start(n, ranks, rank + 1);
  const std::size_t nb = std::size_t(hi - lo);
  std::vector<const char*> at(nb, nullptr);
  {
    Cursor c{recvbuf.data(), recvbuf.data() + recvbuf.size()};
    while (!c.done()) {
      const char* here = c.p;
      const Row r = c.get<Row>();
      if (r.id < lo || r.id >= hi || at[std::size_t(r.id - lo)])
        throw RuntimeFailure("checkpoint: particle " + std::to_string(r.id) + " owned twice or sent to the wrong rank");
      at[std::size_t(r.id - lo)] = here;
      c.p += (std::size_t(r.pairs) + nw) * (2 + sizeof(double) * stride) + std::size_t(r.pairs) * sizeof(int64_t);
    }
  }
  for (std::size_t k = 0; k < nb; ++k)
    if (!at[k]) throw RuntimeFailure("checkpoint: particle " + std::to_string(lo + int64_t(k)) + " is owned by no rank");
  std::vector<Vec3> x(nb), v(nb), omega(rot ? nb : 0), xb(nb), f(nb), torque(rot ? nb : 0);
  std::vector<double> radius(nb), mass(nb), hist;
  std::vector<int32_t> phase(nb), start(nb + (rank == ranks - 1 ? 1 : 0)), pj;
  std::vector<int64_t> id(nb);
  std::vector<uint8_t> motion(nb), image, touching;
  std::vector<std::vector<int32_t>> wall_cand(nw);
  std::vector<std::vector<double>> wall_hist(nw, std::vector<double>(nb * stride));
  std::vector<std::vector<uint8_t>> wall_touch(nw, std::vector<uint8_t>(touch ? nb : 0));
  for (std::size_t k = 0; k < nb; ++k) {
    Cursor c{at[k], recvbuf.data() + recvbuf.size()};
    const Row r = c.get<Row>();
    x[k] = r.x, v[k] = r.v, xb[k] = r.x_build, f[k] = r.f, radius[k] = r.r, mass[k] = r.m;
    phase[k] = r.phase, id[k] = r.id, motion[k] = r.motion;
    if (rot) omega[k] = r.omega, torque[k] = r.torque;
    start[k] = int32_t(pj.size());  // local for now; the block's offset is added below
    for (uint32_t q = 0; q < r.pairs; ++q) {
      pj.push_back(int32_t(c.get<int64_t>()));
      image.push_back(c.get<uint8_t>());
      const uint8_t t = c.get<uint8_t>();
      if (touch) touching.push_back(t);
      hist.resize(hist.size() + stride);
      c.get(hist.data() + hist.size() - stride, stride);
    }
    for (std::size_t wl = 0; wl < nw; ++wl) {
      if (c.get<uint8_t>()) wall_cand[wl].push_back(int32_t(r.id));  // in id order: the serial list's
      const uint8_t t = c.get<uint8_t>();
      if (touch) wall_touch[wl][k] = t;
      c.get(wall_hist[wl].data() + k * stride, stride);
    }
  }
  std::vector<char>().swap(recvbuf);
  // Where this block's rows start in the whole list: an exclusive prefix sum over the ranks.
  int64_t pairs = int64_t(pj.size()), offset = 0, total = 0;
  MPI_Exscan(&pairs, &offset, 1, MPI_INT64_T, MPI_SUM, comm);
  if (rank == 0) offset = 0;  // MPI_Exscan leaves rank 0's undefined
  MPI_Allreduce(&pairs, &total, 1, MPI_INT64_T, MPI_SUM, comm);
  if (total > int64_t(INT32_MAX)) throw RuntimeFailure("checkpoint: " + std::to_string(total) + " listed pairs do not fit the format's 32-bit offsets");
  for (auto& s : start) s += int32_t(offset);
  if (rank == ranks - 1) start.back() = int32_t(total);
  // The same for each wall's candidate list.
  std::vector<int64_t> wall_count(nw), wall_offset(nw, 0), wall_total(nw, 0);
  for (std::size_t wl = 0; wl < nw; ++wl) wall_count[wl] = int64_t(wall_cand[wl].size());
  if (nw > 0) {
    MPI_Exscan(wall_count.data(), wall_offset.data(), int(nw), MPI_INT64_T, MPI_SUM, comm);
    if (rank == 0) std::fill(wall_offset.begin(), wall_offset.end(), 0);
    MPI_Allreduce(wall_count.data(), wall_total.data(), int(nw), MPI_INT64_T, MPI_SUM, comm);
  }

  // The bond set and its failure events, whole, on rank 0 (collective).
  long has_bonds = sim.bonds().size() > 0 || !sim.bond_events().empty();
  MPI_Allreduce(MPI_IN_PLACE, &has_bonds, 1, MPI_LONG, MPI_MAX, comm);
  BondSet bonds;
  std::vector<BondEvent> events;
  if (has_bonds) bonds = gather_bonds(sim), events = gather_bond_events(sim);
  long counts[2] = {long(bonds.size()), long(events.size())};
  MPI_Bcast(counts, 2, MPI_LONG, 0, comm);

  // The temporary is rank 0's name; every rank opens it.
  std::string tmp = rank == 0 ? temporary_path(path) : std::string();
  int len = int(tmp.size());
  MPI_Bcast(&len, 1, MPI_INT, 0, comm);
  tmp.resize(std::size_t(len));
  MPI_Bcast(tmp.data(), len, MPI_CHAR, 0, comm);
  {
    ParallelFile pf(tmp, comm);
    pf.double_attr("tomodem_checkpoint_format", kCheckpointFormat);
    pf.string_attr(pf.root(), "version", version_string());
    pf.string_attr(pf.root(), "tomodem_version", release_version(version_string()));
    pf.string_attr(pf.root(), "scene", scene_text);
    pf.double_attr("written_by_ranks", double(ranks));
    const hsize_t N = hsize_t(n), first = hsize_t(lo), cnt = hsize_t(nb), M = hsize_t(total), off = hsize_t(offset);
    const auto fx = flat(x), fv = flat(v), fxb = flat(xb), ff = flat(f);
    pf.write("/particles/position", H5T_NATIVE_DOUBLE, fx.data(), N, 3, first, cnt, "m");
    pf.write("/particles/velocity", H5T_NATIVE_DOUBLE, fv.data(), N, 3, first, cnt, "m/s");
    pf.write("/particles/radius", H5T_NATIVE_DOUBLE, radius.data(), N, 0, first, cnt, "m");
    pf.write("/particles/mass", H5T_NATIVE_DOUBLE, mass.data(), N, 0, first, cnt, "kg");
    pf.write("/particles/phase", H5T_NATIVE_INT32, phase.data(), N, 0, first, cnt);
    pf.write("/particles/id", H5T_NATIVE_INT64, id.data(), N, 0, first, cnt);
    pf.write("/particles/motion", H5T_NATIVE_UINT8, motion.data(), N, 0, first, cnt);
    if (rot) {
      const auto fo = flat(omega);
      pf.write("/particles/angular_velocity", H5T_NATIVE_DOUBLE, fo.data(), N, 3, first, cnt, "rad/s");
    }
    const Cell& cell = sim.cell();
    pf.write_root("/cell/h", H5T_NATIVE_DOUBLE, mat(cell.h), 3, "m");
    pf.write_root("/cell/origin", H5T_NATIVE_DOUBLE, std::vector<double>{cell.origin.x, cell.origin.y, cell.origin.z}, 0, "m");
    pf.write_root("/cell/velocity_gradient", H5T_NATIVE_DOUBLE, mat(sim.cell_control().velocity_gradient), 3, "1/s");
    std::vector<Vec3> wp, wv, wf;
    for (const Wall& wl : sim.walls()) wp.push_back(wl.point), wv.push_back(wl.velocity), wf.push_back(wl.force);
    pf.write_root("/walls/point", H5T_NATIVE_DOUBLE, flat(wp), 3, "m");
    pf.write_root("/walls/velocity", H5T_NATIVE_DOUBLE, flat(wv), 3, "m/s");
    pf.write_root("/walls/force", H5T_NATIVE_DOUBLE, flat(wf), 3, "N");
    pf.write("/engine/start", H5T_NATIVE_INT32, start.data(), N + 1, 0, first, hsize_t(start.size()));
    pf.write("/engine/j", H5T_NATIVE_INT32, pj.data(), M, 0, off, hsize_t(pj.size()));
    pf.write("/engine/image", H5T_NATIVE_UINT8, image.data(), M, 0, off, hsize_t(image.size()));
    pf.write("/engine/touching", H5T_NATIVE_UINT8, touching.data(), touch ? M : 0, 0, off, hsize_t(touching.size()));
    pf.write("/engine/history", H5T_NATIVE_DOUBLE, hist.data(), M * stride, 0, off * stride, hsize_t(hist.size()));
    pf.write("/engine/x_at_build", H5T_NATIVE_DOUBLE, fxb.data(), N, 3, first, cnt, "m");
    pf.write_root("/engine/h_at_build", H5T_NATIVE_DOUBLE, mat(e.h_at_build), 3, "m");
    for (std::size_t wl = 0; wl < nw; ++wl) {
      const std::string g = "/engine/wall" + std::to_string(wl);
      pf.write(g + "/candidates", H5T_NATIVE_INT32, wall_cand[wl].data(), hsize_t(wall_total[wl]), 0,
               hsize_t(wall_offset[wl]), hsize_t(wall_cand[wl].size()));
      pf.write(g + "/history", H5T_NATIVE_DOUBLE, wall_hist[wl].data(), N * stride, 0, first * stride, cnt * stride);
      pf.write(g + "/touching", H5T_NATIVE_UINT8, wall_touch[wl].data(), touch ? N : 0, 0, first, touch ? cnt : 0);
    }
    pf.write_root("/engine/wall_point_at_build", H5T_NATIVE_DOUBLE, flat(e.wall_point_at_build), 3, "m");
    pf.write("/engine/force", H5T_NATIVE_DOUBLE, ff.data(), N, 3, first, cnt, "N");
    const auto ft = flat(torque);
    pf.write("/engine/torque", H5T_NATIVE_DOUBLE, ft.data(), rot ? N : 0, 3, first, rot ? cnt : 0, "N m");
    if (counts[0] > 0) {
      const BondSet& B = bonds;
      pf.write_root("/bonds/i", H5T_NATIVE_INT32, B.i, 0);
      pf.write_root("/bonds/j", H5T_NATIVE_INT32, B.j, 0);
      pf.write_root("/bonds/image", H5T_NATIVE_DOUBLE, flat(B.image), 3, "1");
      pf.write_root("/bonds/radius", H5T_NATIVE_DOUBLE, B.radius, 0, "m");
      pf.write_root("/bonds/rest_length", H5T_NATIVE_DOUBLE, B.rest_length, 0, "m");
      pf.write_root("/bonds/state", H5T_NATIVE_UINT8, B.state, 0);
      pf.write_root("/bonds/mode", H5T_NATIVE_UINT8, B.mode, 0);
      pf.write_root("/bonds/broken_at", H5T_NATIVE_DOUBLE, B.broken_at, 0, "s");
      pf.write_root("/bonds/shear_force", H5T_NATIVE_DOUBLE, flat(B.shear_force), 3, "N");
      pf.write_root("/bonds/twist", H5T_NATIVE_DOUBLE, B.twist, 0, "N m");
      pf.write_root("/bonds/bend", H5T_NATIVE_DOUBLE, flat(B.bend), 3, "N m");
      std::vector<double> et, eb, em;
      for (const auto& ev : events) et.push_back(ev.time), eb.push_back(ev.bond), em.push_back(ev.mode);
      pf.write_root("/bonds/events/time", H5T_NATIVE_DOUBLE, et, 0, "s");
      pf.write_root("/bonds/events/bond", H5T_NATIVE_DOUBLE, eb, 0);
      pf.write_root("/bonds/events/mode", H5T_NATIVE_DOUBLE, em, 0);
    }
    if (!series.empty()) {
      std::vector<double> rows;
      for (const auto& row : series) rows.insert(rows.end(), row.begin(), row.end());
      pf.write_root("/series/rows", H5T_NATIVE_DOUBLE, rows, series_columns().size());
    }
    pf.write_root("/engine/scalars", H5T_NATIVE_DOUBLE,
                  std::vector<double>{double(e.forces_valid), e.dt, e.time, double(e.step), double(e.builds), e.dissipated,
                                      e.external_work, e.initial_energy},
                  0);
    pf.close();  // every rank's data is in the file (a full disk is found here)
  }
  // Renamed once every rank has closed the file: a run killed before this leaves only the
  // temporary (removed by rank 0's signal handler), never a half checkpoint under the name.
  MPI_Barrier(comm);
  if (rank == 0) commit_output(path, Commit::now);  // as the serial checkpoint
  MPI_Barrier(comm);
}

void decompose_restored(Simulation& sim, const DecompositionOptions& opt) {
  Particles& p = sim.particles();
  const Simulation::EngineState whole = sim.engine_state();
  const std::size_t n = p.size();
  const std::vector<Vec3> x_now = p.x;
  const Mat3 h_now = sim.cell().h;
  // The exact path: the sub-domains, ghosts and list are built at the state of the last build
  // (positions x_at_build, already wrapped into the cell h_at_build), which is the list the
  // uninterrupted run holds; the rebuild clock (x_at_build) stays the checkpoint's. It needs the
  // wrap of that state to move nothing (a position on a face can round to the other side).
  bool exact = whole.x_at_build.size() == n && whole.start.size() == n + 1;
  if (exact) {
    std::vector<Vec3> xb = whole.x_at_build;
    Cell c = sim.cell();
    c.h = whole.h_at_build;
    for (const auto& w : spatial::wrap_into_cell(xb, c)) exact = exact && w[0] == 0 && w[1] == 0 && w[2] == 0;
  }
  int all_exact = exact ? 1 : 0;
  MPI_Allreduce(MPI_IN_PLACE, &all_exact, 1, MPI_INT, MPI_LAND, MPI_COMM_WORLD);
  // The walls too stand where the last build found their candidates.
  std::vector<Vec3> walls_now;
  for (const Wall& w : sim.walls()) walls_now.push_back(w.point);
  const auto back_to_now = [&] {
    p.x = x_now;
    sim.cell().h = h_now;
    for (std::size_t w = 0; w < walls_now.size(); ++w) sim.walls()[w].point = walls_now[w];
  };
  if (all_exact) {
    p.x = whole.x_at_build;
    sim.cell().h = whole.h_at_build;
    for (std::size_t w = 0; w < walls_now.size() && w < whole.wall_point_at_build.size(); ++w)
      sim.walls()[w].point = whole.wall_point_at_build[w];
  }
  try {
    decompose(sim, opt);
  } catch (...) {
    back_to_now();
    throw;
  }
  const DomainHooks& d = *sim.domain();
  Simulation::EngineState local = sim.engine_state();
  if (all_exact) {
    // Back to the checkpoint's state, particle by particle (owned and ghosts are exact copies).
    for (std::size_t i = 0; i < p.size(); ++i) {
      const std::size_t g = std::size_t(p.id[i]);
      p.x[i] = x_now[g];
      local.force[i] = whole.force[g];
      if (p.has_rotation()) local.torque[i] = whole.torque[g];
    }
    sim.cell().h = h_now;
    for (std::size_t w = 0; w < walls_now.size(); ++w) sim.walls()[w].point = walls_now[w];
  }
  // Otherwise the list was rebuilt at the checkpoint's positions (the history carried by particle
  // id): the same physics, but the wrap and the next rebuild fall on other steps (round-off).
  local.forces_valid = whole.forces_valid;
  local.builds = whole.builds;
  // Each failure event is kept once, by the rank that owns the bond's first particle.
  local.bond_events.clear();
  for (const BondEvent& ev : whole.bond_events) {
    const int64_t first = int64_t(whole.bonds.i[std::size_t(ev.bond)]);
    const auto it = std::lower_bound(p.id.begin(), p.id.end(), first);
    if (it != p.id.end() && *it == first && !d.ghost[std::size_t(it - p.id.begin())]) local.bond_events.push_back(ev);
  }
  sim.restore(local);
}

}  // namespace tomodem::dem
