#pragma once
// How the boundaries move: the affine field of a deforming cell, the cell's stress servo
// (mixed control) and the force-controlled walls.
#include <vector>

#include "neighbour_list.hpp"
#include "sim_state.hpp"

namespace tomodem::dem {

/// u_i = v_i + L (x_i − origin): fluctuation plus the affine field of the deforming cell.
void absolute_velocities(const SimState& s, std::vector<Vec3>& u);
/// Positions (and the cell, when it deforms) and walls advanced by one step.
void drift(SimState& s);
/// Sets the stress-controlled components of L from the last tally pass (virial, stiffness sums).
void servo_cell(SimState& s, const Tally& last, const std::vector<double>& stiffness);
/// Sets the velocity of each force-controlled wall from its force error.
void servo_walls(SimState& s, const NeighbourList& nl);

}  // namespace tomodem::dem
