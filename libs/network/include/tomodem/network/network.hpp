#pragma once
// The resistor network of a packing: nodes are the particles of the conducting phases, edges are
// intact bonds (radius a_b) and contacts (contact radius a) with the Holm constriction
// conductance (docs/physics.md#resistor-networks):
//   R_ij = 1/(4 σ_i a) + 1/(4 σ_j a)      (one half-space constriction per side, in series)
// limited, in dense networks, by the flux tube of the face the pair shares in the radical
// (Laguerre) tessellation: per side the prism d/(σA) in series with the disc's constriction in
// a tube of the face's area, ψ(a/b)/(4σa) (docs/conduct.md#neck-conductance).
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <string>
#include <vector>

#include "tomodem/core/packing.hpp"
#include "tomodem/network/graph.hpp"
#include "tomodem/spatial/image.hpp"

namespace tomodem::network {

enum class ContactRadius {
  geometric,  ///< radius of the circle where the two spheres intersect
  hertz,      ///< a = sqrt(R* δ) (Hertz, docs/physics.md#resistor-networks): √2 smaller than geometric for small δ
  hertz_force,  ///< a = (3 F R* / 4 E*)^(1/3) from the packing's contact forces (/contacts/normal_force)
};
ContactRadius parse_contact_radius(const std::string& name);  ///< "geometric" | "hertz" | "hertz-force"

struct NetworkOptions {
  std::vector<std::string> phases;  ///< conducting phases by material name; empty = every phase
  bool use_bonds = true;            ///< intact bonds are edges with a = a_b
  bool use_contacts = true;         ///< detected contacts are edges (pairs with a bond use the bond)
  double gap_tolerance = 1e-3;      ///< contact: gap ≤ gap_tolerance · R̄ (spatial::in_contact)
  ContactRadius contact_radius = ContactRadius::geometric;
  /// Floor of the contact radius, as a fraction of R*: touching pairs (overlap ≤ 0 within the
  /// gap tolerance) would otherwise have a = 0 and no conductance.
  double min_contact_ratio = 0.01;
  /// Dense-network law: each edge's conductance limited by the pair's Laguerre face, edges whose
  /// pair shares no face left out; false: every neck as if alone (--isolated-necks).
  bool face_cap = true;
  /// With face_cap: the limit is flux_tube_conductance() (neck_law "flux_tube"); false: the
  /// face's two-point flux face_conductance() (neck_law "face_capped", the law before issue 18
  /// item 7, which reaches the solid's σ in cells with pores).
  bool flux_tube = true;
  std::string source = "";          ///< file name for error messages
};

enum class EdgeKind : uint8_t { bond = 0, contact = 1 };

struct Network {
  // Nodes
  std::vector<int32_t> particle;  ///< packing index of each node
  std::vector<Vec3> position;     ///< m (as in the packing, not wrapped)
  std::vector<double> radius;     ///< m
  std::vector<int32_t> phase;     ///< material index
  std::vector<double> node_conductivity;  ///< S/m, of the node's phase
  // Edges (graph.i/j index nodes; graph.g = conductance, S)
  Graph graph;
  std::vector<double> contact_radius;       ///< a, m
  std::vector<spatial::Image> image;  ///< j is taken in the periodic image x_j + h·image
  std::vector<EdgeKind> kind;
  /// Area of the pair's Laguerre face, m² (+inf on the hull of an open cell direction); empty
  /// without the face cap.
  std::vector<double> face_area;
  std::size_t face_capped = 0;  ///< edges whose conductance is the face limit's (below Holm's)
  std::size_t no_face = 0;      ///< contacts and bonds left out: their pair shares no face
  // Geometry
  Cell cell;
  std::vector<std::string> phase_names;  ///< all materials, by index
  std::vector<uint8_t> conducting;       ///< per material
  std::size_t n_nodes() const { return particle.size(); }
  std::size_t n_edges() const { return graph.n_edges(); }
  /// Branch vector from node i to node j of edge e, m.
  Vec3 branch(std::size_t e) const;
};

/// Pairs of spheres in contact (spatial::in_contact with the gap tolerance), found with the grid
/// of libs/spatial (O(N); images −1..1 along periodic cell directions). Returned with i < j and
/// the image of j relative to the positions as given.
struct ContactPairs {
  std::vector<int32_t> i, j;
  std::vector<spatial::Image> image;
};
ContactPairs find_contacts(const std::vector<Vec3>& position, const std::vector<double>& radius, const Cell& cell,
                           double gap_tolerance);

/// Holm conductance of a contact of radius a between phases of conductivity s1 and s2, S.
inline double holm_conductance(double a, double s1, double s2) { return 4.0 * a * s1 * s2 / (s1 + s2); }

/// Two-point flux conductance of a Laguerre face of area A between spheres i and j at distance L,
/// S: the face lies on the radical plane at d_i = (L² + r_i² − r_j²)/(2L) from i (clamped to
/// [0, L]), the two half-cells in series. Equal phases: σ A/L, exact for a uniform field because
/// the face is normal to the branch (docs/conduct.md#neck-conductance).
double face_conductance(double area, double L, double r_i, double r_j, double s_i, double s_j);

/// Constriction factor of a disc of radius a at the end of a semi-infinite circular flux tube of
/// radius b (Roess 1950; Cooper, Mikic & Yovanovich 1969): the resistance is ψ/(4σa), ψ = (1 − ε)^1.5,
/// ε = a/b clamped to [0, 1]; ψ = 1 (Holm) for a ≪ b, 0 when the disc fills the tube.
inline double tube_constriction(double a, double b) {
  const double e = b > 0 ? std::min(a / b, 1.0) : 1.0;
  return std::pow(1 - e, 1.5);
}

/// Resistance × σ of the solid from a centre to the face at distance d (1-D, x along the branch):
/// the sphere's circle π(R² − x²) clipped to the face area A (the prism d/A where the neck fills
/// the face). Where the circle narrows from A to the neck disc, the narrowing counts with the
/// weight 1 − ψ: a constriction ψ = 1 (a ≪ b) already holds the spreading from the neck, the
/// face's prism (ψ = 0) none of it.
double tube_body_resistance(double area, double a, double R, double d, double psi);

/// Flux-tube conductance of a neck of radius a across a Laguerre face of area A, S: per side the
/// solid from the centre to the face (tube_body_resistance) in series with the disc's
/// constriction in a tube of radius b = √(A/π), ψ(a/b)/(4σa) (Cooper, Mikic & Yovanovich 1969);
/// the edge takes the smaller of this and Holm's. Face_conductance() when the disc fills the
/// face; A = +inf (open face): Holm.
double flux_tube_conductance(double area, double a, double L, double r_i, double r_j, double s_i, double s_j);

/// The summary's name of the law of these options: "isolated_necks", "face_capped" or "flux_tube".
const char* neck_law_name(const NetworkOptions& options);

/// Builds the network; bad input (unknown phase names, a conducting phase with a non-positive
/// or non-finite conductivity, no particles, a bond index out of range) is an InputError naming
/// options.source, the field and the value.
Network build_network(const Packing& packing, const NetworkOptions& options);

}  // namespace tomodem::network
