#pragma once
// Restarting a decomposed run from a checkpoint (docs/dem.md, "Checkpoints"). MPI build only;
// this header includes no MPI header.
#include "tomodem/dem/decomposition.hpp"

namespace tomodem::dem {

/// decompose() for a simulation that every rank restored whole from a checkpoint
/// (read_checkpoint): the sub-domains, ghosts and neighbour list are rebuilt from the positions
/// and cell of the checkpoint's last neighbour-list build, then the checkpoint's positions,
/// forces, list history and rebuild clock are put back, so the run goes on as if it had never
/// stopped (bit for bit, with one thread per rank). Collective; throws as decompose().
void decompose_restored(Simulation& sim, const DecompositionOptions& opt = {});

}  // namespace tomodem::dem
