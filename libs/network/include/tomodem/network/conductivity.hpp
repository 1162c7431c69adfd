#pragma once
// Effective conductivity of a network: electrode faces at fixed potentials, or a periodic cell
// under an imposed mean potential gradient (full tensor from three solves). Percolation analysis
// (clusters, backbone, dead ends) comes first; only current-carrying clusters enter the solve.
#include <array>
#include <map>
#include <string>
#include <vector>

#include "tomodem/network/network.hpp"
#include "tomodem/network/solver.hpp"

namespace tomodem::network {

/// Fractions of one phase's particle volume (sum of (4/3)π r³ over its particles).
struct PhaseFractions {
  double percolating = 0;  ///< in a cluster that connects both electrodes (wraps the cell when periodic)
  double isolated = 0;     ///< in any other cluster: 1 - percolating
  double dead_end = 0;     ///< percolating but off the backbone: carries no current
  double backbone = 0;     ///< percolating - dead_end
};

struct ConductOptions {
  double electrode_tolerance = 0.05;  ///< open directions: a particle touches a wall when its surface is within tol · r of it
  double voltage = 1.0;               ///< V between the faces (low face at `voltage`, high face at 0)
  SolverOptions solver;
  bool keep_fields = true;            ///< fill potential / edge_current
};

struct AxisResult {
  int axis = 0;
  bool percolates = false;          ///< a cluster connects the two faces
  double sigma_eff = 0;             ///< S/m (0 without a path)
  double sigma_error = 0;           ///< S/m, estimated from the current balance and the residual
  double current_in = 0, current_out = 0;  ///< A through the low and the high face
  double conservation_error = 0;    ///< |in - out| / max(|in|, |out|)
  double length = 0, area = 0;      ///< m, m²: the sample length and cross-section used in σ = I L / (A ΔV)
  std::size_t n_low = 0, n_high = 0;       ///< particles joined to each plate (open direction: touching each wall)
  std::size_t n_solved = 0;         ///< nodes in the spanning clusters
  SolverReport solver;
  double wall_time_s = 0;
  double percolating_fraction = 0;  ///< volume fraction of conducting particles in spanning clusters
  double dead_end_fraction = 0;     ///< of conducting particle volume
  std::map<std::string, PhaseFractions> phases;  ///< per conducting phase
  std::vector<double> potential;    ///< V per node, NaN outside the solved clusters
  std::vector<double> edge_current; ///< A per edge, i → j, 0 outside
  std::vector<int8_t> terminal;     ///< per node: -1, 0 (joined to the low plate / wall), 1 (high)
  std::vector<uint8_t> backbone;    ///< per node
};

/// Electrodes on the two faces of the cell normal to `axis` (0, 1, 2); A is the cell cross-section
/// and σ = I L /(A ΔV). Periodic along `axis`: plates on the faces cut every branch that crosses
/// them, each node joined to the plate on its side by the share of the edge's resistance on that
/// side; L is the cell's thickness (a lattice of equal edges gives the periodic σ exactly, any
/// network at least the periodic σ_kk). Open along `axis`: the particles within
/// electrode_tolerance of a wall are the electrodes, L is the distance between their mean centre
/// planes (docs/conduct.md#boundary-conditions).
AxisResult solve_electrodes(const Network& net, int axis, const ConductOptions& options);

struct TensorResult {
  std::array<std::array<double, 3>, 3> sigma{};  ///< S/m, J = σ E
  std::array<AxisResult, 3> axes;  ///< per imposed field direction (sigma_eff = σ_kk)
  bool wraps[3] = {false, false, false};
  double wall_time_s = 0;
};

/// Periodic cell (all three directions periodic) under imposed mean fields E = e_k, k = 0..2:
/// v_i = u_i − E·x_i with u periodic, J = (1/V) Σ_edges I_ij b_ij. Clusters that do not wrap
/// around the cell carry no current and are left out; dead ends are nodes whose edges all carry
/// less than 1e-9 of the largest edge current.
TensorResult solve_periodic(const Network& net, const ConductOptions& options);

/// Volume-weighted fractions of `nodes` (flag per node) per phase and in total.
double volume_fraction(const Network& net, const std::vector<uint8_t>& flag);

}  // namespace tomodem::network
