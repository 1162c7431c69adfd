// Laguerre (radical) tessellation with CGAL's regular triangulation (the only file that
// includes CGAL). The power cell of a sphere is the dual of its vertex: each incident edge
// (v, w) is dual to the face of points of equal power to both spheres, a polygon whose corners
// are the weighted circumcentres (power centres) of the tetrahedra around the edge.
#include "tomodem/geometry/laguerre.hpp"

#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Regular_triangulation_3.h>
#include <CGAL/Regular_triangulation_cell_base_3.h>
#include <CGAL/Regular_triangulation_vertex_base_3.h>
#include <CGAL/Triangulation_cell_base_with_info_3.h>
#include <CGAL/Triangulation_vertex_base_with_info_3.h>

#include <cmath>
#include <sstream>

#include "tomodem/core/error.hpp"
#include "tomodem/spatial/image.hpp"

namespace tomodem::geometry {

namespace {
using K = CGAL::Exact_predicates_inexact_constructions_kernel;
using Vb = CGAL::Triangulation_vertex_base_with_info_3<int, K, CGAL::Regular_triangulation_vertex_base_3<K>>;
using Cb = CGAL::Triangulation_cell_base_with_info_3<int, K, CGAL::Regular_triangulation_cell_base_3<K>>;
using Tds = CGAL::Triangulation_data_structure_3<Vb, Cb>;
using RT = CGAL::Regular_triangulation_3<K, Tds>;
using WP = K::Weighted_point_3;
using P = K::Point_3;

constexpr double kPi = 3.14159265358979323846;

Vec3 to_vec(const P& p) { return {CGAL::to_double(p.x()), CGAL::to_double(p.y()), CGAL::to_double(p.z())}; }

/// One attempt with images within `margin` of the faces; false when an original cell is open
/// (touches the convex hull) or the volumes do not add up.
/// Vertex info: particle index × 27 + image code (the original sphere has kCentreImage). With
/// `faces`, every face of an original cell is appended there; open cell directions (no images)
/// then leave faces on the hull open instead of failing the attempt.
bool attempt(const std::vector<Vec3>& xw, const std::vector<double>& r, const Cell& cell, double margin,
             Tessellation& out, std::vector<LaguerreFace>* faces = nullptr) {
  const bool closed = cell.periodic[0] && cell.periodic[1] && cell.periodic[2];
  const std::size_t n = r.size();
  const Mat3 hinv = cell.h.inverse();
  const double vol = cell.volume();
  double mk[3];
  for (int k = 0; k < 3; ++k) {
    const Vec3 a = cell.h.col((k + 1) % 3), b = cell.h.col((k + 2) % 3);
    // The margin in fractional units along k; at most one cell length, where every image of the
    // 27 is in (a small box of few particles needs them all, and no more exist).
    mk[k] = std::min(1.0, margin / (vol / norm(cross(a, b))));
  }
  std::vector<std::pair<WP, int>> pts;
  pts.reserve(n * 2);
  for (std::size_t i = 0; i < n; ++i) {
    const Vec3 s = hinv * (xw[i] - cell.origin);
    for (int c = 0; c < spatial::kImageCodes; ++c) {
      const Vec3 nv = spatial::image_vector(c);
      bool keep = true;
      for (int k = 0; k < 3 && keep; ++k) {
        const double t = s[k] + nv[k];
        keep = cell.periodic[k] ? t >= -mk[k] && t <= 1 + mk[k] : nv[k] == 0;
      }
      if (!keep) continue;
      const Vec3 p = xw[i] + cell.h * nv;
      pts.emplace_back(WP(P(p.x, p.y, p.z), r[i] * r[i]), int(i) * spatial::kImageCodes + c);
    }
  }
  RT rt;
  rt.insert(pts.begin(), pts.end());
  // Power centres of all finite cells.
  std::vector<Vec3> centre;
  centre.reserve(rt.number_of_finite_cells());
  const auto wcc = rt.geom_traits().construct_weighted_circumcenter_3_object();
  for (auto c = rt.finite_cells_begin(); c != rt.finite_cells_end(); ++c) {
    c->info() = int(centre.size());
    centre.push_back(to_vec(wcc(c->vertex(0)->point(), c->vertex(1)->point(), c->vertex(2)->point(), c->vertex(3)->point())));
  }
  out.cell_volume.assign(n, 0.0);
  std::vector<RT::Edge> edges;
  std::vector<Vec3> ring;
  for (auto vit = rt.finite_vertices_begin(); vit != rt.finite_vertices_end(); ++vit) {
    const RT::Vertex_handle v = vit;
    if (v->info() % spatial::kImageCodes != spatial::kCentreImage) continue;  // an image
    const int i = v->info() / spatial::kImageCodes;
    edges.clear();
    rt.incident_edges(v, std::back_inserter(edges));
    const Vec3 xv = to_vec(v->point().point());
    double V = 0;
    for (const auto& e : edges) {
      const auto a = e.first->vertex(e.second), b = e.first->vertex(e.third);
      const auto w = a == v ? b : a;
      if (rt.is_infinite(w)) {
        if (closed) return false;  // open cell: the margin is too small
        continue;                  // open direction: the hull, not a neighbour
      }
      ring.clear();
      bool open = false;
      auto cc = rt.incident_cells(e), done = cc;
      do {
        if (rt.is_infinite(cc)) {
          if (closed) return false;
          open = true;
        } else {
          ring.push_back(centre[std::size_t(cc->info())]);
        }
      } while (++cc != done);
      const Vec3 d = to_vec(w->point().point()) - xv;
      const Vec3 ehat = d * (1 / norm(d));
      Vec3 A;
      for (std::size_t k = 1; k + 1 < ring.size(); ++k) A += 0.5 * cross(ring[k] - ring[0], ring[k + 1] - ring[0]);
      const double area = open ? HUGE_VAL : std::abs(dot(A, ehat));
      if (faces) faces->push_back({i, w->info() / spatial::kImageCodes, d, area});
      // Pyramid on the face with apex at the centre of i: (1/3) area × signed height.
      if (!open) V += area * dot(ring[0] - xv, ehat) / 3;
    }
    out.cell_volume[std::size_t(i)] = V;
  }
  out.total_volume = 0;
  for (double V : out.cell_volume) out.total_volume += V;
  out.box_volume = vol;
  out.margin = margin;
  return !closed || std::abs(out.total_volume - vol) <= 1e-10 * vol;
}

/// Centres wrapped into the cell along its periodic directions; the largest radius.
std::vector<Vec3> wrapped(const std::vector<Vec3>& x, const std::vector<double>& r, const Cell& cell, double& rmax) {
  const Mat3 hinv = cell.h.inverse();
  std::vector<Vec3> xw(x.size());
  rmax = 0;
  for (std::size_t i = 0; i < x.size(); ++i) {
    Vec3 s = hinv * (x[i] - cell.origin);
    for (int k = 0; k < 3; ++k)
      if (cell.periodic[k]) s[k] -= std::floor(s[k]);
    xw[i] = cell.origin + cell.h * s;
    rmax = std::max(rmax, r[i]);
  }
  return xw;
}
}  // namespace

std::vector<LaguerreFace> laguerre_faces(const std::vector<Vec3>& x, const std::vector<double>& r, const Cell& cell) {
  std::vector<LaguerreFace> faces;
  const std::size_t n = r.size();
  if (n == 0) return faces;
  double rmax = 0;
  const std::vector<Vec3> xw = wrapped(x, r, cell, rmax);
  Tessellation t;
  double margin = 4 * rmax + 2 * std::cbrt(cell.volume() / double(n));
  for (int tries = 0; tries < 8; ++tries, margin *= 1.5) {
    faces.clear();
    if (attempt(xw, r, cell, margin, t, &faces)) return faces;
  }
  std::ostringstream s;
  s << "Laguerre faces: the power cells do not close (volumes " << t.total_volume << " vs " << t.box_volume
    << " m^3) even with images " << margin << " m beyond the faces";
  throw RuntimeFailure(s.str());
}

Tessellation laguerre(const std::vector<Vec3>& x, const std::vector<double>& r, const Cell& cell) {
  if (!(cell.periodic[0] && cell.periodic[1] && cell.periodic[2]))
    throw InputError("", "cell.periodic", "", "the Laguerre tessellation needs a cell periodic in x, y and z");
  Tessellation t;
  const std::size_t n = r.size();
  if (n == 0) return t;
  // Wrap the centres into the cell.
  const Mat3 hinv = cell.h.inverse();
  std::vector<Vec3> xw(n);
  double rmax = 0;
  for (std::size_t i = 0; i < n; ++i) {
    Vec3 s = hinv * (x[i] - cell.origin);
    for (int k = 0; k < 3; ++k) s[k] -= std::floor(s[k]);
    xw[i] = cell.origin + cell.h * s;
    rmax = std::max(rmax, r[i]);
  }
  // Start with two largest diameters plus two mean spacings; grow until every cell closes.
  double margin = 4 * rmax + 2 * std::cbrt(cell.volume() / double(n));
  for (int tries = 0; tries < 8; ++tries, margin *= 1.5)
    if (attempt(xw, r, cell, margin, t)) {
      t.local_solid_fraction.resize(n);
      for (std::size_t i = 0; i < n; ++i)
        t.local_solid_fraction[i] = t.cell_volume[i] > 0 ? 4 * kPi / 3 * r[i] * r[i] * r[i] / t.cell_volume[i] : 0;
      return t;
    }
  std::ostringstream s;
  s << "Laguerre tessellation: cell volumes do not add up to the box volume (" << t.total_volume << " vs "
    << t.box_volume << " m^3) even with images " << margin << " m beyond the faces";
  throw RuntimeFailure(s.str());
}

}  // namespace tomodem::geometry
