#pragma once
// The checkpoint writer of a decomposed run (checkpoint_mpi.cpp); write_checkpoint calls it.
#include <string>
#include <vector>

namespace tomodem::dem {

class Simulation;

/// Collective: every rank of MPI_COMM_WORLD writes the particles it owns (and their contact
/// history) into one file, in the serial layout, through HDF5's MPI-IO driver.
void write_checkpoint_ranks(const std::string& path, const Simulation& sim, const std::string& scene_text,
                            const std::vector<std::vector<double>>& series);

}  // namespace tomodem::dem
