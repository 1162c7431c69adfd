// Own algorithms (no third-party headers): median, Otsu/multi-Otsu, exact EDT, ball morphology,
// connected components, region statistics. OpenMP over slabs/lines.
#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <numeric>

#include "tomodem/core/error.hpp"
#include "tomodem/image/segment.hpp"

namespace tomodem::image {

// ---------------------------------------------------------------- median
namespace {
// Several voxels per instruction: 8 floats with AVX (-march=native), 4 with SSE. min/max are
// the x86 builtins (GCC splits a 32-byte vector select into scalar code without AVX); the
// scalar tail uses the same b < a ? b : a convention, so both give identical results.
#pragma GCC diagnostic ignored "-Wpsabi"
inline float vmin(float a, float b) { return b < a ? b : a; }
inline float vmax(float a, float b) { return a < b ? b : a; }
#if defined(__AVX__)
using fv = float __attribute__((vector_size(32)));
inline fv vmin(fv a, fv b) { return __builtin_ia32_minps256(b, a); }
inline fv vmax(fv a, fv b) { return __builtin_ia32_maxps256(b, a); }
#elif defined(__SSE__)
using fv = float __attribute__((vector_size(16)));
inline fv vmin(fv a, fv b) { return __builtin_ia32_minps(b, a); }
inline fv vmax(fv a, fv b) { return __builtin_ia32_maxps(b, a); }
#endif
#if defined(__AVX__) || defined(__SSE__)
constexpr std::size_t kLanes = sizeof(fv) / sizeof(float);
inline void load(fv& r, const float* p) { std::memcpy(&r, p, sizeof r); }
inline void store(float* p, fv r) { std::memcpy(p, &r, sizeof r); }
#else
using fv = float;
constexpr std::size_t kLanes = 1;
#endif
inline void load(float& r, const float* p) { r = *p; }
inline void store(float* p, float r) { *p = r; }

template <class T>
inline void cswap(T& a, T& b) {
  const T lo = vmin(a, b);
  b = vmax(a, b);
  a = lo;
}
// Sorting network for 9 values, 25 comparators (checked exhaustively on the 2^9 0/1 inputs,
// which proves it for all inputs; see the unit test Median.* for the kernel against nth_element).
template <class T>
inline void sort9(T* a) {
  static constexpr int net[25][2] = {{0, 3}, {1, 7}, {2, 5}, {4, 8}, {0, 7}, {2, 4}, {3, 8}, {5, 6}, {0, 2},
                                     {1, 3}, {4, 5}, {7, 8}, {1, 4}, {3, 6}, {5, 7}, {0, 1}, {2, 4}, {3, 5},
                                     {6, 8}, {2, 3}, {4, 5}, {6, 7}, {1, 2}, {3, 4}, {5, 6}};
#pragma GCC unroll 25
  for (int c = 0; c < 25; ++c) cswap(a[net[c][0]], a[net[c][1]]);
}
// Rank 14 (the median) of the 27 values held as three sorted columns of 9 (A, B, C).
// The k-th smallest of two sorted lists X, Y is min over i + j = k of max(X_i, Y_j) (1-based,
// X_0 = -inf): every split bounds it from above and the split that takes the k smallest attains
// it. Ranks 5..14 of A u B are enough for the 14th of (A u B) u C, since C holds 9 values.
template <class T>
inline T median27(const T* A, const T* B, const T* C) {
  T ab[15];
#pragma GCC unroll 10
  for (int k = 5; k <= 14; ++k) {
    const int i0 = std::max(0, k - 9), i1 = std::min(9, k);
    T best = (i0 == 0) ? B[k - 1] : vmax(A[i0 - 1], B[k - i0 - 1]);
#pragma GCC unroll 10
    for (int i = i0 + 1; i <= i1; ++i) best = vmin(best, (i == k) ? A[i - 1] : vmax(A[i - 1], B[k - i - 1]));
    ab[k] = best;
  }
  T m = ab[14];
#pragma GCC unroll 9
  for (int l = 1; l <= 9; ++l) m = vmin(m, vmax(ab[14 - l], C[l - 1]));
  return m;
}

// One output row of the 3x3x3 median. rows[3c + b]: input rows at (y + b - 1, z + c - 1),
// borders already replicated; S: scratch of 9 (nx + 2) floats for the sorted (y, z) columns.
void median27_row(const float* const* rows, std::size_t nx, float* out, float* S) {
  const std::size_t ns = nx + 2;
  const auto columns = [&](auto lanes, std::size_t x) {
    decltype(lanes) a[9];
    for (int k = 0; k < 9; ++k) load(a[k], rows[k] + x);
    sort9(a);
    for (int k = 0; k < 9; ++k) store(S + std::size_t(k) * ns + x + 1, a[k]);
  };
  const auto medians = [&](auto lanes, std::size_t x) {
    decltype(lanes) A[9], B[9], C[9];
    for (int k = 0; k < 9; ++k) {
      load(A[k], S + std::size_t(k) * ns + x);
      load(B[k], S + std::size_t(k) * ns + x + 1);
      load(C[k], S + std::size_t(k) * ns + x + 2);
    }
    store(out + x, median27(A, B, C));
  };
  std::size_t x = 0;
  for (; x + kLanes <= nx; x += kLanes) columns(fv{}, x);
  for (; x < nx; ++x) columns(0.0f, x);
  for (int k = 0; k < 9; ++k) {  // replicate the x borders
    S[std::size_t(k) * ns] = S[std::size_t(k) * ns + 1];
    S[std::size_t(k) * ns + nx + 1] = S[std::size_t(k) * ns + nx];
  }
  for (x = 0; x + kLanes <= nx; x += kLanes) medians(fv{}, x);
  for (; x < nx; ++x) medians(0.0f, x);
}
}  // namespace

namespace {
// A length given in voxels of the finest axis, in voxels of each axis.
std::array<double, 3> along_each_axis(const Volume& v, double length_vox) {
  const double finest = std::min({v.spacing[0], v.spacing[1], v.spacing[2]});
  return {length_vox * finest / v.spacing[0], length_vox * finest / v.spacing[1], length_vox * finest / v.spacing[2]};
}
}  // namespace

std::array<int, 3> radii_for_length(const Volume& v, double r_vox) {
  const std::array<double, 3> l = along_each_axis(v, r_vox);
  // The voxel centres within r along each axis; 1e-9 keeps 1um/1um at 1 despite round-off.
  return {int(std::floor(l[0] + 1e-9)), int(std::floor(l[1] + 1e-9)), int(std::floor(l[2] + 1e-9))};
}

std::array<int, 3> gaussian_radii(const Volume& v, double sigma_vox) {
  const std::array<double, 3> l = along_each_axis(v, 4 * sigma_vox);
  return {int(std::ceil(l[0] - 1e-9)), int(std::ceil(l[1] - 1e-9)), int(std::ceil(l[2] - 1e-9))};
}

void gaussian_inplace(Volume& v, double sigma_vox) {
  if (!(sigma_vox > 0)) throw InputError("", "--sigma", value_text(sigma_vox), "must be > 0 (voxels)");
  const std::array<double, 3> sigma = along_each_axis(v, sigma_vox);
  const std::array<int, 3> radii = gaussian_radii(v, sigma_vox);
  const std::array<std::size_t, 3> n{v.dims.nx, v.dims.ny, v.dims.nz};
  const std::size_t nx = n[0], ny = n[1], nz = n[2];
  for (std::size_t a = 0; a < 3; ++a) {
    const int r = radii[a];
    if (n[a] < 2 || r < 1) continue;  // one sample, or a kernel narrower than a voxel: unchanged
    const double s = sigma[a];
    std::vector<double> w(std::size_t(2 * r + 1));
    for (int k = -r; k <= r; ++k) w[std::size_t(k + r)] = std::exp(-0.5 * k * k / (s * s));
    const double sum = std::accumulate(w.begin(), w.end(), 0.0);
    for (auto& x : w) x /= sum;
    const auto at = [&](long i) { return std::size_t(std::clamp<long>(i, 0, long(n[a]) - 1)); };
    if (a == 0) {
      // Rows along x: each copied with r replicated values at both ends.
#pragma omp parallel
      {
        std::vector<double> row(nx + 2 * std::size_t(r));
#pragma omp for schedule(static)
        for (long yz = 0; yz < long(ny * nz); ++yz) {
          float* p = &v.v[std::size_t(yz) * nx];
          for (long i = -r; i < long(nx) + r; ++i) row[std::size_t(i + r)] = p[at(i)];
          for (std::size_t x = 0; x < nx; ++x) {
            double acc = 0;
            for (std::size_t k = 0; k < w.size(); ++k) acc += w[k] * row[x + k];
            p[x] = float(acc);
          }
        }
      }
      continue;
    }
    // Along y (within a plane) or z (within an xz slab): whole rows of x at a time, so the reads
    // are contiguous; `lines` rows of nx floats, `stride` floats apart, for each of `outer` starts.
    const std::size_t lines = n[a], stride = a == 1 ? nx : nx * ny, outer = a == 1 ? nz : ny, step = a == 1 ? nx * ny : nx;
#pragma omp parallel
    {
      std::vector<float> in(lines * nx);
      std::vector<double> acc(nx);
#pragma omp for schedule(static)
      for (long o = 0; o < long(outer); ++o) {
        float* base = &v.v[std::size_t(o) * step];
        for (std::size_t l = 0; l < lines; ++l) std::copy_n(base + l * stride, nx, &in[l * nx]);
        for (std::size_t l = 0; l < lines; ++l) {
          std::fill(acc.begin(), acc.end(), 0.0);
          for (int k = -r; k <= r; ++k) {
            const double wk = w[std::size_t(k + r)];
            const float* src = &in[at(long(l) + k) * nx];
            for (std::size_t x = 0; x < nx; ++x) acc[x] += wk * src[x];
          }
          for (std::size_t x = 0; x < nx; ++x) base[l * stride + x] = float(acc[x]);
        }
      }
    }
  }
}

void median_inplace(Volume& v, int r, bool generic) { median_inplace(v, std::array<int, 3>{r, r, r}, generic); }

void median_inplace(Volume& v, const std::array<int, 3>& radii, bool generic) {
  const int r = radii[2], rx = radii[0], ry = radii[1];
  if (rx < 1 || ry < 1 || r < 0)
    throw InputError("", "--filter-radius", std::to_string(rx) + "," + std::to_string(ry) + "," + std::to_string(r),
                     "median radius must span >= 1 voxel in x and y");
  const std::size_t nx = v.dims.nx, ny = v.dims.ny, nz = v.dims.nz, P = nx * ny;
  const long w = 2 * r + 1, n = w * (2 * ry + 1) * (2 * rx + 1), mid = n / 2;
  // Ring of the original planes z - r .. z + r (plane q in slot q mod w): the output of plane z
  // overwrites the input, so the filter needs the volume plus 2r + 1 planes of memory.
  std::vector<float> ring(std::size_t(w) * P);
  std::vector<long> held(std::size_t(w), -1);
  const auto clampi = [](long i, std::size_t n_) { return std::size_t(std::clamp<long>(i, 0, long(n_) - 1)); };
  const auto plane = [&](long z) { return &ring[std::size_t(long(clampi(z, nz)) % w) * P]; };
#pragma omp parallel
  {
    std::vector<float> S(9 * (nx + 2)), buf(static_cast<std::size_t>(n));
    for (long z = 0; z < long(nz); ++z) {
#pragma omp single
      for (long q = std::max(0L, z - r); q <= std::min(long(nz) - 1, z + r); ++q)
        if (held[std::size_t(q % w)] != q) {
          std::copy_n(&v.v[std::size_t(q) * P], P, &ring[std::size_t(q % w) * P]);
          held[std::size_t(q % w)] = q;
        }
#pragma omp for schedule(static)
      for (long y = 0; y < long(ny); ++y) {
        float* out = &v.v[std::size_t(z) * P + std::size_t(y) * nx];
        if (r == 1 && rx == 1 && ry == 1 && !generic) {
          const float* rows[9];
          for (int c = 0; c < 3; ++c)
            for (int b = 0; b < 3; ++b) rows[3 * c + b] = plane(z + c - 1) + clampi(y + b - 1, ny) * nx;
          median27_row(rows, nx, out, S.data());
          continue;
        }
        for (long x = 0; x < long(nx); ++x) {  // any radius: gather the box and select
          std::size_t k = 0;
          for (long c = -r; c <= r; ++c) {
            const float* pl = plane(z + c);
            for (long b = -ry; b <= ry; ++b) {
              const float* row = pl + clampi(y + b, ny) * nx;
              for (long a = -rx; a <= rx; ++a) buf[k++] = row[clampi(x + a, nx)];
            }
          }
          std::nth_element(buf.begin(), buf.begin() + mid, buf.end());
          out[x] = buf[std::size_t(mid)];
        }
      }
    }
  }
}

Volume median(const Volume& v, int r) {
  Volume out = v;
  median_inplace(out, r);
  return out;
}

// ---------------------------------------------------------------- thresholds
GreyHistogram grey_histogram(const Volume& v, int bins) {
  float lo = std::numeric_limits<float>::max(), hi = std::numeric_limits<float>::lowest();
#pragma omp parallel for reduction(min : lo) reduction(max : hi)
  for (std::size_t i = 0; i < v.v.size(); ++i) { lo = std::min(lo, v.v[i]); hi = std::max(hi, v.v[i]); }
  GreyHistogram H = empty_histogram(lo, hi, bins);
#pragma omp parallel
  {
    std::vector<double> mine(std::size_t(bins), 0.0);
#pragma omp for nowait
    for (std::size_t i = 0; i < v.v.size(); ++i) mine[std::size_t(H.bin(v.v[i]))] += 1;
#pragma omp critical
    for (int b = 0; b < bins; ++b) H.h[std::size_t(b)] += mine[std::size_t(b)];
  }
  return H;
}

GreyHistogram empty_histogram(float lo, float hi, int bins) {
  if (!(hi > lo)) throw InputError("", "volume", std::to_string(lo), "constant volume: nothing to threshold");
  GreyHistogram H;
  H.lo = lo;
  H.width = (double(hi) - double(lo)) / bins;
  H.h.assign(std::size_t(bins), 0.0);
  return H;
}

double otsu_threshold(const Volume& v, int bins) { return multi_otsu_thresholds(v, 2, bins).front(); }

std::vector<double> multi_otsu_thresholds(const Volume& v, int classes, int bins) {
  if (classes != 2 && classes != 3)
    throw InputError("", "--method", "multiotsu" + std::to_string(classes), "2 or 3 classes are supported");
  return multi_otsu_thresholds(grey_histogram(v, bins), classes);
}

std::vector<double> multi_otsu_thresholds(const GreyHistogram& H, int classes) {
  if (classes != 2 && classes != 3)
    throw InputError("", "--method", "multiotsu" + std::to_string(classes), "2 or 3 classes are supported");
  const int bins = int(H.h.size());
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

double intermeans_threshold(const Volume& v, double start) { return intermeans_threshold(grey_histogram(v, 4096), start); }

double intermeans_threshold(const GreyHistogram& H, double start) {
  // Ridler & Calvard (1978) iterative intermeans on a fine histogram (4096 bins), from `start`.
  const int bins = int(H.h.size());
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

double peaks_threshold(const Volume& v, double start) { return peaks_threshold(grey_histogram(v, 1024), start); }

double peaks_threshold(const GreyHistogram& H, double start) {
  // Midpoint of the two phase peaks: the histogram modes below and above `start`, on a
  // 1024-bin histogram smoothed over 9 bins. Under a symmetric blur, an edge between two pure
  // phases crosses this level at its true position (50 % partial volume).
  const int bins = int(H.h.size()), half = 4;
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
// w2: the squared voxel size along the line in units of the finest voxel (1 when isotropic).
void edt_1d(const float* f, int n, float* d, int* vtx, double* z, double w2) {
  int k = -1;
  for (int q = 0; q < n; ++q) {
    if (f[q] >= kInf) continue;
    const double fq = double(f[q]) + w2 * double(q) * q;
    // Intersection s = num / den with the parabola on top of the stack; s <= z[k] is tested as
    // num <= z[k] den (den > 0), so only a parabola that stays pays for a division.
    double num = 0, den = 1;
    while (k >= 0) {
      const int p = vtx[k];
      num = fq - (double(f[p]) + w2 * double(p) * p);
      den = 2.0 * w2 * (q - p);
      if (num <= z[k] * den) --k;
      else break;
    }
    if (k < 0) {
      k = 0;
      vtx[0] = q;
      z[0] = -1e300;
    } else {
      ++k;
      vtx[k] = q;
      z[k] = num / den;
    }
    z[k + 1] = 1e300;
  }
  if (k < 0) { std::fill(d, d + n, kInf); return; }
  k = 0;
  for (int q = 0; q < n; ++q) {
    while (z[k + 1] < q) ++k;
    const double dq = double(q - vtx[k]);
    d[q] = float(w2 * dq * dq + f[vtx[k]]);
  }
}

// First pass, along x, of a field that is 0 or kInf: the squared distance to the nearest 0 of
// the line, from a forward and a backward scan (no parabolas needed for a binary input).
void edt_1d_binary(float* f, int n, float w2) {
  int last = -1;
  for (int q = 0; q < n; ++q) {
    if (f[q] == 0.0f) last = q;
    else if (last >= 0) f[q] = w2 * float(q - last) * float(q - last);
  }
  last = -1;
  for (int q = n - 1; q >= 0; --q) {
    if (f[q] == 0.0f) last = q;
    else if (last >= 0) f[q] = std::min(f[q], w2 * float(last - q) * float(last - q));
  }
}

// One axis pass over every line. Lines along y and z are processed in groups of up to 16
// neighbouring x: each gather/scatter then reads whole cache lines instead of one float per
// cache line (and per page, along z).
void edt_axis(std::vector<float>& g, const Dims& d, int axis, double w2) {
  constexpr std::size_t W = 16;
  const std::size_t n = axis == 0 ? d.nx : axis == 1 ? d.ny : d.nz;
  const std::size_t stride = axis == 0 ? 1 : axis == 1 ? d.nx : d.nx * d.ny;
  const std::size_t xblocks = (d.nx + W - 1) / W;
  const std::size_t groups = axis == 0 ? d.ny * d.nz : (axis == 1 ? d.nz : d.ny) * xblocks;
#pragma omp parallel
  {
    std::vector<float> f(W * n), out(n);
    std::vector<double> z(n + 1);
    std::vector<int> vtx(n);
#pragma omp for schedule(static)
    for (std::ptrdiff_t gi = 0; gi < std::ptrdiff_t(groups); ++gi) {
      if (axis == 0) {
        edt_1d_binary(&g[std::size_t(gi) * d.nx], int(n), float(w2));
        continue;
      }
      const std::size_t outer = std::size_t(gi) / xblocks, x0 = (std::size_t(gi) % xblocks) * W;
      const std::size_t lanes = std::min(W, d.nx - x0);
      const std::size_t base = (axis == 1 ? outer * d.nx * d.ny : outer * d.nx) + x0;
      for (std::size_t i = 0; i < n; ++i)
        for (std::size_t l = 0; l < lanes; ++l) f[l * n + i] = g[base + i * stride + l];
      for (std::size_t l = 0; l < lanes; ++l) {
        edt_1d(&f[l * n], int(n), out.data(), vtx.data(), z.data(), w2);
        std::copy(out.begin(), out.end(), f.begin() + std::ptrdiff_t(l * n));
      }
      for (std::size_t i = 0; i < n; ++i)
        for (std::size_t l = 0; l < lanes; ++l) g[base + i * stride + l] = f[l * n + i];
    }
  }
}

// Exact squared Euclidean distance transform of a field that is 0 (the set) or kInf, in place,
// in units of the finest voxel edge: an axis with coarser voxels (a scan's z) weighs its steps
// by (spacing / finest)^2, so balls and distances are round in metres, not in voxels.
void edt_inplace(std::vector<float>& g, const Dims& d, const std::array<double, 3>& spacing) {
  const double finest = std::min({spacing[0], spacing[1], spacing[2]});
  for (int a = 0; a < 3; ++a) {
    const double w = spacing[std::size_t(a)] / finest;
    edt_axis(g, d, a, w * w);
  }
}

// Squared distance to the nearest voxel with m != 0 (`to_set`) or m == 0 (otherwise).
std::vector<float> edt_to(const Mask& m, bool to_set) {
  std::vector<float> g(m.v.size());
#pragma omp parallel for schedule(static)
  for (std::size_t i = 0; i < g.size(); ++i) g[i] = (m.v[i] != 0) == to_set ? 0.0f : kInf;
  edt_inplace(g, m.dims, m.spacing);
  return g;
}
}  // namespace

std::vector<float> distance_squared(const Mask& m) { return edt_to(m, false); }

std::vector<float> signed_contour_distance(const Mask& solid) {
  const Dims& d = solid.dims;
  const std::ptrdiff_t nx = std::ptrdiff_t(d.nx), ny = std::ptrdiff_t(d.ny), nz = std::ptrdiff_t(d.nz);
  std::vector<float> g(solid.v.size());
  // The contour: solid voxels with a pore among their 26 neighbours inside the volume (ITK's
  // BinaryContourImageFilter, fully connected, as SignedMaurerDistanceMapImageFilter sets it).
#pragma omp parallel for schedule(static)
  for (std::ptrdiff_t z = 0; z < nz; ++z)
    for (std::ptrdiff_t y = 0; y < ny; ++y)
      for (std::ptrdiff_t x = 0; x < nx; ++x) {
        const std::size_t i = std::size_t((z * ny + y) * nx + x);
        bool contour = false;
        if (solid.v[i])
          for (std::ptrdiff_t c = std::max<std::ptrdiff_t>(z - 1, 0); c <= std::min(z + 1, nz - 1) && !contour; ++c)
            for (std::ptrdiff_t b = std::max<std::ptrdiff_t>(y - 1, 0); b <= std::min(y + 1, ny - 1) && !contour; ++b)
              for (std::ptrdiff_t a = std::max<std::ptrdiff_t>(x - 1, 0); a <= std::min(x + 1, nx - 1); ++a)
                if (!solid.v[std::size_t((c * ny + b) * nx + a)]) {
                  contour = true;
                  break;
                }
        g[i] = contour ? 0.0f : kInf;
      }
  edt_inplace(g, d, solid.spacing);
#pragma omp parallel for schedule(static)
  for (std::size_t i = 0; i < g.size(); ++i) {
    const float r = std::sqrt(g[i]);
    g[i] = solid.v[i] ? r : -r;
  }
  return g;
}

Mask erode_ball(const Mask& m, double r) {
  const auto d2 = edt_to(m, false);
  Mask out;
  out.copy_geometry(m);
  out.v.resize(m.v.size());
  const float r2 = float(r * r);
#pragma omp parallel for schedule(static)
  for (std::size_t i = 0; i < d2.size(); ++i) out.v[i] = d2[i] > r2;
  return out;
}

Mask dilate_ball(const Mask& m, double r) {
  const auto d2 = edt_to(m, true);  // distance of every voxel outside m to m
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
  RegionSums sums(static_cast<std::size_t>(n));
  const auto [nx, ny, nz] = l.dims;
  for (std::size_t z = 0; z < nz; ++z)
    for (std::size_t y = 0; y < ny; ++y)
      for (std::size_t x = 0; x < nx; ++x) {
        const int32_t k = l.v[l.index(x, y, z)];
        if (k > 0 && k <= n) sums.add(k, x, y, z, l.dims);
      }
  return sums.regions(l.origin, l.spacing);
}

std::vector<Region> RegionSums::regions(const std::array<double, 3>& origin, const std::array<double, 3>& spacing) const {
  std::vector<Region> r = r_;
  const double vox = spacing[0] * spacing[1] * spacing[2];
  for (std::size_t k = 0; k < r.size(); ++k) {
    Region& R = r[k];
    R.label = int(k + 1);
    if (!R.voxels) continue;
    const double c = double(R.voxels);
    R.centroid = {origin[0] + sum_[k][0] / c * spacing[0], origin[1] + sum_[k][1] / c * spacing[1],
                  origin[2] + sum_[k][2] / c * spacing[2]};
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
  return specific_surface(fx, fy, fz, m.dims, m.spacing);
}

double specific_surface(double fx, double fy, double fz, const Dims& d, const std::array<double, 3>& s) {
  const double area = fx * s[1] * s[2] + fy * s[0] * s[2] + fz * s[0] * s[1];
  const double volume = double(d.count()) * s[0] * s[1] * s[2];
  return (2.0 / 3.0) * area / volume;
}

Mask macropore_mask(const Mask& pores, double r) {
  // Opening by a digital ball loses a few percent of a digital sphere's surface voxels (see the
  // unit test); dilating the eroded cores by r + 1 and keeping only pore voxels recovers them
  // without reaching across the solid.
  // One float field for both passes (memory: 4 bytes per voxel plus the result mask): distances
  // to the solid, then the ball centres (d2 > r^2) as seeds, then distances to the seeds.
  Mask opened;
  std::vector<float> g = edt_to(pores, false);
  const float r2 = float(r * r), r12 = float((r + 1) * (r + 1));
#pragma omp parallel for schedule(static)
  for (std::size_t i = 0; i < g.size(); ++i) g[i] = g[i] > r2 ? 0.0f : kInf;
  edt_inplace(g, pores.dims, pores.spacing);
  opened.copy_geometry(pores);
  opened.v.resize(pores.v.size());
#pragma omp parallel for schedule(static)
  for (std::size_t i = 0; i < g.size(); ++i) opened.v[i] = g[i] <= r12 && pores.v[i];
  return opened;
}

Labels macropores(const Mask& pores, double r, std::size_t min_voxels, int* count) {
  const Mask opened = macropore_mask(pores, r);
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
