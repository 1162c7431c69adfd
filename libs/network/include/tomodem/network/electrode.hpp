#pragma once
// Composite electrodes (SOFC cathodes/anodes): an electronic and an ionic network coupled by
// charge-transfer conductances at the contacts between the two phases.
//   - electronic–electronic and ionic–ionic edges: Holm constriction conductance
//   - electronic–ionic contact of radius a: a triple-phase-boundary ring of length 2πa (the pore
//     phase surrounds every contact), conductance G_ct = g_ct · 2πa (linearised Butler–Volmer,
//     g_ct in S/m per metre of TPB)
//   - current collector: electronic particles touching the low face of `axis`, at `voltage`
//   - electrolyte: ionic particles touching the high face, at 0 V
// The electrode resistance is R = V / I between collector and electrolyte.
#include <string>
#include <vector>

#include "tomodem/core/packing.hpp"
#include "tomodem/network/conductivity.hpp"
#include "tomodem/network/network.hpp"

namespace tomodem::network {

struct CompositeOptions {
  std::vector<std::string> electronic;   ///< phase names (e.g. LSM, Ni)
  std::vector<std::string> ionic;        ///< phase names (e.g. YSZ)
  int axis = 2;
  double charge_transfer = 0;            ///< g_ct, S/m (per metre of TPB length), > 0
  NetworkOptions network;                ///< contact detection; `phases` is ignored
  ConductOptions conduct;
};

struct CompositeResult {
  bool percolates = false;        ///< a path collector → electrolyte exists
  double resistance_ohm = 0;      ///< R = V / I
  double asr_ohm_m2 = 0;          ///< area-specific resistance R · A
  double current = 0;             ///< A (mean of collector and electrolyte currents)
  double conservation_error = 0;  ///< |I_collector − I_electrolyte| / max
  double tpb_length_m = 0;        ///< Σ 2πa over electronic–ionic contacts
  double tpb_density_m_per_m3 = 0;
  double tpb_active_density_m_per_m3 = 0;  ///< contacts in clusters connecting both faces
  double charge_transfer_current_fraction = 0;  ///< Σ|I_ct| / I (≥ 1 when current crosses back and forth)
  std::size_t n_collector = 0, n_electrolyte = 0, n_tpb_contacts = 0;
  double electronic_percolating_fraction = 0, ionic_percolating_fraction = 0;
  SolverReport solver;
  double wall_time_s = 0;
  Network net;                    ///< the coupled network (conductances as solved)
  std::vector<double> potential, edge_current;
};

CompositeResult solve_composite(const Packing& packing, const CompositeOptions& options);

}  // namespace tomodem::network
