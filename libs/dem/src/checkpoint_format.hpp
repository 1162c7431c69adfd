#pragma once
// What every checkpoint writer (checkpoint.cpp, mpi/checkpoint_mpi.cpp) stamps on its file and
// every reader checks (docs/dem.md, "Checkpoints").
#include <string>

namespace tomodem::dem {

/// The layout of the datasets; a reader refuses any other (exit 2).
constexpr double kCheckpointFormat = 1;

/// "0.1.0" of "tomodem 0.1.0 (git 1234abcd)": the release a checkpoint must match.
std::string release_version(const std::string& version);

}  // namespace tomodem::dem
