#pragma once
// The DEM engine: particles, a (possibly periodic, deforming) cell, planar walls, a contact
// model, and velocity-Verlet integration. Stages a scene does not use (rotation, tangential
// history, adhesion, walls, cell deformation, energy tallies) cost nothing: the force loop
// is compiled per law combination and the integrator skips absent stages.
#include <array>
#include <memory>
#include <string>
#include <vector>

#include "tomodem/core/packing.hpp"
#include "tomodem/core/vec3.hpp"
#include "tomodem/dem/bonds.hpp"
#include "tomodem/dem/model.hpp"
#include "tomodem/dem/particles.hpp"

namespace tomodem::dem {

#if TOMODEM_HAVE_MPI
class DomainHooks;  // decomposition.hpp (MPI build only)
#endif

/// A rigid plane; particles interact with it through the scene's contact law (R* = R, m* = m).
struct Wall {
  Vec3 point;               ///< a point on the plane, m
  Vec3 normal{0, 0, 1};     ///< unit normal pointing into the particle side
  Vec3 velocity;            ///< imposed velocity, m/s (velocity control)
  int phase = 0;            ///< material of the wall
  /// Force control: the wall moves along its normal so that the normal force the particles
  /// exert on it reaches target_force (N, compressive positive); velocity is then derived.
  bool force_controlled = false;
  double target_force = 0;
  double servo_gain = 0;    ///< m/(N s); 0 = chosen from the contact stiffness
  // Measured (last step): total force the particles exert on the wall, N.
  Vec3 force;
};

/// How the periodic cell moves: an imposed velocity gradient L (H' = L H), with chosen
/// components replaced by a stress servo (mixed control, e.g. uniaxial stress).
struct CellControl {
  Mat3 velocity_gradient;                 ///< 1/s
  bool stress_controlled[3][3] = {};      ///< component (a,b) servo-controlled
  Mat3 target_stress;                     ///< Pa, tension positive
  double max_strain_rate = 0;             ///< cap of the servo's strain rate, 1/s (0 = none)
  double servo_gain = 0.5;                ///< stress error closed per elastic-wave transit time of the cell
  bool active() const;
};

struct BodyForces {
  Vec3 gravity;                  ///< m/s²
  double local_damping = 0;      ///< Cundall's non-viscous damping λ: F -= λ|F| sign(v), per component
  double fluid_viscosity = 0;    ///< Stokes drag F = -6π η R v, Pa s
};

struct Settings {
  double skin = 0;               ///< Verlet skin, m (0: 0.1 × mean diameter)
  int threads = 1;
  bool track_energy = false;     ///< accumulate dissipation every step (energy budget)
  int check_interval = 100;      ///< steps between stability checks
  bool scalar_kernels = false;   ///< use the scalar force loops everywhere (cross-checks)
  /// Four-wide loops: test only the listed pairs whose gap at the build the motion since could
  /// have closed (docs/dem.md, "Neighbour list"); false tests every listed pair (cross-checks).
  bool pair_bands = true;
};

/// Everything one measurement gives. Stress is the Love–Weber tensor, tension positive,
/// contact plus kinetic parts, over the cell volume (periodic) or the wall box.
struct Measurements {
  long step = 0;
  double time = 0;                 ///< s
  Mat3 stress;                     ///< Pa
  Mat3 stress_contact;             ///< Pa
  double pressure = 0;             ///< -tr(σ)/3, Pa
  double volume = 0;               ///< m³
  double kinetic_energy = 0;       ///< translational + rotational, J
  double elastic_energy = 0;       ///< stored in contacts, J
  double dissipated_energy = 0;    ///< damping, friction slip, body damping (tracked runs), J
  double external_work = 0;        ///< gravity, walls, cell deformation (tracked runs), J
  double energy_balance_error = 0; ///< (E_kin+E_el+E_diss) - (E_0+W_ext), J
  long contacts = 0;               ///< particle–particle contacts carrying force
  long bonds = 0;                  ///< intact bonds
  long wall_contacts = 0;
  double coordination = 0;         ///< 2 contacts / N (walls not counted)
  double unbalanced_force_ratio = 0;  ///< mean |ΣF_i| / mean |F_contact|
  double net_force_rms = 0;        ///< root mean square of |ΣF_i| over the free particles, N
  double inertial_number = 0;      ///< |ε̇| d sqrt(ρ/p) under cell deformation, else 0
  double max_overlap_ratio = 0;    ///< max δ / min(R_i, R_j)
  std::vector<Vec3> wall_forces;   ///< N, per wall
  long neighbor_rebuilds = 0;
  long pair_tests = 0;             ///< distance tests of listed pairs so far (this rank's)
};

class Simulation {
 public:
  /// `materials` gives density per phase (mass of the particles is set from it by Particles::add).
  Simulation(Particles particles, Cell cell, ContactModel model, Settings settings = {});
  ~Simulation();
  Simulation(Simulation&&) noexcept;
  Simulation& operator=(Simulation&&) noexcept;

