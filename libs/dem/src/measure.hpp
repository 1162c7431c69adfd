#pragma once
// Measurements from a tally pass (stress, energies, contact counts, unbalanced force, inertial
// number) and the energy accounts of tracked runs.
#include <limits>

#include "sim_state.hpp"

namespace tomodem::dem {

/// Energy budget of tracked runs (Settings::track_energy), J.
struct EnergyAccount {
  double dissipated = 0, ext_work = 0, e0 = std::numeric_limits<double>::quiet_NaN();
  /// Work of gravity, moving walls, grips and the deforming cell over this step (midpoint velocities).
  void add_external_work(const SimState& s, const Tally& last);
};

/// The periodic cell's volume; with walls, the box between opposite walls along their normals
/// (falling back to the cell volume for open directions), m³.
double measurement_volume(const SimState& s);
/// Translational + rotational kinetic energy of the free particles, J.
double kinetic_energy(const SimState& s);
/// Everything Measurements holds that a tally pass `tl` on the current state gives (bonds and
/// neighbour rebuilds are the caller's).
Measurements measurements_from(const SimState& s, const Tally& tl, const EnergyAccount& energy);

}  // namespace tomodem::dem
