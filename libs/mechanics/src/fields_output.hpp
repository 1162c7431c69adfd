#pragma once
// The --fields output of tomodem-young and tomodem-fracture (docs/cg.md#fields-of-young-and-fracture):
// the solvers' loaded state handed to libs/fields as a LoadedNetwork. Private to libs/mechanics.
#include <string>
#include <vector>

#include "tomodem/fields/block.hpp"
#include "tomodem/mechanics/elastic.hpp"
#include "tomodem/mechanics/fracture.hpp"

namespace tomodem::mechanics {

/// The linear response under uniaxial stress along `axis` at axial strain `strain` (shear strains
/// held at zero, the lateral strains free: the explicit test's state): coarse-grained and written.
/// Returns the summary object (JSON text).
std::string young_fields(const fields::FieldsSettings& fs, const Packing& p, const std::vector<Image>& image,
                         const BondStiffnesses& k, ImplicitOptions io, int axis, double strain, const std::string& file);

/// The fields' width and grid against the sample (free faces at x and z), before any solve.
void check_fracture_fields(const fields::FieldsSettings& fs, const FractureSample& s);
/// The state at the peak load of the sequentially linear analysis `sla`: coarse-grained and written.
std::string fracture_fields(const fields::FieldsSettings& fs, const FractureSample& s, const std::vector<dem::BondLaw>& laws,
                            const FailureOptions& f, const SlaOptions& o, const FractureResult& sla, const std::string& file);

}  // namespace tomodem::mechanics
