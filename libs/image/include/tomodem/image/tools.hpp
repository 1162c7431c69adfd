#pragma once
// The two tools' configurations and drivers (tools/segment, tools/phantom stay thin).
#include <cstdint>
#include <map>
#include <optional>
#include <string>
#include <string_view>

#include "tomodem/core/names.hpp"
#include "tomodem/image/phantom.hpp"
#include "tomodem/image/volume.hpp"

namespace tomodem {
class Summary;
}

namespace tomodem::image {

/// Every option given on the command line, as typed (long name -> values joined by ',').
template <class App>
std::map<std::string, std::string> options_as_written(const App& app) {
  std::map<std::string, std::string> m;
  for (const auto* opt : app.get_options()) {
    if (opt->count() == 0 || opt->get_lnames().empty()) continue;
    std::string v;
    for (const auto& r : opt->results()) v += (v.empty() ? "" : ",") + r;
    m["--" + opt->get_lnames().front()] = v;
  }
  return m;
}

/// Denoising before thresholding: none, median box, Gaussian, curvature anisotropic diffusion, non-local means.
enum class ImageFilter : uint8_t { none, median, gaussian, cad, nlm };
inline constexpr NameTable<ImageFilter, 5> kImageFilterNames = {{{ImageFilter::none, "none"},
                                                                {ImageFilter::median, "median"},
                                                                {ImageFilter::gaussian, "gaussian"},
                                                                {ImageFilter::cad, "cad"},
                                                                {ImageFilter::nlm, "nlm"}}};
inline const char* to_string(ImageFilter f) { return name_of(kImageFilterNames, f); }
inline std::optional<ImageFilter> parse_image_filter(std::string_view name) { return value_of(kImageFilterNames, name); }

/// Threshold selection (docs/segment.md): automatic (otsu, peaks, intermeans, multi-Otsu with two
/// or three classes) or given (manual: one or two levels; hysteresis: low and high).
enum class ThresholdMethod : uint8_t { otsu, peaks, intermeans, multiotsu2, multiotsu3, manual, hysteresis };
inline constexpr NameTable<ThresholdMethod, 7> kThresholdMethodNames = {{{ThresholdMethod::otsu, "otsu"},
                                                                        {ThresholdMethod::peaks, "peaks"},
                                                                        {ThresholdMethod::intermeans, "intermeans"},
                                                                        {ThresholdMethod::multiotsu2, "multiotsu2"},
                                                                        {ThresholdMethod::multiotsu3, "multiotsu3"},
                                                                        {ThresholdMethod::manual, "manual"},
                                                                        {ThresholdMethod::hysteresis, "hysteresis"}}};
inline const char* to_string(ThresholdMethod m) { return name_of(kThresholdMethodNames, m); }
inline std::optional<ThresholdMethod> parse_threshold_method(std::string_view name) {
  return value_of(kThresholdMethodNames, name);
}

struct SegmentConfig {
  std::string input;
  ReadOptions read;
  /// --spacing: one length (every axis) or three, x,y,z ("1um,1um,2um").
  std::string spacing_text, roi_text, macro_radius_text = "3vox", raw_dims_text;
  // filtering
  ImageFilter filter = ImageFilter::median;
  /// Median box radius / NLM patch radius and Gaussian sigma: "2vox" in voxels of the finest axis,
  /// or a length ("2um"); the same length on every axis (anisotropic voxels). A bare number is refused.
  std::string filter_radius_text = "1vox";
  std::string sigma_text = "1vox";
  int iterations = 5;                 ///< cad / nlm iterations
  double conductance = 1.0;           ///< cad
  // thresholding
  ThresholdMethod method = ThresholdMethod::otsu;
  std::vector<double> levels;         ///< manual: one or two thresholds; hysteresis: low, high
  bool pores_bright = false;          ///< pores above the threshold (default: pores dark)
  // cleaning
  double open_r = 0, close_r = 0;     ///< on the solid, ball radius (voxels)
  std::size_t min_island = 0;         ///< remove solid and pore islands below this (voxels)
  int connectivity = 6;
  // macropores
  std::size_t macro_min_voxels = 1;
  // grains
  bool grains = false;
  double h = 1.0;
  std::string packing;                ///< write grains as a packing (.h5)
  // outputs
  std::string output;                 ///< labels .h5
  std::string mha;                    ///< labels .mha/.mhd
  std::string vdb;                    ///< macropores level set
  std::string overlay;                ///< PNG prefix: <prefix>_xy.png, _xz, _yz
  std::string json;                   ///< "" or "-": stdout
  // out of core (docs/segment.md, "Volumes larger than memory")
  std::size_t chunk = 0;              ///< --chunk: block side in voxels (0: from --memory, or in memory)
  std::string memory_text;            ///< --memory: budget ("8GB"); the block side is chosen from it
  /// Option values as the user typed them ("--sigma" -> "1e-0"), for messages that echo them.
  std::map<std::string, std::string> as_written;
};

/// Runs the whole segmentation; returns the JSON summary (also written to cfg.json when set).
/// With --chunk or --memory: run_segment_chunked.
std::string run_segment(const SegmentConfig& cfg);
/// The out-of-core path (chunked.cpp): a raw or HDF5 volume read and processed in blocks with halos,
/// labels written block by block; the same labels as run_segment. `ro`: checked read options.
std::string run_segment_chunked(const SegmentConfig& cfg, const ReadOptions& ro);
/// Writes the grains' packing to cfg.packing (nothing when it is empty), with its provenance.
void write_grains_packing(const SegmentConfig& cfg, Packing& packing, Summary& summary);

struct PhantomConfig {
  PhantomOptions opt;
  std::string output;                 ///< grey volume: extension picks the format (volume.hpp write_volume)
  std::string truth;                  ///< truth labels and macropore ids (.h5); packing kind: + <truth>.packing.h5
  bool as_float = false;
  std::string json;
};
std::string run_phantom(const PhantomConfig& cfg);

}  // namespace tomodem::image
