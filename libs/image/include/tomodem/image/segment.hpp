#pragma once
// Segmentation building blocks as free functions over tomodem::image grids (docs/architecture.md#code-conventions, P7).
// Lengths are in voxels unless a name says otherwise; all filters are 3-D and use OpenMP/ITK threads.
// Anisotropic voxels (a scan's coarser z): a length "in voxels" is in voxels of the finest axis,
// and filters, distances and balls follow each axis's spacing, so they are the same in metres.
#include <algorithm>
#include <array>
#include <string>
#include <vector>

#include "tomodem/core/packing.hpp"
#include "tomodem/core/vec3.hpp"
#include "tomodem/image/volume.hpp"

namespace tomodem {
class Summary;
}

namespace tomodem::image {

// ---- filtering (filters_itk.cpp, binary.cpp) ----
/// Median over a (2r+1)^3 box, borders replicated (exact, own code, OpenMP over rows), in place:
/// plane by plane with a ring of the 2r+1 original planes it still needs, so the memory is the
/// volume plus 2r+1 planes. r = 1: a selection network over sorted 3x3 columns, 4 (SSE) or 8 (AVX)
/// voxels at a time (about 200 min/max per voxel); r > 1, or `generic`: std::nth_element over the box (the
/// reference the benchmark compares against).
void median_inplace(Volume& v, int radius, bool generic = false);
/// The same over a (2rx+1)(2ry+1)(2rz+1) box (rz may be 0: each slice on its own).
void median_inplace(Volume& v, const std::array<int, 3>& radii, bool generic = false);
/// The box half-widths of a median of radius `r_vox` (voxels of the finest axis): the voxel
/// centres within that length along each axis, floor(r s_finest / s_axis). At 1um,1um,2um and
/// r = 1: {1, 1, 0}: on coarser z the kernel spans fewer slices.
std::array<int, 3> radii_for_length(const Volume& v, double r_vox);
/// The same on a copy.
Volume median(const Volume& v, int radius);
/// Gaussian smoothing, sigma in voxels of the finest axis, the same length on every axis
/// (ITK SmoothingRecursiveGaussianImageFilter with a sigma per axis: an infinite response; the
/// phantoms' blur and the level sets' smoothing).
Volume gaussian(const Volume& v, double sigma_vox);
/// The half-widths of gaussian_inplace's kernel along each axis: ceil(4 sigma_axis) voxels,
/// sigma_axis = sigma_vox × finest spacing / the axis's spacing.
std::array<int, 3> gaussian_radii(const Volume& v, double sigma_vox);
/// Gaussian smoothing in place (`--filter gaussian`): the sampled Gaussian cut at 4 sigma
/// (scipy.ndimage's default) and normalised to sum 1, one axis after the other, borders
/// replicated, sums in double (own code, OpenMP). A voxel depends only on the voxels within
/// gaussian_radii of it, so a block with that halo gives its core exactly (the chunked path).
void gaussian_inplace(Volume& v, double sigma_vox);
/// Curvature anisotropic diffusion (ITK, on the voxel spacing relative to the finest axis); time
/// step 0.0625 is the 3-D stability limit for the finest axis.
Volume anisotropic_diffusion(const Volume& v, int iterations, double conductance, double time_step = 0.0625);
/// Non-local means (ITK PatchBasedDenoisingImageFilter, Gaussian noise model).
Volume nlm(const Volume& v, int patch_radius, int iterations);

/// Caps OpenMP and ITK threads together (0: leave the defaults).
void set_threads(int n);

// ---- thresholds (binary.cpp) ----
/// A histogram of grey values: `bins` equal bins from the smallest to the largest value; counts
/// are whole numbers held in doubles (exact below 2^53), so one built chunk by chunk is the same.
struct GreyHistogram {
  double lo = 0, width = 1;
  std::vector<double> h;
  int bin(float x) const { return std::min(int(h.size()) - 1, int((double(x) - lo) / width)); }
};
/// The volume's histogram (InputError on a constant volume).
GreyHistogram grey_histogram(const Volume& v, int bins);
/// Empty bins between lo and hi, to be filled with bin() (InputError unless hi > lo).
GreyHistogram empty_histogram(float lo, float hi, int bins);
/// The thresholds below from a histogram (256 bins for Otsu, 4096 intermeans, 1024 peaks).
std::vector<double> multi_otsu_thresholds(const GreyHistogram& h, int classes);
double intermeans_threshold(const GreyHistogram& h4096, double start);
double peaks_threshold(const GreyHistogram& h1024, double start);
/// Histogram of `bins` bins between the volume's min and max; thresholds in grey values.
double otsu_threshold(const Volume& v, int bins = 256);
/// Multi-Otsu with n classes (2 or 3): n-1 thresholds, ascending (exhaustive search).
std::vector<double> multi_otsu_thresholds(const Volume& v, int classes, int bins = 256);
/// Ridler–Calvard intermeans: t = (mean below t + mean above t) / 2, iterated from `start`
/// (Otsu). Unlike Otsu it does not drift toward the larger class when one phase is a few percent
/// of the volume, so blurred edges are cut at their 50 % level.
double intermeans_threshold(const Volume& v, double start);
/// Midpoint of the two phase peaks (histogram modes on either side of `start`, e.g. Otsu):
/// the 50 % partial-volume level of blurred edges, unbiased by the class sizes.
double peaks_threshold(const Volume& v, double start);
/// value >= t  (or < t with `below`) as 0/1.
Mask threshold(const Volume& v, double t, bool below = false);
/// Hysteresis: voxels above `low` connected (26-n) to a voxel above `high`; built from ITK's
/// ReconstructionByDilationImageFilter (marker = above high, mask = above low).
Mask hysteresis(const Volume& v, double low, double high);

// ---- binary morphology and labelling (binary.cpp) ----
/// Squared Euclidean distance (in finest voxels²; exact for anisotropic spacing) of every voxel to the nearest voxel where m == 0
/// (for m != 0 voxels; 0 elsewhere). Felzenszwalb–Huttenlocher, exact, separable.
std::vector<float> distance_squared(const Mask& m);
/// The signed distance of ITK's SignedMaurerDistanceMapImageFilter (inside positive, image
/// spacing, in finest voxels): in the solid, the distance to its nearest contour voxel (a solid
/// voxel with a pore among its 26 neighbours; 0 on the contour); in the pores, minus the distance
/// to the nearest solid voxel. Exact and separable (one transform, to the contour).
std::vector<float> signed_contour_distance(const Mask& solid);
Mask erode_ball(const Mask& m, double r);   ///< Euclidean ball of radius r (finest voxels; round in metres)
Mask dilate_ball(const Mask& m, double r);
Mask open_ball(const Mask& m, double r);
Mask close_ball(const Mask& m, double r);
/// Connected components of m != 0; 6- or 26-connectivity; labels 1..n ordered by first voxel
/// (x fastest). Returns n in *count.
Labels components(const Mask& m, int connectivity, int* count);
/// Sets to 0 the components (of m != 0) smaller than min_voxels; returns how many were removed.
int remove_islands(Mask& m, std::size_t min_voxels, int connectivity = 6);

struct Region {
  int label = 0;
  std::size_t voxels = 0;
  Vec3 centroid{};            ///< m (physical)
  double volume_m3 = 0;
  double equivalent_diameter_m = 0;  ///< (6V/π)^(1/3)
  bool touches_surface = false;      ///< has a voxel on a face of the volume
};
/// Statistics of labels 1..n.
std::vector<Region> regions(const Labels& l, int n);
/// The sums behind regions(), voxel by voxel in any order: counts and centroid sums are whole
/// numbers in doubles, so a volume summed block by block (the chunked path) gives the same.
class RegionSums {
 public:
  explicit RegionSums(std::size_t n) : r_(n), sum_(n, std::array<double, 3>{0, 0, 0}) {}
  /// Voxel (x, y, z) of a volume of dims d carries label k (1..n).
  void add(int32_t k, std::size_t x, std::size_t y, std::size_t z, const Dims& d) {
    Region& R = r_[std::size_t(k - 1)];
    ++R.voxels;
    std::array<double, 3>& s = sum_[std::size_t(k - 1)];
    s[0] += double(x);
    s[1] += double(y);
    s[2] += double(z);
    if (x == 0 || y == 0 || z == 0 || x + 1 == d.nx || y + 1 == d.ny || z + 1 == d.nz) R.touches_surface = true;
  }
  /// The regions in metres (origin: the centre of voxel 0); a label without voxels keeps zeros.
  std::vector<Region> regions(const std::array<double, 3>& origin, const std::array<double, 3>& spacing) const;

