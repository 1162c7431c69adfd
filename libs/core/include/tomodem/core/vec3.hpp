#pragma once
// Small fixed-size vector and matrix types shared by every library.
// Plain structs (no Eigen in widely included headers): they map one-to-one onto
// HDF5 N×3 datasets and keep the DEM inner loops free of expression templates.
#include <cmath>

namespace tomodem {

struct Vec3 {
  double x = 0, y = 0, z = 0;
  constexpr Vec3() = default;
  constexpr Vec3(double x_, double y_, double z_) : x(x_), y(y_), z(z_) {}
  constexpr double operator[](int k) const { return k == 0 ? x : (k == 1 ? y : z); }
  double& operator[](int k) { return k == 0 ? x : (k == 1 ? y : z); }
  Vec3& operator+=(const Vec3& o) { x += o.x; y += o.y; z += o.z; return *this; }
  Vec3& operator-=(const Vec3& o) { x -= o.x; y -= o.y; z -= o.z; return *this; }
  Vec3& operator*=(double s) { x *= s; y *= s; z *= s; return *this; }
};

inline constexpr Vec3 operator+(Vec3 a, const Vec3& b) { return {a.x + b.x, a.y + b.y, a.z + b.z}; }
inline constexpr Vec3 operator-(Vec3 a, const Vec3& b) { return {a.x - b.x, a.y - b.y, a.z - b.z}; }
inline constexpr Vec3 operator-(const Vec3& a) { return {-a.x, -a.y, -a.z}; }
inline constexpr Vec3 operator*(double s, const Vec3& a) { return {s * a.x, s * a.y, s * a.z}; }
inline constexpr Vec3 operator*(const Vec3& a, double s) { return {s * a.x, s * a.y, s * a.z}; }
inline constexpr double dot(const Vec3& a, const Vec3& b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
inline constexpr Vec3 cross(const Vec3& a, const Vec3& b) {
  return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x};
}
inline double norm2(const Vec3& a) { return dot(a, a); }
inline double norm(const Vec3& a) { return std::sqrt(dot(a, a)); }

/// Row-major 3×3 matrix. Used for cell matrices (columns are the cell vectors),
/// velocity gradients and stress tensors.
struct Mat3 {
  double a[3][3] = {{0, 0, 0}, {0, 0, 0}, {0, 0, 0}};
  static Mat3 identity() { Mat3 m; m.a[0][0] = m.a[1][1] = m.a[2][2] = 1; return m; }
  static Mat3 diagonal(const Vec3& d) { Mat3 m; m.a[0][0] = d.x; m.a[1][1] = d.y; m.a[2][2] = d.z; return m; }
  double& operator()(int r, int c) { return a[r][c]; }
  double operator()(int r, int c) const { return a[r][c]; }
  Vec3 col(int c) const { return {a[0][c], a[1][c], a[2][c]}; }
  Vec3 operator*(const Vec3& v) const {
    return {a[0][0] * v.x + a[0][1] * v.y + a[0][2] * v.z, a[1][0] * v.x + a[1][1] * v.y + a[1][2] * v.z,
            a[2][0] * v.x + a[2][1] * v.y + a[2][2] * v.z};
  }
  Mat3 operator*(const Mat3& o) const {
    Mat3 r;
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j) r.a[i][j] = a[i][0] * o.a[0][j] + a[i][1] * o.a[1][j] + a[i][2] * o.a[2][j];
    return r;
  }
  Mat3& operator+=(const Mat3& o) { for (int i = 0; i < 9; ++i) (&a[0][0])[i] += (&o.a[0][0])[i]; return *this; }
  Mat3& operator*=(double s) { for (int i = 0; i < 9; ++i) (&a[0][0])[i] *= s; return *this; }
  double trace() const { return a[0][0] + a[1][1] + a[2][2]; }
  double det() const {
    return a[0][0] * (a[1][1] * a[2][2] - a[1][2] * a[2][1]) - a[0][1] * (a[1][0] * a[2][2] - a[1][2] * a[2][0]) +
           a[0][2] * (a[1][0] * a[2][1] - a[1][1] * a[2][0]);
  }
  Mat3 transpose() const { Mat3 r; for (int i = 0; i < 3; ++i) for (int j = 0; j < 3; ++j) r.a[i][j] = a[j][i]; return r; }
  Mat3 inverse() const {
    Mat3 r;
    const double d = det();
    r.a[0][0] = (a[1][1] * a[2][2] - a[1][2] * a[2][1]) / d;
    r.a[0][1] = (a[0][2] * a[2][1] - a[0][1] * a[2][2]) / d;
    r.a[0][2] = (a[0][1] * a[1][2] - a[0][2] * a[1][1]) / d;
    r.a[1][0] = (a[1][2] * a[2][0] - a[1][0] * a[2][2]) / d;
    r.a[1][1] = (a[0][0] * a[2][2] - a[0][2] * a[2][0]) / d;
    r.a[1][2] = (a[0][2] * a[1][0] - a[0][0] * a[1][2]) / d;
    r.a[2][0] = (a[1][0] * a[2][1] - a[1][1] * a[2][0]) / d;
    r.a[2][1] = (a[0][1] * a[2][0] - a[0][0] * a[2][1]) / d;
    r.a[2][2] = (a[0][0] * a[1][1] - a[0][1] * a[1][0]) / d;
    return r;
  }
};

/// Outer product a ⊗ b.
inline Mat3 outer(const Vec3& a, const Vec3& b) {
  Mat3 m;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) m.a[i][j] = a[i] * b[j];
  return m;
}

}  // namespace tomodem
