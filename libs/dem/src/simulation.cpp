#include "tomodem/dem/simulation.hpp"

#include <omp.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>

#include "bond_kernel.hpp"
#include "kernel.hpp"
#include "sinter_law.hpp"
#include "tomodem/core/error.hpp"
#include "tomodem/core/tool.hpp"
#include "tomodem/spatial/grid.hpp"
#include "tomodem/dem/law_registry.hpp"

namespace tomodem::dem {

bool CellControl::active() const {
  for (int a = 0; a < 3; ++a)
    for (int b = 0; b < 3; ++b)
      if (stress_controlled[a][b] || velocity_gradient(a, b) != 0) return true;
  return false;
}

namespace {
using spatial::image_vector;
using spatial::kCentreImage;

/// Frobenius norm, used to bound how far periodic images moved since the last build.
double frobenius(const Mat3& m) {
  double s = 0;
  for (int a = 0; a < 3; ++a)
    for (int b = 0; b < 3; ++b) s += m(a, b) * m(a, b);
  return std::sqrt(s);
}
}  // namespace

struct Simulation::Impl {
  Particles p;
  Cell cell;
  ContactModel model;
  Settings set;
  std::vector<Wall> walls;
  CellControl control;
  BodyForces body;
  KernelSet kern;
  int stride = 0;  // history doubles per contact

  // Half neighbour list (CSR) with per-pair history that survives rebuilds.
  std::vector<int32_t> start, nj, owner;
  std::vector<uint8_t> img, touch;
  std::vector<double> hist;
  std::vector<Vec3> x_build;
  Mat3 h_build;
  std::vector<Vec3> wall_point_build;
  bool need_build = true;
  long builds = 0;
  double skin = 0, reach_max = 0;
  Vec3 shift[27], vshift[27];

  struct WallData {
    std::vector<int32_t> candidates;
    std::vector<double> hist;
    std::vector<uint8_t> touch;
  };
  std::vector<WallData> wall_data;

  std::vector<Vec3> u;  // absolute velocities when the cell deforms
  int threads = 1;
  std::size_t pair_capacity_hint = 0;  ///< pairs in the last list (+N), to reserve the next one
  std::vector<std::vector<Vec3>> fbuf, tbuf;
  std::vector<std::vector<double>> sbuf;
  std::vector<int> split;

  // Bonds (empty unless the scene has them): per-particle partners for the contact exclusion.
  BondSet bonds;
  std::vector<BondLaw> bond_laws;
  BondFailure bond_failure = BondFailure::none;
  BondKernel bond_kernel[2] = {nullptr, nullptr};
  std::vector<BondEvent> bond_events;
  std::vector<std::vector<BondEvent>> event_buf;
  std::vector<std::size_t> bond_split;

  double dt = 0, t = 0;
  long nstep = 0;
  bool forces_valid = false;
  Tally last;  // tally of the last tally pass
  std::vector<double> stiffness;
  double dissipated = 0, ext_work = 0, e0 = std::numeric_limits<double>::quiet_NaN();

  Impl(Particles particles, Cell c, ContactModel m, Settings s)
      : p(std::move(particles)), cell(c), model(std::move(m)), set(s) {
    kern = select_kernels(model, !set.scalar_kernels);
    stride = kern.normal_history + kern.tangential_history + kern.rolling_history;
    if (model.needs_rotation()) p.enable_rotation();
    if (p.size() == 0) throw InputError("", "particles", "0", "a scene needs at least one particle");
    double dsum = 0;
    for (double r : p.r) dsum += 2 * r;
    skin = set.skin > 0 ? set.skin : 0.1 * dsum / double(p.size());
    threads = std::max(1, set.threads);
    // Largest extra range of an adhesive law (JKR keeps contacts in tension).
    double rmax = *std::max_element(p.r.begin(), p.r.end());
    for (const auto& pp : model.pairs) reach_max = std::max(reach_max, kern.reach(pp, rmax));
  }

  bool deforming() const { return control.active(); }

  // ------------------------------------------------------------ neighbour search
  /// Cell vectors (integer, per particle) subtracted by the last wrap: a pair seen through image
  /// n before the wrap is seen through n + w_j − w_i after it (its history must follow).
  std::vector<spatial::Image> wrapped;

  void wrap_positions() { wrapped = spatial::wrap_into_cell(p.x, cell); }

  /// Image code of pair (i, j) after the wrap, from its code before; -1 when out of range.
  int image_after_wrap(std::size_t i, int j, int code) const {
    spatial::Image n = spatial::image_of_code(code);
    for (int k = 0; k < 3; ++k) n[std::size_t(k)] += wrapped[std::size_t(j)][std::size_t(k)] - wrapped[i][std::size_t(k)];
    return spatial::image_code(n);
  }

  void update_image_tables() {
    const Mat3 lh = control.velocity_gradient * cell.h;
    for (int c = 0; c < 27; ++c) {
      const Vec3 n = image_vector(c);
      shift[c] = cell.h * n;
      vshift[c] = lh * n;
    }
  }

  /// The half list (CSR) from the spatial grid. One level (narrow size distributions): each
  /// thread lists the rows of a contiguous range of particles straight into the CSR, and the
  /// ranges are joined in order, so the list is the same for every thread count. Several levels
  /// (wide distributions): spatial::half_list.
  void search_pairs(std::vector<int32_t>& new_start, std::vector<int32_t>& new_j, std::vector<uint8_t>& new_img) {
    const std::size_t n = p.size();
    const double extra = skin + reach_max;
    const spatial::Grid grid(p.x, p.r, cell, extra);
    update_image_tables();
    if (grid.levels() > 1) {
      spatial::half_list(grid, p.x, p.r, shift, extra, new_start, new_j, new_img, threads);
      return;
    }
    new_start.assign(n + 1, 0);
    std::vector<std::vector<int32_t>> part_j(threads);
    std::vector<std::vector<uint8_t>> part_img(threads);
    int parts = 1;
#pragma omp parallel num_threads(threads) if (threads > 1)
    {
      const int t = omp_get_thread_num();
#pragma omp single
      parts = omp_get_num_threads();
      const std::size_t i0 = n * t / parts, i1 = n * (t + 1) / parts;
      auto& pj = part_j[t];
      auto& pimg = part_img[t];
      pj.reserve(pair_capacity_hint / parts);
      pimg.reserve(pair_capacity_hint / parts);
      for (std::size_t i = i0; i < i1; ++i) {
        const Vec3 xi = p.x[i];
        const double ri = p.r[i];
        grid.visit(i, [&](int32_t j, int code) {
          // Each pair once: i < j for any image, and i == j only for the positive half of images.
          if (j < int32_t(i) || (j == int32_t(i) && code <= kCentreImage)) return;
          const Vec3 d = p.x[std::size_t(j)] + shift[code] - xi;
          const double rc = ri + p.r[std::size_t(j)] + extra;
          if (dot(d, d) < rc * rc) {
            pj.push_back(j);
            pimg.push_back(uint8_t(code));
          }
        });
        new_start[i + 1] = int32_t(pj.size());
      }
    }
    if (parts == 1) {
      new_j.swap(part_j[0]);
      new_img.swap(part_img[0]);
      return;
    }
    std::size_t total = 0;
    for (int t = 0; t < parts; ++t) total += part_j[t].size();
    new_j.reserve(total);
    new_img.reserve(total);
    for (int t = 0; t < parts; ++t) {
      const auto offset = int32_t(new_j.size());
      for (std::size_t i = n * t / parts; i < n * (t + 1) / parts; ++i) new_start[i + 1] += offset;
      new_j.insert(new_j.end(), part_j[t].begin(), part_j[t].end());
      new_img.insert(new_img.end(), part_img[t].begin(), part_img[t].end());
      std::vector<int32_t>().swap(part_j[t]);
      std::vector<uint8_t>().swap(part_img[t]);
    }
  }

