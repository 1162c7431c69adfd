// The bond slots of the law registry (tomodem/dem/law_registry.hpp): every bond law and failure
// criterion describes itself and constructs (its loop is compiled and runs), its stiffness,
// energy and strength are the formulas of docs/physics.md written out here, and bad names and
// keys are refused with the registry's names and the entry's keys. The docs table (bond rows
// included) is checked by LawRegistry.DocsTableIsTheRegistrysTable.
#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <string>

#include "bond_kernel.hpp"
#include "scenes.hpp"
#include "tomodem/core/error.hpp"
#include "tomodem/dem/law_registry.hpp"
#include "tomodem/dem/scene.hpp"

using namespace tomodem;
using namespace tomodem::dem;
using namespace tomodem::dem::testing;
namespace fs = std::filesystem;

namespace {

/// The message of the InputError `f` throws, "" if none.
template <class F>
std::string error_of(F&& f) {
  try {
    f();
  } catch (const InputError& e) {
    return e.what();
  }
  return "";
}

bool has(const std::string& text, const std::string& part) { return text.find(part) != std::string::npos; }

/// Two equal spheres bonded at their touching distance, criterion `failure`, laws of glass.
Simulation bonded_pair(BondFailure failure, double tensile, double fracture_energy) {
  const double R = 0.5e-3, rho = 2500, E = 1e9, nu = 0.25;
  Particles p;
  p.add({2e-3, 2e-3, 2e-3}, R, rho, 0);
  p.add({2e-3 + 2 * R, 2e-3, 2e-3}, R, rho, 0);
  ContactModel m;
  m.normal = NormalLaw::hertz;
  m.materials = {material(E, nu, rho)};
  m.finalize();
  Simulation sim(std::move(p), Cell::box({0, 0, 0}, {4e-3, 4e-3, 4e-3}, true), m, Settings{});
  BondSet bonds;
  bonds.add(0, 1, {0, 0, 0}, 0.2 * R, 2 * R);
  BondLaw law;
  law.E_star = E / (2 * (1 - nu * nu));  // like phases: 1/E* = 2(1 − ν²)/E
  law.G_star = 0;
  law.tensile_strength = tensile;
  law.shear_strength = tensile;
  law.fracture_energy = fracture_energy;
  sim.set_bonds(bonds, {law}, failure);
  sim.set_time_step(0.2 * sim.critical_time_step());
  return sim;
}

}  // namespace

// Every entry describes itself completely, and every criterion has a compiled bond loop.
TEST(BondRegistry, EveryEntryIsDescribedAndConstructs) {
  ASSERT_FALSE(bond_law_entries().empty());
  ASSERT_GE(bond_failure_entries().size(), 3u);
  for (const BondLawInfo& e : bond_law_entries()) {
    EXPECT_EQ(e.slot, "bond");
    EXPECT_FALSE(e.summary.empty()) << e.key;
    EXPECT_EQ(find_bond_law(e.key), &e) << e.key;
    EXPECT_EQ(&parse_bond_law(e.key, "", "bond law"), &e) << e.key;
    EXPECT_TRUE(e.stiffness && e.energy) << e.key;
  }
  for (const BondFailureInfo& e : bond_failure_entries()) {
    EXPECT_EQ(e.slot, "bond failure");
    EXPECT_FALSE(e.summary.empty()) << e.key;
    EXPECT_EQ(find_bond_failure(e.key), &e) << e.key;
    EXPECT_EQ(&bond_failure_info(e.id), &e) << e.key;
    EXPECT_EQ(parse_bond_failure(e.key, "", "--criterion"), e.id) << e.key;
    EXPECT_TRUE(e.strength) << e.key;
    EXPECT_TRUE(select_bond_kernel(e.id, true) && select_bond_kernel(e.id, false)) << e.key;
  }
  for (const std::string& key : bond_param_keys()) {
    int declared = 0;
    for (const BondLawInfo& e : bond_law_entries()) declared += e.param(key) != nullptr;
    for (const BondFailureInfo& e : bond_failure_entries()) declared += e.param(key) != nullptr;
    EXPECT_GE(declared, 1) << key;
  }
  for (const BondLawInfo& e : bond_law_entries())
    for (const BondParam& p : e.params) {
      EXPECT_EQ(std::string(p.option).rfind("--", 0), 0u) << e.key << "." << p.key;
      EXPECT_TRUE(p.ref != nullptr) << e.key << "." << p.key;
    }
  for (const BondFailureInfo& e : bond_failure_entries())
    for (const BondParam& p : e.params) {
      EXPECT_EQ(std::string(p.option).rfind("--", 0), 0u) << e.key << "." << p.key;
      EXPECT_TRUE(p.ref != nullptr) << e.key << "." << p.key;
    }
}

