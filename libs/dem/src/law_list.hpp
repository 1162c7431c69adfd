#pragma once
// The registry list: every contact and bond law of every slot, one line each, in the order messages and
// docs/dem.md list them. Law files under src/laws/ are included by the generated header (CMake
// globs that folder), so a new law is its own file plus one line here.
#include "laws.hpp"
#include "sinter_law.hpp"
#include "tomodem_dem_law_files.hpp"

namespace tomodem::dem::law {

/// A list of law types; `End` closes each list so that every law line ends with a comma.
template <class... L>
struct List {};
struct End {};

using NormalLaws = List<
    NormalLinear,
    NormalHertz,
    NormalDMT,
    NormalJKR,
    NormalSintering,
    NormalLuding,
    End>;

using TangentialLaws = List<
    TangentialNone,
    TangentialLinear,
    TangentialMindlin,
    TangentialViscous,
    End>;

using RollingLaws = List<
    RollingNone,
    RollingElasticPlastic,
    End>;

using DampingLaws = List<
    DampingRestitution,
    DampingNone,
    End>;

/// Bond laws (src/laws/bond_*.hpp). The bond loop runs the first: a second law needs its key
/// per phase pair in BondLaw and a choice in select_bond_kernel.
using BondLaws = List<
    BondParallel,
    End>;

/// Bond failure criteria; each is its own instantiation of the bond loop.
using BondFailures = List<
    FailureNone,
    FailureStress,
    FailureLefm,
    End>;

}  // namespace tomodem::dem::law
