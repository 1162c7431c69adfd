#pragma once
// The sintered packings of the dense-network tests (mechanics: E under Hashin–Shtrikman;
// network: σ under it, issue 18 item 7): a 100-sphere green packing (random loose, 0.60,
// monodisperse 2 µm, as tests/bench/sinter/green.yaml) sintered freely in one run to 0.9 by
// docs/sintering.md's alumina program taken to 1800 K with a long hold (1600 K stalls near 0.85),
// with a snapshot at each of 0.6, 0.7, 0.8 and 0.9: the particles, and the necks as bonds with
// their periodic images.
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "tomodem/dem/scene.hpp"
#include "tomodem/dem/sinter.hpp"
#include "tomodem/geometry/pack.hpp"
#include "tomodem/spatial/union_volume.hpp"

namespace tomodem::test {

struct SinteredSnapshot {
  Packing packing;          ///< contacts left out; bonds = the necks
  std::vector<Vec3> image;  ///< per bond: the periodic image of j (whole cells)
  double green_density = 0, green_volume = 0;  ///< union density and cell volume of the green packing
};

inline std::vector<SinteredSnapshot> sintered_sweep(const Material& material) {
  geometry::PackSpec spec;
  geometry::PhaseSpec ph;
  ph.name = material.name;
  ph.material = material;
  ph.psd.kind = geometry::PsdKind::monodisperse;
  ph.psd.diameter = 2e-6;
  spec.phases = {ph};
  spec.n_particles = 100;
  spec.initial_solid_fraction = 0.3;
  spec.seed = 1;
  spec.normal = dem::NormalLaw::hertz;
  spec.friction = 0.5;
  spec.method = geometry::PackMethod::dynamic;
  spec.target = geometry::Target::solid_fraction;
  spec.target_solid_fraction = 0.6;
  spec.unbalanced_force_ratio = 0.01;
  spec.max_steps = 10000;
  spec.tessellate = false;
  const Packing green = geometry::make_packing(spec).packing;

  const std::filesystem::path dir = std::filesystem::temp_directory_path() /
                                    ("tomodem_sintered_sweep_" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir);
  const std::string file = (dir / "sinter.yaml").string();
  std::ofstream(file) << "physics: {tangential: viscous}\n"
                         "sintering:\n"
                         "  temperature:\n"
                         "    start: 300\n"
                         "    segments: [{rate: 50, to: 1800}, {hold: 1.0e6}]\n"
                         "  phases:\n"
                         "    - {material: " + material.name + ", atomic_volume: 8.47e-30, boundary_diffusion: 8.6e-10,\n"
                         "       activation_energy: 418.0e3, dihedral_angle: 150, tangential_viscosity: 1.0}\n"
                         "  stop: {relative_density: 0.9}\n"
                         "  accuracy: {strain_per_step: 5.0e-6}\n";
  dem::Scene scene = dem::sinter_scene(green, "green", file);
  dem::SinterSettings s = dem::read_sinter_settings(scene);
  dem::check_sinter_settings(scene, s);
  std::vector<SinteredSnapshot> out;
  dem::SinterSnapshots snap;
  snap.densities = {0.6, 0.7, 0.8, 0.9};
  snap.take = [&](dem::Simulation& sim, const dem::SinterRow&, std::size_t) {
    SinteredSnapshot o;
    o.packing = dem::to_packing(sim, green.materials);
    o.packing.contacts = ContactTable{};
    o.packing.bonds = dem::necks_to_bond_table(sim);
    o.image = dem::necks_to_bonds(sim).image;
    o.green_density = spatial::union_relative_density(green.particles.position, green.particles.radius, green.cell);
    o.green_volume = green.cell.volume();
    out.push_back(std::move(o));
  };
  dem::run_sintering(*scene.sim, s, false, snap);
  std::filesystem::remove_all(dir);
  return out;
}

}  // namespace tomodem::test
