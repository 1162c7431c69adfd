#pragma once
// Time-step limits and the stability check: the step a state allows (Rayleigh time, two-particle
// Verlet limit, viscous necks, bonds), the contact network's Gershgorin bound, and the refusal
// (NumericalError, exit 3) of a run whose particles run away or overlap too far.
#include <vector>

#include "neighbour_list.hpp"
#include "sim_state.hpp"

namespace tomodem::dem {

/// Simulation::critical_time_step.
double critical_time_step(const SimState& s, const NeighbourList& nl);
/// Simulation::viscous_sums.
double viscous_sums(const SimState& s, const NeighbourList& nl, std::vector<double>& per_particle);
/// Gershgorin bound of the step from the per-particle stiffness sums of the last tally pass.
double network_critical_step(const SimState& s, const std::vector<double>& stiffness);
/// Throws NumericalError naming the particles when the state is no longer stable.
void check_stability(const SimState& s, const NeighbourList& nl, const Tally& last,
                     const std::vector<double>& stiffness);

}  // namespace tomodem::dem
