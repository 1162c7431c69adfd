// Fields outputs on bad input (docs/cg.md#bad-input): the fields: block of tomodem-dem, --fields of
// tomodem-young and tomodem-fracture, --vdb of tomodem-cg. Every row exits 2 naming the file or
// option, the field and the value, writes nothing and leaves its inputs as they were
// (tests/e2e/young/bad_input.hpp).
#include "../../validation/fields/lattices.hpp"
#include "../../validation/mechanics/networks.hpp"
#include "../young/bad_input.hpp"
#include "tomodem/core/packing_io.hpp"
#include "tomodem/mechanics/network.hpp"

using namespace tomodem;
using namespace tomodem::bad_input;

namespace {
/// A small static lattice scene with `fields` as its fields: block (and `output` as its output:).
std::string scene(const std::string& fields, const std::string& output = "{packing: lattice.h5}") {
  return "materials:\n  - {name: glass, youngs_modulus: 7.0e10, poisson_ratio: 0.22, density: 2500}\n"
         "particles:\n  generate: {arrangement: simple_cubic, cells: 4, radius: 0.5e-3, spacing: 0.99e-3, phase: glass}\n"
         "physics: {normal: hertz}\nprotocol: {steps: 20}\noutput: " +
         output + "\nfields: " + fields + "\n";
}

void make_inputs(const fs::path& d) {
  write_packing((d / "pack.h5").string(), fields::test::spring_lattice(4, 1e-3, Mat3::identity(), 1e4));
  mechanics::Network net;
  net.packing = mechanics::test::lattice("simple_cubic", 6, 1e-3, 0.5e-3);
  mechanics::test::bond_ratio(net, 0.2);
  mechanics::write_network((d / "net.h5").string(), net);
  const std::pair<const char*, std::string> scenes[] = {
      {"unknown_key.yaml", scene("{output: f.h5, widht: 1.5}")},
      {"narrow.yaml", scene("{output: f.h5, width: 0.2}")},
      {"wide.yaml", scene("{output: f.h5, width: 10}")},
      {"vdb_slice.yaml", scene("{output: f.h5, vdb: f.vdb, slice: z=0.5}")},
      {"no_output.yaml", scene("{width: 1.5}")},
      {"outside.yaml", scene("{output: ../f.h5}")},
      {"every.yaml", scene("{output: f.h5, every: -5}")},
      {"window.yaml", scene("{output: f.h5, every: 5, from: 1.0e-3, to: 0.5e-3}")},
      {"kernel.yaml", scene("{output: f.h5, kernel: box}")},
      {"nodes.yaml", scene("{output: f.h5, nodes: [4, x, 4]}")},
      {"clash.yaml", scene("{output: lattice.h5}")},
      {"deforming.yaml", scene("{output: f.h5, every: 5}") + "boundary: {strain_rate: {zz: -1.0}}\n"},
  };
  for (const auto& [name, text] : scenes) spit(d / name, text);
}

const InputCache& inputs() {
  static const InputCache cache("fields-block", make_inputs);
  return cache;
}

class FieldsBadInput : public ::testing::TestWithParam<Case> {};
TEST_P(FieldsBadInput, RefusedWithoutOutput) { run_case(GetParam(), inputs().dir()); }

const Case kCases[] = {
    // tomodem-cg: the width against the particle spacing, VDB for full grids only
    {"cg_width_below_spacing", "cg", "pack.h5 -o f.h5 --width 0.3", 2, {"--width", "0.3", "0.5 mean diameters"}},
    {"cg_vdb_with_slice", "cg", "pack.h5 -o f.h5 --vdb f.vdb --slice z=0.5", 2, {"--vdb", "f.vdb", "slice"}},
    {"cg_vdb_with_profile", "cg", "pack.h5 -o f.h5 --vdb f.vdb --profile x", 2, {"--vdb", "f.vdb", "profile"}},
    {"cg_vdb_over_input", "cg", "pack.h5 -o f.h5 --vdb pack.h5", 2, {"--vdb", "pack.h5"}},
    // tomodem-dem: the fields: block, named by file, field (line) and value
    {"dem_unknown_key", "dem", "unknown_key.yaml", 2, {"unknown_key.yaml", "fields.widht", "unknown key"}},
    {"dem_width_below_spacing", "dem", "narrow.yaml", 2, {"narrow.yaml", "fields.width", "0.2", "0.5 mean diameters"}},
    {"dem_width_above_cell", "dem", "wide.yaml", 2, {"wide.yaml", "fields.width", "10", "exceeds the cell"}},
    {"dem_vdb_with_slice", "dem", "vdb_slice.yaml", 2, {"vdb_slice.yaml", "fields.vdb", "f.vdb", "slice"}},
    {"dem_no_output", "dem", "no_output.yaml", 2, {"no_output.yaml", "fields.output", "missing"}},
    {"dem_output_outside", "dem", "outside.yaml", 2, {"outside.yaml", "fields.output", "../f.h5"}},
    {"dem_every_negative", "dem", "every.yaml", 2, {"every.yaml", "fields.every", "-5"}},
    {"dem_window_reversed", "dem", "window.yaml", 2, {"window.yaml", "fields.to", "0.5e-3"}},
    {"dem_kernel", "dem", "kernel.yaml", 2, {"kernel.yaml", "fields.kernel", "box"}},
    {"dem_nodes", "dem", "nodes.yaml", 2, {"nodes.yaml", "fields.nodes", "4,x,4"}},
    {"dem_output_clash", "dem", "clash.yaml", 2, {"clash.yaml", "fields.output", "lattice.h5"}},
    {"dem_deforming_cell_average", "dem", "deforming.yaml", 2, {"deforming.yaml", "fields.every", "5", "one grid"}},
    // tomodem-young and tomodem-fracture: --fields
    {"young_width_below_spacing", "young", "net.h5 --fields f.h5 --fields-width 0.1", 2, {"--fields-width", "0.1"}},
    {"young_width_above_cell", "young", "net.h5 --fields f.h5 --fields-width 100", 2, {"--fields-width", "exceeds"}},
    {"young_vdb_with_slice", "young", "net.h5 --fields f.h5 --fields-vdb f.vdb --fields-slice z=0.5", 2,
     {"--fields-vdb", "f.vdb", "slice"}},
    {"young_fields_over_input", "young", "net.h5 --fields net.h5", 2, {"--fields", "net.h5"}},
    {"young_kernel", "young", "net.h5 --fields f.h5 --fields-kernel box", 2, {"--fields-kernel", "box"}},
    {"fracture_explicit", "fracture", "net.h5 --method explicit --fields f.h5", 2, {"--fields", "f.h5", "sla"}},
    {"fracture_width_below_spacing", "fracture", "net.h5 --fields f.h5 --fields-width 0.2 --no-elastic --fracture-energy 1", 2,
     {"--fields-width", "0.2"}},
};
INSTANTIATE_TEST_SUITE_P(Rows, FieldsBadInput, ::testing::ValuesIn(kCases), case_name);
}  // namespace
