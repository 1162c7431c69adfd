// Spatial domain decomposition of the DEM engine over MPI (docs/dem.md, "Running on several
// ranks"). The engine calls the hooks of decomposition.hpp at its synchronisation points; this
// file holds the communication: migration with contact history, the ghost layer, the forward
// refresh of ghosts every force pass, and the reductions.
//
// Choices (as LAMMPS's granular pair styles with "newton off"):
//  - A pair of an owned particle and a ghost is computed on both ranks; each keeps the pair's
//    history. Both compute it from the same bits (a ghost is an exact copy), so the two copies of
//    the history stay equal, and no force is sent back (no reverse communication, no order of
//    arrival in any sum).
//  - Ghosts are copies, not images: a rank's neighbour list sees periodic images through the
//    serial engine's image codes, so a pair has the same image code, the same separation
//    arithmetic and the same row position on every rank count.
//  - The history of a pair travels keyed by the ids of its particles and an image vector that
//    wrapping into the cell does not change: K = n − (W_j − W_i), n the pair's image, W the
//    lattice vectors a particle has been wrapped by since the start.
//  - Messages go straight to the (up to 26) neighbouring sub-domains, at most one per pair of
//    ranks per exchange; the ghost margin must not exceed a sub-domain's width.
//  - Walls: a rank computes the wall contacts of its owned particles only (a ghost's force is
//    never used). A wall's force, which its servo and the outputs read, is gathered contact by
//    contact and added in particle order on every rank: the serial sum's bits, so every rank
//    moves the wall alike. A particle's wall history travels with it, keyed by its id.
#include "tomodem/dem/decomposition.hpp"

#include <mpi.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <numeric>
#include <sstream>
#include <map>
#include <unordered_map>

#include "../kernel.hpp"
#include "../measure.hpp"
#include "../neighbour_list.hpp"
#include "../sim_state.hpp"
#include "tomodem/core/error.hpp"
#include "tomodem/dem/scene.hpp"
#include "tomodem/dem/simulation.hpp"
#include "tomodem/spatial/grid.hpp"

namespace tomodem::dem {
namespace {

using spatial::Image;

/// Appends and reads plain values to and from a byte buffer (one message per neighbour).
struct Writer {
  std::vector<char>& b;
  template <class T>
  void put(const T& v) {
    const std::size_t o = b.size();
    b.resize(o + sizeof(T));
    std::memcpy(b.data() + o, &v, sizeof(T));
  }
  void put(const double* v, int n) {
    const std::size_t o = b.size();
    b.resize(o + sizeof(double) * std::size_t(n));
    std::memcpy(b.data() + o, v, sizeof(double) * std::size_t(n));
  }
};
struct Reader {
  const char* p;
  const char* end;
  template <class T>
  T get() {
    T v;
    std::memcpy(&v, p, sizeof(T));
    p += sizeof(T);
    return v;
  }
  void get(double* v, int n) {
    std::memcpy(v, p, sizeof(double) * std::size_t(n));
    p += sizeof(double) * std::size_t(n);
  }
  bool done() const { return p >= end; }
};

/// One particle with everything that travels with it.
struct Entry {
  int64_t id = 0;
  Vec3 x, v, f, omega, torque;
  double r = 0, m = 0, inv_m = 0, inv_I = 0;
  int32_t phase = 0;
  Motion motion = Motion::free;
  Image w{0, 0, 0};  // lattice vectors wrapped off since the start
  uint8_t ghost = 0;
};

/// A pair's history, keyed by (id of its row particle, id of its partner, K).
struct Key {
  int64_t a, b;
  Image k;
  bool operator==(const Key& o) const { return a == o.a && b == o.b && k == o.k; }
};
struct KeyHash {
  std::size_t operator()(const Key& q) const {
    std::size_t h = std::hash<int64_t>()(q.a) * 1000003u ^ std::hash<int64_t>()(q.b);
    for (int c : q.k) h = h * 31u + std::size_t(c + 1024);
    return h;
  }
};
struct Record {
  Key key;
  uint8_t touch = 0;
  std::size_t hist = 0;  // offset in the history pool
};

/// A bond as it travels and as a rank keeps it between builds (decomposition.hpp, "Bonds").
struct BondRec {
  int32_t gid = 0;       // index in the whole sample's bond set
  int64_t a = 0, b = 0;  // ids of its particles (a: the set's i)
  Image k{0, 0, 0};      // image n − (W_b − W_a): unchanged by wrapping
  double radius = 0, rest = 0;
  uint8_t state = 0, mode = 0, local = 0;
  double broken_at = 0, twist = 0;
  Vec3 shear, bend, image;  // image: the last one it was computed with
};

void copy_bond_state(std::map<int32_t, BondRec>& recs, const BondSet& B, const std::vector<int32_t>& ids);

class Domain final : public DomainHooks {
 public:
  explicit Domain(const DecompositionOptions& opt);

  void forward(SimState& s) override;
  void refresh_ghost_bodies(Particles& p) override;
  bool any(bool local) override;
  void before_build(SimState& s, NeighbourList& nl) override;
  void after_build(SimState& s, NeighbourList& nl) override;
  void reduce(Tally& t) override;
  void sum(double* v, int n) override;
  double min(double v) override;
  void walls(SimState& s, NeighbourList& nl, const ForceJob& jb, bool tally, Tally& total, double* stiffness) override;
  std::vector<Vec3> ordered_sum(const std::vector<OrderedTerm>& terms, int groups) override;
  std::vector<char> all_bytes(const std::vector<char>& mine) override;
  Measurements measure(const SimState& s, const Tally& tally, const EnergyAccount& energy) override;

  DomainLayout layout() const;
  MPI_Comm comm() const { return comm_; }
  int32_t bond_count() const { return n_bonds_; }
  ~Domain() override {
    int finalized = 0;
    MPI_Finalized(&finalized);
    if (!finalized) MPI_Comm_free(&comm_);
  }

 private:
  MPI_Comm comm_;
  int rank_ = 0, size_ = 1;
  int dims_[3] = {1, 1, 1}, coords_[3] = {0, 0, 0};
  double reach_ = 0;            // 2 r_max + skin + adhesive reach: the ghost margin, m
  std::vector<int> nbr_;        // neighbouring ranks (distinct, not this one), ascending
  std::vector<Image> w_;        // per local particle
  std::vector<std::vector<int32_t>> send_idx_, recv_idx_;  // forward lists per neighbour
  std::unordered_map<Key, Record, KeyHash> kept_;          // history to put back after a build
  std::vector<double> pool_;
  bool initial_ = true;
  long migrated_ = 0, exchanges_ = 0;
  bool has_bonds_ = false;               // the sample has bonds (the same on every rank)
  int32_t n_bonds_ = 0;                  // in the whole sample
  std::map<int32_t, BondRec> bonds_;     // every bond with an owned end, by global index
  // Wall history of owned particles across a build, by id: per wall the touch flag then the
  // history doubles (a particle with none is not listed).
  std::unordered_map<int64_t, std::vector<double>> kept_walls_;

