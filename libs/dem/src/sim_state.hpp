#pragma once
// What every part of the engine reads (docs/architecture.md, "The DEM engine"): particles, cell,
// walls, model, chosen kernels, bonds and clocks. The parts (neighbour_list, force_loop,
// boundary, stability, measure) keep their own state and take this one by reference;
// Simulation::Impl is this state plus the parts.
#include <cstdint>
#include <utility>
#include <vector>

#include "bond_kernel.hpp"
#include "kernel.hpp"
#include "tomodem/dem/simulation.hpp"
#if TOMODEM_HAVE_MPI
#include "tomodem/dem/decomposition.hpp"
#endif

namespace tomodem::dem {

struct SimState {
  SimState(Particles particles, Cell c, ContactModel m, Settings s)
      : p(std::move(particles)), cell(c), model(std::move(m)), set(s) {}

  Particles p;
  Cell cell;
  ContactModel model;
  Settings set;
  std::vector<Wall> walls;
  CellControl control;
  BodyForces body;
  KernelSet kern;
  int stride = 0;  // history doubles per contact
  int threads = 1;

  // Bonds (empty unless the scene has them).
  BondSet bonds;
  std::vector<BondLaw> bond_laws;
  BondFailure bond_failure = BondFailure::none;
  BondKernel bond_kernel[2] = {nullptr, nullptr};
  std::vector<BondEvent> bond_events;

  double dt = 0, t = 0;
  long nstep = 0;
#if TOMODEM_HAVE_MPI
  DomainHooks* domain = nullptr;  // the decomposition (decomposition.hpp); null when serial
#endif

  bool deforming() const { return control.active(); }
};

}  // namespace tomodem::dem
