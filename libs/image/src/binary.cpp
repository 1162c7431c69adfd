// Own algorithms (no third-party headers): median, Otsu/multi-Otsu, exact EDT, ball morphology,
// connected components, region statistics. OpenMP over slabs/lines.
#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>

#include "tomodem/core/error.hpp"
#include "tomodem/image/segment.hpp"

namespace tomodem::image {

// ---------------------------------------------------------------- median
Volume median(const Volume& v, int r) {
  if (r < 1) throw InputError("", "--filter-radius", std::to_string(r), "median radius must be >= 1");
  const auto [nx, ny, nz] = v.dims;
  Volume out;
  out.copy_geometry(v);
  out.v.resize(v.v.size());
  const int w = 2 * r + 1, n = w * w * w, mid = n / 2;
  const auto clampi = [](long i, std::size_t n_) { return static_cast<std::size_t>(std::clamp<long>(i, 0, long(n_) - 1)); };
#pragma omp parallel
  {
    std::vector<float> buf(static_cast<std::size_t>(n));
#pragma omp for schedule(dynamic, 1)
    for (long z = 0; z < long(nz); ++z)
      for (long y = 0; y < long(ny); ++y) {
        const bool inner_yz = z >= r && z + r < long(nz) && y >= r && y + r < long(ny);
        for (long x = 0; x < long(nx); ++x) {
          int k = 0;
          if (inner_yz && x >= r && x + r < long(nx)) {
            for (long c = -r; c <= r; ++c)
              for (long b = -r; b <= r; ++b) {
                const float* row = &v.v[v.index(std::size_t(x - r), std::size_t(y + b), std::size_t(z + c))];
                for (int a = 0; a < w; ++a) buf[k++] = row[a];
              }
          } else {  // replicate the border
            for (long c = -r; c <= r; ++c)
              for (long b = -r; b <= r; ++b)
                for (long a = -r; a <= r; ++a)
                  buf[k++] = v.at(clampi(x + a, nx), clampi(y + b, ny), clampi(z + c, nz));
          }
          std::nth_element(buf.begin(), buf.begin() + mid, buf.end());
          out.v[v.index(std::size_t(x), std::size_t(y), std::size_t(z))] = buf[mid];
        }
      }
  }
  return out;
}

// ---------------------------------------------------------------- thresholds
namespace {
struct Histogram {
  double lo = 0, width = 1;
  std::vector<double> h;
};
Histogram histogram(const Volume& v, int bins) {
  float lo = std::numeric_limits<float>::max(), hi = std::numeric_limits<float>::lowest();
#pragma omp parallel for reduction(min : lo) reduction(max : hi)
  for (std::size_t i = 0; i < v.v.size(); ++i) { lo = std::min(lo, v.v[i]); hi = std::max(hi, v.v[i]); }
  if (!(hi > lo)) throw InputError("", "volume", std::to_string(lo), "constant volume: nothing to threshold");
  Histogram H;
  H.lo = lo;
  H.width = (double(hi) - double(lo)) / bins;
  H.h.assign(std::size_t(bins), 0.0);
  std::vector<std::vector<double>> part;
#pragma omp parallel
  {
    std::vector<double> mine(std::size_t(bins), 0.0);
#pragma omp for nowait
    for (std::size_t i = 0; i < v.v.size(); ++i) {
      const int b = std::min(bins - 1, int((double(v.v[i]) - H.lo) / H.width));
      mine[std::size_t(b)] += 1;
    }
#pragma omp critical
    for (int b = 0; b < bins; ++b) H.h[std::size_t(b)] += mine[std::size_t(b)];
  }
  return H;
}
}  // namespace

double otsu_threshold(const Volume& v, int bins) { return multi_otsu_thresholds(v, 2, bins).front(); }

std::vector<double> multi_otsu_thresholds(const Volume& v, int classes, int bins) {
  if (classes != 2 && classes != 3)
    throw InputError("", "--method", "multiotsu" + std::to_string(classes), "2 or 3 classes are supported");
  const Histogram H = histogram(v, bins);
  // Cumulative weight and first moment (bin index units); maximise the between-class variance
  // sum_k w_k mu_k^2 (the total mean is constant).
  std::vector<double> P(std::size_t(bins) + 1, 0), S(std::size_t(bins) + 1, 0);
  for (int b = 0; b < bins; ++b) {
    P[std::size_t(b) + 1] = P[std::size_t(b)] + H.h[std::size_t(b)];
    S[std::size_t(b) + 1] = S[std::size_t(b)] + H.h[std::size_t(b)] * (b + 0.5);
  }
  const auto term = [&](int a, int b) {  // bins [a, b)
    const double w = P[std::size_t(b)] - P[std::size_t(a)];
    if (w <= 0) return 0.0;
    const double s = S[std::size_t(b)] - S[std::size_t(a)];
    return s * s / w;
  };
  std::vector<double> t;
  if (classes == 2) {
    // Well separated modes leave an empty gap where every split scores the same: take the
    // middle of that plateau of maxima rather than its first bin.
    std::vector<double> c(std::size_t(bins), -1);
    double best = -1;
    for (int i = 1; i < bins; ++i) best = std::max(best, c[std::size_t(i)] = term(0, i) + term(i, bins));
    int first = -1, last = -1;
    for (int i = 1; i < bins; ++i)
      if (c[std::size_t(i)] >= best * (1 - 1e-12)) { if (first < 0) first = i; last = i; }
    t = {H.lo + 0.5 * (first + last) * H.width};
  } else {
    double best = -1;
    int k1 = 1, k2 = 2;
    for (int i = 1; i < bins - 1; ++i)
      for (int j = i + 1; j < bins; ++j) {
        const double c = term(0, i) + term(i, j) + term(j, bins);
        if (c > best) { best = c; k1 = i; k2 = j; }
      }
    t = {H.lo + k1 * H.width, H.lo + k2 * H.width};
  }
  return t;  // a voxel in bin >= k has value >= t: "value >= t" is the upper class
}

double intermeans_threshold(const Volume& v, double start) {
  // Ridler & Calvard (1978) iterative intermeans on a fine histogram (4096 bins), from `start`.
  const int bins = 4096;
  const Histogram H = histogram(v, bins);
  double t = start;
  for (int it = 0; it < 200; ++it) {
    double w0 = 0, s0 = 0, w1 = 0, s1 = 0;
    for (int b = 0; b < bins; ++b) {
      const double x = H.lo + (b + 0.5) * H.width, n = H.h[std::size_t(b)];
      if (x < t) { w0 += n; s0 += n * x; } else { w1 += n; s1 += n * x; }
    }
    if (w0 == 0 || w1 == 0) break;
    const double next = 0.5 * (s0 / w0 + s1 / w1);
    const bool done = std::abs(next - t) < 0.5 * H.width;
    t = next;
    if (done) break;
  }
  return t;
}

double peaks_threshold(const Volume& v, double start) {
  // Midpoint of the two phase peaks: the histogram modes below and above `start`, on a
  // 1024-bin histogram smoothed over 9 bins. Under a symmetric blur, an edge between two pure
  // phases crosses this level at its true position (50 % partial volume).
  const int bins = 1024, half = 4;
  const Histogram H = histogram(v, bins);
  std::vector<double> sm(std::size_t(bins), 0);
  for (int b = 0; b < bins; ++b)
    for (int k = std::max(0, b - half); k <= std::min(bins - 1, b + half); ++k) sm[std::size_t(b)] += H.h[std::size_t(k)];
  const int split = std::clamp(int((start - H.lo) / H.width), 1, bins - 1);
  const auto lo_peak = std::max_element(sm.begin(), sm.begin() + split) - sm.begin();
  const auto hi_peak = std::max_element(sm.begin() + split, sm.end()) - sm.begin();
  return H.lo + (0.5 * double(lo_peak + hi_peak) + 0.5) * H.width;
}

Mask threshold(const Volume& v, double t, bool below) {
  Mask m;
  m.copy_geometry(v);
  m.v.resize(v.v.size());
#pragma omp parallel for schedule(static)
  for (std::size_t i = 0; i < v.v.size(); ++i) m.v[i] = below ? (v.v[i] < t) : (v.v[i] >= t);
  return m;
}

// ---------------------------------------------------------------- distance transform
namespace {
constexpr float kInf = 1e20f;
// Felzenszwalb & Huttenlocher (2012): lower envelope of the parabolas rooted at finite samples.
void edt_1d(const float* f, int n, float* d, int* vtx, double* z) {
  int k = -1;
  for (int q = 0; q < n; ++q) {
    if (f[q] >= kInf) continue;
    const double fq = double(f[q]) + double(q) * q;
    double s = 0;
    while (k >= 0) {
      const int p = vtx[k];
      s = (fq - (double(f[p]) + double(p) * p)) / (2.0 * (q - p));
      if (s <= z[k]) --k;
      else break;
    }
    if (k < 0) {
      k = 0;
      vtx[0] = q;
      z[0] = -1e300;
    } else {
      ++k;
      vtx[k] = q;
      z[k] = s;
    }
    z[k + 1] = 1e300;
  }
  if (k < 0) { std::fill(d, d + n, kInf); return; }
  k = 0;
  for (int q = 0; q < n; ++q) {
    while (z[k + 1] < q) ++k;
    const double dq = double(q - vtx[k]);
    d[q] = float(dq * dq + f[vtx[k]]);
  }
}

void edt_axis(std::vector<float>& g, const Dims& d, int axis) {
  const std::size_t n = axis == 0 ? d.nx : axis == 1 ? d.ny : d.nz;
  const std::size_t stride = axis == 0 ? 1 : axis == 1 ? d.nx : d.nx * d.ny;
  const std::size_t lines = d.count() / n;
#pragma omp parallel
  {
    std::vector<float> f(n), out(n);
    std::vector<double> z(n + 1);
    std::vector<int> vtx(n);
#pragma omp for schedule(static)
    for (std::ptrdiff_t l = 0; l < std::ptrdiff_t(lines); ++l) {
      std::size_t base;
      if (axis == 0) base = std::size_t(l) * d.nx;
      else if (axis == 1) base = (std::size_t(l) / d.nx) * d.nx * d.ny + std::size_t(l) % d.nx;
      else base = std::size_t(l);
      for (std::size_t i = 0; i < n; ++i) f[i] = g[base + i * stride];
      edt_1d(f.data(), int(n), out.data(), vtx.data(), z.data());
      for (std::size_t i = 0; i < n; ++i) g[base + i * stride] = out[i];
    }
  }
}
}  // namespace

std::vector<float> distance_squared(const Mask& m) {
  std::vector<float> g(m.v.size());
#pragma omp parallel for schedule(static)
  for (std::size_t i = 0; i < g.size(); ++i) g[i] = m.v[i] ? kInf : 0.0f;
  for (int a = 0; a < 3; ++a) edt_axis(g, m.dims, a);
  return g;
}

Mask erode_ball(const Mask& m, double r) {
  const auto d2 = distance_squared(m);
  Mask out;
  out.copy_geometry(m);
  out.v.resize(m.v.size());
  const float r2 = float(r * r);
#pragma omp parallel for schedule(static)
  for (std::size_t i = 0; i < d2.size(); ++i) out.v[i] = d2[i] > r2;
  return out;
}

Mask dilate_ball(const Mask& m, double r) {
  Mask inv = m;
  for (auto& x : inv.v) x = !x;
  const auto d2 = distance_squared(inv);  // distance of every voxel outside m to m
  Mask out;
  out.copy_geometry(m);
  out.v.resize(m.v.size());
  const float r2 = float(r * r);
#pragma omp parallel for schedule(static)
  for (std::size_t i = 0; i < d2.size(); ++i) out.v[i] = d2[i] <= r2;
  return out;
}

Mask open_ball(const Mask& m, double r) { return r > 0 ? dilate_ball(erode_ball(m, r), r) : m; }
Mask close_ball(const Mask& m, double r) { return r > 0 ? erode_ball(dilate_ball(m, r), r) : m; }

// ---------------------------------------------------------------- components
namespace {
int32_t find(std::vector<int32_t>& p, int32_t a) {
  while (p[std::size_t(a)] != a) {
    p[std::size_t(a)] = p[std::size_t(p[std::size_t(a)])];
    a = p[std::size_t(a)];
  }
  return a;
}
void unite(std::vector<int32_t>& p, int32_t a, int32_t b) {
  a = find(p, a);
  b = find(p, b);
  if (a < b) p[std::size_t(b)] = a;
  else if (b < a) p[std::size_t(a)] = b;
}
}  // namespace

Labels components(const Mask& m, int connectivity, int* count) {
  if (connectivity != 6 && connectivity != 26)
    throw InputError("", "--connectivity", std::to_string(connectivity), "expected 6 or 26");
  const auto [nx, ny, nz] = m.dims;
  Labels L;
  L.copy_geometry(m);
  L.v.assign(m.v.size(), 0);
  std::vector<int32_t> parent{0};
  // Backward neighbours (already visited in scan order).
  std::vector<std::array<int, 3>> nb;
  for (int c = -1; c <= 0; ++c)
    for (int b = -1; b <= 1; ++b)
      for (int a = -1; a <= 1; ++a) {
        if (c == 0 && (b > 0 || (b == 0 && a >= 0))) continue;
        if (connectivity == 6 && std::abs(a) + std::abs(b) + std::abs(c) != 1) continue;
        nb.push_back({a, b, c});
      }
  for (std::size_t z = 0; z < nz; ++z)
    for (std::size_t y = 0; y < ny; ++y)
      for (std::size_t x = 0; x < nx; ++x) {
        const std::size_t i = m.index(x, y, z);
        if (!m.v[i]) continue;
        int32_t lab = 0;
        for (const auto& o : nb) {
          const long X = long(x) + o[0], Y = long(y) + o[1], Z = long(z) + o[2];
          if (X < 0 || Y < 0 || Z < 0 || X >= long(nx) || Y >= long(ny)) continue;
          const int32_t q = L.v[m.index(std::size_t(X), std::size_t(Y), std::size_t(Z))];
          if (!q) continue;
          if (!lab) lab = q;
          else if (q != lab) unite(parent, lab, q);
        }
        if (!lab) {
          lab = int32_t(parent.size());
          parent.push_back(lab);
        }
        L.v[i] = lab;
      }
  std::vector<int32_t> final_id(parent.size(), 0);
  int32_t n = 0;
  for (auto& x : L.v) {
    if (!x) continue;
    const int32_t root = find(parent, x);
    if (!final_id[std::size_t(root)]) final_id[std::size_t(root)] = ++n;
    x = final_id[std::size_t(root)];
  }
  if (count) *count = n;
  return L;
}

int remove_islands(Mask& m, std::size_t min_voxels, int connectivity) {
  if (min_voxels <= 1) return 0;
  int n = 0;
  const Labels L = components(m, connectivity, &n);
  std::vector<std::size_t> size(std::size_t(n) + 1, 0);
  for (auto x : L.v) ++size[std::size_t(x)];
  int removed = 0;
  for (int k = 1; k <= n; ++k) removed += size[std::size_t(k)] < min_voxels;
  for (std::size_t i = 0; i < L.v.size(); ++i)
    if (L.v[i] && size[std::size_t(L.v[i])] < min_voxels) m.v[i] = 0;
  return removed;
}

std::vector<Region> regions(const Labels& l, int n) {
  std::vector<Region> r(static_cast<std::size_t>(n));
  std::vector<std::array<double, 3>> sum(static_cast<std::size_t>(n), std::array<double, 3>{0, 0, 0});
  const auto [nx, ny, nz] = l.dims;
  for (std::size_t z = 0; z < nz; ++z)
    for (std::size_t y = 0; y < ny; ++y)
      for (std::size_t x = 0; x < nx; ++x) {
        const int32_t k = l.v[l.index(x, y, z)];
        if (k <= 0 || k > n) continue;
        auto& R = r[std::size_t(k - 1)];
        ++R.voxels;
        sum[std::size_t(k - 1)][0] += double(x);
        sum[std::size_t(k - 1)][1] += double(y);
        sum[std::size_t(k - 1)][2] += double(z);
        if (x == 0 || y == 0 || z == 0 || x + 1 == nx || y + 1 == ny || z + 1 == nz) R.touches_surface = true;
      }
  const double vox = l.spacing[0] * l.spacing[1] * l.spacing[2];
  for (int k = 0; k < n; ++k) {
    auto& R = r[std::size_t(k)];
    R.label = k + 1;
    if (!R.voxels) continue;
    const double c = double(R.voxels);
    R.centroid = {l.origin[0] + sum[std::size_t(k)][0] / c * l.spacing[0], l.origin[1] + sum[std::size_t(k)][1] / c * l.spacing[1],
                  l.origin[2] + sum[std::size_t(k)][2] / c * l.spacing[2]};
    R.volume_m3 = c * vox;
    R.equivalent_diameter_m = std::cbrt(6.0 * R.volume_m3 / M_PI);
  }
  return r;
}

double specific_surface(const Mask& m) {
  const auto [nx, ny, nz] = m.dims;
  double fx = 0, fy = 0, fz = 0;
#pragma omp parallel for reduction(+ : fx, fy, fz) schedule(static)
  for (std::ptrdiff_t zz = 0; zz < std::ptrdiff_t(nz); ++zz) {
    const std::size_t z = std::size_t(zz);
    for (std::size_t y = 0; y < ny; ++y)
      for (std::size_t x = 0; x < nx; ++x) {
        const bool a = m.v[m.index(x, y, z)] != 0;
        if (x + 1 < nx && a != (m.v[m.index(x + 1, y, z)] != 0)) fx += 1;
        if (y + 1 < ny && a != (m.v[m.index(x, y + 1, z)] != 0)) fy += 1;
        if (z + 1 < nz && a != (m.v[m.index(x, y, z + 1)] != 0)) fz += 1;
      }
  }
  const auto& s = m.spacing;
  const double area = fx * s[1] * s[2] + fy * s[0] * s[2] + fz * s[0] * s[1];
  const double volume = double(m.dims.count()) * s[0] * s[1] * s[2];
  return (2.0 / 3.0) * area / volume;
}

Labels macropores(const Mask& pores, double r, std::size_t min_voxels, int* count) {
  // Opening by a digital ball loses a few percent of a digital sphere's surface voxels (see the
  // unit test); dilating the eroded cores by r + 1 and keeping only pore voxels recovers them
  // without reaching across the solid.
  Mask opened = dilate_ball(erode_ball(pores, r), r + 1);
  for (std::size_t i = 0; i < opened.v.size(); ++i) opened.v[i] = opened.v[i] && pores.v[i];
  int n = 0;
  Labels L = components(opened, 6, &n);
  std::vector<std::size_t> size(std::size_t(n) + 1, 0);
  for (auto x : L.v) ++size[std::size_t(x)];
  std::vector<int32_t> id(std::size_t(n) + 1, 0);
  int32_t kept = 0;
  for (int k = 1; k <= n; ++k)
    if (size[std::size_t(k)] >= min_voxels) id[std::size_t(k)] = ++kept;
  for (auto& x : L.v) x = id[std::size_t(x)];
  if (count) *count = kept;
  return L;
}

}  // namespace tomodem::image