  /// The history worth carrying over a rebuild: pairs whose springs or contact flag are set,
  /// re-imaged after the wrap. Kept apart so the old list can be freed before the new one is
  /// built (peak memory one list, not two: in a gas most listed pairs never touch).
  struct KeptHistory {
    std::vector<int32_t> start;  // per particle, CSR over the kept pairs
    std::vector<int32_t> j;
    std::vector<uint8_t> img, touch;
    std::vector<double> hist;
  };

  KeptHistory keep_history() {
    KeptHistory kept;
    if (start.empty() || (stride == 0 && !kern.touch_flag)) return kept;
    const std::size_t n = p.size();
    kept.start.assign(n + 1, 0);
    for (std::size_t i = 0; i < n; ++i) {
      for (int q = start[i]; q < start[i + 1]; ++q) {
        const double* h = &hist[std::size_t(q) * stride];
        bool carries = kern.touch_flag && touch[q];
        for (int s = 0; s < stride; ++s) carries = carries || h[s] != 0;
        const int code = carries ? image_after_wrap(i, nj[q], img[q]) : -1;
        if (code < 0) continue;
        kept.j.push_back(nj[q]);
        kept.img.push_back(uint8_t(code));
        kept.touch.push_back(kern.touch_flag ? touch[q] : 0);
        kept.hist.insert(kept.hist.end(), h, h + stride);
      }
      kept.start[i + 1] = int32_t(kept.j.size());
    }
    return kept;
  }

  void build_neighbors() {
    wrap_positions();
    for (std::size_t b = 0; b < bonds.size(); ++b)
      bonds.image[b] += spatial::as_vector(wrapped[bonds.j[b]]) - spatial::as_vector(wrapped[bonds.i[b]]);
    const std::size_t n = p.size();
    const KeptHistory kept = keep_history();
    pair_capacity_hint = nj.size() + n;
    std::vector<int32_t>().swap(nj);
    std::vector<int32_t>().swap(owner);
    std::vector<uint8_t>().swap(img);
    std::vector<double>().swap(hist);
    std::vector<uint8_t>().swap(touch);
    std::vector<int32_t> new_start, new_j;
    std::vector<uint8_t> new_img;
    search_pairs(new_start, new_j, new_img);
    if (!bonds.i.empty()) exclude_bonded(new_start, new_j, new_img);
    // Carry the kept history to the pairs that stay in the list (short per-particle lists: linear
    // search); a pair whose particle crossed a periodic face keeps its spring and JKR flag.
    std::vector<double> new_hist(new_j.size() * stride, 0.0);
    std::vector<uint8_t> new_touch(kern.touch_flag ? new_j.size() : 0, 0);
    if (!kept.start.empty()) {
#pragma omp parallel for num_threads(threads) if (threads > 1) schedule(static)
      for (long i = 0; i < long(n); ++i)
        for (int q = kept.start[i]; q < kept.start[i + 1]; ++q)
          for (int k = new_start[i]; k < new_start[i + 1]; ++k)
            if (new_j[k] == kept.j[q] && new_img[k] == kept.img[q]) {
              std::copy_n(&kept.hist[std::size_t(q) * stride], stride, &new_hist[std::size_t(k) * stride]);
              if (kern.touch_flag) new_touch[k] = kept.touch[q];
              break;
            }
    }
    start.swap(new_start);
    nj.swap(new_j);
    img.swap(new_img);
    hist.swap(new_hist);
    touch.swap(new_touch);

    // Wall candidates: particles within reach of each wall.
    wall_data.resize(walls.size());
    wall_point_build.resize(walls.size());
    for (std::size_t w = 0; w < walls.size(); ++w) {
      auto& wd = wall_data[w];
      wd.hist.resize(n * stride, 0.0);
      if (kern.touch_flag) wd.touch.resize(n, 0);
      wd.candidates.clear();
      for (std::size_t i = 0; i < n; ++i)
        if (dot(p.x[i] - walls[w].point, walls[w].normal) < p.r[i] + skin + reach_max) wd.candidates.push_back(int32_t(i));
        else {
          std::fill_n(wd.hist.begin() + std::ptrdiff_t(i) * stride, stride, 0.0);
          if (kern.touch_flag) wd.touch[i] = 0;
        }
      wall_point_build[w] = walls[w].point;
    }

    partition_threads();
    fill_owner();
    x_build = p.x;
    h_build = cell.h;
    need_build = false;
    ++builds;
  }

  /// Removes pairs joined by a bond from a new half list: an intact bond carries them, and a
  /// broken one is their contact (compression and friction between the fracture faces, in the
  /// bond loop: the faces close at the rest length, not at R_i + R_j).
  void exclude_bonded(std::vector<int32_t>& st, std::vector<int32_t>& jj, std::vector<uint8_t>& im) const {
    const std::size_t n = p.size();
    std::vector<std::vector<std::pair<int32_t, int>>> partners(n);
    for (std::size_t b = 0; b < bonds.size(); ++b) {
      const Vec3& v = bonds.image[b];
      const int code = (int(std::lround(v.x)) + 1) * 9 + (int(std::lround(v.y)) + 1) * 3 + int(std::lround(v.z)) + 1;
      partners[bonds.i[b]].push_back({bonds.j[b], code});
    }
    std::size_t out = 0;
    int32_t begin = st[0];
    for (std::size_t i = 0; i < n; ++i) {
      const int32_t end = st[i + 1];
      for (int32_t k = begin; k < end; ++k) {
        bool bonded = false;
        for (const auto& pc : partners[i]) bonded = bonded || (pc.first == jj[k] && pc.second == im[k]);
        if (bonded) continue;
        jj[out] = jj[k];
        im[out] = im[k];
        ++out;
      }
      begin = end;
      st[i + 1] = int32_t(out);
    }
    jj.resize(out);
    im.resize(out);
  }

  void fill_owner() {
    owner.resize(nj.size());
    for (std::size_t i = 0; i + 1 < start.size(); ++i)
      for (int k = start[i]; k < start[i + 1]; ++k) owner[k] = int32_t(i);
  }

