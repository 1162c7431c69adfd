#pragma once
// The --fields options of tomodem-young and tomodem-fracture (docs/cg.md#fields-of-young-and-fracture):
// tomodem-cg's kernel and grid options under a --fields- prefix, named so in the messages.
#include <CLI/CLI.hpp>

#include <string>

#include "tomodem/fields/block.hpp"

namespace tomodem::fields {

/// Adds --fields FILE.h5 and --fields-{vdb,kernel,width,cutoff,nodes,slice,profile,quadrature};
/// `state` says which state is coarse-grained (the option's help).
inline void add_fields_options(CLI::App& app, FieldsSettings& s, const std::string& state) {
  SettingNames& n = s.names;
  n.output = "--fields", n.vdb = "--fields-vdb", n.kernel = "--fields-kernel", n.width = "--fields-width";
  n.cutoff = "--fields-cutoff", n.nodes = "--fields-nodes", n.slice = "--fields-slice", n.profile = "--fields-profile";
  n.quadrature = "--fields-quadrature";
  app.add_option("--fields", s.output, "coarse-grained fields (.h5 + .xdmf, docs/cg.md) of " + state);
  app.add_option("--fields-vdb", s.vdb, "fields: also the scalar and vector fields as OpenVDB grids (full grids)");
  app.add_option("--fields-kernel", s.kernel, "fields: gaussian | lucy")->capture_default_str();
  app.add_option("--fields-width", s.width, "fields: kernel width, mean diameters (1.5) or a length (20um)")
      ->capture_default_str();
  app.add_option("--fields-cutoff", s.cutoff, "fields: Gaussian cut-off in widths")->capture_default_str();
  app.add_option("--fields-nodes", s.nodes, "fields: nodes N or NX,NY,NZ (default: one per half width)");
  app.add_option("--fields-slice", s.slice, "fields: a plane AXIS=FRACTION instead of the 3-D grid");
  app.add_option("--fields-profile", s.profile, "fields: a 1-D profile along x, y or z");
  app.add_option("--fields-quadrature", s.quadrature, "fields: points per branch vector (0: automatic)")
      ->capture_default_str();
}

}  // namespace tomodem::fields
