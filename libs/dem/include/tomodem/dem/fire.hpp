#pragma once
// FIRE energy minimisation (Bitzek, Koskinen, Gähler, Moseler & Gumbsch, PRL 97 (2006) 170201)
// as a mode of the DEM integrator: the Simulation's own velocity-Verlet step, with the velocity
// mixed towards the force (v ← (1−α)v + α|v|F̂), the step grown while the power F·v stays
// positive and the motion stopped when it turns negative. At a fixed cell this relaxes a
// frictionless packing to a local minimum of its elastic energy (zero net force on every
// particle); with friction it is a quasi-static relaxation to mechanical equilibrium.
#include <functional>

#include "tomodem/dem/simulation.hpp"

namespace tomodem::dem {

struct FireOptions {
  double dt_start = 0.1;   ///< first step, fraction of Simulation::critical_time_step()
  /// Largest step, fraction of the critical (two-particle) step. A particle with Z contacts of
  /// stiffness k has ω² up to 2Zk/m (Gershgorin); at Z = 6 that is 2/sqrt(12) ≈ 0.41 of the
  /// two-particle limit, so 0.35 stays inside the network's stability limit.
  double dt_max = 0.35;
  double dt_min = 0.01;    ///< floor of the step after repeated stops
  int n_min = 5;           ///< Bitzek et al.: steps of positive power before the step grows
  double f_inc = 1.1, f_dec = 0.5, alpha_start = 0.1, f_alpha = 0.99;
  double unbalanced_force_ratio = 1e-4;  ///< converged: mean |ΣF_i| / mean |F_contact| below this
  /// N; when > 0, converged instead when the root-mean-square net force on the free particles is
  /// below it (adhesive packings, whose contact forces balance to zero pair by pair).
  double force_tolerance = 0;
  /// J: stop as soon as the elastic plus kinetic energy falls below this (an unjammed packing
  /// reaches zero; a caller bracketing a target pressure stops early once it is clearly below).
  double energy_floor = 0;
  long max_steps = 200000;
  /// Stiffness-scaled masses (density scaling of quasi-static DEM; a Jacobi preconditioner of
  /// the minimisation): every free particle gets m_i ∝ Σ_c S_c of its contacts, so all particles
  /// have the same stability margin and the step is set by the contact network instead of the
  /// Rayleigh time of the smallest particle. The minimum does not depend on the masses; the
  /// physical masses are restored at the end. Off: physical masses and the Rayleigh limit.
  bool scale_masses = true;
  /// Largest move of any particle in one step, fraction of the smallest radius (as LAMMPS's
  /// min_modify dmax): in an unjammed packing the mixing can send a particle into its
  /// neighbours faster than the masses (updated every check_interval steps) allow for. With
  /// adaptive_step_cap it is the largest cap, not the one always in force.
  double max_move = 0.02;
  /// The cap (max_move) and the floor of the scaled masses follow the motion: at every check 4×
  /// the largest step since the last, between max_move r_min / 10 and max_move r_min
  /// (docs/pack.md); scaled masses and Hertz-family normal laws only (a spring law's floor does
  /// not depend on the speed). Off: the fixed cap and the floor of a full-speed collision.
  bool adaptive_step_cap = true;
  int check_interval = 20;  ///< steps between measurements (one extra force pass each)
};

struct FireResult {
  bool converged = false;    ///< force criterion met with contacts carrying load
  bool below_floor = false;  ///< energy fell below energy_floor (or no contact carries force)
  long steps = 0;
  Measurements last;         ///< measurement at the stop
};

/// Minimises at the current cell (the cell control must be inactive). Local damping is switched
/// off during the minimisation and the caller's time step, damping and masses are restored afterwards.
/// Velocities are zero at the start and at a converged stop.
FireResult minimise_fire(Simulation& sim, const FireOptions& options = {});

/// The periodic cell as a degree of freedom of the minimisation (LAMMPS `fix box/relax` with
/// FIRE; Bitzek et al. 2006, Guénolé et al., Comput. Mater. Sci. 175 (2020) 109584): the
/// enthalpy H = U + P V is minimised over the particle positions and the cell's log strains ε_a
/// (one isotropic strain, or three on the diagonal of h), whose generalised forces are
/// −∂H/∂ε_a = V(−σ_aa − P) from the contact (virial) stress σ, tension positive.
struct EnthalpyOptions {
  double pressure = 0;             ///< target P, Pa (> 0)
  bool diagonal = false;           ///< three independent normal strains (else one isotropic)
  double pressure_tolerance = 0.01;  ///< converged also needs |p − P| / P below this
  /// Called every report_interval steps with the step count and the contact pressure.
  std::function<void(long, double)> report;
  long report_interval = 2000;
  /// Stop (not converged) as soon as the contact pressure first reaches the target: the jammed
  /// structure, to be polished at fixed cell.
  bool stop_on_arrival = false;
  /// FIRE's restart (stop on negative power) for the cell and the particles separately (a
  /// particle restart leaves the cell moving): the cell's work P ΔV then cannot keep the joint
  /// power positive while the particles climb (the stall of a relaxation at a fixed pressure,
  /// docs/pack.md). Off: one power over both, as a
  /// compression from the gas needs (the cell drives it; with separate restarts the arrival
  /// overshoots and the fixed-cell bracket that follows fails on Jamming.StagedEnthalpy...'s
  /// unstaged run).
  bool separate_cell_restart = false;
};

/// Minimises the enthalpy at target pressure from the current state: converged when the
/// unbalanced-force ratio is below options.unbalanced_force_ratio and the contact pressure is
/// within pressure_tolerance of the target. The cell moves through the engine's velocity
/// gradient (affine field, tangential springs kept and advanced by the relative motion only);
/// the cell control is left at rest. energy_floor and force_tolerance are not used.
FireResult minimise_enthalpy(Simulation& sim, const FireOptions& options, const EnthalpyOptions& cell);

}  // namespace tomodem::dem
