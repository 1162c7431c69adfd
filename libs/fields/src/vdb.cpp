// VDB output of a full fields grid (docs/cg.md#vdb-output). OpenVDB stays in this file.
#include <cmath>
#include <string>
#include <utility>
#include <vector>

#include "common.hpp"
#include "tomodem/core/error.hpp"
#include "tomodem/core/output.hpp"
#include "tomodem/core/packing_io.hpp"

#ifdef TOMODEM_HAVE_OPENVDB
#include <openvdb/openvdb.h>
#endif

namespace tomodem::fields::detail {

#ifdef TOMODEM_HAVE_OPENVDB

bool have_vdb() { return true; }

namespace {
/// von Mises stress of the symmetric part of σ (9 values, row-major).
double von_mises(const double* s) {
  double S[3][3];
  for (int a = 0; a < 3; ++a)
    for (int b = 0; b < 3; ++b) S[a][b] = 0.5 * (s[3 * a + b] + s[3 * b + a]);
  const double p = (S[0][0] + S[1][1] + S[2][2]) / 3;
  double j2 = 0;
  for (int a = 0; a < 3; ++a)
    for (int b = 0; b < 3; ++b) {
      const double d = S[a][b] - (a == b ? p : 0);
      j2 += d * d;
    }
  return std::sqrt(1.5 * j2);
}

/// Index (i0, i1, i2) → position in metres: node (I + ½)/n of the cell vectors (row-vector
/// convention of OpenVDB: world = [i j k 1] · M).
openvdb::math::Transform::Ptr node_transform(const Cell& cell, const std::array<int, 3>& n) {
  Vec3 g0 = cell.origin;
  Vec3 step[3];
  for (int a = 0; a < 3; ++a) {
    step[a] = (1.0 / n[a]) * cell.h.col(a);
    g0 += 0.5 * step[a];
  }
  openvdb::math::Mat4d M(step[0].x, step[0].y, step[0].z, 0.0,  //
                         step[1].x, step[1].y, step[1].z, 0.0,  //
                         step[2].x, step[2].y, step[2].z, 0.0,  //
                         g0.x, g0.y, g0.z, 1.0);
  return openvdb::math::Transform::createLinearTransform(M);
}

template <class GridT>
typename GridT::Ptr make_grid(const std::string& name, const std::string& unit, const openvdb::math::Transform::Ptr& t) {
  typename GridT::Ptr g = GridT::create(typename GridT::ValueType(0));
  g->setName(name);
  g->setTransform(t->copy());
  g->insertMeta("unit", openvdb::StringMetadata(unit));
  g->insertMeta("length_unit", openvdb::StringMetadata("m"));
  g->insertMeta("index_order", openvdb::StringMetadata("(i0, i1, i2) along cell vectors 0, 1, 2; row i0*n1*n2 + i1*n2 + i2 of the .h5"));
  return g;
}
}  // namespace

void write_vdb(const std::string& path, const Accumulator::Fields& f, const Cell& cell,
               const std::vector<std::pair<std::string, std::string>>& attributes) {
  openvdb::initialize();
  const auto t = node_transform(cell, f.dims);
  const std::size_t N = f.points.size();
  const int n1 = f.dims[1], n2 = f.dims[2];
  auto coord = [&](std::size_t k) { return openvdb::Coord(int(k / (std::size_t(n1) * n2)), int((k / n2) % n1), int(k % n2)); };
  openvdb::GridPtrVec grids;
  auto scalar = [&](const std::string& name, const std::string& unit, auto value) {
    auto g = make_grid<openvdb::DoubleGrid>(name, unit, t);
    auto acc = g->getAccessor();
    for (std::size_t k = 0; k < N; ++k) acc.setValue(coord(k), value(k));
    grids.push_back(g);
  };
  auto vector = [&](const std::string& name, const std::string& unit, const std::vector<Vec3>& v) {
    if (v.empty()) return;
    auto g = make_grid<openvdb::Vec3DGrid>(name, unit, t);
    g->setVectorType(openvdb::VEC_INVARIANT);  // world-space vectors, not to be transformed
    g->setIsInWorldSpace(true);
    auto acc = g->getAccessor();
    for (std::size_t k = 0; k < N; ++k) acc.setValue(coord(k), openvdb::Vec3d(v[k].x, v[k].y, v[k].z));
    grids.push_back(g);
  };
  scalar("density", "kg/m^3", [&](std::size_t k) { return f.density[k]; });
  scalar("pressure", "Pa", [&](std::size_t k) {
    const double* s = &f.stress[9 * k];
    return -(s[0] + s[4] + s[8]) / 3;
  });
  scalar("von_mises", "Pa", [&](std::size_t k) { return von_mises(&f.stress[9 * k]); });
  scalar("speed", "m/s", [&](std::size_t k) { return norm(f.velocity[k]); });
  vector("velocity", "m/s", f.velocity);
  vector("momentum", "kg/(m^2 s)", f.momentum);
  vector("divergence_static_stress", "N/m^3", f.divergence);
  vector("displacement", "m", f.displacement);
  openvdb::MetaMap meta;
  for (const auto& [k, v] : attributes) meta.insertMeta(k, openvdb::StringMetadata(v));
  meta.insertMeta("length_unit", openvdb::StringMetadata("m"));
  const std::string tmp = temporary_path(path);
  try {
    openvdb::io::File file(tmp);
    file.write(grids, meta);
    file.close();
  } catch (const std::exception& e) {
    discard_output(path);
    throw RuntimeFailure("cannot write " + path + ": " + e.what());
  }
  commit_output(path);
}

#else

bool have_vdb() { return false; }

void write_vdb(const std::string& path, const Accumulator::Fields&, const Cell&,
               const std::vector<std::pair<std::string, std::string>>&) {
  throw RuntimeFailure("cannot write " + path + ": this build has no OpenVDB");
}

#endif

}  // namespace tomodem::fields::detail
