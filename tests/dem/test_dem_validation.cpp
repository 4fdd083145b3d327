// Validation runs of the bonded-disc DEM (label `validation`, not in CI). Each writes its numbers
// to <build>/validation/dem/ for docs/validation/dem.md.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <numbers>

#include "geohaz/dem/experiments.hpp"
#include "geohaz/dem/output.hpp"
#include "bonded_lab_spec.hpp"

using namespace geohaz;
using namespace geohaz::dem;
namespace fs = std::filesystem;

namespace {

fs::path out_dir() {
  const fs::path d = fs::path(GEOHAZ_BINARY_DIR) / "validation" / "dem";
  fs::create_directories(d);
  return d;
}

LabTestSpec lab(double rmin) { return geohaz::dem::testing::bonded_lab({0.05, 0.1, rmin, 11, 3000, 10000, 0.1}); }

}  // namespace

TEST(DemValidation, BiaxialCompressionSeries) {
  LabTestSpec spec = lab(0.8e-3);
  const BondedSample sample = build_bonded_sample(spec.packing, spec.material);
  nlohmann::json j;
  j["discs"] = sample.packed.discs.size();
  j["bonds"] = sample.bonds.intact_count();
  j["porosity"] = sample.packed.porosity;
  std::vector<double> s3, s1;
  for (double c : {0.0, 5e6, 10e6, 20e6}) {
    spec.confining_stress = c;
    DemSolver s;
    const auto r = run_lab_test(spec, sample, s);
    char name[64];
    std::snprintf(name, sizeof name, "biaxial_sigma3_%gMPa", c / 1e6);
    write_curve_csv(out_dir() / (std::string(name) + ".csv"), r.curve);
    write_sample_png(out_dir() / (std::string(name) + ".png"), s);
    j["tests"].push_back({{"sigma3", c},
                          {"peak", r.peak_stress},
                          {"peak_strain", r.peak_strain},
                          {"E", r.youngs_modulus},
                          {"nu", r.poisson_ratio},
                          {"tensile", r.tensile_breaks},
                          {"shear", r.shear_breaks},
                          {"crack_angle", r.crack_plane_angle}});
    s3.push_back(c);
    s1.push_back(r.peak_stress);
    EXPECT_GT(r.tensile_breaks, r.shear_breaks);
  }
  for (std::size_t k = 1; k < s1.size(); ++k) EXPECT_GT(s1[k], s1[k - 1]);
  const auto mc = fit_mohr_coulomb(s3, s1);
  j["mohr_coulomb"] = {{"c", mc.cohesion}, {"phi", mc.friction_angle}, {"plane", mc.failure_plane_angle}};
  // Tension on the same sample.
  spec.test = LabTest::BiaxialTension;
  spec.post_peak_stop = 0.3;
  DemSolver st;
  const auto rt = run_lab_test(spec, sample, st);
  j["tension"] = {{"peak", rt.peak_stress}, {"E", rt.youngs_modulus}};
  std::ofstream(out_dir() / "biaxial.json") << j.dump(2) << "\n";
  EXPECT_TRUE(mc.valid);
}

TEST(DemValidation, ModulusIndependentOfDiscSize) {
  nlohmann::json j;
  for (double rmin : {1.2e-3, 0.8e-3, 0.5e-3}) {
    LabTestSpec s = lab(rmin);
    s.material.bond.tensile_strength = s.material.bond.shear_strength = 1e12;
    s.max_axial_strain = 1e-3;
    s.confining_stress = 1e6;
    const BondedSample sample = build_bonded_sample(s.packing, s.material);
    DemSolver solver;
    const auto r = run_lab_test(s, sample, solver);
    j.push_back(
        {{"r_min", rmin}, {"discs", sample.packed.discs.size()}, {"E", r.youngs_modulus}, {"nu", r.poisson_ratio}});
  }
  std::ofstream(out_dir() / "modulus_vs_size.json") << j.dump(2) << "\n";
  const double e0 = j[0]["E"], e2 = j[2]["E"];
  EXPECT_NEAR(e2 / e0, 1.0, 0.1);
}