 private:
  std::vector<Region> r_;
  std::vector<std::array<double, 3>> sum_;
};
/// The summary keys of the macropores: `macropores` (id, voxels, volume_m3, equivalent_diameter_m,
/// centroid_m, touches_surface), `n_macropores_touching_surface`, `pore_size_distribution`.
void macropore_summary(const std::vector<Region>& regs, Summary& summary);
/// The grains as a packing: one sphere of each grain's volume at its centroid, phase 1 where the
/// second solid phase holds most of its voxels; and the summary's `n_grains` and `grains` keys.
/// Indexed by label: `inscribed_d2`, the grain's largest squared distance to the pores (finest
/// voxels², distance_squared); `n_phase2`, its voxels of the second solid phase. `unassigned`:
/// the solid voxels no marker reached (grain 0: specks without a marker of their own).
Packing grains_packing(const std::vector<Region>& grains, const std::vector<float>& inscribed_d2,
                       const std::vector<std::size_t>& n_phase2, const Dims& dims, const std::array<double, 3>& spacing,
                       const std::array<double, 3>& origin, bool two_phases, double h, std::size_t unassigned,
                       Summary& summary);

/// Interface area between m != 0 and m == 0 per unit total volume (1/m): face count × 2/3,
/// the mean-projection correction of voxel faces for isotropic surfaces (Lang et al. 2001).
double specific_surface(const Mask& m);
/// The same from the counts of unlike neighbour pairs along x, y and z (one formula for both paths).
double specific_surface(double fx, double fy, double fz, const Dims& d, const std::array<double, 3>& spacing);

// ---- macropores and grains (binary.cpp, flood.cpp) ----
/// Macropores = pore voxels within r + 1 of the centres where a ball of radius r (voxels) fits
/// in the pores (an opening whose dilation is one voxel wider, restricted to the pores, so the
/// digital ball's lost surface voxels come back); labelled (6-connectivity), filtered by min_voxels.
Labels macropores(const Mask& pores, double r, std::size_t min_voxels, int* count);
/// The macropore voxels before labelling (what macropores() labels). A voxel's value depends on
/// the pores within 2r + 2 (finest) voxels of it only, so a block with that halo gives its core exactly.
Mask macropore_mask(const Mask& pores, double r);

struct GrainOptions {
  double h = 1.0;            ///< h-maxima height of the distance map (voxels)
  int connectivity = 26;     ///< of markers and watershed
};
/// Separates touching grains of `solid`: signed contour distance (as ITK's Maurer), h-maxima markers,
/// morphological watershed from markers on -distance, restricted to the solid.
Labels watershed_grains(const Mask& solid, const GrainOptions& opt, int* count);
/// watershed_grains in its two steps, for a block of a larger volume (the chunked path numbers the
/// markers over the whole volume between them): the marker voxels (the h-maxima's regional maxima
/// of the distance map, in the solid; 0/1), and the watershed from given markers (labels > 0).
Mask grain_peaks(const Mask& solid, const GrainOptions& opt);
Labels watershed_from_markers(const Mask& solid, const Labels& markers, const GrainOptions& opt);

}  // namespace tomodem::image
