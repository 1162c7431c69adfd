#pragma once
// The load-bearing section of a bond in a dense network (docs/fracture.md#dense-networks): a
// neck cannot carry load over more than the face its two particles share in the radical
// (Laguerre) tessellation, so where the laws cap the stiffness at that face the failure criterion
// takes its stresses on a disc of the face's area instead of the isolated neck's πa².
// Included only by the sources that need it (the SLA and the tests), not by network.hpp.
#include <cmath>
#include <vector>

#include "tomodem/mechanics/network.hpp"

namespace tomodem::mechanics {

/// Radius of the load-bearing disc of a neck of radius a whose pair shares a face of area
/// `face_area`: a while πa² fits the face, else sqrt(A_face/π) (equal area; the section moduli
/// πa_s³/4 and πa_s³/2 of the criterion follow from it). No face (0: the stiffness is capped at 0,
/// the bond carries nothing) and an open face (+inf) leave a.
inline double section_radius(double a, double face_area) {
  return face_area > 0 && face_area < M_PI * a * a ? std::sqrt(face_area / M_PI) : a;
}

/// The isolated neck equivalent to a bond of section radius a_s and springs k_n, k_t (capped at
/// the face or not): its factors g_n = k_n/(2E* a_s), g_t = k_t/(8G* a_s), so that the registry's
/// criteria (dem::bond_strength) see the bond's own stiffness. The LEFM criterion of an isolated
/// neck is F_c² = 4 k Γ A (k = 2E* a g_n, A = πa²): with this it holds for the capped spring and
/// the section A = πa_s² (docs/fracture.md#dense-networks). Unchanged for an uncapped neck.
inline dem::BondStiffness equivalent_neck(const dem::BondLaw& law, double a_s, double kn, double kt) {
  dem::BondStiffness k{kn, kt, 0, 0, kn / (2 * law.E_star * a_s), 0};
  if (law.G_star > 0) k.gt = kt / (8 * law.G_star * a_s);
  return k;
}

/// bond_stiffnesses with, per bond, the radius of its load-bearing section (section_radius of
/// the pair's face where its law caps at the face, the neck radius otherwise): one tessellation
/// for both.
BondStiffnesses bond_stiffnesses(const Packing& p, const std::vector<dem::BondLaw>& laws,
                                 std::vector<double>& section);

}  // namespace tomodem::mechanics