TEST(DemValidation, GranularColumnCollapse) {
  // Quasi-2D collapse of a column of unbonded discs (width L0 = 40 mm ≈ 20 diameters, height
  // H0 = a L0, random dense packing) against a wall.
  // Lube et al. (2005) / Lajeunesse et al. (2005): (L∞ − L0)/L0 ≈ 1.2 a for a ≲ 2–3 and
  // ≈ 1.9 a^{2/3} (Lube) for larger a; H∞/L0 ≈ a for a < 1.15 and ≈ a^{0.4} (Lube: H∞/L0 = a^{2/5}) beyond.
  nlohmann::json j;
  const double r = 1e-3;
  for (double a : {0.5, 1.0, 2.0, 4.0}) {
    DemSolver s;
    s.law = LinearSpringCoulomb{2e5, 1e5};
    s.contact.friction = 0.5;
    s.contact.restitution = 0.3;
    s.contact.rolling_friction = 0.1;
    // A random dense packing (radius expansion in the column's box, no locked-in stress).
    PackingSpec pk;
    pk.width = 0.04;
    pk.height = a * pk.width;
    pk.r_min = 0.8e-3;
    pk.r_max = 1.2e-3;
    pk.porosity = 0.2;
    pk.locked_in_stress = 0;
    pk.seed = 5;
    PackedSample col = pack_discs_in_box(pk, s.law);
    s.discs = col.discs;
    const double L0 = col.width, H0 = col.height;
    WallSegment floor;
    floor.a = Vec2(-1, 0);
    floor.b = Vec2(10, 0);
    floor.friction = 0.5;
    s.walls.push_back(floor);
    WallSegment back = floor;
    back.a = Vec2(0, -0.1);
    back.b = Vec2(0, 10);
    s.walls.push_back(back);
    s.initialise();
    const double tend = 6 * std::sqrt(H0 / 9.81) + 0.3;
    s.run_until(tend);
    const auto& x = s.discs.get<Position<2>>();
    const auto& R = s.discs.get<Radius>();
    // Run-out: the front (99.5 % quantile of x + R), height at the wall.
    std::vector<double> xs;
    double h = 0;
    for (std::size_t i = 0; i < s.discs.size(); ++i) {
      xs.push_back(x[i].x() + R[i]);
      if (x[i].x() < 3 * r) h = std::max(h, x[i].y() + R[i]);
    }
    std::sort(xs.begin(), xs.end());
    const double Linf = xs[static_cast<std::size_t>(0.995 * (xs.size() - 1))];
    const double runout = (Linf - L0) / L0;
    const double lube = a < 1.8 ? 1.2 * a : 1.9 * std::pow(a, 2.0 / 3.0);
    j.push_back({{"a", a},
                 {"discs", s.discs.size()},
                 {"runout_norm", runout},
                 {"lube2005", lube},
                 {"H_inf_over_L0", h / L0},
                 {"time", tend}});
    std::printf("column a=%.1f: (Linf-L0)/L0 = %.2f (Lube 2005: %.2f), Hinf/L0 = %.2f\n", a, runout, lube, h / L0);
    EXPECT_GT(runout, 0.3 * lube);
    EXPECT_LT(runout, 3.0 * lube);
  }
  std::ofstream(out_dir() / "column_collapse.json") << j.dump(2) << "\n";
}

TEST(DemValidation, AvalancheHoverLVersusVolume) {
  // A 35° slope onto a flat floor; the source wedge is scaled by s (area ∝ s²). Report H/L against
  // Scheidegger (1973); assert only that the run-out is physical.
  nlohmann::json j;
  for (double sc : {0.5, 1.0, 1.5}) {
    AvalancheSpec a;
    a.terrain = {Vec2(0, 200), Vec2(285.6, 0), Vec2(1200, 0)};
    const Vec2 o(20, 186);
    const double t = std::tan(35 * std::numbers::pi / 180);
    const double Lx = 40 * sc, h = 17 * sc;
    a.source = {o, o + Vec2(Lx, -Lx * t), o + Vec2(Lx, -Lx * t + h), o + Vec2(0, h)};
    a.support = {o + Vec2(Lx + 0.5, -Lx * t - 10), o + Vec2(Lx + 0.5, -Lx * t + h + 10)};
    a.packing.r_min = 0.6;
    a.packing.r_max = 1.0;
    a.packing.porosity = 0.18;
    a.packing.locked_in_stress = 0;
    a.packing.seed = 3;
    a.material.law = LinearSpringCoulomb{2e9, 0.8e9};
    a.material.contact.friction = 0.5;
    a.material.contact.rolling_friction = 0.1;
    a.material.contact.restitution = 0.3;
    a.material.bond.modulus = 1e9;
    a.material.bond.tensile_strength = a.material.bond.shear_strength = 1e6;
    a.material.bond.tensile_strength_std = a.material.bond.shear_strength_std = 0.2e6;
    a.material.joint_sets = {JointSet{35, 5, 0.7, 8}, JointSet{-60, 8, 0.5, 6}};
    a.settle_time = 1.5;
    a.strength_factor = 0.5;
    a.runout_time = 30;
    a.record_interval = 0.5;
    a.terrain_friction = 0.5;
    DemSolver s;
    const auto r = run_avalanche(a, s);
    j.push_back({{"scale", sc},
                 {"discs", r.discs},
                 {"area", r.area},
                 {"volume", r.volume},
                 {"H", r.fall_height},
                 {"L", r.runout},
                 {"H_over_L", r.h_over_l},
                 {"scheidegger", r.scheidegger_h_over_l},
                 {"fragments", r.fragment_sizes.size()}});
    std::printf("avalanche scale %.1f: V = %.3g m3, H/L = %.3f (Scheidegger %.3f)\n", sc, r.volume, r.h_over_l,
                r.scheidegger_h_over_l);
    if (sc == 1.0) write_avalanche_png(out_dir() / "avalanche_deposit.png", s, a.terrain, a.source);
    EXPECT_GT(r.h_over_l, 0.05);
    EXPECT_LT(r.h_over_l, 1.5);
  }
  std::ofstream(out_dir() / "avalanche_h_over_l.json") << j.dump(2) << "\n";
}
