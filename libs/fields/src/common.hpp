#pragma once
// What tomodem-cg and the fields outputs of dem/young/fracture share beyond the public
// settings: the diagnostics of the summary, the Love stress, VDB output. Private to libs/fields.
#include <cmath>
#include <string>
#include <utility>
#include <vector>

#include "tomodem/fields/block.hpp"
#include "tomodem/fields/cg.hpp"

namespace tomodem::fields::detail {

struct Diagnostics {
  double mass_error = NAN, divergence_residual = NAN, stress_scale = 0;
  Mat3 mean_static;  ///< grid mean of σ_contact + σ_bond (full grids)
};
/// mass_error and divergence_residual (docs/cg.md#summary-json) of time-averaged fields.
Diagnostics diagnose(const Accumulator::Fields& f, GridSpec::Kind kind, double total_mass, double width);
/// Love-Weber static stress -(1/V) Σ F⊗d of one snapshot (contacts and bonds), Pa.
Mat3 love_static(const Snapshot& s);
/// |love - mean| / |love| (Frobenius), NaN when the Love stress is zero.
double relative_stress_difference(const Mat3& love, const Mat3& mean);

/// InputError of `fn` re-thrown with `file` (core's range checks name no file).
template <class F>
auto in_file(const std::string& file, F&& fn) -> decltype(fn());

/// Writes the scalar fields (density, pressure = -tr(σ)/3, von Mises of sym σ, |v|) and the vector
/// fields (velocity, momentum, divergence, displacement) of a full grid as OpenVDB grids whose
/// transform maps node (i0, i1, i2) to its position in metres (docs/cg.md#vdb-output); each grid
/// records its value unit and the length unit "m" as metadata, the file the root attributes.
/// Atomic (temporary name, rename). RuntimeFailure when the build has no OpenVDB.
void write_vdb(const std::string& path, const Accumulator::Fields& f, const Cell& cell,
               const std::vector<std::pair<std::string, std::string>>& attributes);
/// Whether this build writes VDB files.
bool have_vdb();

}  // namespace tomodem::fields::detail

#include "tomodem/core/error.hpp"

namespace tomodem::fields::detail {
template <class F>
auto in_file(const std::string& file, F&& fn) -> decltype(fn()) {
  try {
    return fn();
  } catch (const InputError& e) {
    if (!e.file().empty() || file.empty()) throw;
    throw InputError(file, e.field(), e.value(), e.why());
  }
}
}  // namespace tomodem::fields::detail
