#pragma once
// Fields written by the tools that hold a state in memory (docs/cg.md#fields-from-a-dem-run,
// docs/cg.md#fields-of-young-and-fracture): the `fields:` block of a tomodem-dem scene and
// `--fields` of tomodem-young and tomodem-fracture. Their files hold no contact or bond forces
// tomodem-cg could read, so the tools coarse-grain their own state. The settings are tomodem-cg's
// (one set of parsers, checks and messages; only the names in the messages differ: "--width",
// "fields.width (line 4)", "--fields-width"), and one writer makes the HDF5 + XDMF (+ VDB) files
// and the summary keys of all of them.
#include <cstdint>
#include <limits>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "tomodem/core/packing.hpp"
#include "tomodem/fields/cg.hpp"
#include "tomodem/spatial/image.hpp"

namespace tomodem::dem {
class Simulation;
}

namespace tomodem::fields {

/// How each setting is named in messages, and the file it was written in ("" the command line).
struct SettingNames {
  std::string file;
  std::string output = "-o", vdb = "--vdb", kernel = "--kernel", width = "--width", cutoff = "--cutoff",
              nodes = "--nodes", slice = "--slice", profile = "--profile", quadrature = "--quadrature";
};

/// Kernel, grid and outputs as the user wrote them (tomodem-cg's options).
struct FieldsSettings {
  std::string output;               ///< fields .h5; its .xdmf sidecar beside it ("" none asked)
  std::string vdb;                  ///< OpenVDB file of the scalar and vector fields ("" none; full grids only)
  std::string kernel = "gaussian";  ///< gaussian | lucy
  std::string width = "1";          ///< mean diameters ("1.5", "1.5d") or a length with a unit ("20um")
  double cutoff = 3;                ///< Gaussian cut-off in widths, [2, 8]
  std::string nodes;                ///< "N" or "NX,NY,NZ" along the cell vectors; "" a node every half width
  std::string slice;                ///< "z=0.5"
  std::string profile;              ///< "z"
  int quadrature = 0;               ///< points per branch (0: automatic)
  SettingNames names;
  bool requested() const { return !output.empty(); }
};

/// The settings resolved against a cell and a mean diameter.
struct FieldsSetup {
  double mean_diameter = 0;   ///< m
  double width = 0;           ///< m
  bool width_in_diameters = true;
  Kernel kernel;
  GridSpec grid;
};

/// "1.5" or "1.5d" (mean diameters) or a length with a unit: the width in metres.
double parse_width(const std::string& text, double mean_diameter, bool* in_diameters, const SettingNames& names);
/// The grid of the settings on `cell` (automatic: a node every half width along each cell vector).
GridSpec parse_grid(const FieldsSettings& s, const Cell& cell, double width);
/// Everything that needs no particles: kernel, cut-off, quadrature, grid text, slice/profile,
/// a VDB file asked with a slice or a profile. InputError (exit 2) naming the setting.
void check_settings(const FieldsSettings& s);
/// Checks and resolves against a cell and mean diameter: a width below half a mean diameter (the
/// kernel then resolves single particles, not a continuum) or above the cell's smallest extent is
/// refused, and a grid the memory does not hold.
FieldsSetup make_setup(const FieldsSettings& s, const Cell& cell, double mean_diameter);
/// The outputs the settings name, for check_outputs: the .h5, its .xdmf sidecar, the .vdb.
std::vector<std::pair<std::string, std::string>> output_names(const FieldsSettings& s);

/// Masses m = ρ (4/3)πR³ from the materials' densities (or `density` for every phase, kg/m³).
std::vector<double> particle_masses(const Packing& p, const std::string& file, double density = 0);

/// The snapshots of one run, accumulated on one grid, written with the usual provenance.
class FieldsOutput {
 public:
  /// `cell` and `mean_diameter` fix the grid (make_setup); `threads` 0: OpenMP's default.
  FieldsOutput(const FieldsSettings& s, const Cell& cell, double mean_diameter, int threads);
  ~FieldsOutput();
  FieldsOutput(FieldsOutput&&) noexcept;
  FieldsOutput& operator=(FieldsOutput&&) noexcept;
  void add(const Snapshot& s);
  int snapshots() const;
  const FieldsSetup& setup() const;
  /// Writes the fields file (HDF5 + XDMF) and the VDB when asked. Root attributes: tool,
  /// version, parameters (JSON text), created_utc, then `attributes` (e.g. state: which state).
  /// Returns the summary object as JSON text: outputs, grid, dims, n_points, kernel, width_m,
  /// width_mean_diameters, snapshots, n_contacts, n_bonds, total_mass_kg, mass_error,
  /// divergence_residual, love_static_stress_Pa, cg_mean_static_stress_Pa,
  /// mean_stress_difference, plus `attributes` as keys.
  std::string write(const std::string& tool, const std::string& parameters_json,
                    const std::vector<std::pair<std::string, std::string>>& attributes);

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

// ---- tomodem-dem: the `fields:` block ------------------------------------------------------

/// The `fields:` block of a scene (docs/cg.md#fields-from-a-dem-run): the settings above plus
/// when to take snapshots, MercuryDPM's timeMin/timeMax/saveCount.
struct FieldsBlock {
  bool present = false;
  FieldsSettings settings;   ///< output relative to tomodem-dem's --output-dir
  long every = 0;            ///< steps between snapshots; 0: the final state only
  double from = 0;           ///< s: no snapshot before this time
  double to = std::numeric_limits<double>::infinity();  ///< s: none after
  bool displacement = false; ///< displacement and strain from the state at the start of the run
  std::string text;          ///< the block as written (provenance)
};
/// Reads `fields:` of a scene (the text load_scene stored). Unknown keys, wrong types and values
/// out of range are InputErrors naming the scene file and "fields.<key> (line N)".
FieldsBlock parse_fields_block(const std::string& scene_text, const std::string& scene_file);

/// A DEM state as the coarse-graining sees it: the packing tomodem-dem writes (positions,
/// velocities relative to the affine field, contacts with their forces) through make_snapshot, so
/// the fields equal tomodem-cg's of that packing, plus the intact bonds with their elastic forces
/// (normal from the stretch, the accumulated shear force). `reference`: displacement from it.
Snapshot snapshot_of(dem::Simulation& sim, const std::vector<Material>& materials, const std::string& scene_file,
                     const Packing* reference = nullptr);

/// tomodem-dem's side of the block: checks it against the scene before the run, takes the
/// snapshots the run reaches, writes at the end.
class DemFields {
 public:
  /// InputError (exit 2, before any step) for what the block cannot do with this scene: a
  /// deforming cell with every > 0 (a time average needs one grid), a run on several ranks.
  DemFields(const FieldsBlock& b, dem::Simulation& sim, const std::vector<Material>& materials,
            const std::string& scene_file, const std::string& output_path, const std::string& vdb_path);
  ~DemFields();
  /// Steps between calls of at_step (0: never; the final state is taken by write()).
  long every() const;
  /// A snapshot of the current state when its step and time fall in the block's window.
  void at_step(dem::Simulation& sim);
  /// Takes the final state when no snapshot was taken, writes, returns the summary object (JSON text).
  std::string write(dem::Simulation& sim, const std::string& scene_text);

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

// ---- tomodem-young and tomodem-fracture: a loaded bonded network ---------------------------

/// What carries force between the two particles of a bond in the loaded state.
enum class PairRole : uint8_t { none = 0, bond = 1, contact = 2 };

/// A bonded network in a loaded state, as the elastic and fracture solvers hold it.
struct LoadedNetwork {
  const Packing* reference = nullptr;     ///< the unloaded network (positions, radii, materials, bonds)
  std::vector<spatial::Image> image;      ///< per bond: the image of j seen from i (unloaded)
  Cell cell;                              ///< the loaded cell (young: (I + ε)·H about the cell centre)
  std::vector<Vec3> displacement;         ///< per particle, m, from the unloaded position
  std::vector<Vec3> force;                ///< per bond: the force on j from i in this state, N
  std::vector<PairRole> role;             ///< per bond: bond, contact (closed faces of a broken bond) or none
};
/// The snapshot of a loaded network: positions x + u in the loaded cell, displacements u against
/// the unloaded cell, branch vectors x_j + H'·n + u_j − x_i − u_i, forces as given. No velocities.
Snapshot snapshot_of(const LoadedNetwork& s, const std::string& file);

}  // namespace tomodem::fields