// Each criterion's loop runs: a bonded pair at rest stays bonded with zero force for every
// criterion (u_n = 0: no stress, so none can break), and pulled apart at a fixed speed it
// breaks under the criteria that break bonds and never under `none`.
TEST(BondRegistry, EveryCriterionRunsItsLoop) {
  for (const BondFailureInfo& e : bond_failure_entries()) {
    Simulation rest = bonded_pair(e.id, 1e6, 1.0);
    rest.run(20);
    EXPECT_EQ(rest.bonds().intact_count(), 1u) << e.key;
    Simulation pulled = bonded_pair(e.id, 1e6, 1.0);
    // 1 m/s apart, k_n ≈ 1.2e5 N/m, m* ≈ 6.5e-7 kg: ½m*v² ≈ 3e-7 J against the ½k_n u² the bond
    // holds at its limit, 4e-9 J at σ_c = 1 MPa (u = σ_c πa²/k_n ≈ 2.5e-7 m) and 6e-8 J at the
    // LEFM σ_c ≈ 4 MPa for Γ = 1 J/m²: it breaks within the first ~µm, long before 500 steps
    // (Δt ≈ 1e-6 s). Under `none` it oscillates by v sqrt(m*/k_n) ≈ 2e-6 m and holds.
    pulled.particles().v[0] = {-0.5, 0, 0};
    pulled.particles().v[1] = {0.5, 0, 0};
    pulled.run(500);
    EXPECT_EQ(pulled.bonds().intact_count(), e.breaks ? 0u : 1u) << e.key;
  }
}

// The parallel bond's stiffnesses and energy are docs/physics.md#bond-stiffness written out:
// k_n = 2E*a g_n, k_t = 8G*a g_t, g = 1 + c (a/R̄)², R̄ = 2R_iR_j/(R_i+R_j), k_twist = ½k_t a²,
// k_bend = ¼k_n a², and the energy is the sum of the four springs' ½ k x². Same operations in a
// different order: equal to a few ulps (1e-14 relative).
TEST(BondRegistry, ParallelBondStiffnessAndEnergyAreTheFormulas) {
  const BondLawInfo& law = parse_bond_law("parallel", "", "bond law");
  BondLaw l;
  l.E_star = 1e9, l.G_star = 4e8;
  const double a = 0.3e-3, ri = 1e-3, rj = 0.5e-3, rb = 2 * ri * rj / (ri + rj);
  const double gn = 1 + 4.0 * (a / rb) * (a / rb), gt = 1 + 1.2 * (a / rb) * (a / rb);
  const BondStiffness k = law.stiffness(l, a, ri, rj);
  const double kn = 2 * 1e9 * a * gn, kt = 8 * 4e8 * a * gt;
  EXPECT_NEAR(k.kn, kn, 1e-14 * kn);
  EXPECT_NEAR(k.kt, kt, 1e-14 * kt);
  EXPECT_NEAR(k.ktwist, 0.5 * kt * a * a, 1e-14 * kt * a * a);
  EXPECT_NEAR(k.kbend, 0.25 * kn * a * a, 1e-14 * kn * a * a);
  const double un = 1e-6, tw = 2e-4;
  const Vec3 fs{0, 3, 4}, mb{1e-3, 0, 0};
  const double energy = 0.5 * kn * un * un + 0.5 * 25 / kt + 0.5 * tw * tw / (0.5 * kt * a * a) +
                        0.5 * 1e-6 / (0.25 * kn * a * a);
  EXPECT_NEAR(law.energy(k, un, fs, tw, mb), energy, 1e-14 * energy);
}

// The criteria's strengths: stress gives the strengths set; LEFM with g = 1 is Tada's external
// circular crack, so the critical axial force F_c = σ_c πa² has K_I = F_c/(2a sqrt(πa)) equal to
// K_IC = sqrt(2E*Γ) (Irwin, plane strain: 2E* = E/(1 − ν²) for like phases); none never breaks.
TEST(BondRegistry, CriteriaStrengthsAreTheirFormulas) {
  BondLaw l;
  l.E_star = 1e9, l.G_star = 4e8, l.tensile_strength = 2e6, l.shear_strength = 3e6, l.fracture_energy = 1.5;
  l.g_n_coefficient = l.g_t_coefficient = 0;
  const double a = 0.2e-3;
  const BondStiffness k = bond_stiffness(l, a, 1e-3, 1e-3);
  const BondStrength s = bond_failure_info(BondFailure::stress).strength(l, a, k);
  EXPECT_EQ(s.tension, 2e6);
  EXPECT_EQ(s.shear, 3e6);
  const BondStrength g = bond_failure_info(BondFailure::lefm).strength(l, a, k);
  const double Fc = g.tension * M_PI * a * a, KI = Fc / (2 * a * std::sqrt(M_PI * a));
  EXPECT_NEAR(KI, std::sqrt(2 * l.E_star * l.fracture_energy), 1e-12 * KI);  // round-off of sqrt and π
  // τ_c = 2 sqrt(8G*Γ g_t/(πa)): the same ligament under shear, with k_t = 8G*a g_t in place of k_n.
  EXPECT_NEAR(g.shear, 2 * std::sqrt(8 * l.G_star * l.fracture_energy / (M_PI * a)), 1e-12 * g.shear);
  const BondStrength n = bond_failure_info(BondFailure::none).strength(l, a, k);
  EXPECT_TRUE(std::isinf(n.tension) && std::isinf(n.shear));
  // The public bond_strength (libs/mechanics' SLA) is the registry's.
  EXPECT_EQ(bond_strength(BondFailure::lefm, l, a, k).tension, g.tension);
}