  /// Splits the particles among threads by pair count (deterministic for a thread count).
  void partition_threads() {
    bond_split.assign(threads + 1, bonds.size());
    for (int t = 0; t < threads; ++t) bond_split[t] = bonds.size() * std::size_t(t) / std::size_t(threads);
    const std::size_t n = p.size();
    split.assign(threads + 1, int(n));
    split[0] = 0;
    const double per = double(nj.size()) / threads;
    int t = 1;
    for (std::size_t i = 0; i < n && t < threads; ++i)
      if (start[i + 1] >= per * t) split[t++] = int(i + 1);
  }

  bool rebuild_due() const {
    if (need_build) return true;
    double dmax2 = 0;
    const long n = long(p.size());
#pragma omp parallel for num_threads(threads) if (threads > 1) schedule(static) reduction(max : dmax2)
    for (long i = 0; i < n; ++i) dmax2 = std::max(dmax2, norm2(p.x[i] - x_build[i]));
    const double dmax = std::sqrt(dmax2);
    Mat3 dh = cell.h;
    for (int a = 0; a < 3; ++a)
      for (int b = 0; b < 3; ++b) dh(a, b) -= h_build(a, b);
    if (2 * dmax + std::sqrt(3.0) * frobenius(dh) > skin) return true;
    for (std::size_t w = 0; w < walls.size(); ++w)
      if (dmax + norm(walls[w].point - wall_point_build[w]) > skin) return true;
    return false;
  }

  // ------------------------------------------------------------ forces
  ForceJob job() {
    ForceJob jb;
    jb.x = p.x.data();
    if (deforming()) {
      u.resize(p.size());
      const Mat3& L = control.velocity_gradient;
      for (std::size_t i = 0; i < p.size(); ++i) u[i] = p.v[i] + L * (p.x[i] - cell.origin);
      jb.u = u.data();
    } else {
      jb.u = p.v.data();
    }
    jb.omega = p.has_rotation() ? p.omega.data() : nullptr;
    jb.r = p.r.data();
    jb.m = p.m.data();
    jb.phase = p.phase.data();
    jb.start = start.data();
    jb.owner = owner.data();
    jb.j = nj.data();
    jb.img = img.data();
    jb.hist = hist.data();
    jb.touch = touch.empty() ? nullptr : touch.data();
    jb.hist_stride = stride;
    jb.shift = shift;
    jb.vshift = vshift;
    jb.pairs = model.pairs.data();
    jb.n_phases = model.n_phases;
    jb.dt = dt;
    return jb;
  }

  /// Computes all forces and torques at the current state. With `tally`, also the virial,
  /// energies and per-particle stiffness (into `last`).
  void compute_forces(bool tally, Vec3* pair_force = nullptr) {
    if (rebuild_due()) build_neighbors();
    update_image_tables();
    const std::size_t n = p.size();
    const bool rot = p.has_rotation();
    ForceJob jb = job();
    jb.pair_force = pair_force;
    BondJob bj{};
    const bool have_bonds = !bonds.i.empty();
    if (have_bonds) {
      bj = BondJob{p.x.data(), jb.u, p.omega.data(), p.r.data(), p.m.data(), p.phase.data(), &bonds,
                   bond_laws.data(), model.n_phases, cell.h, control.velocity_gradient * cell.h, dt, t};
      event_buf.assign(threads, {});
    }
    std::vector<Tally> tallies(threads);
    if (tally) stiffness.resize(n);
    if (int(fbuf.size()) < threads) {
      fbuf.resize(threads);
      tbuf.resize(threads);
      sbuf.resize(threads);
    }
    // The helper threads' buffers stay zero between calls (the reduction below clears what it
    // reads), so each is touched twice a step instead of three times; one parallel region.
    for (int q = 1; q < threads; ++q) {
      if (fbuf[q].size() != n) fbuf[q].assign(n, Vec3{});
      if (rot && tbuf[q].size() != n) tbuf[q].assign(n, Vec3{});
      if (tally && sbuf[q].size() != n) sbuf[q].assign(n, 0.0);
    }
    const long reduce_from = (have_bonds || threads == 1) ? 0 : split[1];
#pragma omp parallel num_threads(threads) if (threads > 1)
    {
      const int tid = omp_get_thread_num();
#pragma omp for schedule(static)
      for (long i = 0; i < long(n); ++i) {
        p.f[i] = Vec3{};
        if (rot) p.torque[i] = Vec3{};
        if (tally) stiffness[i] = 0;
      }
      Vec3* f = tid > 0 ? fbuf[tid].data() : p.f.data();
      Vec3* tq = rot ? (tid > 0 ? tbuf[tid].data() : p.torque.data()) : nullptr;
      double* st = tally ? (tid > 0 ? sbuf[tid].data() : stiffness.data()) : nullptr;
      kern.pair[tally](jb, split[tid], split[tid + 1], f, tq, &tallies[tid], st);
      if (have_bonds)
        bond_kernel[tally](bj, bond_split[tid], bond_split[tid + 1], f, tq, &tallies[tid], st, &event_buf[tid]);
#pragma omp barrier
      // Reduce the per-thread buffers in a fixed order: the result depends on the thread count
      // only through round-off, and not at all on scheduling.
      // A pair list stores j ≥ i, so without bonds thread q writes only to particles from its
      // first one, split[q], on: the rest of its buffer stays zero and is not read.
#pragma omp for schedule(static)
      for (long i = reduce_from; i < long(n); ++i)
        for (int q = 1; q < threads && (have_bonds || split[q] <= i); ++q) {
          p.f[i] += fbuf[q][i];
          fbuf[q][i] = Vec3{};
          if (rot) {
            p.torque[i] += tbuf[q][i];
            tbuf[q][i] = Vec3{};
          }
          if (tally) {
            stiffness[i] += sbuf[q][i];
            sbuf[q][i] = 0;
          }
        }
    }
    Tally total;
    for (const auto& tt : tallies) total.add(tt);
    if (have_bonds)
      for (const auto& ev : event_buf)
        if (!ev.empty()) bond_events.insert(bond_events.end(), ev.begin(), ev.end());
    // Walls (few candidates each): serial, through the same law functions.
    for (std::size_t w = 0; w < walls.size(); ++w) {
      WallJob wj{walls[w].point, walls[w].normal, walls[w].velocity, walls[w].phase,
                 wall_data[w].candidates.data(), int(wall_data[w].candidates.size()), wall_data[w].hist.data(),
                 wall_data[w].touch.empty() ? nullptr : wall_data[w].touch.data()};
      Tally wt;
      kern.wall[tally](jb, wj, p.f.data(), rot ? p.torque.data() : nullptr, &wt, tally ? stiffness.data() : nullptr);
      // The wall force is needed by force-controlled walls every step; recompute it cheaply
      // from the tally pass or, without tally, from the particles' change of force.
      walls[w].force = wt.wall_force;
      total.add(wt);
    }
    apply_body_forces(tally ? &total : nullptr);
    if (tally) last = total;
    forces_valid = true;
  }

