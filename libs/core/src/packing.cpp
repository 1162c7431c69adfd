#include "tomodem/core/packing.hpp"

namespace tomodem {

void ParticleTable::resize(std::size_t n) {
  position.resize(n);
  radius.resize(n);
  phase.resize(n, 0);
}

Cell Cell::box(const Vec3& lo, const Vec3& hi, bool periodic_all) {
  Cell c;
  c.origin = lo;
  c.h = Mat3::diagonal(hi - lo);
  c.periodic[0] = c.periodic[1] = c.periodic[2] = periodic_all;
  return c;
}

namespace {
template <class T>
void push_row(std::vector<T>& out, const std::vector<T>& in, std::size_t k) {
  if (k < in.size()) out.push_back(in[k]);
}
/// Rows (i, j) of a pair table whose particles are both kept, with i and j renumbered.
template <class Table, class Copy>
void select_pairs(const Table& in, Table& out, const std::vector<int32_t>& index, Copy copy) {
  for (std::size_t k = 0; k < in.size(); ++k) {
    const int32_t a = index[std::size_t(in.i[k])], b = index[std::size_t(in.j[k])];
    if (a < 0 || b < 0) continue;
    out.i.push_back(a);
    out.j.push_back(b);
    copy(k);
  }
}
}  // namespace

Packing select_particles(const Packing& p, const std::vector<uint8_t>& keep) {
  const std::size_t n = p.particles.size();
  std::vector<int32_t> index(n, -1);
  Packing out;
  out.cell = p.cell;
  out.materials = p.materials;
  out.provenance = p.provenance;
  out.results.scalars = p.results.scalars;
  out.results.units = p.results.units;
  const ParticleTable& P = p.particles;
  ParticleTable& Q = out.particles;
  for (std::size_t i = 0; i < n; ++i) {
    if (!keep[i]) continue;
    index[i] = int32_t(Q.radius.size());
    Q.position.push_back(P.position[i]);
    Q.radius.push_back(P.radius[i]);
    Q.phase.push_back(P.phase[i]);
    if (P.velocity.size() == n) Q.velocity.push_back(P.velocity[i]);
    if (P.angular_velocity.size() == n) Q.angular_velocity.push_back(P.angular_velocity[i]);
  }
  const ContactTable& C = p.contacts;
  ContactTable& D = out.contacts;
  select_pairs(C, D, index, [&](std::size_t k) {
    push_row(D.overlap, C.overlap, k);
    push_row(D.normal_force, C.normal_force, k);
    push_row(D.tangential_force, C.tangential_force, k);
  });
  const BondTable& B = p.bonds;
  BondTable& E = out.bonds;
  select_pairs(B, E, index, [&](std::size_t k) {
    push_row(E.radius, B.radius, k);
    push_row(E.rest_length, B.rest_length, k);
    push_row(E.state, B.state, k);
    push_row(E.broken_at, B.broken_at, k);
  });
  for (const auto& [name, columns] : p.results.series) {
    bool per_particle = !columns.empty();
    for (const auto& [c, v] : columns) per_particle = per_particle && v.size() == n;
    for (const auto& [c, v] : columns) {
      auto& w = out.results.series[name][c];
      if (!per_particle) {
        w = v;
        continue;
      }
      for (std::size_t i = 0; i < n; ++i)
        if (keep[i]) w.push_back(v[i]);
    }
  }
  return out;
}

}  // namespace tomodem
