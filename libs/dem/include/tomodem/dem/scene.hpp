#pragma once
// A tomodem-dem scene: particles (from a packing file or generated), materials, physics,
// boundaries, a protocol and outputs, read from YAML (format: docs/dem.md).
#include <cstdint>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "tomodem/core/names.hpp"
#include "tomodem/core/packing.hpp"
#include "tomodem/dem/simulation.hpp"

namespace tomodem::dem {

struct Protocol {
  bool auto_timestep = true;
  double timestep = 0;            ///< s, when not automatic
  double timestep_fraction = 0.2; ///< of the critical step, when automatic
  long steps = 0;                 ///< total steps (from duration when given)
  long output_interval = 0;       ///< steps between time-series rows (0: 100 rows)
  double stop_unbalanced_force = 0;  ///< stop when the unbalanced-force ratio falls below (0: off)
  double stop_kinetic_energy = 0;    ///< stop when the kinetic energy falls below, J (0: off)
  long checkpoint_interval = 0;   ///< steps between checkpoints (0: only at the end, if asked)
};

struct SceneOutputs {
  std::string packing;     ///< final packing (.h5 + .xdmf), relative to the output folder
  std::string series;      ///< CSV time series
  std::string checkpoint;  ///< HDF5 checkpoint
};

/// Called by run_protocol at the steps that are multiples of `every` (the first step of the run
/// included): the coarse-graining snapshots of tomodem-dem's fields: block (docs/cg.md).
struct StepObserver {
  long every = 0;  ///< 0: never
  std::function<void(Simulation&)> at_step;
};

struct Scene {
  std::string file;        ///< the scene file, for messages
  std::string text;        ///< the scene as read, stored as provenance
  std::vector<Material> materials;
  std::unique_ptr<Simulation> sim;
  Protocol protocol;
  SceneOutputs outputs;
  std::vector<std::string> inputs;  ///< files the scene read (hashed into provenance)
  /// Time-series rows (series_columns()) of the runs before a restart, from the checkpoint: the
  /// series continues instead of starting again.
  std::vector<std::vector<double>> series_before;
  StepObserver observer;   ///< set by the tool (not read from the scene)
};

/// The columns of the time series (CSV header and /results/series/dem), with their units.
const std::vector<std::string>& series_columns();
std::vector<double> series_row(const Measurements& m);
/// series_before followed by this run's rows (the row at the restart step once).
std::vector<std::vector<double>> full_series(const Scene& scene, const std::vector<Measurements>& run);

/// Reads and validates a scene. Every problem is an InputError naming the file, the field
/// (with its line) and the value. `threads` > 0 overrides the scene's setting.
Scene load_scene(const std::string& path, int threads = 0);

/// A cubic lattice: simple cubic (1 site), BCC (2) or FCC (4 sites per cubic cell). Scenes and
/// tools parse the name at the edge (`particles.generate.arrangement`, pack's `arrangement`).
enum class LatticeKind : uint8_t { simple_cubic, bcc, fcc };
inline constexpr NameTable<LatticeKind, 3> kLatticeNames = {
    {{LatticeKind::simple_cubic, "simple_cubic"}, {LatticeKind::bcc, "bcc"}, {LatticeKind::fcc, "fcc"}}};
inline const char* to_string(LatticeKind l) { return name_of(kLatticeNames, l); }
inline std::optional<LatticeKind> parse_lattice(std::string_view name) { return value_of(kLatticeNames, name); }
/// Sites per cubic cell: 1, 2 or 4.
int lattice_basis_size(LatticeKind kind);

/// Lattice and random generators used by scenes and tests.
/// The sites of `kind`, n cells per side, spacing a.
std::vector<Vec3> lattice_sites(LatticeKind kind, int n, double a);
/// Random sequential insertion of `count` non-overlapping spheres of radius r in a box.
std::vector<Vec3> random_sites(int count, double r, const Vec3& lo, const Vec3& hi, bool periodic, unsigned seed);

/// One row of the time series.
struct SeriesRow {
  Measurements m;
};

struct RunReport {
  long steps = 0;                ///< steps done in this run
  double wall_time_s = 0;
  double particle_steps_per_second = 0;
  Measurements final;
  std::vector<Measurements> series;
  std::string stop_reason;       ///< "steps", "unbalanced_force", "kinetic_energy"
};

/// Runs the protocol from the current step to protocol.steps; measurements every
/// output_interval steps; checkpoints if asked (`checkpoint_path`, written atomically); the
/// scene's observer at the multiples of its `every`.
RunReport run_protocol(Scene& scene, const std::string& checkpoint_path, bool progress);

/// Checkpoint: particles, cell, walls, cell control and the engine state, bit-exact, and the time
/// series so far (`series`, rows of series_columns()).
void write_checkpoint(const std::string& path, const Simulation& sim, const std::string& scene_text,
                      const std::vector<std::vector<double>>& series = {});
/// What a restart found in the checkpoint besides the state.
struct RestartInfo {
  std::vector<std::string> physics_changes;  ///< "materials[0].density: 2500 -> 2600", ...
};
/// Restores a checkpoint into the simulation built from `scene`. Every dataset is checked
/// (presence, length, finite values, indices) before use: a damaged or foreign checkpoint is an
/// InputError naming the file and the dataset. The scene the checkpoint was written with is
/// compared with this one: a change of physics (materials, laws, time step, cell, walls,
/// boundary, particles) is refused naming what changed, unless `allow_changed_physics`, when the
/// changes are returned for the caller to warn about. The checkpoint's time series goes into
/// scene.series_before.
RestartInfo read_checkpoint(const std::string& path, Scene& scene, bool allow_changed_physics = false);
/// The physics fields that differ between two scene texts (empty when the same physics).
std::vector<std::string> physics_changes(const std::string& before, const std::string& now);

/// The shared data model of the final state (particles, cell, contacts, materials, results).
Packing to_packing(Simulation& sim, const std::vector<Material>& materials);
/// The same with the particle arrays moved out of `sim` instead of copied, for its last use (the
/// CLI's memory peak, issue 19): `sim` is left with empty positions, radii, phases, velocities and
/// spins, to be destroyed.
Packing to_packing(Simulation&& sim, const std::vector<Material>& materials);

}  // namespace tomodem::dem