  int rank_of(const int c[3]) const { return (c[0] * dims_[1] + c[1]) * dims_[2] + c[2]; }
  int box_of(double s, int k) const { return std::clamp(int(std::floor(s * dims_[k])), 0, dims_[k] - 1); }
  void margins(const SimState& s, double e[3]) const;
  std::vector<std::vector<char>> exchange(const std::vector<std::vector<char>>& out, int tag) const;
  void collect_history(const SimState& s, const NeighbourList& nl, std::vector<std::vector<int>>& attached,
                       std::vector<Record>& records, std::vector<double>& pool) const;
  bool ghost_of(const Vec3& sp, int q, const SimState& s, const double e[3]) const;
  void pack(Writer& w, const Entry& e, bool rot, bool full) const;
  Entry unpack(Reader& r, bool rot, bool full) const;
  void install(SimState& s, std::vector<Entry>& all);
  void init(const SimState& s, const NeighbourList& nl);
  static Entry entry_of(const SimState& s, std::size_t i, const Image& w, uint8_t ghost);
  void bonds_from_local(const SimState& s);
  void install_bonds(SimState& s);
  bool wall_state(const SimState& s, const NeighbourList& nl, std::size_t i, std::vector<double>& out) const;
  void install_walls(const SimState& s, NeighbourList& nl);

