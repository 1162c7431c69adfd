#pragma once
// Carving macropores into a homogeneous packing (docs/carve.md): a macropore geometry (OpenVDB
// level set, label volume, closed surface mesh, spheres or an analytic signed distance) is
// mapped onto the packing's cell, the particles inside are removed by a rule, and the result is
// measured (macroporosity achieved vs the geometry's, solid fraction away from the pores,
// floating particles and clusters). OpenVDB, CGAL and OpenCV stay inside the .cpp files.
#include <array>
#include <cstdint>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "tomodem/core/packing.hpp"
#include "tomodem/core/vec3.hpp"

namespace tomodem::carve {

/// An axis-aligned box, m.
struct Box {
  Vec3 lo, hi;
  Vec3 size() const { return hi - lo; }
  Vec3 centre() const { return 0.5 * (lo + hi); }
};

/// The macropores in their own (image) frame, in metres. distance() is a signed distance,
/// negative inside a macropore; beyond band() from the surface its magnitude may be capped at
/// band() (narrow-band level sets), the sign stays right. Points outside bounds() are solid
/// unless the mapping tiles the image. distance() must be safe to call from several threads.
class Macropores {
 public:
  virtual ~Macropores() = default;
  virtual double distance(const Vec3& p) const = 0;
  virtual Box bounds() const = 0;
  /// Distances are exact up to this magnitude (m); infinity for exact distance fields.
  virtual double band() const;
  /// Length of the finest detail (voxel size, mesh edge), m: finite-difference steps and the
  /// default resolution of the integration grid.
  virtual double resolution() const = 0;
  virtual std::string describe() const = 0;
};

/// OpenVDB FloatGrid level set (negative inside), as tomodem-segment writes it. A level set does
/// not store the extent of the image it came from: bounds() is the macropores' bounding box (the
/// active narrow band less its width); Mapping::image_box places a larger image. World units:
/// `metres_per_unit` > 0 overrides; otherwise the grid's metadata `metres_per_unit` (or `units`
/// "m"/"mm"/"um"), and without either metres are assumed with a warning. `grid` "" takes the
/// grid named "macropores", else the first float grid. InputError: unreadable file, no float
/// grid, no interior (no negative value).
std::unique_ptr<Macropores> load_level_set(const std::string& path, const std::string& grid = "",
                                           double metres_per_unit = 0);

/// Label volume (any format image::read_volume reads; HDF5 dataset `dataset`, default
/// "/labels" of tomodem-segment): voxels whose value is one of `labels` (empty: any non-zero)
/// are macropore. The signed distance is the exact Euclidean distance transform of the voxel
/// set (surfaces on the voxel faces), interpolated trilinearly. `spacing` > 0 overrides the file's.
std::unique_ptr<Macropores> load_label_volume(const std::string& path, const std::string& dataset,
                                              const std::vector<int>& labels, double spacing = 0);

/// Closed triangle surface mesh (STL, OFF, PLY, OBJ: CGAL Polygon_mesh_processing IO), in units of
/// `metres_per_unit` (default 1: the mesh is in m). Inside test by ray parity against an AABB tree
/// (CGAL Side_of_triangle_mesh), distance to the tree. InputError: unreadable, not closed (border
/// edges counted), no volume.
std::unique_ptr<Macropores> load_mesh(const std::string& path, double metres_per_unit = 1);

/// Spheres as macropores (e.g. pore formers): the particles of a packing file, or given directly.
/// The bounds are the packing's cell (a periodic cell: the spheres' periodic images are included,
/// so tiling the bounds repeats them seamlessly). Only axis-aligned boxes.
std::unique_ptr<Macropores> load_spheres(const std::string& packing_path);
std::unique_ptr<Macropores> make_spheres(std::vector<Vec3> centres, std::vector<double> radii, const Box& bounds,
                                         bool periodic = false);

/// An analytic signed distance (tests, phantoms): `sdf` in m, negative inside.
std::unique_ptr<Macropores> make_analytic(std::function<double(const Vec3&)> sdf, const Box& bounds, double resolution,
                                          std::string name = "analytic");

/// Image frame -> packing frame: p_pack = cell centre + offset + scale · R · (p_img − image centre),
/// R = Rz(γ) Ry(β) Rx(α) (degrees). `fit`: the scale is chosen so the image box just fits the
/// cell's bounding box (smallest ratio of the extents). `tile`: the image repeats with its box as
/// the period (for packings larger than the image). The image box is the geometry's bounds()
/// unless `use_image_box` gives it (m, image frame).
struct Mapping {
  bool use_image_box = false;
  Box image_box;
  double scale = 1;
  Vec3 offset{0, 0, 0};               ///< m
  std::array<double, 3> rotation_deg{0, 0, 0};
  bool fit = false;
  bool tile = false;
};

enum class Rule { centre, fraction };
/// What happens to a particle cut by the surface (neither wholly inside nor wholly outside).
enum class Cut { rule, keep, remove };
/// How the inside volume fraction of a cut particle is obtained: `exact` = sphere/surface overlap
/// with the surface approximated by the sphere (or plane) of the signed distance's local mean
/// curvature (exact for spherical and planar pores; falls back to sampling where the level set's
/// band is too narrow); `sample` = points of a cubic grid in the sphere.
enum class FractionMethod { exact, sample };

struct Options {
  Mapping mapping;
  Rule rule = Rule::centre;
  double fraction = 0.5;              ///< rule fraction: removed when more than this is inside
  Cut cut = Cut::rule;
  FractionMethod method = FractionMethod::exact;
  int samples_per_diameter = 8;       ///< sample method: grid points across a diameter (~0.52 n³ points)
  int target_grid = 0;                ///< integration grid per axis for the target (0: from the resolution, 64..256)
  long relax_steps = 0;               ///< DEM steps after carving (Hertz, Cundall damping 0.7, fixed cell)
  bool remove_floating = false;       ///< drop particles outside the main contact cluster
  double contact_gap = 1e-3;          ///< contact when gap ≤ this × R̄ (spatial::in_contact)
  double outside_margin = 0;          ///< m; 0: 2 r_max (solid_fraction_outside region: distance > margin)
  int threads = 0;                    ///< OpenMP threads (0: default)
  std::string packing_file;           ///< names in messages
};

/// Contact-graph connectivity (contacts: spatial::in_contact with contact_gap).
struct Connectivity {
  long n_clusters = 0;                 ///< connected components (isolated particles count)
  long n_floating_particles = 0;       ///< particles without any contact
  long n_floating_clusters = 0;        ///< clusters of ≥ 2 particles apart from the main cluster
  long n_particles_in_floating_clusters = 0;
  long main_cluster_size = 0;          ///< the largest cluster spanning the cell, else the largest
  int main_cluster_wrap_rank = 0;      ///< directions in which the main cluster wraps the cell (0..3)
  std::vector<uint8_t> outside_main;   ///< per particle: 1 when not in the main cluster
};

struct Report {
  std::size_t n_in = 0, n_out = 0, n_removed = 0, n_cut = 0, n_removed_floating = 0;
  double macroporosity_target = 0;     ///< volume fraction of the cell inside the mapped macropores
  double macroporosity_achieved = 0;   ///< removed solid volume / (solid fraction before × cell volume)
  double image_coverage = 0;           ///< fraction of the cell covered by the mapped image box
  double solid_fraction_before = 0, solid_fraction_after = 0;
  double solid_fraction_outside = 0;   ///< solid fraction of the region farther than the margin from the pores
  double solid_fraction_outside_spread = 0;  ///< homogeneous packing's std of that average (sub-box estimate)
  double outside_margin = 0;           ///< m
  double outside_volume_fraction = 0;  ///< of the cell
  double scale = 1;                    ///< mapping scale used (after fit)
  Connectivity before, after;
  long relax_steps = 0;
  double relax_unbalanced_force_ratio = 0;
  double target_grid = 0;
  double time_classify_s = 0, time_target_s = 0, time_connectivity_s = 0, time_relax_s = 0;
  double wall_time_s = 0;
};

struct Result {
  Packing packing;                     ///< the carved packing (bonds and contacts re-indexed)
  std::vector<uint8_t> removed;        ///< per input particle
  Report report;
};

/// Geometry mapped into the packing frame (signed distances in m of the packing).
class MappedPores {
 public:
  MappedPores(const Macropores& pores, const Mapping& mapping, const Cell& cell);
  double distance(const Vec3& p_pack) const;
  double band() const { return band_; }
  double resolution() const { return res_; }
  double scale() const { return scale_; }
  Vec3 to_image(const Vec3& p_pack) const;
  Vec3 to_packing(const Vec3& p_img) const;
  /// The mapped image box's corners (packing frame).
  std::array<Vec3, 8> corners() const;

 private:
  const Macropores& pores_;
  Cell cell_;
  Mat3 hinv_, rot_, rot_t_;
  Vec3 c_img_, c_pack_;
  Box img_;
  double scale_ = 1, band_ = 0, res_ = 0;
  bool tile_ = false;
};

/// Inside volume fraction of a sphere of radius r whose centre has signed distance d, for a
/// surface of local mean curvature κ = Δφ (sum of principal curvatures; 0: a plane). Exact for
/// planes and spheres (lens volume of two spheres).
double inside_fraction(double d, double r, double laplacian);

/// Carves `in` (InputError: no overlap between image and cell, nothing carved away... see docs).
Result carve(const Packing& in, const Macropores& pores, const Options& opt);

/// Connectivity of a packing's contact graph.
Connectivity connectivity(const Packing& p, double contact_gap);

/// Mid-plane (z = cell centre) picture: the macropore region tinted, the particles cut by the
/// plane as discs coloured by phase, particles outside the main cluster in orange. PNG (OpenCV).
void write_midplane_png(const std::string& path, const Packing& carved, const MappedPores& pores,
                        const std::vector<uint8_t>& outside_main, int pixels = 800);

}  // namespace tomodem::carve