// Unknown names list the registry's names; `none` is refused where bonds must break.
TEST(BondRegistry, UnknownNamesListTheRegistrysNames) {
  const std::string bad = error_of([] { parse_bond_failure("griffith", "run.yaml", "--criterion", true); });
  EXPECT_TRUE(has(bad, "run.yaml") && has(bad, "--criterion") && has(bad, "griffith")) << bad;
  EXPECT_TRUE(has(bad, bond_failure_names(true))) << bad;
  for (const BondFailureInfo& e : bond_failure_entries())
    if (e.breaks) EXPECT_TRUE(has(bad, e.key)) << bad;
  const std::string none = error_of([] { parse_bond_failure("none", "", "--criterion", true); });
  EXPECT_TRUE(has(none, "never break") && has(none, "lefm")) << none;
  EXPECT_EQ(parse_bond_failure("none", "", "--criterion", false), BondFailure::none);
  const std::string law = error_of([] { parse_bond_law("beam", "", "bond law"); });
  EXPECT_TRUE(has(law, "beam") && has(law, bond_law_names())) << law;
}

// A parameter the chosen entry does not take is refused with the entry's keys; a required one
// missing and a value out of range name the option.
TEST(BondRegistry, KeysAnEntryDoesNotTakeAreRefused) {
  const BondFailureInfo& stress = *find_bond_failure("stress");
  const std::string foreign = error_of([&] {
    check_bond_settings(stress, {{"tensile_strength", 1e8, true}, {"shear_strength", 2e8, true}, {"fracture_energy", 5, true}});
  });
  EXPECT_TRUE(has(foreign, "--fracture-energy") && has(foreign, "5")) << foreign;
  EXPECT_TRUE(has(foreign, "the stress bond failure criterion does not take fracture_energy")) << foreign;
  EXPECT_TRUE(has(foreign, "it takes " + stress.keys())) << foreign;
  // The contact keys are not bond keys: a scene key given to a criterion is refused too.
  const std::string contact = error_of([&] { check_bond_settings(stress, {{"restitution", 0.5, true}}); });
  EXPECT_TRUE(has(contact, "restitution") && has(contact, stress.keys())) << contact;
  const std::string missing = error_of([&] {
    check_bond_settings(stress, {{"tensile_strength", 1e8, true}, {"shear_strength", 0, false}});
  });
  EXPECT_TRUE(has(missing, "--shear-strength") && has(missing, "needs shear_strength")) << missing;
  const std::string range = error_of([&] { check_bond_settings(stress, {{"tensile_strength", 1e8, true},
                                                                         {"shear_strength", 1e8, true},
                                                                         {"friction", -1, true}}); });
  EXPECT_TRUE(has(range, "--friction") && has(range, "-1")) << range;
  // Not given and not taken: nothing to refuse; values land in the fields the entry names.
  const std::vector<BondSetting> ok = {{"tensile_strength", 1e8, true}, {"shear_strength", 2e8, true},
                                       {"fracture_energy", 0, false}, {"friction", 0.4, true}};
  EXPECT_EQ(error_of([&] { check_bond_settings(stress, ok); }), "");
  BondLaw l;
  apply_bond_settings(stress, ok, l);
  EXPECT_EQ(l.tensile_strength, 1e8);
  EXPECT_EQ(l.shear_strength, 2e8);
  EXPECT_EQ(l.friction, 0.4);
  EXPECT_EQ(l.fracture_energy, 0.0);
}

// The bond keys and the contact keys are two lists: a bond key in a scene's `physics` is
// unknown there ("friction" is in both, with two meanings, and accepted by each).
TEST(BondRegistry, BondKeysAreNotSceneKeys) {
  const std::vector<std::string> contact = all_param_keys();
  const fs::path dir = fs::temp_directory_path() / ("tomodem-bond-registry-" + std::to_string(::getpid()));
  fs::create_directories(dir);
  const fs::path file = dir / "scene.yaml";
  for (const std::string& key : bond_param_keys()) {
    if (std::find(contact.begin(), contact.end(), key) != contact.end()) continue;
    std::ofstream(file) << "materials:\n  - {name: glass, youngs_modulus: 1.0e8, poisson_ratio: 0.25, density: 2500}\n"
                           "particles:\n  generate: {arrangement: simple_cubic, cells: 2, radius: 0.5e-3, spacing: 1.0e-3}\n"
                           "physics: {normal: hertz, " << key << ": 1}\nprotocol: {steps: 1}\n";
    const std::string msg = error_of([&] { load_scene(file.string(), 1); });
    EXPECT_TRUE(has(msg, key)) << key << ": " << msg;
  }
  fs::remove_all(dir);
}
