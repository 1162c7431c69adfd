#include "force_loop.hpp"

#include <omp.h>

#include <cmath>

#include "boundary.hpp"

namespace tomodem::dem {

ForceJob ForceLoop::job(const SimState& s, NeighbourList& nl) {
  const Particles& p = s.p;
  ForceJob jb;
  jb.x = p.x.data();
  if (s.deforming()) {
    absolute_velocities(s, u);
    jb.u = u.data();
  } else {
    jb.u = p.v.data();
  }
  jb.omega = p.has_rotation() ? p.omega.data() : nullptr;
  jb.r = p.r.data();
  jb.m = p.m.data();
  jb.phase = p.phase.data();
  jb.start = nl.start.data();
  jb.owner = nl.owner.data();
  jb.j = nl.nj.data();
  jb.img = nl.img.data();
  jb.hist = nl.hist.data();
  jb.touch = nl.touch.empty() ? nullptr : nl.touch.data();
  jb.hist_stride = s.stride;
  jb.shift = nl.shift;
  jb.vshift = nl.vshift;
  jb.pairs = s.model.pairs.data();
  jb.n_phases = s.model.n_phases;
  jb.dt = s.dt;
  if (s.kern.vectorised) {  // filled with the forces' zeroing in compute()
    sphere.resize(p.size());
    for (int c = 0; c < 27; ++c) shift4[c] = PackedSphere{nl.shift[c].x, nl.shift[c].y, nl.shift[c].z, 0};
    jb.sphere = sphere.data();
    jb.shift4 = shift4;
  }
  return jb;
}

// The helper threads' buffers stay zero between calls (the reduction in compute() clears what
// it reads), so each is touched twice a step instead of three times.
void ForceLoop::prepare_buffers(int threads, std::size_t n, bool rot, bool tally) {
  if (int(fbuf.size()) < threads) {
    fbuf.resize(threads);
    tbuf.resize(threads);
    sbuf.resize(threads);
  }
  for (int q = 1; q < threads; ++q) {
    if (fbuf[q].size() != n) fbuf[q].assign(n, Vec3{});
    if (rot && tbuf[q].size() != n) tbuf[q].assign(n, Vec3{});
    if (tally && sbuf[q].size() != n) sbuf[q].assign(n, 0.0);
  }
}

void ForceLoop::compute(SimState& s, NeighbourList& nl, bool tally, Vec3* pair_force) {
  Particles& p = s.p;
  const int threads = s.threads;
  const std::vector<int>& split = nl.split;
  const std::size_t n = p.size();
  const bool rot = p.has_rotation();
  ForceJob jb = job(s, nl);
  jb.pair_force = pair_force;
  BondJob bj{};
  const bool have_bonds = !s.bonds.i.empty();
  if (have_bonds) {
    bj = BondJob{p.x.data(), jb.u, p.omega.data(), p.r.data(), p.m.data(), p.phase.data(), &s.bonds,
                 s.bond_laws.data(), s.model.n_phases, s.cell.h, s.control.velocity_gradient * s.cell.h, s.dt, s.t};
    event_buf.assign(threads, {});
  }
  std::vector<Tally> tallies(threads);
  if (tally) stiffness.resize(n);
  prepare_buffers(threads, n, rot, tally);
  const long reduce_from = (have_bonds || threads == 1) ? 0 : split[1];
  PackedSphere* packed = jb.sphere ? sphere.data() : nullptr;  // job() sized it for the four-wide loops
  const bool banded = s.set.pair_bands && bands.prepare(s, nl, packed != nullptr, tally);
  pair_tests += banded ? bands.tested() : long(nl.nj.size());
#pragma omp parallel num_threads(threads) if (threads > 1)
  {
    const int tid = omp_get_thread_num();
#pragma omp for schedule(static)
    for (long i = 0; i < long(n); ++i) {
      p.f[i] = Vec3{};
      if (rot) p.torque[i] = Vec3{};
      if (tally) stiffness[i] = 0;
      if (packed) packed[i] = PackedSphere{p.x[i].x, p.x[i].y, p.x[i].z, p.r[i]};
    }
    Vec3* f = tid > 0 ? fbuf[tid].data() : p.f.data();
    Vec3* tq = rot ? (tid > 0 ? tbuf[tid].data() : p.torque.data()) : nullptr;
    double* st = tally ? (tid > 0 ? sbuf[tid].data() : stiffness.data()) : nullptr;
#if TOMODEM_HAVE_MPI
    if (s.domain && tally) {
      // Newton off: a pair of an owned particle and a ghost is computed on both ranks, but its
      // tally (virial, energies, contacts) counts only where its row's particle is owned.
      const uint8_t* ghost = s.domain->ghost.data();
      Tally elsewhere;
      for (int a = split[tid], b; a < split[tid + 1]; a = b) {
        for (b = a + 1; b < split[tid + 1] && ghost[b] == ghost[a];) ++b;
        s.kern.pair[1](jb, a, b, f, tq, ghost[a] ? &elsewhere : &tallies[tid], st);
      }
    } else
#endif
    if (banded) {
      s.kern.pair[0](bands.job(jb, tid), split[tid], split[tid + 1], f, tq, &tallies[tid], st);
      bands.forget_apart(nl, tid, s.stride);
    } else {
      s.kern.pair[tally](jb, split[tid], split[tid + 1], f, tq, &tallies[tid], st);
    }
    if (have_bonds) {
#if TOMODEM_HAVE_MPI
      if (s.domain) {
        // As for pairs: a bond with a ghost is computed on both ranks (the same failure on both);
        // its tally and its failure event count where its first particle is owned.
        const uint8_t* ghost = s.domain->ghost.data();
        const std::size_t e = nl.bond_split[tid + 1];
        Tally elsewhere;
        std::vector<BondEvent> told_elsewhere;
        for (std::size_t a = nl.bond_split[tid], b; a < e; a = b) {
          const uint8_t g = ghost[s.bonds.i[a]];
          for (b = a + 1; b < e && ghost[s.bonds.i[b]] == g;) ++b;
          s.bond_kernel[tally](bj, a, b, f, tq, g ? &elsewhere : &tallies[tid], st, g ? &told_elsewhere : &event_buf[tid]);
        }
        for (BondEvent& ev : event_buf[tid]) ev.bond = s.domain->bond_id[std::size_t(ev.bond)];
      } else
#endif
      s.bond_kernel[tally](bj, nl.bond_split[tid], nl.bond_split[tid + 1], f, tq, &tallies[tid], st, &event_buf[tid]);
    }
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
      if (!ev.empty()) s.bond_events.insert(s.bond_events.end(), ev.begin(), ev.end());
  wall_forces(s, nl, jb, tally, total);
  body_forces(s, tally ? &total : nullptr);
  if (tally) last = total;
}

/// Walls (few candidates each): serial, through the same law functions.
void ForceLoop::wall_forces(SimState& s, NeighbourList& nl, const ForceJob& jb, bool tally, Tally& total) {
#if TOMODEM_HAVE_MPI
  // Decomposed: the owned particles' contacts, each wall's force summed over the ranks.
  if (s.domain) return s.domain->walls(s, nl, jb, tally, total, tally ? stiffness.data() : nullptr);
#endif
  Particles& p = s.p;
  for (std::size_t w = 0; w < s.walls.size(); ++w) {
    Wall& wall = s.walls[w];
    WallData& wd = nl.wall_data[w];
    WallJob wj{wall.point, wall.normal, wall.velocity, wall.phase, wd.candidates.data(), int(wd.candidates.size()),
               wd.hist.data(), wd.touch.empty() ? nullptr : wd.touch.data()};
    Tally wt;
    s.kern.wall[tally](jb, wj, p.f.data(), p.has_rotation() ? p.torque.data() : nullptr, &wt,
                       tally ? stiffness.data() : nullptr);
    // The wall force is needed by force-controlled walls every step; recompute it cheaply
    // from the tally pass or, without tally, from the particles' change of force.
    wall.force = wt.wall_force;
    total.add(wt);
  }
}

/// Gravity, Stokes drag and Cundall's local damping; their dissipation into `tally`.
void ForceLoop::body_forces(SimState& s, Tally* tally) const {
  Particles& p = s.p;
  const BodyForces& body = s.body;
  const double dt = s.dt;
  const std::size_t n = p.size();
  const Vec3 g = body.gravity;
  const uint8_t* ghost = nullptr;  // decomposed: a ghost's dissipation is tallied by its owner
#if TOMODEM_HAVE_MPI
  if (s.domain) ghost = s.domain->ghost.data();
#endif
  if (g.x != 0 || g.y != 0 || g.z != 0)
    for (std::size_t i = 0; i < n; ++i) p.f[i] += p.m[i] * g;
  if (body.fluid_viscosity > 0) {
    const double c = 6 * M_PI * body.fluid_viscosity;
    for (std::size_t i = 0; i < n; ++i) {
      p.f[i] -= (c * p.r[i]) * p.v[i];
      if (tally && !(ghost && ghost[i])) tally->dissipated += c * p.r[i] * norm2(p.v[i]) * dt;
    }
  }
  if (body.local_damping > 0) {
    const double lam = body.local_damping;
    for (std::size_t i = 0; i < n; ++i) {
      Tally* const tally_i = (ghost && ghost[i]) ? nullptr : tally;
      Vec3& f = p.f[i];
      const Vec3& v = p.v[i];
      for (int k = 0; k < 3; ++k) {
        const double d = -lam * std::abs(f[k]) * (v[k] > 0 ? 1 : (v[k] < 0 ? -1 : 0));
        if (tally_i) tally_i->dissipated -= d * v[k] * dt;
        f[k] += d;
      }
      if (p.has_rotation()) {
        Vec3& tq = p.torque[i];
        const Vec3& w = p.omega[i];
        for (int k = 0; k < 3; ++k) {
          const double d = -lam * std::abs(tq[k]) * (w[k] > 0 ? 1 : (w[k] < 0 ? -1 : 0));
          if (tally_i) tally_i->dissipated -= d * w[k] * dt;
          tq[k] += d;
        }
      }
    }
  }
}

}  // namespace tomodem::dem