  Particles& particles();
  const Particles& particles() const;
  const Cell& cell() const;
  Cell& cell();  ///< the cell may be replaced between steps (e.g. on restart)
  const ContactModel& model() const;
  /// The kernels were chosen from the model when the Simulation was built, so it is read-only;
  /// the sintering driver changes only the per-temperature pair values (docs/sintering.md).
  void set_sinter_values(int phase_a, int phase_b, const SinterValues& v);
  const Settings& settings() const;
  std::vector<Wall>& walls();
  const std::vector<Wall>& walls() const;
  CellControl& cell_control();
  const CellControl& cell_control() const;
  BodyForces& body_forces();
  void add_wall(const Wall& w);

  /// Largest step the current state allows: Rayleigh time of the smallest particle for the
  /// Hertz family, the two-particle Verlet limit 2 sqrt(m*/k)(sqrt(1+ζ²)-ζ) for linear laws.
  double critical_time_step() const;
  /// Viscous laws (sintering): fills Σ_c (η_n + 5 η_t) per particle over its current contacts, N s/m
  /// (the explicit limit is Δt < m_i / that sum) and returns Σ_c η_n l_c² (N s m, l the branch
  /// length), from which the cell's viscous modulus Σ η l²/(5V) follows. Zero for elastic laws.
  double viscous_sums(std::vector<double>& per_particle) const;
  /// Contact stress of the last tally pass (every step while the cell deforms), Pa, tension positive.
  Mat3 contact_stress() const;
  /// Per-particle Σ S_c of the last tally pass (measure()): tangent normal stiffness of the
  /// force-carrying contacts and intact bonds, N/m. Empty before the first measurement.
  const std::vector<double>& stiffness_sums() const;
  /// Sets Δt; throws InputError when it exceeds critical_time_step(). `check_limit` false is for
  /// callers that keep the step stable by other means (FIRE with stiffness-scaled masses, whose
  /// limit is the contact network's, not the Rayleigh time of the physical particles).
  void set_time_step(double dt, bool check_limit = true);
  double time_step() const;
  double time() const;
  long step_count() const;

  void step();
  void run(long steps);
  /// Measures the current state (one extra force tally pass).
  Measurements measure();
  /// Call after changing particles (count or positions) from outside.
  void invalidate_neighbors();
  /// Names the allocated optional stages ("rotation", "tangential history", ...).
  std::string describe() const;

  /// Bonded-particle model: bonds (i < j) with one law per phase pair (or one for all) and a
  /// failure criterion. Bonded pairs leave the contact list until their bond breaks.
  void set_bonds(BondSet bonds, std::vector<BondLaw> laws, BondFailure failure = BondFailure::none);
  const BondSet& bonds() const;
  const std::vector<BondLaw>& bond_laws() const;
  void set_bond_laws(std::vector<BondLaw> laws);
  const std::vector<BondEvent>& bond_events() const;

  /// Contact network snapshot (i < j, overlap, forces on j from i).
  ContactTable contacts();
  /// Everything beyond particles, cell and walls that the next step depends on: the neighbour
  /// list with its contact history, the last forces, clocks and energy accounts. Saving and
  /// restoring it (with the particles, cell and walls) makes a restart bit-exact.
  struct EngineState {
    std::vector<int32_t> start, j;
    std::vector<uint8_t> image, touching;
    std::vector<double> history;
    std::vector<Vec3> x_at_build;
    Mat3 h_at_build;
    std::vector<std::vector<int32_t>> wall_candidates;
    std::vector<std::vector<double>> wall_history;
    std::vector<std::vector<uint8_t>> wall_touching;
    std::vector<Vec3> wall_point_at_build;
    std::vector<Vec3> force, torque;
    bool forces_valid = false;
    double dt = 0, time = 0;
    long step = 0, builds = 0;
    double dissipated = 0, external_work = 0, initial_energy = 0;
    BondSet bonds;
    std::vector<BondEvent> bond_events;
  };
  EngineState engine_state() const;
  /// Restores a state saved from a simulation with the same particles, model and walls.
  void restore(const EngineState& state);

#if TOMODEM_HAVE_MPI
  /// Hands the synchronisation points (ghost refresh, re-neighbouring, reductions) to a domain
  /// decomposition (decomposition.hpp: use decompose()); rebuilds the list at once.
  void attach_domain(std::unique_ptr<DomainHooks> domain);
  DomainHooks* domain() const;  ///< null for a serial run
#endif

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace tomodem::dem