 public:
  /// Records of the bonds with an owned end, their state as `local` (the rank's set) has it now.
  std::vector<BondRec> bond_records(const BondSet& local) const;
};

Domain::Domain(const DecompositionOptions& opt) {
  MPI_Comm_dup(MPI_COMM_WORLD, &comm_);
  MPI_Comm_rank(comm_, &rank_);
  MPI_Comm_size(comm_, &size_);
  int dims[3] = {opt.dims[0], opt.dims[1], opt.dims[2]};
  for (int k = 0; k < 3; ++k)
    if (dims[k] < 0) throw InputError("", "dims", std::to_string(dims[k]), "sub-domain counts must be >= 0 (0: chosen)");
  int fixed = 1;
  for (int k = 0; k < 3; ++k) fixed *= dims[k] > 0 ? dims[k] : 1;
  if (size_ % fixed != 0)
    throw InputError("", "dims", std::to_string(dims[0]) + "x" + std::to_string(dims[1]) + "x" + std::to_string(dims[2]),
                     "does not divide the " + std::to_string(size_) + " ranks");
  MPI_Dims_create(size_, 3, dims);
  for (int k = 0; k < 3; ++k) dims_[k] = dims[k];
  coords_[0] = rank_ / (dims_[1] * dims_[2]);
  coords_[1] = (rank_ / dims_[2]) % dims_[1];
  coords_[2] = rank_ % dims_[2];
}

/// The ghost margin and the neighbouring ranks, from the whole sample (every rank holds it at
/// the start, so every rank finds the same numbers).
void Domain::init(const SimState& s, const NeighbourList& nl) {
  const double rmax = *std::max_element(s.p.r.begin(), s.p.r.end());
  // A bond's partner must be a ghost while the bond can act: its rest length counts as a reach
  // (a broken bond farther apart than that is out of contact: it only resets its shear spring).
  double bond_reach = 0;
  for (double l : s.bonds.rest_length) bond_reach = std::max(bond_reach, l);
  reach_ = (std::max(2 * rmax, bond_reach) + nl.skin + nl.reach_max) * (1 + 1e-9);  // margin: round-off of fractional coordinates
  has_bonds_ = s.bonds.size() > 0;
  n_bonds_ = int32_t(s.bonds.size());
  bond_id.resize(s.bonds.size());
  std::iota(bond_id.begin(), bond_id.end(), 0);
  for (std::size_t b = 0; b < s.bonds.size(); ++b) {
    BondRec r;
    r.gid = int32_t(b);
    r.a = s.p.id[std::size_t(s.bonds.i[b])], r.b = s.p.id[std::size_t(s.bonds.j[b])];
    for (int k = 0; k < 3; ++k) r.k[std::size_t(k)] = int(std::lround(s.bonds.image[b][k]));
    r.radius = s.bonds.radius[b], r.rest = s.bonds.rest_length[b];
    bonds_.emplace(r.gid, r);
  }
  for (int a = -1; a <= 1; ++a)
    for (int b = -1; b <= 1; ++b)
      for (int c = -1; c <= 1; ++c) {
        int q[3] = {coords_[0] + a, coords_[1] + b, coords_[2] + c};
        bool inside = true;
        for (int k = 0; k < 3; ++k) {
          if (s.cell.periodic[k]) q[k] = (q[k] + dims_[k]) % dims_[k];
          inside = inside && q[k] >= 0 && q[k] < dims_[k];
        }
        const int r = inside ? rank_of(q) : rank_;
        if (r != rank_) nbr_.push_back(r);
      }
  std::sort(nbr_.begin(), nbr_.end());
  nbr_.erase(std::unique(nbr_.begin(), nbr_.end()), nbr_.end());
  w_.assign(s.p.size(), Image{0, 0, 0});
}

/// Ghost margin in fractional coordinates along each cell vector (reach / perpendicular width);
/// a sub-domain must be at least as wide, or a ghost would be needed from beyond a neighbour.
void Domain::margins(const SimState& s, double e[3]) const {
  const double vol = s.cell.volume();
  for (int k = 0; k < 3; ++k) {
    const double width = vol / norm(cross(s.cell.h.col((k + 1) % 3), s.cell.h.col((k + 2) % 3)));
    e[k] = reach_ / width;
    if (dims_[k] > 1 && e[k] > 1.0 / dims_[k]) {
      std::ostringstream m;
      m << "sub-domains along cell vector " << k << " would be " << width / dims_[k] << " m wide, thinner than the "
        << "interaction reach plus skin " << reach_ << " m; use fewer ranks along it (at most "
        << int(std::floor(width / reach_)) << ")";
      throw InputError("", "ranks", std::to_string(size_) + " (" + std::to_string(dims_[0]) + "x" +
                                        std::to_string(dims_[1]) + "x" + std::to_string(dims_[2]) + ")",
                       m.str());
    }
  }
}

std::vector<std::vector<char>> Domain::exchange(const std::vector<std::vector<char>>& out, int tag) const {
  const std::size_t nn = nbr_.size();
  std::vector<uint64_t> sizes_out(nn), sizes_in(nn);
  std::vector<MPI_Request> req(2 * nn);
  for (std::size_t q = 0; q < nn; ++q) {
    sizes_out[q] = out[q].size();
    MPI_Irecv(&sizes_in[q], 1, MPI_UINT64_T, nbr_[q], tag, comm_, &req[2 * q]);
    MPI_Isend(&sizes_out[q], 1, MPI_UINT64_T, nbr_[q], tag, comm_, &req[2 * q + 1]);
  }
  MPI_Waitall(int(req.size()), req.data(), MPI_STATUSES_IGNORE);
  std::vector<std::vector<char>> in(nn);
  for (std::size_t q = 0; q < nn; ++q) {
    in[q].resize(sizes_in[q]);
    MPI_Irecv(in[q].data(), int(sizes_in[q]), MPI_BYTE, nbr_[q], tag + 1, comm_, &req[2 * q]);
    MPI_Isend(out[q].data(), int(out[q].size()), MPI_BYTE, nbr_[q], tag + 1, comm_, &req[2 * q + 1]);
  }
  MPI_Waitall(int(req.size()), req.data(), MPI_STATUSES_IGNORE);
  return in;
}

bool Domain::any(bool local) {
  int v = local ? 1 : 0, g = 0;
  MPI_Allreduce(&v, &g, 1, MPI_INT, MPI_LOR, comm_);
  return g != 0;
}

double Domain::min(double v) {
  double g = v;
  MPI_Allreduce(&v, &g, 1, MPI_DOUBLE, MPI_MIN, comm_);
  return g;
}

void Domain::sum(double* v, int n) {
  // Gathered and added in rank order: the same bits on every rank, whatever MPI's reduction tree.
  std::vector<double> all(std::size_t(n) * std::size_t(size_));
  MPI_Allgather(v, n, MPI_DOUBLE, all.data(), n, MPI_DOUBLE, comm_);
  for (int k = 0; k < n; ++k) {
    double t = 0;
    for (int r = 0; r < size_; ++r) t += all[std::size_t(r) * std::size_t(n) + std::size_t(k)];
    v[k] = t;
  }
}

std::vector<Vec3> Domain::ordered_sum(const std::vector<OrderedTerm>& terms, int groups) {
  // Every rank's terms on every rank (a wall's contacts: few), sorted by (group, id), added from
  // zero: the serial loop's order, so the serial bits on every rank.
  const int len = int(terms.size() * sizeof(OrderedTerm));
  std::vector<int> lens(static_cast<std::size_t>(size_)), offs(static_cast<std::size_t>(size_), 0);
  MPI_Allgather(&len, 1, MPI_INT, lens.data(), 1, MPI_INT, comm_);
  std::partial_sum(lens.begin(), lens.end() - 1, offs.begin() + 1);
  std::vector<OrderedTerm> all(std::size_t(offs.back() + lens.back()) / sizeof(OrderedTerm));
  MPI_Allgatherv(terms.data(), len, MPI_BYTE, all.data(), lens.data(), offs.data(), MPI_BYTE, comm_);
  std::sort(all.begin(), all.end(), [](const OrderedTerm& a, const OrderedTerm& b) {
    return a.group != b.group ? a.group < b.group : a.id < b.id;
  });
  std::vector<Vec3> out(static_cast<std::size_t>(groups));
  for (const OrderedTerm& t : all) out.at(std::size_t(t.group)) += t.v;
  return out;
}

std::vector<char> Domain::all_bytes(const std::vector<char>& mine) {
  const int len = int(mine.size());
  std::vector<int> lens(static_cast<std::size_t>(size_)), offs(static_cast<std::size_t>(size_), 0);
  MPI_Allgather(&len, 1, MPI_INT, lens.data(), 1, MPI_INT, comm_);
  std::partial_sum(lens.begin(), lens.end() - 1, offs.begin() + 1);
  std::vector<char> all(std::size_t(offs.back() + lens.back()));
  MPI_Allgatherv(mine.data(), len, MPI_BYTE, all.data(), lens.data(), offs.data(), MPI_BYTE, comm_);
  return all;
}

void Domain::walls(SimState& s, NeighbourList& nl, const ForceJob& jb, bool tally, Tally& total, double* stiffness) {
  // The serial wall pass (ForceLoop::wall_forces) one owned candidate at a time: a particle
  // gets the same force bits (its walls in wall order after its pairs and bonds), and each
  // contact's own tally gives its force on the wall, −f, exactly.
  Particles& p = s.p;
  std::vector<OrderedTerm> terms;
  for (std::size_t w = 0; w < s.walls.size(); ++w) {
    Wall& wall = s.walls[w];
    WallData& wd = nl.wall_data[w];
    for (const int32_t i : wd.candidates) {
      const WallJob wj{wall.point, wall.normal, wall.velocity, wall.phase, &i, 1, wd.hist.data(),
                       wd.touch.empty() ? nullptr : wd.touch.data()};
      Tally wt;
      s.kern.wall[tally](jb, wj, p.f.data(), p.has_rotation() ? p.torque.data() : nullptr, &wt, stiffness);
      if (!tally) continue;
      total.add(wt);  // a contact that just opened still tallies what it released
      if (wt.wall_contacts > 0) terms.push_back({int32_t(w), p.id[std::size_t(i)], wt.wall_force});
    }
  }
  // Without a tally the serial pass leaves the walls' force at zero (its tally holds it).
  const std::vector<Vec3> f = tally ? ordered_sum(terms, int(s.walls.size())) : std::vector<Vec3>(s.walls.size());
  for (std::size_t w = 0; w < s.walls.size(); ++w) s.walls[w].force = f[w];
}

void Domain::reduce(Tally& t) {
  double v[15];
  for (int a = 0; a < 3; ++a)
    for (int b = 0; b < 3; ++b) v[3 * a + b] = t.virial(a, b);
  v[9] = t.elastic, v[10] = t.dissipated, v[11] = t.sum_contact_force;
  v[12] = double(t.contacts), v[13] = double(t.wall_contacts), v[14] = double(t.bonds);
  sum(v, 15);
  for (int a = 0; a < 3; ++a)
    for (int b = 0; b < 3; ++b) t.virial(a, b) = v[3 * a + b];
  t.elastic = v[9], t.dissipated = v[10], t.sum_contact_force = v[11];
  t.contacts = long(v[12]), t.wall_contacts = long(v[13]), t.bonds = long(v[14]);
  double mx = t.max_overlap_ratio;
  MPI_Allreduce(&mx, &t.max_overlap_ratio, 1, MPI_DOUBLE, MPI_MAX, comm_);
}

void Domain::forward(SimState& s) {
  const bool rot = s.p.has_rotation();
  const int per = rot ? 9 : 6;
  const std::size_t nn = nbr_.size();
  std::vector<std::vector<double>> out(nn), in(nn);
  std::vector<MPI_Request> req(2 * nn);
  for (std::size_t q = 0; q < nn; ++q) {
    in[q].resize(recv_idx_[q].size() * std::size_t(per));
    MPI_Irecv(in[q].data(), int(in[q].size()), MPI_DOUBLE, nbr_[q], 30, comm_, &req[2 * q]);
    auto& o = out[q];
    o.reserve(send_idx_[q].size() * std::size_t(per));
    for (int32_t i : send_idx_[q]) {
      const Vec3 &x = s.p.x[i], &v = s.p.v[i];
      o.insert(o.end(), {x.x, x.y, x.z, v.x, v.y, v.z});
      if (rot) o.insert(o.end(), {s.p.omega[i].x, s.p.omega[i].y, s.p.omega[i].z});
    }
    MPI_Isend(o.data(), int(o.size()), MPI_DOUBLE, nbr_[q], 30, comm_, &req[2 * q + 1]);
  }
  MPI_Waitall(int(req.size()), req.data(), MPI_STATUSES_IGNORE);
  for (std::size_t q = 0; q < nn; ++q) {
    const double* d = in[q].data();
    for (int32_t i : recv_idx_[q]) {
      s.p.x[i] = {d[0], d[1], d[2]};
      s.p.v[i] = {d[3], d[4], d[5]};
      if (rot) s.p.omega[i] = {d[6], d[7], d[8]};
      d += per;
    }
  }
}

void Domain::refresh_ghost_bodies(Particles& p) {
  const bool rot = p.has_rotation();
  const int per = rot ? 4 : 3;
  const std::size_t nn = nbr_.size();
  std::vector<std::vector<double>> out(nn), in(nn);
  std::vector<MPI_Request> req(2 * nn);
  for (std::size_t q = 0; q < nn; ++q) {
    in[q].resize(recv_idx_[q].size() * std::size_t(per));
    MPI_Irecv(in[q].data(), int(in[q].size()), MPI_DOUBLE, nbr_[q], 32, comm_, &req[2 * q]);
    for (int32_t i : send_idx_[q]) {
      out[q].insert(out[q].end(), {p.r[i], p.m[i], p.inv_m[i]});
      if (rot) out[q].push_back(p.inv_I[i]);
    }
    MPI_Isend(out[q].data(), int(out[q].size()), MPI_DOUBLE, nbr_[q], 32, comm_, &req[2 * q + 1]);
  }
  MPI_Waitall(int(req.size()), req.data(), MPI_STATUSES_IGNORE);
  for (std::size_t q = 0; q < nn; ++q) {
    const double* d = in[q].data();
    for (int32_t i : recv_idx_[q]) {
      p.r[i] = d[0], p.m[i] = d[1], p.inv_m[i] = d[2];
      if (rot) p.inv_I[i] = d[3];
      d += per;
    }
  }
}

/// Every listed pair with history worth keeping (springs or contact flag set), attached to its
/// owned particle(s): a particle that migrates takes the history of all its pairs along.
void Domain::collect_history(const SimState& s, const NeighbourList& nl, std::vector<std::vector<int>>& attached,
                             std::vector<Record>& records, std::vector<double>& pool) const {
  const std::size_t n = s.p.size();
  attached.assign(n, {});
  const int stride = s.stride;
  const bool touch_flag = s.kern.touch_flag;
  if (nl.start.size() != n + 1 || (stride == 0 && !touch_flag)) return;
  for (std::size_t a = 0; a < n; ++a)
    for (int q = nl.start[a]; q < nl.start[a + 1]; ++q) {
      const double* h = &nl.hist[std::size_t(q) * std::size_t(stride)];
      bool carries = touch_flag && nl.touch[std::size_t(q)];
      for (int k = 0; k < stride; ++k) carries = carries || h[k] != 0;
      if (!carries) continue;
      const std::size_t b = std::size_t(nl.nj[std::size_t(q)]);
      Image key_image = spatial::image_of_code(nl.img[std::size_t(q)]);
      for (int k = 0; k < 3; ++k) key_image[k] -= w_[b][k] - w_[a][k];
      Record rec{Key{s.p.id[a], s.p.id[b], key_image}, touch_flag ? nl.touch[std::size_t(q)] : uint8_t(0), pool.size()};
      pool.insert(pool.end(), h, h + stride);
      if (!ghost[a]) attached[a].push_back(int(records.size()));
      if (!ghost[b] && b != a) attached[b].push_back(int(records.size()));
      records.push_back(rec);
    }
}

Entry Domain::entry_of(const SimState& s, std::size_t i, const Image& w, uint8_t ghost) {
  const Particles& p = s.p;
  Entry e;
  e.id = p.id[i], e.x = p.x[i], e.v = p.v[i], e.f = p.f[i];
  e.r = p.r[i], e.m = p.m[i], e.inv_m = p.inv_m[i], e.phase = p.phase[i], e.motion = p.motion[i];
  if (p.has_rotation()) e.omega = p.omega[i], e.torque = p.torque[i], e.inv_I = p.inv_I[i];
  e.w = w;
  e.ghost = ghost;
  return e;
}

void Domain::pack(Writer& w, const Entry& e, bool rot, bool full) const {
  w.put(e.id);
  w.put(e.x), w.put(e.v), w.put(e.r), w.put(e.m), w.put(e.inv_m), w.put(e.phase), w.put(e.motion), w.put(e.w);
  if (rot) w.put(e.omega), w.put(e.inv_I);
  if (full) {
    w.put(e.f);
    if (rot) w.put(e.torque);
  }
}

Entry Domain::unpack(Reader& r, bool rot, bool full) const {
  Entry e;
  e.id = r.get<int64_t>();
  e.x = r.get<Vec3>(), e.v = r.get<Vec3>(), e.r = r.get<double>(), e.m = r.get<double>(), e.inv_m = r.get<double>();
  e.phase = r.get<int32_t>(), e.motion = r.get<Motion>(), e.w = r.get<Image>();
  if (rot) e.omega = r.get<Vec3>(), e.inv_I = r.get<double>();
  if (full) {
    e.f = r.get<Vec3>();
    if (rot) e.torque = r.get<Vec3>();
  }
  return e;
}

/// Whether any periodic image of a particle at fractional position sp lies within the ghost
/// margin of rank q's box.
bool Domain::ghost_of(const Vec3& sp, int q, const SimState& s, const double e[3]) const {
  const int c[3] = {q / (dims_[1] * dims_[2]), (q / dims_[2]) % dims_[1], q % dims_[2]};
  for (int k = 0; k < 3; ++k) {
    const bool open = !s.cell.periodic[k];
    const double lo = (open && c[k] == 0) ? -HUGE_VAL : double(c[k]) / dims_[k] - e[k];
    const double hi = (open && c[k] == dims_[k] - 1) ? HUGE_VAL : double(c[k] + 1) / dims_[k] + e[k];
    bool hit = false;
    for (int n = open ? 0 : -1; n <= (open ? 0 : 1) && !hit; ++n) hit = sp[k] + n >= lo && sp[k] + n <= hi;
    if (!hit) return false;
  }
  return true;
}

/// Replaces the local particles by `all`, in id order (the serial engine's order).
void Domain::install(SimState& s, std::vector<Entry>& all) {
  std::sort(all.begin(), all.end(), [](const Entry& a, const Entry& b) { return a.id < b.id; });
  Particles& p = s.p;
  const bool rot = p.has_rotation();
  const std::size_t n = all.size();
  p.x.resize(n), p.v.resize(n), p.f.resize(n), p.r.resize(n), p.m.resize(n), p.inv_m.resize(n);
  p.phase.resize(n), p.id.resize(n), p.motion.resize(n);
  if (rot) p.omega.resize(n), p.torque.resize(n), p.inv_I.resize(n);
  w_.resize(n);
  ghost.resize(n);
  for (std::size_t i = 0; i < n; ++i) {
    const Entry& e = all[i];
    p.id[i] = e.id, p.x[i] = e.x, p.v[i] = e.v, p.f[i] = e.f, p.r[i] = e.r, p.m[i] = e.m, p.inv_m[i] = e.inv_m;
    p.phase[i] = e.phase, p.motion[i] = e.motion;
    if (rot) p.omega[i] = e.omega, p.torque[i] = e.torque, p.inv_I[i] = e.inv_I;
    w_[i] = e.w;
    ghost[i] = e.ghost;
  }
}

void Domain::before_build(SimState& s, NeighbourList& nl) {
  const std::size_t n = s.p.size();
  if (initial_) init(s, nl), ghost.assign(n, 0);
  double e[3];
  margins(s, e);  // first: a refusal leaves the state as it was
  bonds_from_local(s);
  // The bonds of each owned particle, to travel with it.
  std::unordered_multimap<int64_t, int32_t> bonds_of;
  for (const auto& [gid, r] : bonds_) bonds_of.emplace(r.a, gid), bonds_of.emplace(r.b, gid);
  std::vector<std::vector<int>> attached;
  std::vector<Record> records;
  std::vector<double> pool;
  collect_history(s, nl, attached, records, pool);
  kept_walls_.clear();
  std::vector<double> ws;
  // Wrap the owned particles into the cell (the serial engine's wrap, particle by particle).
  {
    std::vector<Vec3> xo;
    std::vector<std::size_t> idx;
    for (std::size_t i = 0; i < n; ++i)
      if (!ghost[i]) xo.push_back(s.p.x[i]), idx.push_back(i);
    const std::vector<Image> wr = spatial::wrap_into_cell(xo, s.cell);
    for (std::size_t q = 0; q < idx.size(); ++q) {
      s.p.x[idx[q]] = xo[q];
      for (int k = 0; k < 3; ++k) w_[idx[q]][k] += wr[q][k];
    }
  }
  const Mat3 hinv = s.cell.h.inverse();
  const bool rot = s.p.has_rotation();
  const int stride = s.stride;
  // Migration: owned particles whose box is another rank's (at the start: dropped, every rank
  // holds the whole sample).
  std::vector<std::vector<char>> out(nbr_.size());
  std::vector<Entry> mine;
  std::vector<uint8_t> stays(n, 0);
  for (std::size_t i = 0; i < n; ++i) {
    if (ghost[i]) continue;
    const Vec3 sp = hinv * (s.p.x[i] - s.cell.origin);
    int c[3];
    for (int k = 0; k < 3; ++k) c[k] = box_of(sp[k], k);
    const int dest = rank_of(c);
    if (dest == rank_) {
      stays[i] = 1;
      mine.push_back(entry_of(s, i, w_[i], 0));
      if (wall_state(s, nl, i, ws)) kept_walls_[s.p.id[i]] = ws;
      continue;
    }
    if (initial_) continue;
    const auto it = std::lower_bound(nbr_.begin(), nbr_.end(), dest);
    if (it == nbr_.end() || *it != dest)
      throw NumericalError("particle " + std::to_string(s.p.id[i]) + " moved farther than one sub-domain between "
                           "two neighbour-list builds (rank " + std::to_string(rank_) + " to " + std::to_string(dest) +
                           "): the run is unstable");
    Writer w{out[std::size_t(it - nbr_.begin())]};
    pack(w, entry_of(s, i, w_[i], 0), rot, true);
    w.put(uint32_t(attached[i].size()));
    for (int r : attached[i]) {
      w.put(records[std::size_t(r)].key), w.put(records[std::size_t(r)].touch);
      w.put(&pool[records[std::size_t(r)].hist], stride);
    }
    const auto range = bonds_of.equal_range(s.p.id[i]);
    w.put(uint32_t(std::distance(range.first, range.second)));
    for (auto it2 = range.first; it2 != range.second; ++it2) w.put(bonds_.at(it2->second));
    const bool with_walls = wall_state(s, nl, i, ws);
    w.put(uint8_t(with_walls));
    if (with_walls) w.put(ws.data(), int(ws.size()));
    ++migrated_;
  }
  // History that stays: pairs with an owned particle that stays here.
  kept_.clear();
  pool_.clear();
  for (std::size_t i = 0; i < n; ++i)
    if (stays[i])
      for (int r : attached[i]) {
        Record rec = records[std::size_t(r)];
        if (kept_.count(rec.key)) continue;
        rec.hist = pool_.size();
        pool_.insert(pool_.end(), pool.begin() + std::ptrdiff_t(records[std::size_t(r)].hist),
                     pool.begin() + std::ptrdiff_t(records[std::size_t(r)].hist) + stride);
        kept_.emplace(rec.key, rec);
      }
  const std::vector<std::vector<char>> arrived = exchange(out, 10);
  for (const auto& buf : arrived) {
    Reader rd{buf.data(), buf.data() + buf.size()};
    while (!rd.done()) {
      mine.push_back(unpack(rd, rot, true));
      const uint32_t nr = rd.get<uint32_t>();
      for (uint32_t q = 0; q < nr; ++q) {
        Record rec;
        rec.key = rd.get<Key>();
        rec.touch = rd.get<uint8_t>();
        rec.hist = pool_.size();
        pool_.resize(pool_.size() + std::size_t(stride));
        rd.get(&pool_[rec.hist], stride);
        kept_.emplace(rec.key, rec);
      }
      const uint32_t nb = rd.get<uint32_t>();
      for (uint32_t q = 0; q < nb; ++q) {
        const BondRec br = rd.get<BondRec>();
        bonds_.emplace(br.gid, br);  // already here (its other end is owned here): the same state
      }
      if (rd.get<uint8_t>()) {
        std::vector<double>& v = kept_walls_[mine.back().id];
        v.resize(s.walls.size() * std::size_t(stride + 1));
        rd.get(v.data(), int(v.size()));
      }
    }
  }
  // Ghosts: each owned particle to every neighbour whose box it reaches (through any image).
  std::sort(mine.begin(), mine.end(), [](const Entry& a, const Entry& b) { return a.id < b.id; });
  // The rank keeps the bonds with an end it owns now.
  const auto owned_here = [&](int64_t id) {
    const auto it = std::lower_bound(mine.begin(), mine.end(), id, [](const Entry& en, int64_t v) { return en.id < v; });
    return it != mine.end() && it->id == id;
  };
  for (auto it = bonds_.begin(); it != bonds_.end();)
    it = (owned_here(it->second.a) || owned_here(it->second.b)) ? std::next(it) : bonds_.erase(it);
  std::vector<std::vector<char>> gout(nbr_.size());
  std::vector<std::vector<int64_t>> sent(nbr_.size());
  for (const Entry& en : mine) {
    const Vec3 sp = hinv * (en.x - s.cell.origin);
    bool interior = true;
    for (int k = 0; k < 3; ++k) {
      const double lo = double(coords_[k]) / dims_[k], hi = double(coords_[k] + 1) / dims_[k];
      interior = interior && (dims_[k] == 1 || (sp[k] > lo + e[k] && sp[k] < hi - e[k]));
    }
    if (interior) continue;
    for (std::size_t q = 0; q < nbr_.size(); ++q)
      if (ghost_of(sp, nbr_[q], s, e)) {
        Writer w{gout[q]};
        pack(w, en, rot, false);
        sent[q].push_back(en.id);
      }
  }
  const std::vector<std::vector<char>> garrived = exchange(gout, 20);
  std::vector<std::vector<int64_t>> got(nbr_.size());
  std::vector<Entry> all = std::move(mine);
  for (std::size_t q = 0; q < garrived.size(); ++q) {
    Reader rd{garrived[q].data(), garrived[q].data() + garrived[q].size()};
    while (!rd.done()) {
      Entry g = unpack(rd, rot, false);
      g.ghost = 1;
      got[q].push_back(g.id);
      all.push_back(g);
    }
  }
  install(s, all);
  install_bonds(s);
  // Forward lists in local indices (ids are unique on a rank, and sorted).
  const auto local = [&](int64_t id) {
    return int32_t(std::lower_bound(s.p.id.begin(), s.p.id.end(), id) - s.p.id.begin());
  };
  send_idx_.assign(nbr_.size(), {});
  recv_idx_.assign(nbr_.size(), {});
  for (std::size_t q = 0; q < nbr_.size(); ++q) {
    for (int64_t id : sent[q]) send_idx_[q].push_back(local(id));
    for (int64_t id : got[q]) recv_idx_[q].push_back(local(id));
  }
  // The old list indexes particles that moved: the build starts afresh, the history is in kept_.
  nl.start.clear();
  nl.need_build = true;
  initial_ = false;
  ++exchanges_;
}

/// Copies the state of the bonds in `B` (the rank's set, bond_id mapping it) into `recs`.
void copy_bond_state(std::map<int32_t, BondRec>& recs, const BondSet& B, const std::vector<int32_t>& ids) {
  for (std::size_t b = 0; b < B.size(); ++b) {
    BondRec& r = recs.at(ids[b]);
    r.state = B.state[b], r.mode = B.mode[b], r.broken_at = B.broken_at[b];
    r.shear = B.shear_force[b], r.twist = B.twist[b], r.bend = B.bend[b], r.image = B.image[b];
  }
}

void Domain::bonds_from_local(const SimState& s) { copy_bond_state(bonds_, s.bonds, bond_id); }

/// The rank's bond set: every kept bond whose two particles are here, in the whole set's order
/// (the serial order of the force sums), with local indices and the image n = K + W_b − W_a.
void Domain::install_bonds(SimState& s) {
  BondSet& B = s.bonds;
  B = BondSet{};
  bond_id.clear();
  const auto local = [&](int64_t id) {
    const auto it = std::lower_bound(s.p.id.begin(), s.p.id.end(), id);
    return (it != s.p.id.end() && *it == id) ? int32_t(it - s.p.id.begin()) : int32_t(-1);
  };
  bool lost = false;
  int64_t lost_a = 0, lost_b = 0;
  for (auto& [gid, r] : bonds_) {
    const int32_t i = local(r.a), j = local(r.b);
    r.local = i >= 0 && j >= 0;
    if (!r.local) {
      // Out of each other's reach: farther apart than the rest length plus the skin, so out of
      // contact until they come back within reach (the serial engine resets the spring too).
      if (r.state == BondSet::intact) lost = true, lost_a = r.a, lost_b = r.b;
      r.shear = Vec3{};
      continue;
    }
    Vec3 image;
    for (int k = 0; k < 3; ++k) image[k] = double(r.k[std::size_t(k)] + w_[std::size_t(j)][std::size_t(k)] - w_[std::size_t(i)][std::size_t(k)]);
    B.i.push_back(i), B.j.push_back(j), B.image.push_back(image), B.radius.push_back(r.radius);
    B.rest_length.push_back(r.rest), B.state.push_back(r.state), B.mode.push_back(r.mode);
    B.broken_at.push_back(r.broken_at), B.shear_force.push_back(r.shear), B.twist.push_back(r.twist);
    B.bend.push_back(r.bend);
    bond_id.push_back(gid);
  }
  if (has_bonds_ && any(lost))
    throw NumericalError(lost ? "the intact bond of particles " + std::to_string(lost_a) + " and " + std::to_string(lost_b) +
                                    " stretched beyond the ghost reach (" + std::to_string(reach_) +
                                    " m): the run is unstable or the bonds need failure"
                              : std::string("an intact bond stretched beyond the ghost reach on another rank: the run is unstable"));
}

std::vector<BondRec> Domain::bond_records(const BondSet& local) const {
  std::map<int32_t, BondRec> now = bonds_;
  copy_bond_state(now, local, bond_id);
  std::vector<BondRec> out;
  for (const auto& kv : now) out.push_back(kv.second);
  return out;
}

/// The wall state of local particle i (an owned one, before the build): per wall its touch flag
/// and history doubles; false when it has none (nothing to carry).
bool Domain::wall_state(const SimState& s, const NeighbourList& nl, std::size_t i, std::vector<double>& out) const {
  const std::size_t nw = s.walls.size(), stride = std::size_t(s.stride);
  if (nw == 0 || nl.wall_data.size() != nw) return false;
  out.assign(nw * (stride + 1), 0.0);
  bool carries = false;
  for (std::size_t w = 0; w < nw; ++w) {
    const WallData& wd = nl.wall_data[w];
    double* o = &out[w * (stride + 1)];
    if (i < wd.touch.size() && wd.touch[i]) o[0] = 1, carries = true;
    if ((i + 1) * stride > wd.hist.size()) continue;
    for (std::size_t k = 0; k < stride; ++k) {
      o[1 + k] = wd.hist[i * stride + k];
      carries = carries || o[1 + k] != 0;
    }
  }
  return carries;
}

/// After a build: the wall candidates are the owned particles the list found (a ghost's wall
/// contacts are its owner's), with the history each carried (find_wall_candidates kept the
/// entries by local index, which the exchange reordered: they are rewritten here).
void Domain::install_walls(const SimState& s, NeighbourList& nl) {
  const std::size_t stride = std::size_t(s.stride);
  for (std::size_t w = 0; w < nl.wall_data.size(); ++w) {
    WallData& wd = nl.wall_data[w];
    std::fill(wd.hist.begin(), wd.hist.end(), 0.0);
    std::fill(wd.touch.begin(), wd.touch.end(), uint8_t(0));
    std::size_t out = 0;
    for (const int32_t i : wd.candidates) {
      if (ghost[std::size_t(i)]) continue;
      wd.candidates[out++] = i;
      const auto it = kept_walls_.find(s.p.id[std::size_t(i)]);
      if (it == kept_walls_.end()) continue;
      const double* v = &it->second[w * (stride + 1)];
      if (!wd.touch.empty()) wd.touch[std::size_t(i)] = v[0] != 0;
      std::copy_n(v + 1, stride, wd.hist.begin() + std::ptrdiff_t(std::size_t(i) * stride));
    }
    wd.candidates.resize(out);
  }
  kept_walls_.clear();
}

void Domain::after_build(SimState& s, NeighbourList& nl) {
  const int stride = s.stride;
  const bool touch_flag = s.kern.touch_flag;
  install_walls(s, nl);
  if (kept_.empty()) return;
  const std::size_t n = s.p.size();
  for (std::size_t a = 0; a < n; ++a)
    for (int q = nl.start[a]; q < nl.start[a + 1]; ++q) {
      const std::size_t b = std::size_t(nl.nj[std::size_t(q)]);
      Image key_image = spatial::image_of_code(nl.img[std::size_t(q)]);
      for (int k = 0; k < 3; ++k) key_image[k] -= w_[b][k] - w_[a][k];
      const auto it = kept_.find(Key{s.p.id[a], s.p.id[b], key_image});
      if (it == kept_.end()) continue;
      std::copy_n(&pool_[it->second.hist], stride, &nl.hist[std::size_t(q) * std::size_t(stride)]);
      if (touch_flag) nl.touch[std::size_t(q)] = it->second.touch;
    }
  kept_.clear();
  pool_.clear();
}

Measurements Domain::measure(const SimState& s, const Tally& tl, const EnergyAccount& energy) {
  const Particles& p = s.p;
  Measurements m;
  m.step = s.nstep;
  m.time = s.t;
  m.volume = measurement_volume(s);  // every rank holds the cell and the walls
  // Owned particles' sums: kinetic stress (9), kinetic energy, Σ|F|, free count, count, Σd, mass,
  // volume, Σ|F|².
  double v[18] = {};
  for (std::size_t i = 0; i < p.size(); ++i) {
    if (ghost[i]) continue;
    v[13] += 1, v[14] += 2 * p.r[i], v[15] += p.m[i], v[16] += 4.0 / 3.0 * M_PI * p.r[i] * p.r[i] * p.r[i];
    if (p.motion[i] != Motion::free) continue;
    const Mat3 k = outer(p.m[i] * p.v[i], p.v[i]);
    for (int a = 0; a < 3; ++a)
      for (int b = 0; b < 3; ++b) v[3 * a + b] += k(a, b);
    v[9] += 0.5 * p.m[i] * norm2(p.v[i]);
    if (p.has_rotation()) v[9] += 0.5 * p.inertia(i) * norm2(p.omega[i]);
    v[10] += norm(p.f[i]);
    v[11] += 1;
    v[17] += norm2(p.f[i]);
  }
  sum(v, 18);
  Mat3 sc = tl.virial, kin;
  sc *= -1.0 / m.volume;
  for (int a = 0; a < 3; ++a)
    for (int b = 0; b < 3; ++b) kin(a, b) = -v[3 * a + b] / m.volume;
  m.stress_contact = sc;
  m.stress = sc;
  m.stress += kin;
  m.pressure = -m.stress.trace() / 3;
  m.kinetic_energy = v[9];
  m.elastic_energy = tl.elastic;
  m.dissipated_energy = energy.dissipated;
  m.external_work = energy.ext_work;
  // The account's terms are global already (reduced tallies, summed work): as the serial run.
  if (s.set.track_energy && !std::isnan(energy.e0))
    m.energy_balance_error = m.kinetic_energy + m.elastic_energy + energy.dissipated - (energy.e0 + energy.ext_work);
  m.contacts = tl.contacts;
  m.wall_contacts = tl.wall_contacts;
  m.coordination = 2.0 * double(tl.contacts) / v[13];
  const long nc = tl.contacts + tl.wall_contacts;
  m.unbalanced_force_ratio = (nc > 0 && v[11] > 0) ? (v[10] / v[11]) / (tl.sum_contact_force / double(nc)) : 0;
  m.net_force_rms = v[11] > 0 ? std::sqrt(v[17] / v[11]) : 0;
  if (s.deforming() && m.pressure > 0) {
    double rate = 0;
    for (int a = 0; a < 3; ++a) rate = std::max(rate, std::abs(s.control.velocity_gradient(a, a)));
    m.inertial_number = rate * (v[14] / v[13]) * std::sqrt(v[15] / v[16] / m.pressure);
  }
  m.max_overlap_ratio = tl.max_overlap_ratio;
  for (const auto& w : s.walls) m.wall_forces.push_back(w.force);  // the same on every rank (walls())
  return m;
}

DomainLayout Domain::layout() const {
  DomainLayout l;
  l.rank = rank_, l.ranks = size_;
  for (int k = 0; k < 3; ++k) l.dims[k] = dims_[k], l.coords[k] = coords_[k];
  for (uint8_t g : ghost) (g ? l.ghosts : l.owned) += 1;
  l.migrated = migrated_;
  l.exchanges = exchanges_;
  return l;
}

/// Every rank's bytes, concatenated in rank order on rank 0 (empty elsewhere).
std::vector<char> gather_bytes(MPI_Comm comm, const std::vector<char>& mine) {
  int rank = 0, size = 1;
  MPI_Comm_rank(comm, &rank);
  MPI_Comm_size(comm, &size);
  const int len = int(mine.size());
  std::vector<int> lens(static_cast<std::size_t>(size)), offs(static_cast<std::size_t>(size), 0);
  MPI_Gather(&len, 1, MPI_INT, lens.data(), 1, MPI_INT, 0, comm);
  std::vector<char> all;
  if (rank == 0) {
    std::partial_sum(lens.begin(), lens.end() - 1, offs.begin() + 1);
    all.resize(std::size_t(offs.back() + lens.back()));
  }
  MPI_Gatherv(mine.data(), len, MPI_BYTE, all.data(), lens.data(), offs.data(), MPI_BYTE, 0, comm);
  return all;
}

/// The owned rows of this rank's contact table, gathered on rank 0 in the serial order, indexed
/// by position in `ids` (the gathered particles' ids, sorted; rank 0 only).
ContactTable contacts_on_rank0(Simulation& sim, const Domain& d, const std::vector<int64_t>& ids) {
  ContactTable local = sim.contacts();
  const Particles& p = sim.particles();
  // Rows of owned particles only (a ghost's row is listed by its owner).
  std::vector<char> mine;
  Writer w{mine};
  for (std::size_t c = 0; c < local.size(); ++c)
    if (!d.ghost[std::size_t(local.i[c])]) {
      w.put(p.id[std::size_t(local.i[c])]), w.put(p.id[std::size_t(local.j[c])]);
      w.put(local.overlap[c]), w.put(local.normal_force[c]), w.put(local.tangential_force[c]);
    }
  const std::vector<char> all = gather_bytes(d.comm(), mine);
  ContactTable out;
  if (d.layout().rank != 0) return out;
  struct Row {
    int64_t a, b;
    double overlap;
    Vec3 fn, ft;
  };
  std::vector<Row> rows;
  Reader rd{all.data(), all.data() + all.size()};
  while (!rd.done()) {
    Row r;
    r.a = rd.get<int64_t>(), r.b = rd.get<int64_t>(), r.overlap = rd.get<double>();
    r.fn = rd.get<Vec3>(), r.ft = rd.get<Vec3>();
    rows.push_back(r);
  }
  // A row comes whole from its owner, already by (partner, image): a stable sort by the two ids
  // keeps the images' order, so the table is the serial one.
  std::stable_sort(rows.begin(), rows.end(), [](const Row& x, const Row& y) { return x.a != y.a ? x.a < y.a : x.b < y.b; });
  const auto index = [&](int64_t id) { return int32_t(std::lower_bound(ids.begin(), ids.end(), id) - ids.begin()); };
  for (const Row& r : rows) {
    out.i.push_back(index(r.a)), out.j.push_back(index(r.b));
    out.overlap.push_back(r.overlap), out.normal_force.push_back(r.fn), out.tangential_force.push_back(r.ft);
  }
  return out;
}

}  // namespace

// ------------------------------------------------------------------------------------ public
void decompose(Simulation& sim, const DecompositionOptions& opt) {
  if (sim.domain()) throw InputError("", "decompose", "twice", "the simulation is already decomposed");
  sim.attach_domain(std::make_unique<Domain>(opt));
}

DomainLayout layout(const Simulation& sim) {
  if (const auto* d = dynamic_cast<const Domain*>(sim.domain())) return d->layout();
  DomainLayout l;
  l.owned = long(sim.particles().size());
  return l;
}

Particles gather_particles(const Simulation& sim) {
  const auto* d = dynamic_cast<const Domain*>(sim.domain());
  const Particles& p = sim.particles();
  if (!d) return p;
  const bool rot = p.has_rotation();
  std::vector<char> mine;
  Writer w{mine};
  for (std::size_t i = 0; i < p.size(); ++i)
    if (!d->ghost[i]) {
      w.put(p.id[i]), w.put(p.x[i]), w.put(p.v[i]), w.put(p.r[i]), w.put(p.m[i]), w.put(p.inv_m[i]);
      w.put(p.phase[i]), w.put(p.motion[i]);
      if (rot) w.put(p.omega[i]), w.put(p.inv_I[i]);
    }
  const std::vector<char> all = gather_bytes(d->comm(), mine);
  int rank = 0;
  MPI_Comm_rank(d->comm(), &rank);
  Particles out;
  if (rank != 0) return out;
  std::vector<Entry> es;
  Reader rd{all.data(), all.data() + all.size()};
  while (!rd.done()) {
    Entry e;
    e.id = rd.get<int64_t>(), e.x = rd.get<Vec3>(), e.v = rd.get<Vec3>(), e.r = rd.get<double>();
    e.m = rd.get<double>(), e.inv_m = rd.get<double>(), e.phase = rd.get<int32_t>(), e.motion = rd.get<Motion>();
    if (rot) e.omega = rd.get<Vec3>(), e.inv_I = rd.get<double>();
    es.push_back(e);
  }
  std::sort(es.begin(), es.end(), [](const Entry& a, const Entry& b) { return a.id < b.id; });
  for (const Entry& e : es) {
    out.x.push_back(e.x), out.v.push_back(e.v), out.f.push_back({}), out.r.push_back(e.r), out.m.push_back(e.m);
    out.inv_m.push_back(e.inv_m), out.phase.push_back(e.phase), out.id.push_back(e.id), out.motion.push_back(e.motion);
    if (rot) out.omega.push_back(e.omega), out.torque.push_back({}), out.inv_I.push_back(e.inv_I);
  }
  out.rotation = rot;
  return out;
}

ContactTable gather_contacts(Simulation& sim) {
  const auto* d = dynamic_cast<const Domain*>(sim.domain());
  if (!d) return sim.contacts();
  const Particles p = gather_particles(sim);
  return contacts_on_rank0(sim, *d, p.id);
}

Packing gather_packing(Simulation& sim, const std::vector<Material>& materials) {
  const auto* d = dynamic_cast<const Domain*>(sim.domain());
  if (!d) return to_packing(sim, materials);
  const Particles p = gather_particles(sim);
  ContactTable contacts = contacts_on_rank0(sim, *d, p.id);
  Packing out;
  if (d->layout().rank != 0) return out;
  // The fields of dem::to_packing (checkpoint.cpp), from the gathered arrays.
  out.particles.position = p.x;
  out.particles.radius = p.r;
  out.particles.phase = p.phase;
  out.particles.velocity = p.v;
  if (p.has_rotation()) out.particles.angular_velocity = p.omega;
  out.cell = sim.cell();
  out.contacts = std::move(contacts);
  out.materials = materials;
  return out;
}

BondSet gather_bonds(const Simulation& sim) {
  const auto* d = dynamic_cast<const Domain*>(sim.domain());
  if (!d) return sim.bonds();
  const Particles ids = gather_particles(sim);
  const Particles& p = sim.particles();
  std::vector<char> mine;
  Writer w{mine};
  // Each bond once: from the rank that owns its first particle.
  for (const BondRec& r : d->bond_records(sim.bonds())) {
    const auto it = std::lower_bound(p.id.begin(), p.id.end(), r.a);
    if (it != p.id.end() && *it == r.a && !d->ghost[std::size_t(it - p.id.begin())]) w.put(r);
  }
  const std::vector<char> all = gather_bytes(d->comm(), mine);
  BondSet out;
  if (d->layout().rank != 0) return out;
  const auto index = [&](int64_t id) { return int32_t(std::lower_bound(ids.id.begin(), ids.id.end(), id) - ids.id.begin()); };
  std::vector<BondRec> recs(std::size_t(d->bond_count()));
  Reader rd{all.data(), all.data() + all.size()};
  while (!rd.done()) {
    const BondRec r = rd.get<BondRec>();
    recs.at(std::size_t(r.gid)) = r;
  }
  for (const BondRec& r : recs) {
    out.i.push_back(index(r.a)), out.j.push_back(index(r.b)), out.image.push_back(r.image);
    out.radius.push_back(r.radius), out.rest_length.push_back(r.rest), out.state.push_back(r.state);
    out.mode.push_back(r.mode), out.broken_at.push_back(r.broken_at), out.shear_force.push_back(r.shear);
    out.twist.push_back(r.twist), out.bend.push_back(r.bend);
  }
  return out;
}

std::vector<BondEvent> gather_bond_events(const Simulation& sim) {
  const auto* d = dynamic_cast<const Domain*>(sim.domain());
  if (!d) return sim.bond_events();
  std::vector<char> mine;
  Writer w{mine};
  for (const BondEvent& e : sim.bond_events()) w.put(e);  // each kept once, by its first particle's owner
  const std::vector<char> all = gather_bytes(d->comm(), mine);
  std::vector<BondEvent> out;
  if (d->layout().rank != 0) return out;
  Reader rd{all.data(), all.data() + all.size()};
  while (!rd.done()) out.push_back(rd.get<BondEvent>());
  std::stable_sort(out.begin(), out.end(), [](const BondEvent& a, const BondEvent& b) {
    return a.time != b.time ? a.time < b.time : a.bond < b.bond;
  });
  return out;
}

}  // namespace tomodem::dem
