#pragma once
// The shared data model: what every tool reads and writes (HDF5 layout in docs/data-model.md).
// Structure of arrays; optional columns are empty vectors when absent. SI units throughout.
#include <cstdint>
#include <map>
#include <string>
#include <vector>

#include "tomodem/core/vec3.hpp"

namespace tomodem {

/// /particles
struct ParticleTable {
  std::vector<Vec3> position;          ///< m
  std::vector<double> radius;          ///< m
  std::vector<int32_t> phase;          ///< index into Packing::materials
  std::vector<Vec3> velocity;          ///< m/s (optional)
  std::vector<Vec3> angular_velocity;  ///< rad/s (optional)
  std::size_t size() const { return radius.size(); }
  void resize(std::size_t n);          ///< resizes the mandatory columns only
};

/// /cell: a parallelepiped with lower corner `origin` and cell vectors as the columns of `h`.
struct Cell {
  Vec3 origin{0, 0, 0};           ///< m
  Mat3 h = Mat3::identity();      ///< m, columns are the three cell vectors
  bool periodic[3] = {false, false, false};
  double volume() const { return std::abs(h.det()); }
  static Cell box(const Vec3& lo, const Vec3& hi, bool periodic_all);
  Vec3 upper() const { return origin + h.col(0) + h.col(1) + h.col(2); }
};

/// /bonds: solid necks between particles i and j.
struct BondTable {
  enum State : uint8_t { intact = 0, broken = 1 };
  std::vector<int32_t> i, j;
  std::vector<double> radius;       ///< a_b, m
  std::vector<double> rest_length;  ///< centre distance at bonding, m
  std::vector<uint8_t> state;       ///< State
  std::vector<double> broken_at;    ///< s, NaN while intact
  std::size_t size() const { return i.size(); }
};

/// /contacts (optional snapshot of the contact network).
struct ContactTable {
  std::vector<int32_t> i, j;
  std::vector<double> overlap;          ///< m, positive when interpenetrating
  std::vector<Vec3> normal_force;       ///< N, on j from i
  std::vector<Vec3> tangential_force;   ///< N, on j from i
  std::size_t size() const { return i.size(); }
};

/// /materials/<name>: one per phase, in phase-index order.
struct Material {
  std::string name;
  double youngs_modulus = 0;   ///< Pa
  double poisson_ratio = 0;    ///< -
  double density = 0;          ///< kg/m^3
  double surface_energy = 0;   ///< J/m^2
  double conductivity = 0;     ///< S/m
};

/// /results: scalars and time series of the step that wrote the file.
struct Results {
  std::map<std::string, double> scalars;
  std::map<std::string, std::string> units;  ///< unit per scalar or series name
  /// Each series is a set of equally long columns (e.g. "time_s", "kinetic_energy_J").
  std::map<std::string, std::map<std::string, std::vector<double>>> series;
};

/// Attributes on the root group: where the file came from.
struct Provenance {
  std::string tool;           ///< e.g. "tomodem-dem"
  std::string version;        ///< tomodem version and git hash
  std::string parameters;     ///< the effective parameters as text (YAML)
  std::map<std::string, std::string> input_hashes;  ///< input path -> content hash (hex)
  double wall_time_s = 0;
  std::string created_utc;    ///< ISO 8601
};

struct Packing {
  ParticleTable particles;
  Cell cell;
  BondTable bonds;
  ContactTable contacts;
  std::vector<Material> materials;
  Results results;
  Provenance provenance;
};

/// The particles with keep[i] != 0, in their order: contacts and bonds between kept particles
/// re-indexed, the optional columns and the result series whose columns all have one value per
/// particle filtered alike; cell, materials, result scalars and provenance copied.
Packing select_particles(const Packing& p, const std::vector<uint8_t>& keep);

}  // namespace tomodem
