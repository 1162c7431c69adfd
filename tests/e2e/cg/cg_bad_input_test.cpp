// tomodem-cg on bad input: every row exits 2 naming the option or the file and field, writes
// nothing and leaves its inputs as they were (tests/e2e/young/bad_input.hpp).
#include "../../validation/fields/lattices.hpp"
#include "../young/bad_input.hpp"
#include "tomodem/core/h5.hpp"
#include "tomodem/core/packing_io.hpp"

using namespace tomodem;
using namespace tomodem::bad_input;

namespace {
void make_inputs(const fs::path& d) {
  const Packing p = fields::test::spring_lattice(4, 1e-3, Mat3::identity(), 1e4);
  write_packing((d / "pack.h5").string(), p);
  Packing bigger = fields::test::spring_lattice(5, 1e-3, Mat3::identity(), 1e4);
  write_packing((d / "five.h5").string(), bigger);
  Packing stretched = fields::test::spring_lattice(4, 1e-3, Mat3::diagonal({1.01, 1, 1}), 1e4);
  write_packing((d / "stretched.h5").string(), stretched);
  Packing bare = p;
  bare.materials.clear();
  write_packing((d / "nomaterials.h5").string(), bare);
  Packing bonded = p;
  for (std::size_t c = 0; c < p.contacts.size(); ++c) {
    bonded.bonds.i.push_back(p.contacts.i[c]);
    bonded.bonds.j.push_back(p.contacts.j[c]);
    bonded.bonds.radius.push_back(1e-4);
    bonded.bonds.rest_length.push_back(1e-3);
    bonded.bonds.state.push_back(0);
    bonded.bonds.broken_at.push_back(NAN);
  }
  write_packing((d / "bonded.h5").string(), bonded);
  write_damaged(d / "noradius.h5", p, [](h5::File& f) { f.remove("/particles/radius"); });
  {
    h5::File f((d / "checkpoint.h5").string(), h5::File::Mode::create);
    f.set_attr("/", "tomodem_checkpoint_format", 1.0);
    f.write("/particles/radius", std::vector<double>{1e-3});
    f.close();
  }
}

const InputCache& inputs() {
  static const InputCache cache("cg", make_inputs);
  return cache;
}

class CgBadInput : public ::testing::TestWithParam<Case> {};
TEST_P(CgBadInput, RefusedWithoutOutput) { run_case(GetParam(), inputs().dir()); }

const Case kCases[] = {
    {"width_above_cell", "cg", "pack.h5 -o f.h5 --width 5", 2, {"--width", "exceeds the cell"}},
    {"width_unit", "cg", "pack.h5 -o f.h5 --width 3furlongs", 2, {"--width", "3furlongs", "unit"}},
    {"width_negative", "cg", "pack.h5 -o f.h5 --width=-1", 2, {"--width"}},
    {"grid_beyond_memory", "cg", "pack.h5 -o f.h5 --nodes 100000", 2, {"--nodes", "100000"}},
    {"grid_text", "cg", "pack.h5 -o f.h5 --nodes 4,x,4", 2, {"--nodes", "4,x,4"}},
    {"slice_axis", "cg", "pack.h5 -o f.h5 --slice w=0.5", 2, {"--slice", "w=0.5"}},
    {"slice_fraction", "cg", "pack.h5 -o f.h5 --slice z=1.5", 2, {"--slice", "1.5"}},
    {"slice_and_profile", "cg", "pack.h5 -o f.h5 --slice z=0.5 --profile x", 2, {"--slice", "--profile"}},
    {"kernel", "cg", "pack.h5 -o f.h5 --kernel box", 2, {"--kernel", "box"}},
    {"cutoff", "cg", "pack.h5 -o f.h5 --cutoff 1", 2, {"--cutoff"}},
    {"no_density", "cg", "nomaterials.h5 -o f.h5", 2, {"nomaterials.h5", "/materials", "--density"}},
    {"missing_radius", "cg", "noradius.h5 -o f.h5", 2, {"noradius.h5", "/particles/radius"}},
    {"checkpoint", "cg", "checkpoint.h5 -o f.h5", 2, {"checkpoint.h5", "checkpoint"}},
    {"cells_differ", "cg", "pack.h5 stretched.h5 -o f.h5", 2, {"stretched.h5", "/cell/h"}},
    {"reference_count", "cg", "pack.h5 --reference five.h5 -o f.h5", 2, {"five.h5", "/particles/radius"}},
    {"stored_bond_forces", "cg", "bonded.h5 -o f.h5 --bond-forces stored", 2, {"bonded.h5", "/bonds/force"}},
    {"bond_forces_mode", "cg", "bonded.h5 -o f.h5 --bond-forces maybe", 2, {"--bond-forces", "maybe"}},
    {"output_over_input", "cg", "pack.h5 -o pack.h5", 2, {"-o", "pack.h5"}},
    {"missing_input", "cg", "absent.h5 -o f.h5", 2, {"absent.h5"}},
};
INSTANTIATE_TEST_SUITE_P(Rows, CgBadInput, ::testing::ValuesIn(kCases), case_name);
}  // namespace
