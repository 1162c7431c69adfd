// tomodem-fracture on bad input (issue 16): every row exits 2 naming the file or option and the
// value, writes nothing and leaves its inputs as they were (../young/bad_input.hpp).
#include "../../validation/mechanics/networks.hpp"
#include "../young/bad_input.hpp"

using namespace tomodem;
using namespace tomodem::bad_input;

namespace {

void make_inputs(const fs::path& d) {
  Material m = mechanics::test::ceramic();
  m.surface_energy = 1.0;
  mechanics::Network net;
  net.packing = mechanics::test::lattice("simple_cubic", 6, 1e-3, 0.5e-3, m);
  mechanics::test::bond_ratio(net, 0.1);
  mechanics::write_network((d / "bonded.h5").string(), net);
  const Packing& b = net.packing;
  write_damaged(d / "cell_zero.h5", b, [](h5::File& f) {
    f.write("/cell/h", std::vector<double>{6e-3, 0, 0, 0, 0, 0, 0, 0, 6e-3}, {3, 3});  // no y vector
  });
  write_damaged(d / "cell_singular.h5", b, [](h5::File& f) {
    f.write("/cell/h", std::vector<double>{6e-3, 0, 6e-3, 0, 6e-3, 6e-3, 0, 0, 0}, {3, 3});  // c = a + b
  });
  write_damaged(d / "bond_self.h5", b, [&](h5::File& f) {
    auto j = b.bonds.j;
    j[7] = b.bonds.i[7];
    f.write("/bonds/j", j);
  });
  write_damaged(d / "bond_nan_rest.h5", b, [&](h5::File& f) {
    auto l = b.bonds.rest_length;
    l[3] = NAN;
    f.write("/bonds/rest_length", l);
  });
  write_not_packings(d, d / "bonded.h5", b);
}

const InputCache& inputs() {
  static const InputCache cache("fracture", make_inputs);
  return cache;
}

const std::string B = "{D}/bonded.h5";

const std::vector<Case> kCases = {
    // ---- inputs
    {"zero_cell_vector", "fracture", "{D}/cell_zero.h5", 2, {"cell_zero.h5", "/cell/h", "column 1", "zero length"}},
    {"singular_cell", "fracture", "{D}/cell_singular.h5", 2, {"cell_singular.h5", "/cell/h", "coplanar"}},
    {"self_bond", "fracture", "{D}/bond_self.h5", 2, {"bond_self.h5", "/bonds/j[7]", "itself"}},
    {"nan_rest_length", "fracture", "{D}/bond_nan_rest.h5", 2, {"bond_nan_rest.h5", "/bonds/rest_length[3]", "nan"}},
    {"half_file", "fracture", "{D}/half.h5", 2, {"half.h5", "cut short"}},
    {"random_bytes", "fracture", "{D}/random.h5", 2, {"random.h5", "not an HDF5 file"}},
    {"empty_file", "fracture", "{D}/empty.h5", 2, {"empty.h5"}},
    {"folder", "fracture", "{D}/folder.h5", 2, {"folder.h5", "directory"}},
    {"hdf5_not_a_packing", "fracture", "{D}/plain.h5", 2, {"plain.h5", "tomodem_format"}},
    {"wrong_type", "fracture", "{D}/type.h5", 2, {"type.h5", "/particles/phase"}},
    // ---- options: refused whatever the method and criterion, never ignored
    {"tensile_strength_negative_lefm", "fracture", B + " --tensile-strength -1", 2, {"--tensile-strength", "-1"}},
    {"shear_strength_nan", "fracture", B + " --criterion stress --tensile-strength 1e6 --shear-strength nan", 2,
     {"--shear-strength", "nan"}},
    {"fracture_energy_inf", "fracture", B + " --fracture-energy inf", 2, {"--fracture-energy", "inf"}},
    {"friction_nan", "fracture", B + " --friction nan", 2, {"--friction", "nan"}},
    // ---- the bond failure slot of the law registry (docs/dem.md#contact-laws: its example)
    {"criterion_unknown", "fracture", B + " --criterion griffith", 2, {"--criterion", "griffith", "expected stress or lefm"}},
    {"criterion_none", "fracture", B + " --criterion none", 2, {"--criterion", "never break"}},
    {"energy_not_taken_by_stress", "fracture",
     B + " --criterion stress --tensile-strength 3e8 --shear-strength 6e8 --fracture-energy 2", 2,
     {"--fracture-energy", "the stress bond failure criterion does not take fracture_energy",
      "it takes tensile_strength, shear_strength, friction"}},
    {"strength_not_taken_by_lefm", "fracture", B + " --shear-strength 6e8", 2,
     {"--shear-strength", "does not take shear_strength", "it takes fracture_energy, friction"}},
    {"grip_negative", "fracture", B + " --grip -1e-3", 2, {"--grip", "-0.001"}},
    {"a_over_w_centre_too_long", "fracture", B + " --a-over-w 0.6", 2, {"--a-over-w", "0.6"}},
    {"crack_offset_nan", "fracture", B + " --crack-offset nan", 2, {"--crack-offset", "nan"}},
    {"youngs_modulus_zero", "fracture", B + " --youngs-modulus 0", 2, {"--youngs-modulus", "0"}},
    {"poisson_ratio_half", "fracture", B + " --poisson-ratio 0.5", 2, {"--poisson-ratio", "0.5"}},
    {"density_negative_sla", "fracture", B + " --density -2500", 2, {"--density", "-2500"}},
    {"strain_rate_negative", "fracture", B + " --strain-rate -1", 2, {"--strain-rate", "-1"}},
    {"woodbury_negative", "fracture", B + " --woodbury-bonds -2", 2, {"--woodbury-bonds", "-2"}},
    {"woodbury_overflows_int", "fracture", B + " --woodbury-bonds 1000000000", 2, {"--woodbury-bonds", "1000000000"}},
    {"max_breaks_zero", "fracture", B + " --max-breaks 0", 2, {"--max-breaks", "0"}},
    {"timestep_fraction_sla", "fracture", B + " --timestep-fraction 2", 2, {"--timestep-fraction", "2"}},
    {"geometry_unknown", "fracture", B + " --geometry middle", 2, {"--geometry", "middle"}},
    {"cracks_zero", "fracture", B + " --cracks 0", 2, {"--cracks", "0"}},
    {"crack_orientations_unknown", "fracture", B + " --cracks 3 --crack-orientations two", 2,
     {"--crack-orientations", "two"}},
    {"cracks_explicit", "fracture", B + " --method explicit --cracks 2", 2, {"--cracks", "2", "applies to sla only"}},
    // ---- outputs
    {"map_is_input", "fracture", B + " --map {D}/bonded.h5", 2, {"--map", "bonded.h5"}},
    {"curve_is_input", "fracture", B + " --curve {D}/bonded.h5", 2, {"--curve", "bonded.h5"}},
    {"plot_png_is_curve", "fracture", B + " --curve {D}/c.png --plot {D}/c", 2, {"--plot", "c.png", "same file"}},
    // The plot's data and script are outputs too: they overwrote a --curve or an input before.
    {"plot_dat_is_curve", "fracture", B + " --curve {D}/c.dat --plot {D}/c", 2, {"--plot (its .dat)", "c.dat", "same file"}},
    {"plot_gp_is_json", "fracture", B + " --json {D}/c.gp --plot {D}/c", 2, {"c.gp", "same file"}},
    {"map_sidecar_is_json", "fracture", B + " --json {D}/m.xdmf --map {D}/m.h5", 2, {"m.xdmf", "same file"}},
    {"explicit_curve_is_json", "fracture", B + " --method both --curve {D}/c.csv --json {D}/c_explicit.csv", 2,
     {"c_explicit.csv", "same file"}},
    {"map_folder_missing", "fracture", B + " --map {D}/nowhere/m.h5", 2, {"--map", "nowhere"}},
};

class FractureBadInput : public ::testing::TestWithParam<Case> {};

TEST_P(FractureBadInput, ExitsTwoNamesTheValueAndWritesNothing) { run_case(GetParam(), inputs().dir()); }

INSTANTIATE_TEST_SUITE_P(Rows, FractureBadInput, ::testing::ValuesIn(kCases), case_name);

}  // namespace