  void apply_body_forces(Tally* tally) {
    const std::size_t n = p.size();
    const Vec3 g = body.gravity;
    if (g.x != 0 || g.y != 0 || g.z != 0)
      for (std::size_t i = 0; i < n; ++i) p.f[i] += p.m[i] * g;
    if (body.fluid_viscosity > 0) {
      const double c = 6 * M_PI * body.fluid_viscosity;
      for (std::size_t i = 0; i < n; ++i) {
        p.f[i] -= (c * p.r[i]) * p.v[i];
        if (tally) tally->dissipated += c * p.r[i] * norm2(p.v[i]) * dt;
      }
    }
    if (body.local_damping > 0) {
      const double lam = body.local_damping;
      for (std::size_t i = 0; i < n; ++i) {
        Vec3& f = p.f[i];
        const Vec3& v = p.v[i];
        for (int k = 0; k < 3; ++k) {
          const double d = -lam * std::abs(f[k]) * (v[k] > 0 ? 1 : (v[k] < 0 ? -1 : 0));
          if (tally) tally->dissipated -= d * v[k] * dt;
          f[k] += d;
        }
        if (p.has_rotation()) {
          Vec3& tq = p.torque[i];
          const Vec3& w = p.omega[i];
          for (int k = 0; k < 3; ++k) {
            const double d = -lam * std::abs(tq[k]) * (w[k] > 0 ? 1 : (w[k] < 0 ? -1 : 0));
            if (tally) tally->dissipated -= d * w[k] * dt;
            tq[k] += d;
          }
        }
      }
    }
  }

  // ------------------------------------------------------------ integration
  void kick(double h) {
    const std::size_t n = p.size();
    const bool rot = p.has_rotation();
#pragma omp parallel for num_threads(threads) if (threads > 1) schedule(static)
    for (long i = 0; i < long(n); ++i) {
      p.v[i] += (h * p.inv_m[i]) * p.f[i];
      if (rot) p.omega[i] += (h * p.inv_I[i]) * p.torque[i];
    }
  }

  void drift() {
    const std::size_t n = p.size();
    if (deforming()) {
      const Mat3 L = control.velocity_gradient;
      const Vec3 o = cell.origin;
#pragma omp parallel for num_threads(threads) if (threads > 1) schedule(static)
      for (long i = 0; i < long(n); ++i) p.x[i] += dt * (p.v[i] + L * (p.x[i] - o));
      Mat3 dh = L * cell.h;
      dh *= dt;
      cell.h += dh;
    } else {
#pragma omp parallel for num_threads(threads) if (threads > 1) schedule(static)
      for (long i = 0; i < long(n); ++i) p.x[i] += dt * p.v[i];
    }
    for (auto& w : walls) w.point += dt * w.velocity;
  }

  bool tally_every_step() const {
    if (set.track_energy || deforming()) return true;
    for (const auto& w : walls)
      if (w.force_controlled) return true;
    return false;
  }

  void step() {
    if (dt <= 0) throw InputError("", "timestep", std::to_string(dt), "the time step must be set and positive");
    const bool tally_all = tally_every_step();
    if (!forces_valid) {
      // Forces at the current state, before any time has passed: the incremental springs
      // (tangential, rolling) must not advance by v_rel·Δt here, or every contact present at the
      // start (or after invalidate_neighbors) gets one step of displacement that never happened.
      const double h = dt;
      dt = 0;
      compute_forces(tally_all);
      dt = h;
    }
    if (set.track_energy && std::isnan(e0)) e0 = total_energy();
    kick(0.5 * dt);
    if (set.track_energy) accumulate_external_work();
    drift();
    t += dt;
    ++nstep;
    const bool check = set.check_interval > 0 && nstep % set.check_interval == 0;
    compute_forces(tally_all || check);
    if (tally_all || check) {
      if (set.track_energy) dissipated += last.dissipated;
    }
    kick(0.5 * dt);
    if (deforming()) servo_cell();
    servo_walls();
    if (check) check_stability();
  }

  /// Work of gravity, moving walls and the deforming cell over this step (midpoint velocities).
  void accumulate_external_work() {
    const Vec3 g = body.gravity;
    if (g.x != 0 || g.y != 0 || g.z != 0)
      for (std::size_t i = 0; i < p.size(); ++i) ext_work += p.m[i] * dot(g, p.v[i]) * dt;
    for (const auto& w : walls) ext_work += -dot(w.force, w.velocity) * dt;
    // Particles moved at a prescribed velocity (grips) work against the forces they receive.
    for (std::size_t i = 0; i < p.size(); ++i)
      if (p.motion[i] == Motion::prescribed) ext_work -= dot(p.f[i], p.v[i]) * dt;
    if (deforming()) {
      const double vol = cell.volume();
      const Mat3& L = control.velocity_gradient;
      // Power of the boundary on the contact network: -Σ F_ij ⊗ l_ij : L = V σ_c : L.
      double pw = 0;
      for (int a = 0; a < 3; ++a)
        for (int b = 0; b < 3; ++b) pw -= last.virial(a, b) * L(a, b);
      ext_work += pw * dt;
      (void)vol;
    }
  }

  void servo_cell() {
    // Mixed control: each stress-controlled component gets the strain rate that closes its
    // error over a relaxation time of the cell's elastic-wave transit L/c (a faster servo
    // outruns the packing and oscillates). The modulus is the affine estimate
    // C = Σ_c S_n l²/(5V) (isotropic average of n_a⁴), c = sqrt(C/ρ_bulk).
    const double vol = cell.volume();
    Mat3 sigma = last.virial;
    sigma *= -1.0 / vol;
    double ksum = 0, mass = 0, dmean = 0;
    for (std::size_t i = 0; i < p.size(); ++i) {
      if (!stiffness.empty()) ksum += stiffness[i];
      mass += p.m[i];
      dmean += 2 * p.r[i];
    }
    dmean /= double(p.size());
    const double modulus = 0.5 * ksum * dmean * dmean / (5 * vol);  // stiffness sums count each contact twice
    double width = 0;
    for (int k = 0; k < 3; ++k) width = std::max(width, norm(cell.h.col(k)));
    const double transit = modulus > 0 ? width / std::sqrt(modulus / (mass / vol)) : 0;
    for (int a = 0; a < 3; ++a)
      for (int b = 0; b < 3; ++b) {
        if (!control.stress_controlled[a][b]) continue;
        const double err = sigma(a, b) - control.target_stress(a, b);
        double rate;
        if (modulus > 0) rate = -control.servo_gain * err / (modulus * std::max(transit, dt));
        else rate = err > 0 ? -control.max_strain_rate : control.max_strain_rate;
        if (control.max_strain_rate > 0) rate = std::clamp(rate, -control.max_strain_rate, control.max_strain_rate);
        control.velocity_gradient(a, b) = rate;
      }
  }

  void servo_walls() {
    double rmin = *std::min_element(p.r.begin(), p.r.end());
    for (std::size_t w = 0; w < walls.size(); ++w) {
      Wall& wl = walls[w];
      if (!wl.force_controlled) continue;
      const double f_now = -dot(wl.force, wl.normal);  // compressive force from the particles
      const double vmax = 1e-3 * rmin / dt;
      double gain = wl.servo_gain;
      if (gain <= 0) {
        // Move the wall by a fraction of the force error over the wall contacts' stiffness.
        const double kw = wall_stiffness(w);
        gain = kw > 0 ? 0.05 / (kw * dt) : 0;
      }
      double vn = gain > 0 ? gain * (wl.target_force - f_now) : (f_now < wl.target_force ? vmax : -vmax);
      vn = std::clamp(vn, -vmax, vmax);
      wl.velocity = vn * wl.normal;
    }
  }

