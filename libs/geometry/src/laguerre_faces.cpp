// One index of the Laguerre faces for the dense-network caps (docs/bond.md#dense-networks,
// docs/conduct.md): tessellate once, look up the face between i and an image of j.
#include "tomodem/geometry/laguerre_faces.hpp"

#include <cmath>
#include <utility>

namespace tomodem::geometry {

bool spans_space(const std::vector<Vec3>& x, const Cell& cell) {
  if (x.empty()) return false;
  std::vector<Vec3> d;
  for (const Vec3& p : x) d.push_back(p - x[0]);
  for (int k = 0; k < 3; ++k)
    if (cell.periodic[k]) d.push_back(cell.h.col(k));
  const auto farthest = [&](const auto& dist) {
    double best = 0;
    Vec3 arg;
    for (const Vec3& v : d)
      if (dist(v) > best) best = dist(v), arg = v;
    return std::make_pair(best, arg);
  };
  const auto [l1, v1] = farthest([](const Vec3& v) { return norm(v); });
  if (!(l1 > 0)) return false;
  const Vec3 u1 = v1 * (1 / l1);
  const auto [l2, v2] = farthest([&](const Vec3& v) { return norm(v - dot(v, u1) * u1); });
  if (!(l2 > 1e-12 * l1)) return false;
  Vec3 n = cross(u1, v2);
  n *= 1 / norm(n);
  return farthest([&](const Vec3& v) { return std::abs(dot(v, n)); }).first > 1e-12 * l1;
}

LaguerreFaces::LaguerreFaces(const std::vector<Vec3>& x, const std::vector<double>& r, const Cell& cell)
    : spans_(geometry::spans_space(x, cell)), of_(x.size()) {
  if (!spans_) return;
  faces_ = laguerre_faces(x, r, cell);
  for (std::size_t f = 0; f < faces_.size(); ++f) of_[std::size_t(faces_[f].i)].push_back(f);
}

double LaguerreFaces::area(int i, int j, const Vec3& offset, double tol) const {
  if (!spans_) return HUGE_VAL;
  // Several images of j can neighbour i in a small cell: the one at this offset.
  for (std::size_t f : of_[std::size_t(i)])
    if (faces_[f].j == j && norm(faces_[f].offset - offset) <= tol * norm(offset)) return faces_[f].area;
  return 0;
}

double LaguerreFaces::area_at_distance(int i, int j, double distance, double tol) const {
  if (!spans_) return HUGE_VAL;
  double best = HUGE_VAL, area = 0;
  for (std::size_t f : of_[std::size_t(i)]) {
    if (faces_[f].j != j) continue;
    const double miss = std::abs(norm(faces_[f].offset) - distance);
    if (miss < best) best = miss, area = faces_[f].area;
  }
  // No face within tol of the distance: the pair's radical disc lies inside other cells.
  return best <= tol * distance ? area : 0;
}

}  // namespace tomodem::geometry
