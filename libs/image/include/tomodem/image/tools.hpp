#pragma once
// The two tools' configurations and drivers (tools/segment, tools/phantom stay thin).
#include <map>
#include <string>

#include "tomodem/image/phantom.hpp"
#include "tomodem/image/volume.hpp"

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

struct SegmentConfig {
  std::string input;
  ReadOptions read;
  std::string spacing_text, roi_text, macro_radius_text = "3vox", raw_dims_text;
  // filtering
  std::string filter = "median";      ///< none | median | gaussian | cad | nlm
  int filter_radius = 1;              ///< median box radius; NLM patch radius (voxels)
  double sigma = 1.0;                 ///< gaussian sigma (voxels)
  int iterations = 5;                 ///< cad / nlm iterations
  double conductance = 1.0;           ///< cad
  // thresholding
  std::string method = "otsu";        ///< otsu | peaks | intermeans | multiotsu2 | multiotsu3 | manual | hysteresis
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
  /// Option values as the user typed them ("--sigma" -> "1e-0"), for messages that echo them.
  std::map<std::string, std::string> as_written;
};

/// Runs the whole segmentation; returns the JSON summary (also written to cfg.json when set).
std::string run_segment(const SegmentConfig& cfg);

struct PhantomConfig {
  PhantomOptions opt;
  std::string output;                 ///< grey volume: extension picks the format (volume.hpp write_volume)
  std::string truth;                  ///< truth labels and macropore ids (.h5); packing kind: + <truth>.packing.h5
  bool as_float = false;
  std::string json;
};
std::string run_phantom(const PhantomConfig& cfg);

}  // namespace tomodem::image