  /// Sum of the normal stiffness of a wall's contacts at their overlaps (the normal law's own).
  double wall_stiffness(std::size_t w) const {
    const LawInfo& normal_law = law_info(model.normal);
    double k = 0;
    const Wall& wl = walls[w];
    for (int i : wall_data[w].candidates) {
      const double delta = p.r[i] - dot(p.x[i] - wl.point, wl.normal);
      if (delta <= 0) continue;
      k += normal_law.stiffness(model.pair(p.phase[i], wl.phase), p.r[i], delta);
    }
    return k;
  }

  double kinetic_energy() const {
    double e = 0;
    for (std::size_t i = 0; i < p.size(); ++i) {
      if (p.motion[i] != Motion::free) continue;
      e += 0.5 * p.m[i] * norm2(p.v[i]);
      if (p.has_rotation()) e += 0.5 * p.inertia(i) * norm2(p.omega[i]);
    }
    return e;
  }

  double total_energy() {
    // Elastic energy needs a tally pass; the state is restored afterwards.
    Measurements m = measure_now();
    return m.kinetic_energy + m.elastic_energy;
  }

  // ------------------------------------------------------------ stability
  void check_stability() {
    std::vector<std::size_t> bad;
    for (std::size_t i = 0; i < p.size(); ++i) {
      const Vec3& x = p.x[i];
      const Vec3& v = p.v[i];
      if (!std::isfinite(x.x + x.y + x.z + v.x + v.y + v.z) || norm(v) * dt > 0.5 * p.r[i]) bad.push_back(i);
    }
    if (!bad.empty()) {
      std::ostringstream s;
      s << "unstable at step " << nstep << " (t = " << t << " s): particle";
      s << (bad.size() > 1 ? "s " : " ");
      for (std::size_t k = 0; k < std::min<std::size_t>(bad.size(), 5); ++k) s << (k ? ", " : "") << p.id[bad[k]];
      if (bad.size() > 5) s << " and " << bad.size() - 5 << " more";
      s << " moved more than half a radius in one step or became non-finite. Likely cause: the time step "
        << dt << " s is too large for the contact stiffness (critical estimate "
        << network_critical_step() << " s from the current contacts), or an input velocity is too high.";
      throw NumericalError(s.str());
    }
    // Sintering necks interpenetrate by design (Coble's a² = 2Rh): the overlap limit is elastic.
    if (law_info(model.normal).stiffness_kind != StiffnessKind::viscous && last.max_overlap_ratio > 0.5) {
      std::ostringstream s;
      // Name the pair (a scan of the list, only on this error path).
      std::size_t wi = 0, wj = 0;
      double worst = -1;
      for (std::size_t i = 0; i + 1 < start.size(); ++i)
        for (int k = start[i]; k < start[i + 1]; ++k) {
          const std::size_t j = std::size_t(nj[k]);
          const double ratio = (p.r[i] + p.r[j] - norm(p.x[j] + shift[img[k]] - p.x[i])) / std::min(p.r[i], p.r[j]);
          if (ratio > worst) worst = ratio, wi = i, wj = j;
        }
      s << "unstable at step " << nstep << " (t = " << t << " s): a contact overlaps by "
        << last.max_overlap_ratio << " of the smaller radius (limit 0.5)";
      if (worst > 0)
        s << " (particles " << p.id[wi] << " and " << p.id[wj] << ", radii " << p.r[wi] << " and " << p.r[wj]
          << " m, speeds " << norm(p.v[wi]) << " and " << norm(p.v[wj]) << " m/s, masses " << p.m[wi] << " and "
          << p.m[wj] << " kg)";
      s << ". Likely cause: a time step of " << dt
        << " s against a critical estimate of " << network_critical_step()
        << " s, or loads far above what the stiffness can carry.";
      throw NumericalError(s.str());
    }
  }

  /// Gershgorin bound of the highest frequency from the per-particle stiffness sums:
  /// ω_max² ≤ max_i 2 Σ_c S_c / m_i, so Δt_crit ≥ sqrt(2 m_i / Σ_c S_c) (Verlet: 2/ω).
  double network_critical_step() const {
    double best = std::numeric_limits<double>::infinity();
    for (std::size_t i = 0; i < stiffness.size(); ++i)
      if (stiffness[i] > 0) best = std::min(best, std::sqrt(2 * p.m[i] / stiffness[i]));
    return best;
  }

  // ------------------------------------------------------------ measurement
  Measurements measure_now(std::vector<Vec3>* pair_force = nullptr) {
    // A tally pass on the current state. History (incremental springs, JKR flags) is saved
    // and restored, so measuring never changes the trajectory.
    // Rebuild first when due: a rebuild inside the tally pass would resize the history, and
    // restoring the saved copy afterwards would leave it shorter than the neighbour list.
    if (rebuild_due()) build_neighbors();
    if (pair_force) pair_force->assign(nj.size(), Vec3{});
    const std::vector<double> h = hist;
    const std::vector<uint8_t> tf = touch;
    std::vector<WallData> wd = wall_data;
    std::vector<Vec3> wall_force;
    for (auto& w : walls) wall_force.push_back(w.force);
    const std::vector<Vec3> f = p.f, tq = p.torque;
    const bool valid = forces_valid;
    const BondSet bond_state = bonds;
    const std::size_t n_events = bond_events.size();
    const bool build_flag = need_build;
    compute_forces(true, pair_force ? pair_force->data() : nullptr);
    const Tally tl = last;
    Measurements m;
    m.step = nstep;
    m.time = t;
    m.volume = measurement_volume();
    Mat3 sc = tl.virial;
    sc *= -1.0 / m.volume;
    m.stress_contact = sc;
    Mat3 kin;
    for (std::size_t i = 0; i < p.size(); ++i)
      if (p.motion[i] == Motion::free) kin += outer(p.m[i] * p.v[i], p.v[i]);
    kin *= -1.0 / m.volume;
    m.stress = sc;
    m.stress += kin;
    m.pressure = -m.stress.trace() / 3;
    m.kinetic_energy = kinetic_energy();
    m.elastic_energy = tl.elastic;
    m.dissipated_energy = dissipated;
    m.external_work = ext_work;
    if (set.track_energy && !std::isnan(e0))
      m.energy_balance_error = m.kinetic_energy + m.elastic_energy + dissipated - (e0 + ext_work);
    m.contacts = tl.contacts;
    m.wall_contacts = tl.wall_contacts;
    m.coordination = 2.0 * double(tl.contacts) / double(p.size());
    double fres = 0;
    long nfree = 0;
    for (std::size_t i = 0; i < p.size(); ++i)
      if (p.motion[i] == Motion::free) fres += norm(p.f[i]), ++nfree;
    const long nc = tl.contacts + tl.wall_contacts;
    m.unbalanced_force_ratio = (nc > 0 && nfree > 0) ? (fres / nfree) / (tl.sum_contact_force / nc) : 0;
    if (deforming() && m.pressure > 0) {
      double rate = 0, dsum = 0, mass = 0, vs = 0;
      for (int a = 0; a < 3; ++a) rate = std::max(rate, std::abs(control.velocity_gradient(a, a)));
      for (std::size_t i = 0; i < p.size(); ++i) {
        dsum += 2 * p.r[i];
        mass += p.m[i];
        vs += 4.0 / 3.0 * M_PI * p.r[i] * p.r[i] * p.r[i];
      }
      m.inertial_number = rate * (dsum / p.size()) * std::sqrt(mass / vs / m.pressure);
    }
    m.max_overlap_ratio = tl.max_overlap_ratio;
    for (auto& w : walls) m.wall_forces.push_back(w.force);
    m.neighbor_rebuilds = builds;
    // Restore.
    hist = h;
    touch = tf;
    wall_data = wd;
    for (std::size_t w = 0; w < walls.size(); ++w) walls[w].force = wall_force[w];
    p.f = f;
    p.torque = tq;
    forces_valid = valid;
    bonds = bond_state;
    bond_events.resize(n_events);
    need_build = build_flag;
    m.bonds = long(bonds.intact_count());
    return m;
  }

