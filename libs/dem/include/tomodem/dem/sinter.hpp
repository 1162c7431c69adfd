#pragma once
// Sintering in the DEM core (docs/sintering.md): temperature programs, free and constrained
// sintering of a periodic packing under the `sintering` contact law, stops at a target relative
// density or time, and the necks handed over as bonds.
#include <functional>
#include <string>
#include <vector>

#include "tomodem/core/packing.hpp"
#include "tomodem/dem/bonds.hpp"
#include "tomodem/dem/scene.hpp"
#include "tomodem/dem/simulation.hpp"
#include "tomodem/spatial/overlap.hpp"

namespace tomodem::dem {

constexpr double kBoltzmann = 1.380649e-23;  ///< J/K
constexpr double kGasConstant = 8.314462618; ///< J/(mol K)

/// Piecewise-linear temperature history: from `start`, each segment either ramps at `rate`
/// (K/s, > 0) to `target` (heating or cooling) or holds for `hold` seconds.
struct TemperatureProgram {
  struct Segment {
    double rate = 0;    ///< K/s (ramp), 0 for a hold
    double target = 0;  ///< K (ramp)
    double hold = 0;    ///< s (hold)
  };
  double start = 293.15;  ///< K
  std::vector<Segment> segments;
  double temperature(double t) const;  ///< K at time t (the last temperature after the end)
  double rate(double t) const;         ///< dT/dt at t, K/s
  double duration() const;             ///< s
  /// Start of the next segment boundary after t (the end of the program at most), s.
  double next_boundary(double t) const;
};

/// Sintering parameters of one phase (Arrhenius grain-boundary diffusion).
struct SinterPhase {
  bool sinters = false;
  double atomic_volume = 0;         ///< Ω, m³
  double boundary_diffusion = 0;    ///< δ_b D_b0, m³/s
  double activation_energy = 0;     ///< Q, J/mol
  double surface_energy = 0;        ///< γ_s, J/m²
  double dihedral_angle = 0;        ///< ψ, rad
  double tangential_viscosity = 0;  ///< η (dimensionless)
  /// Δ_b = Ω δ_b D_b0 exp(−Q/(R T))/(k T), m⁵/(N s).
  double delta_b(double T) const;
};

struct SinterSettings {
  TemperatureProgram program;
  std::vector<SinterPhase> phases;  ///< per material (scene order)
  double initial_neck = 0.05;       ///< a_min/R of a neck when its contact forms
  double target_density = 0;        ///< stop at this relative density (0: off)
  double max_time = 0;              ///< stop at this time, s (0: end of the program)
  bool fixed[3] = {false, false, false};  ///< cell axes held (constrained sintering); others stress-free
  double strain_per_step = 5e-6;    ///< accuracy: strain (ε̇ Δt) allowed per step (docs/sintering.md)
  double neck_area_per_step = 1e-3; ///< accuracy: relative growth of the mean neck area a² per step
  double temperature_step = 2.0;    ///< accuracy: K allowed per step
  double viscous_fraction = 0.5;    ///< Δt / (m_i/Σ η) after mass scaling (< 1: stable)
  bool conserve_volume = true;      ///< grow the radii so the union of the spheres keeps its volume
  int update_interval = 10;         ///< steps between mass-scaling, density and radius updates
  int output_rows = 200;            ///< rows of the densification curve (about)
  std::string curve = "densification.csv";
  std::string packing = "sintered.h5";
  std::string necks = "necks.csv";  ///< neck-size distribution (histogram of a/R)
  bool plots = true;                ///< densification, shrinkage and neck-size plots (PNG + SVG, gnuplot)
};

/// Reads the `sintering` section of a scene (docs/sintering.md) from scene.text; every problem is
/// an InputError naming the file, the field and the value.
SinterSettings read_sinter_settings(const Scene& scene);

/// One row of the densification curve.
struct SinterRow {
  long step = 0;
  double time = 0, temperature = 0;
  double density = 0;        ///< union of the spheres (exact: power-cell clipping) / cell volume
  double density_pairwise = 0;  ///< Σ 4/3 π r³ − Σ lens over V: the former estimate (low by the triple overlaps)
  double density_cell = 0;   ///< ρ₀ V₀ / V (mass conservation through the cell shrinkage)
  double rate = 0;           ///< dρ/dt, 1/s
  double shrinkage[3] = {0, 0, 0};  ///< 1 − L_k/L_k0 per cell axis
  double mean_neck_ratio = 0;       ///< ⟨a/R⟩ over sintering contacts (R = 2R_iR_j/(R_i+R_j))
  double coordination = 0;
  double time_step = 0, mass_scaling = 0;  ///< s; mean m/m_physical
};

struct SinterReport {
  std::vector<SinterRow> rows;
  SinterRow initial, final;
  std::string stop_reason;  ///< "target_density", "time", "program_end"
  long steps = 0;
  double wall_time_s = 0;
  double min_time_step = 0, max_time_step = 0, max_mass_scaling = 0;
  /// Largest Δt Σ_c(η_n + 5η_t)/m_i of any particle and step, over the contacts of that step's
  /// force pass: leapfrog's viscous rows are stable below 2; the mass scaling aims at
  /// viscous_fraction (0.5), a fresh neck on a particle with no other neck gives up to that too.
  double max_viscous_step_ratio = 0;
  /// Largest |ρ_union − ρ₀V₀/V| / (ρ₀V₀/V) over the rows, snapshots and the end (mass conservation,
  /// docs/sintering.md); above kMassTolerance with conserve_volume on, the run has lost (or made) mass.
  double max_mass_mismatch = 0;
  /// Radius updates whose uniform correction hit its bound (each halves the step for a while).
  long mass_catch_ups = 0;
};

/// Relative mismatch between the union density and ρ₀V₀/V that a volume-conserving run keeps to:
/// the Newton update leaves a second-order residual (≈ 1e-6) and the density checks run right after
/// an update; 1e-3 is what the cell's shrinkage is known to (docs/sintering.md, "Mass conservation").
constexpr double kMassTolerance = 1e-3;

/// Relative density of the spheres from their exact union volume (each sphere clipped to its
/// power cell: spatial/union_volume.hpp), and the mean neck ratio ⟨a/R⟩.
struct DensityState {
  double solid_volume = 0, density = 0, mean_neck_ratio = 0;  ///< density: exact union / cell
  double density_pairwise = 0;  ///< pairwise lens sum (triple overlaps subtracted twice)
  long contacts = 0;
};
DensityState density_state(const Simulation& sim);  ///< collective when decomposed
/// Volume of the lens shared by two spheres at centre distance d, m³ (0 when apart).
using spatial::lens_volume;

/// Sets Δ_b, γ_s, ψ and η of every phase pair for temperature T (K). Unlike sintering phases
/// combine as: Δ_b geometric mean, γ_s, ψ and η arithmetic means; a pair with a non-sintering
/// phase gets Δ_b = 0 (Hertz repulsion).
void apply_temperature(ContactModel& model, const std::vector<SinterPhase>& phases, double T, double initial_neck);
/// The same for a running simulation (through Simulation::set_sinter_values).
void apply_temperature(Simulation& sim, const std::vector<SinterPhase>& phases, double T, double initial_neck);

/// Checks the settings against the scene's packing (target above the start, the program reaches
/// sintering temperatures); throws InputError naming the field.
void check_sinter_settings(const Scene& scene, const SinterSettings& s);

/// Runs the program on a scene's simulation: mass scaling and the automatic step, the stress-free
/// (or constrained) cell, radius growth; restores the physical masses at the end. On a decomposed
/// simulation (decomposition.hpp) it is collective and every rank gets the same report
/// (docs/sintering.md, "On several ranks"); snapshots are refused there.
SinterReport run_sintering(Simulation& sim, const SinterSettings& s, bool progress = false);

/// Snapshots of one run at given relative densities (tomodem-sinter --snapshots-at): `take(sim,
/// row, k)` is called once per density, ascending, the first time the density check (every
/// update_interval steps, after the radius update) finds the run at or above densities[k]; the
/// simulation then has its scaled masses and its velocities (the run goes on after the call).
struct SinterSnapshots {
  std::vector<double> densities;
  std::function<void(Simulation&, const SinterRow&, std::size_t)> take;
};
SinterReport run_sintering(Simulation& sim, const SinterSettings& s, bool progress, const SinterSnapshots& snapshots);

/// Estimate of the relative density the program reaches: two free spheres of the mean radius
/// (quasi-static, neck from initial_neck R) integrated over the whole program give the linear
/// shrinkage s; the packing's density then scales as rho0 / (1 - s)^3 (mass conservation, affine
/// shrinkage). The mean-field strain rate of a packing is this pair's rate for equal necks, and
/// larger necks are slower, so it is an estimate from above for a packing (docs/sintering.md).
double program_reach_estimate(const Simulation& sim, const SinterSettings& s);

/// The first half of sinter_packing: a green packing as a periodic sintering scene with the
/// settings file's `sintering` and `physics` sections (the same checks and messages).
Scene sinter_scene(const Packing& green, const std::string& source, const std::string& settings_file, int threads = 1);

/// The necks as bonds: every sintering contact becomes a bond with radius = neck radius and
/// rest length = current centre distance (image through the periodic cell). Decomposed: collective,
/// the whole sample's necks on every rank in the serial order, i and j the particle ids.
BondSet necks_to_bonds(const Simulation& sim);
/// The same as the /bonds table of the shared data model.
BondTable necks_to_bond_table(const Simulation& sim);
/// a/R̄ of every neck of a bond set (R̄ = 2R_iR_j/(R_i+R_j) from the particles' radii).
std::vector<double> neck_ratios(const BondSet& bonds, const std::vector<double>& radius);

/// A packing sintered to a target density: tomodem-bond's `sinter` method (necks → bonds).
struct SinteredPacking {
  Packing packing;               ///< particles, cell and materials after sintering; necks as /bonds
  std::vector<Vec3> bond_image;  ///< per bond: x_j + H·image − x_i is the bond vector (i < j)
  SinterReport report;
};
/// Sinters a green packing (its particles, materials and periodic cell) with the settings of a
/// sintering file: the `sintering` section of a tomodem-sinter scene (docs/sintering.md) and an
/// optional `physics` section with `tangential` (none | viscous) and `restitution` (Hertz pairs of
/// non-sintering phases). `target_density` > 0 replaces sintering.stop.relative_density; a program
/// that ends below the target is an InputError. `source` names the packing in messages.
SinteredPacking sinter_packing(const Packing& green, const std::string& source, const std::string& settings_file,
                               double target_density, int threads = 1, bool progress = false);

}  // namespace tomodem::dem
