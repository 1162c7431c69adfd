// Exact union volume of spheres by power-cell clipping (union_volume.hpp). For one sphere of
// radius R at the origin, B ∩ P (P the convex polyhedron of its radical half-spaces, closed by a
// box) is the signed sum over the faces of P of B ∩ cone(origin, face): a ray from the centre
// enters and leaves P through faces whose planes face away from / towards it. On a face plane at
// distance h with foot F, a point at polar radius ρ' about F is reached by a ray of length
// L = sqrt(h² + ρ'²) through the solid angle h ρ' dρ' dθ / L³, and the ball holds min(R, L)³/3
// of that ray's cone. Splitting the face into triangles (F, p, q) and integrating in θ gives
// closed forms (tan for the part inside the disc ρ' < sqrt(R² − h²), arcsin outside).
#include "tomodem/spatial/union_volume.hpp"

#include <algorithm>
#include <cmath>

#include "tomodem/spatial/grid.hpp"
#include "tomodem/spatial/image.hpp"
#include "tomodem/spatial/overlap.hpp"

namespace tomodem::spatial {

namespace {

/// One face of the clipped polyhedron: its corners are verts[begin, begin + size) of the
/// polyhedron that holds it, in cyclic order (either orientation).
struct Face {
  std::size_t begin, size;
  Vec3 n;    ///< unit outward normal
  double h;  ///< n·x on the face (signed distance from the sphere's centre)
};

/// The faces share one vertex array, so a cut appends to buffers that keep their capacity.
struct Polyhedron {
  std::vector<Face> faces;
  std::vector<Vec3> verts;
  void clear() {
    faces.clear();
    verts.clear();
  }
};

/// A corner of a new face and its polar angle in the face plane about the corners' centroid.
struct CapCorner {
  double angle;
  Vec3 p;
};

/// Buffers reused across cuts and calls (clip_sphere runs inside OpenMP loops: one per thread);
/// allocating per face and per cut was about half of clip_sphere's instructions (issue 18).
struct Scratch {
  Polyhedron poly, next;
  std::vector<Vec3> cap;
  std::vector<CapCorner> corners;
  std::vector<double> u, v;
};

Scratch& scratch() {
  thread_local Scratch s;
  return s;
}

Vec3 perpendicular(const Vec3& n) {
  const Vec3 a = std::abs(n.x) < 0.6 ? Vec3{1, 0, 0} : Vec3{0, 1, 0};
  const Vec3 e = cross(n, a);
  return (1 / norm(e)) * e;
}

/// Convex polyhedron ∩ {n·x ≤ h} (Sutherland–Hodgman per face, the new face from the points on
/// the plane), built in `next` and swapped into `poly`. tol: distances below it count as on the
/// plane.
void clip(Polyhedron& poly, Polyhedron& next, std::vector<Vec3>& cap, std::vector<CapCorner>& corners,
          const Vec3& n, double h, double tol) {
  bool any_out = false, any_in = false;
  for (const Vec3& p : poly.verts) {
    const double s = dot(n, p) - h;
    any_out |= s > tol;
    any_in |= s < -tol;
  }
  if (!any_out) return;  // nothing cut away
  if (!any_in) {
    poly.clear();
    return;
  }
  next.clear();
  cap.clear();
  std::vector<Vec3>& out = next.verts;
  for (const Face& f : poly.faces) {
    const Vec3* v = poly.verts.data() + f.begin;
    const std::size_t m = f.size, begin = out.size();
    for (std::size_t k = 0; k < m; ++k) {
      const Vec3& p = v[k];
      const Vec3& q = v[(k + 1) % m];
      const double sp = dot(n, p) - h, sq = dot(n, q) - h;
      if (sp <= tol) out.push_back(p);
      if (std::abs(sp) <= tol) cap.push_back(p);
      if ((sp < -tol && sq > tol) || (sp > tol && sq < -tol)) {
        const Vec3 x = p + (sp / (sp - sq)) * (q - p);
        out.push_back(x);
        cap.push_back(x);
      }
    }
    if (out.size() - begin >= 3)
      next.faces.push_back({begin, out.size() - begin, f.n, f.h});
    else
      out.resize(begin);
  }
  if (cap.size() >= 3) {
    Vec3 c;
    for (const Vec3& p : cap) c += p;
    c *= 1.0 / double(cap.size());
    const Vec3 e1 = perpendicular(n), e2 = cross(n, e1);
    corners.clear();
    // atan2 keys, not a comparison by half-plane and cross product: each corner cut from an edge
    // comes twice (once from each face on the edge, equal to round-off), and the order of such a
    // pair, which decides the copy kept, needs atan2 itself to stay the same (tried: more atan2
    // calls than one per corner).
    for (const Vec3& p : cap) corners.push_back({std::atan2(dot(p - c, e2), dot(p - c, e1)), p});
    std::sort(corners.begin(), corners.end(),
              [](const CapCorner& a, const CapCorner& b) { return a.angle < b.angle; });
    const std::size_t begin = out.size();
    for (const CapCorner& a : corners)
      if (out.size() == begin || norm(a.p - out.back()) > tol) out.push_back(a.p);
    while (out.size() - begin > 1 && norm(out[begin] - out.back()) <= tol) out.pop_back();
    if (out.size() - begin >= 3)
      next.faces.push_back({begin, out.size() - begin, n, h});
    else
      out.resize(begin);
  }
  std::swap(poly, next);
}

double cross2(double ax, double ay, double bx, double by) { return ax * by - ay * bx; }

/// ∫ over the triangle (F, p, q) of the face at distance hh > 0 (p, q in the face's frame about
/// F, counter-clockwise seen from the centre's far side), as a signed θ-integral: the ball's
/// share of the cone (vol) and the area of the triangle inside the disc (area).
void triangle(double px, double py, double qx, double qy, double hh, double R, double& vol, double& area) {
  const double dx = qx - px, dy = qy - py, l2 = dx * dx + dy * dy;
  if (!(l2 > 0)) return;
  const double t = -(px * dx + py * dy) / l2;
  const double ex = px + t * dx, ey = py + t * dy, pe = std::hypot(ex, ey);
  if (pe <= 1e-14 * R) return;  // the edge's line passes through F: a triangle of no area
  const double ux = ex / pe, uy = ey / pe;
  const double fp = std::atan2(cross2(ux, uy, px, py), ux * px + uy * py);
  const double fq = std::atan2(cross2(ux, uy, qx, qy), ux * qx + uy * qy);
  const bool disc = hh < R;
  const double rho2 = disc ? R * R - hh * hh : 0;
  const double C = disc ? hh * rho2 / 6 + R * R * hh / 3 : R * R * R / 3;
  const double k = hh / std::sqrt(hh * hh + pe * pe);
  auto in_v = [&](double f) { return hh / 6 * pe * pe * std::tan(f); };
  auto in_a = [&](double f) { return 0.5 * pe * pe * std::tan(f); };
  auto out_v = [&](double f) { return C * f - R * R * R / 3 * std::asin(k * std::sin(f)); };
  auto out_a = [&](double f) { return 0.5 * rho2 * f; };
  const double a = std::min(fp, fq), b = std::max(fp, fq), sign = fq >= fp ? 1.0 : -1.0;
  double v = 0, A = 0;
  const double fc = disc && pe < std::sqrt(rho2) ? std::acos(pe / std::sqrt(rho2)) : 0;
  if (fc > 0) {
    // |φ| < φ_c: the edge runs inside the disc.
    const double lo = std::max(a, -fc), hi = std::min(b, fc);
    if (hi > lo) v += in_v(hi) - in_v(lo), A += in_a(hi) - in_a(lo);
    if (a < -fc) {
      const double e = std::min(b, -fc);
      v += out_v(e) - out_v(a), A += out_a(e) - out_a(a);
    }
    if (b > fc) {
      const double s = std::max(a, fc);
      v += out_v(b) - out_v(s), A += out_a(b) - out_a(s);
    }
  } else {
    v += out_v(b) - out_v(a), A += out_a(b) - out_a(a);
  }
  vol += sign * v;
  area += sign * A;
}

}  // namespace

HalfSpace radical_plane(const Vec3& d, double ri, double rj) {
  const double D = norm(d);
  return {(1 / D) * d, (D * D + ri * ri - rj * rj) / (2 * D)};
}

ClippedSphere clip_sphere(double R, const std::vector<HalfSpace>& cuts) {
  ClippedSphere out;
  if (!(R > 0)) return out;
  for (const HalfSpace& c : cuts)
    if (c.h <= -R) return out;  // the whole sphere is cut away
  // A box around the ball (its faces outside it), cut by the planes that reach into the ball.
  const double w = 1.5 * R, tol = 1e-12 * R;
  Scratch& S = scratch();
  Polyhedron& poly = S.poly;
  poly.clear();
  for (int axis = 0; axis < 3; ++axis)
    for (int s = -1; s <= 1; s += 2) {
      const int a = (axis + 1) % 3, b = (axis + 2) % 3;
      Vec3 n;
      n[axis] = s;
      poly.faces.push_back({poly.verts.size(), 4, n, w});
      const double ca[4] = {-w, w, w, -w}, cb[4] = {-w, -w, w, w};
      for (int k = 0; k < 4; ++k) {
        Vec3 p;
        p[axis] = s * w;
        p[a] = ca[k];
        p[b] = cb[k];
        poly.verts.push_back(p);
      }
    }
  for (const HalfSpace& c : cuts)
    if (c.h < R) clip(poly, S.next, S.cap, S.corners, c.n, c.h, tol);
  double vol = 0, hA = 0;
  std::vector<double>& u = S.u;
  std::vector<double>& v = S.v;
  for (const Face& f : poly.faces) {
    const double hh = std::abs(f.h);
    if (hh <= 1e-14 * R) continue;  // a plane through the centre: a flat cone
    const Vec3 nn = f.h > 0 ? f.n : -f.n;  // away from the centre
    const Vec3 e1 = perpendicular(nn), e2 = cross(nn, e1), F = hh * nn;
    u.clear();
    v.clear();
    double a2 = 0;
    for (std::size_t k = 0; k < f.size; ++k) {
      const Vec3& p = poly.verts[f.begin + k];
      u.push_back(dot(p - F, e1)), v.push_back(dot(p - F, e2));
    }
    const std::size_t m = u.size();
    for (std::size_t k = 0; k < m; ++k) a2 += cross2(u[k], v[k], u[(k + 1) % m], v[(k + 1) % m]);
    double fv = 0, fa = 0;
    for (std::size_t k = 0; k < m; ++k) {
      const std::size_t p = a2 >= 0 ? k : m - 1 - k, q = a2 >= 0 ? (k + 1) % m : (2 * m - 2 - k) % m;
      triangle(u[p], v[p], u[q], v[q], hh, R, fv, fa);
    }
    vol += (f.h > 0 ? 1 : -1) * fv;
    hA += f.h * fa;
  }
  out.volume = std::max(0.0, vol);
  // Divergence theorem about the centre: V = (R A_sphere + Σ h_f A_f)/3.
  out.sphere_area = std::max(0.0, (3 * out.volume - hA) / R);
  return out;
}

UnionVolume union_volume(const std::vector<Vec3>& x, const std::vector<double>& r, const Cell& cell, int threads) {
  const std::size_t n = r.size();
  UnionVolume u;
  u.share.assign(n, 0.0);
  u.exposed_area.assign(n, 0.0);
  std::vector<std::vector<HalfSpace>> cuts(n);
  double lens = 0;
  for (const Pair& q : pairs_within(x, r, cell, 0, threads)) {
    const std::size_t i = std::size_t(q.i), j = std::size_t(q.j);
    const Vec3 d = x[j] + cell.h * as_vector(q.image) - x[i];
    const double D = norm(d);
    if (D >= r[i] + r[j]) continue;
    lens += lens_volume(r[i], r[j], D);
    if (D <= 1e-12 * (r[i] + r[j])) {
      // Coincident centres: the smaller sphere (or the later of two equal ones) is hidden.
      const bool hide_i = r[j] > r[i] || (r[j] == r[i] && j < i);
      cuts[hide_i ? i : j].push_back({Vec3{1, 0, 0}, -2 * r[hide_i ? i : j]});
      continue;
    }
    cuts[i].push_back(radical_plane(d, r[i], r[j]));
    cuts[j].push_back(radical_plane(-d, r[j], r[i]));
  }
#pragma omp parallel for schedule(dynamic, 64) num_threads(std::max(1, threads)) if (threads > 1 && n > 1000)
  for (std::ptrdiff_t i = 0; i < std::ptrdiff_t(n); ++i) {
    const ClippedSphere c = clip_sphere(r[std::size_t(i)], cuts[std::size_t(i)]);
    u.share[std::size_t(i)] = c.volume;
    u.exposed_area[std::size_t(i)] = c.sphere_area;
  }
  for (std::size_t i = 0; i < n; ++i) {
    u.spheres += sphere_volume(r[i]);
    u.union_volume += u.share[i];
  }
  u.pairwise = u.spheres - lens;
  return u;
}

double union_relative_density(const std::vector<Vec3>& x, const std::vector<double>& r, const Cell& cell,
                              int threads) {
  if (r.empty()) return 0;
  return union_volume(x, r, cell, threads).union_volume / cell.volume();
}

}  // namespace tomodem::spatial