  /// The periodic cell's volume; with walls, the box between opposite walls along their normals
  /// (falling back to the cell volume for open directions).
  double measurement_volume() const {
    if (walls.empty()) return cell.volume();
    Vec3 ext{cell.h(0, 0), cell.h(1, 1), cell.h(2, 2)};
    for (int k = 0; k < 3; ++k) {
      double lo = std::numeric_limits<double>::infinity(), hi = -lo;
      int count = 0;
      for (const auto& w : walls) {
        if (std::abs(std::abs(w.normal[k]) - 1) > 1e-12) continue;
        const double c = w.point[k];
        if (w.normal[k] > 0) lo = std::min(lo, c);
        else hi = std::max(hi, c);
        ++count;
      }
      if (count >= 2 && hi > lo) ext[k] = hi - lo;
    }
    return ext.x * ext.y * ext.z;
  }
};

// ---------------------------------------------------------------- public interface
Simulation::Simulation(Particles particles, Cell cell, ContactModel model, Settings settings)
    : impl_(std::make_unique<Impl>(std::move(particles), cell, std::move(model), settings)) {}
Simulation::~Simulation() = default;
Simulation::Simulation(Simulation&&) noexcept = default;
Simulation& Simulation::operator=(Simulation&&) noexcept = default;

Particles& Simulation::particles() { return impl_->p; }
const Particles& Simulation::particles() const { return impl_->p; }
const Cell& Simulation::cell() const { return impl_->cell; }
Cell& Simulation::cell() { return impl_->cell; }
const ContactModel& Simulation::model() const { return impl_->model; }
void Simulation::set_sinter_values(int a, int b, const SinterValues& v) {
  for (PairParams* pp : {&impl_->model.pair(a, b), &impl_->model.pair(b, a)}) {
    pp->sinter_delta_b = v.delta_b;
    pp->sinter_gamma = v.gamma;
    pp->sinter_dihedral = v.dihedral;
    pp->sinter_eta = v.eta;
    pp->sinter_initial_neck = v.initial_neck;
  }
}
Mat3 Simulation::contact_stress() const {
  Mat3 s = impl_->last.virial;
  s *= -1.0 / impl_->cell.volume();
  return s;
}

double Simulation::viscous_sums(std::vector<double>& sum) const {
  const Impl& s = *impl_;
  sum.assign(s.p.size(), 0.0);
  if (s.model.normal != NormalLaw::sintering || s.start.size() != s.p.size() + 1) return 0;
  using law::NormalSintering;
  const bool tangential = s.model.tangential == TangentialLaw::viscous;
  const Mat3& H = s.cell.h;
  double modulus = 0;
  for (std::size_t i = 0; i < s.p.size(); ++i)
    for (int k = s.start[i]; k < s.start[i + 1]; ++k) {
      const int j = s.nj[k];
      const Vec3 d = s.p.x[j] + H * image_vector(s.img[k]) - s.p.x[i];
      const double l = norm(d), delta = s.p.r[i] + s.p.r[j] - l;
      const PairParams& pp = s.model.pair(s.p.phase[i], s.p.phase[j]);
      if (delta <= 0 || !(pp.sinter_delta_b > 0)) continue;
      const double R = 2 * s.p.r[i] * s.p.r[j] / (s.p.r[i] + s.p.r[j]);
      double a = s.hist[std::size_t(k) * s.stride];
      if (a <= 0) a = NormalSintering::initial_neck(pp, R, delta);
      const double en = NormalSintering::viscosity(pp, a);
      const double c = en + (tangential ? 5 * NormalSintering::tangential_viscosity(pp, a, R) : 0);
      sum[i] += c;
      sum[std::size_t(j)] += c;
      modulus += en * l * l;
    }
  return modulus;
}
const Settings& Simulation::settings() const { return impl_->set; }
std::vector<Wall>& Simulation::walls() { return impl_->walls; }
CellControl& Simulation::cell_control() { return impl_->control; }
const CellControl& Simulation::cell_control() const { return impl_->control; }
const std::vector<Wall>& Simulation::walls() const { return impl_->walls; }
BodyForces& Simulation::body_forces() { return impl_->body; }
void Simulation::add_wall(const Wall& w) {
  Wall c = w;
  c.normal = (1.0 / norm(w.normal)) * w.normal;
  impl_->walls.push_back(c);
  impl_->need_build = true;
  impl_->forces_valid = false;
}

double Simulation::critical_time_step() const {
  const Impl& s = *impl_;
  double best = std::numeric_limits<double>::infinity();
  const LawInfo& normal_law = law_info(s.model.normal);
  if (normal_law.stiffness_kind == StiffnessKind::spring) {
    // Two-particle Verlet limit of a damped linear spring: Δt < 2(sqrt(1+ζ²) - ζ)/ω, ω² = k/m*,
    // with the law's largest stiffness and ζ = c/2 of its dashpot.
    double mmin = std::numeric_limits<double>::infinity();
    for (std::size_t i = 0; i < s.p.size(); ++i)
      if (s.p.motion[i] == Motion::free) mmin = std::min(mmin, s.p.m[i]);
    for (const auto& pp : s.model.pairs) {
      const double k = normal_law.stiffness(pp, 0, 0);
      if (k <= 0) continue;
      const double z = 0.5 * pp.damping;
      // m* of the two lightest particles (a wall contact has m* = m, twice as large: not limiting).
      best = std::min(best, 2 * (std::sqrt(1 + z * z) - z) * std::sqrt(0.5 * mmin / k));
    }
  } else {
    if (normal_law.stiffness_kind == StiffnessKind::viscous) {
      // Explicit limit of the viscous necks (Gershgorin on M⁻¹C with the rotations): m_i/Σ(η_n + 5η_t).
      std::vector<double> visc;
      viscous_sums(visc);
      for (std::size_t i = 0; i < visc.size(); ++i)
        if (visc[i] > 0 && s.p.motion[i] == Motion::free) best = std::min(best, s.p.m[i] / visc[i]);
    }
    // Rayleigh time of each particle: π R sqrt(ρ/G)/(0.1631ν + 0.8766), G and ν of its phase.
    // Under the sintering law only phases with a non-sintering (Hertz) pair have a spring.
    std::vector<char> elastic(s.model.materials.size(), normal_law.stiffness_kind != StiffnessKind::viscous);
    for (int a = 0; a < int(elastic.size()); ++a)
      for (int b = 0; b < s.model.n_phases; ++b) elastic[a] = elastic[a] || !(s.model.pair(a, b).sinter_delta_b > 0);
    for (std::size_t i = 0; i < s.p.size(); ++i) {
      const int ph = s.p.phase[i];
      if (ph >= int(s.model.materials.size()) || !elastic[ph]) continue;
      const Material& mat = s.model.materials[ph];
      const double nu = mat.poisson_ratio;
      const double G = mat.youngs_modulus / (2 * (1 + nu));
      const double rho = s.p.m[i] / (4.0 / 3.0 * M_PI * std::pow(s.p.r[i], 3));
      if (G > 0) best = std::min(best, M_PI * s.p.r[i] * std::sqrt(rho / G) / (0.1631 * nu + 0.8766));
    }
  }
  // Bonds: the two-particle limit of the normal spring, and of the rotation about the centres
  // under the bending spring plus the shear spring's lever (k_bend + 2 k_t R²).
  for (std::size_t b = 0; b < s.bonds.size(); ++b) {
    const int i = s.bonds.i[b], j = s.bonds.j[b];
    const BondLaw& law = s.bond_laws[s.p.phase[i] * s.model.n_phases + s.p.phase[j]];
    const BondStiffness k = bond_stiffness(law, s.bonds.radius[b], s.p.r[i], s.p.r[j]);
    const double ms = s.p.m[i] * s.p.m[j] / (s.p.m[i] + s.p.m[j]);
    const double Ii = s.p.inertia(i), Ij = s.p.inertia(j), is = Ii * Ij / (Ii + Ij);
    const double rmax = std::max(s.p.r[i], s.p.r[j]);
    const double z = law.damping_ratio, damp = std::sqrt(1 + z * z) - z;
    best = std::min(best, 2 * damp * std::sqrt(ms / k.kn));
    best = std::min(best, 2 * damp * std::sqrt(is / (k.kbend + 2 * k.kt * rmax * rmax)));
    best = std::min(best, 2 * damp * std::sqrt(is / k.ktwist));
  }
  return best;
}

const std::vector<double>& Simulation::stiffness_sums() const { return impl_->stiffness; }
void Simulation::set_time_step(double dt, bool check_limit) {
  if (!(dt > 0) || !std::isfinite(dt))
    throw InputError("", "timestep", std::to_string(dt), "the time step must be a positive number");
  const double crit = check_limit ? critical_time_step() : dt;
  if (dt > crit) {
    std::ostringstream s;
    s << "above the stable limit " << crit << " s ("
      << (law_info(impl_->model.normal).stiffness_kind == StiffnessKind::spring ? "two-particle Verlet limit"
                                                                                 : "Rayleigh time")
      << "); use 'auto' or a smaller value";
    throw InputError("", "timestep", std::to_string(dt), s.str());
  }
  // Forces stay valid: recomputing them would apply the incremental springs twice.
  impl_->dt = dt;
}
double Simulation::time_step() const { return impl_->dt; }
double Simulation::time() const { return impl_->t; }
long Simulation::step_count() const { return impl_->nstep; }
void Simulation::step() { impl_->step(); }
void Simulation::run(long steps) {
  for (long k = 0; k < steps; ++k) impl_->step();
}
Measurements Simulation::measure() { return impl_->measure_now(); }
void Simulation::invalidate_neighbors() {
  impl_->need_build = true;
  impl_->forces_valid = false;
}

std::string Simulation::describe() const {
  const Impl& s = *impl_;
  std::ostringstream o;
  o << "laws " << s.model.describe() << (s.kern.vectorised ? " (vectorised loop)" : "") << "; allocated:";
  o << (s.p.has_rotation() ? " rotation" : "");
  o << (s.kern.normal_history ? " normal-history" : "");
  o << (s.kern.tangential_history ? " tangential-history" : "");
  o << (s.kern.rolling_history ? " rolling-history" : "");
  o << (s.kern.touch_flag ? " contact-flags" : "");
  o << (s.walls.empty() ? "" : " walls");
  o << (s.control.active() ? " deforming-cell" : "");
  o << (s.set.track_energy ? " energy-tally" : "");
  o << (s.bonds.size() ? " bonds" : "");
  if (!s.p.has_rotation() && !s.kern.tangential_history && s.walls.empty()) o << " (positions and forces only)";
  return o.str();
}

ContactTable Simulation::contacts() {
  Impl& s = *impl_;
  std::vector<Vec3> force;
  s.measure_now(&force);  // per-pair forces of the current state (trajectory unchanged)
  ContactTable ct;
  for (std::size_t i = 0; i < s.p.size(); ++i)
    for (int k = s.start[i]; k < s.start[i + 1]; ++k) {
      const int j = s.nj[k];
      const Vec3 d = s.p.x[j] + s.shift[s.img[k]] - s.p.x[i];
      const double delta = s.p.r[i] + s.p.r[j] - norm(d);
      const bool touching = s.kern.touch_flag ? s.touch[k] != 0 : delta > 0;
      if (!touching) continue;
      ct.i.push_back(int32_t(i));
      ct.j.push_back(j);
      ct.overlap.push_back(delta);
      const Vec3 n = (1.0 / norm(d)) * d;
      const Vec3 fn = dot(force[k], n) * n;
      ct.normal_force.push_back(fn);
      ct.tangential_force.push_back(force[k] - fn);
    }
  return ct;
}

Simulation::EngineState Simulation::engine_state() const {
  const Impl& s = *impl_;
  EngineState e;
  e.start = s.start;
  e.j = s.nj;
  e.image = s.img;
  e.touching = s.touch;
  e.history = s.hist;
  e.x_at_build = s.x_build;
  e.h_at_build = s.h_build;
  for (const auto& wd : s.wall_data) {
    e.wall_candidates.push_back(wd.candidates);
    e.wall_history.push_back(wd.hist);
    e.wall_touching.push_back(wd.touch);
  }
  e.wall_point_at_build = s.wall_point_build;
  e.force = s.p.f;
  e.torque = s.p.torque;
  e.forces_valid = s.forces_valid && !s.need_build;
  e.dt = s.dt;
  e.time = s.t;
  e.step = s.nstep;
  e.builds = s.builds;
  e.dissipated = s.dissipated;
  e.external_work = s.ext_work;
  e.initial_energy = s.e0;
  e.bonds = s.bonds;
  e.bond_events = s.bond_events;
  return e;
}

void Simulation::restore(const EngineState& e) {
  Impl& s = *impl_;
  const std::size_t n = s.p.size();
  // Every array is checked against the scene before anything is replaced: a damaged checkpoint,
  // or one of another scene, must never index out of bounds. The field names the dataset of the
  // checkpoint file (the caller adds the file).
  const std::string mismatch = " (the checkpoint does not match the scene: particle count, laws or walls differ, or it is damaged)";
  const auto size_is = [&](const std::string& ds, std::size_t got, std::size_t want) {
    if (got != want)
      throw InputError("", ds, std::to_string(got) + " values", "expected " + std::to_string(want) + mismatch);
  };
  size_is("/engine/start", e.start.size(), n + 1);
  if (e.start[0] != 0 || std::size_t(e.start[n]) != e.j.size())
    throw InputError("", "/engine/start", std::to_string(e.start[0]) + " .. " + std::to_string(e.start[n]),
                     "must run from 0 to the length of /engine/j (" + std::to_string(e.j.size()) + ")" + mismatch);
  for (std::size_t i = 0; i < n; ++i)
    if (e.start[i] > e.start[i + 1])
      throw InputError("", "/engine/start[" + std::to_string(i) + "]", std::to_string(e.start[i]), "must not decrease" + mismatch);
  for (std::size_t k = 0; k < e.j.size(); ++k)
    if (e.j[k] < 0 || std::size_t(e.j[k]) >= n)
      throw InputError("", "/engine/j[" + std::to_string(k) + "]", std::to_string(e.j[k]),
                       "not a particle index in [0, " + std::to_string(n) + ")" + mismatch);
  size_is("/engine/image", e.image.size(), e.j.size());
  for (std::size_t k = 0; k < e.image.size(); ++k)
    if (e.image[k] >= 27) throw InputError("", "/engine/image[" + std::to_string(k) + "]", std::to_string(e.image[k]), "must be below 27" + mismatch);
  size_is("/engine/touching", e.touching.size(), s.kern.touch_flag ? e.j.size() : 0);
  size_is("/engine/history", e.history.size(), e.j.size() * std::size_t(s.stride));
  size_is("/engine/x_at_build", e.x_at_build.size(), n);
  size_is("/engine/force", e.force.size(), n);
  if (s.p.has_rotation()) size_is("/engine/torque", e.torque.size(), n);
  size_is("/walls/point", e.wall_candidates.size(), s.walls.size());
  size_is("/engine/wall_point_at_build", e.wall_point_at_build.size(), s.walls.size());
  for (std::size_t w = 0; w < s.walls.size(); ++w) {
    const std::string g = "/engine/wall" + std::to_string(w);
    for (int32_t i : e.wall_candidates[w])
      if (i < 0 || std::size_t(i) >= n) throw InputError("", g + "/candidates", std::to_string(i), "not a particle index" + mismatch);
    size_is(g + "/history", e.wall_history[w].size(), n * std::size_t(s.stride));
    size_is(g + "/touching", e.wall_touching[w].size(), s.kern.touch_flag ? n : 0);
  }
  if (!(std::isfinite(e.dt) && e.dt > 0)) throw InputError("", "/engine/scalars[1]", std::to_string(e.dt), "the time step must be positive" + mismatch);
  if (!std::isfinite(e.time) || e.step < 0) throw InputError("", "/engine/scalars", std::to_string(e.step), "time and step must be finite and >= 0" + mismatch);
  size_is("/bonds/i", e.bonds.size(), s.bonds.size());
  {
    const BondSet& B = e.bonds;
    const std::size_t nb = B.size();
    size_is("/bonds/image", B.image.size(), nb);
    size_is("/bonds/state", B.state.size(), nb);
    size_is("/bonds/mode", B.mode.size(), nb);
    size_is("/bonds/broken_at", B.broken_at.size(), nb);
    size_is("/bonds/shear_force", B.shear_force.size(), nb);
    size_is("/bonds/twist", B.twist.size(), nb);
    size_is("/bonds/bend", B.bend.size(), nb);
    for (const auto& ev : e.bond_events)
      if (ev.bond < 0 || std::size_t(ev.bond) >= nb)
        throw InputError("", "/bonds/events/bond", std::to_string(ev.bond), "not a bond index" + mismatch);
  }
  s.start = e.start;
  s.nj = e.j;
  s.img = e.image;
  s.touch = e.touching;
  s.hist = e.history;
  s.x_build = e.x_at_build;
  s.h_build = e.h_at_build;
  s.wall_data.resize(s.walls.size());
  for (std::size_t w = 0; w < s.walls.size(); ++w) {
    s.wall_data[w].candidates = e.wall_candidates[w];
    s.wall_data[w].hist = e.wall_history[w];
    s.wall_data[w].touch = e.wall_touching[w];
  }
  s.wall_point_build = e.wall_point_at_build;
  s.p.f = e.force;
  if (s.p.has_rotation()) s.p.torque = e.torque;
  s.forces_valid = e.forces_valid;
  s.need_build = false;
  s.dt = e.dt;
  s.t = e.time;
  s.nstep = e.step;
  s.builds = e.builds;
  s.dissipated = e.dissipated;
  s.ext_work = e.external_work;
  s.e0 = e.initial_energy;
  s.bonds = e.bonds;
  s.bond_events = e.bond_events;
  s.partition_threads();
  s.fill_owner();
}

void Simulation::set_bonds(BondSet bonds, std::vector<BondLaw> laws, BondFailure failure) {
  Impl& s = *impl_;
  const std::size_t np = std::size_t(s.model.n_phases) * s.model.n_phases;
  if (laws.size() == 1 && np > 1) laws.assign(np, laws[0]);
  if (laws.size() != np)
    throw InputError("", "bonds", std::to_string(laws.size()), "one bond law per phase pair is needed");
  for (std::size_t b = 0; b < bonds.size(); ++b)
    if (bonds.i[b] < 0 || bonds.j[b] >= int32_t(s.p.size()) || bonds.i[b] >= bonds.j[b] || !(bonds.radius[b] > 0))
      throw InputError("", "bonds[" + std::to_string(b) + "]", "", "needs 0 <= i < j < N and a positive radius");
  s.bonds = std::move(bonds);
  s.bond_laws = std::move(laws);
  s.bond_failure = failure;
  s.bond_kernel[0] = select_bond_kernel(failure, false);
  s.bond_kernel[1] = select_bond_kernel(failure, true);
  s.p.enable_rotation();  // bonds carry moments
  s.need_build = true;
  s.forces_valid = false;
}
const BondSet& Simulation::bonds() const { return impl_->bonds; }
const std::vector<BondLaw>& Simulation::bond_laws() const { return impl_->bond_laws; }
void Simulation::set_bond_laws(std::vector<BondLaw> laws) {
  const std::size_t np = std::size_t(impl_->model.n_phases) * impl_->model.n_phases;
  if (laws.size() == 1 && np > 1) laws.assign(np, laws[0]);
  if (laws.size() != np) throw InputError("", "bonds", std::to_string(laws.size()), "one bond law per phase pair is needed");
  impl_->bond_laws = std::move(laws);
}
const std::vector<BondEvent>& Simulation::bond_events() const { return impl_->bond_events; }

}  // namespace tomodem::dem
