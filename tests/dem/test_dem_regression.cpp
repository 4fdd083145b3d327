// Regression tests of the bonded-disc DEM: small biaxial tests whose qualitative behaviour is
// established for bonded-particle models (Potyondy & Cundall 2004), an unbonded pile, and the
// dem-avalanche app on tiny configs (exit codes, outputs).
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <numbers>
#include <sstream>

#include "bonded_lab_spec.hpp"
#include "column_collapse.hpp"
#include "geohaz/core/plot.hpp"
#include "geohaz/core/raster.hpp"
#include "geohaz/core/snapshot.hpp"
#include "geohaz/dem/experiments.hpp"
#include "geohaz/dem/summary_keys.hpp"
#include "run_command.hpp"
#include "summary_keys_check.hpp"

using namespace geohaz;
using namespace geohaz::dem;
namespace fs = std::filesystem;

namespace {

LabTestSpec small_lab(double rmin = 1.2e-3) {
  return geohaz::dem::testing::bonded_lab({0.03, 0.06, rmin, 1, 1500, 5000, 0.25});
}

/// Elastic modulus only: strong bonds, stop at a small strain.
double elastic_modulus(LabTestSpec s) {
  s.material.bond.tensile_strength = s.material.bond.shear_strength = 1e12;
  s.max_axial_strain = 1.5e-3;
  s.confining_stress = 1e6;
  const BondedSample sample = build_bonded_sample(s.packing, s.material);
  DemSolver solver;
  const auto r = run_lab_test(s, sample, solver);
  // Fit over the whole (linear) record past the first few points.
  std::vector<double> e, q;
  for (std::size_t k = r.curve.size() / 4; k < r.curve.size(); ++k) {
    e.push_back(r.curve[k].axial_strain);
    q.push_back(r.curve[k].axial_stress);
  }
  double me = 0, mq = 0;
  for (std::size_t k = 0; k < e.size(); ++k) {
    me += e[k] / e.size();
    mq += q[k] / q.size();
  }
  double sxy = 0, sxx = 0;
  for (std::size_t k = 0; k < e.size(); ++k) {
    sxy += (e[k] - me) * (q[k] - mq);
    sxx += (e[k] - me) * (e[k] - me);
  }
  return sxy / sxx;
}

}  // namespace

TEST(DemRegression, BiaxialPeakRisesWithConfinementAndBreaksAreMostlyTensile) {
  LabTestSpec spec = small_lab();
  const BondedSample sample = build_bonded_sample(spec.packing, spec.material);
  ASSERT_GT(sample.packed.discs.size(), 150u);
  std::vector<double> s3, s1, nu;
  for (double c : {0.0, 10e6}) {
    spec.confining_stress = c;
    DemSolver solver;
    const auto r = run_lab_test(spec, sample, solver);
    s3.push_back(c);
    s1.push_back(r.peak_stress);
    nu.push_back(r.poisson_ratio);
    std::printf("sigma3 = %g MPa: peak %.1f MPa, E = %.1f GPa, nu = %.3f\n", c / 1e6, r.peak_stress / 1e6,
                r.youngs_modulus / 1e9, r.poisson_ratio);
    // Potyondy & Cundall (2004, §4.3): most bond breaks are tensile even in compression.
    EXPECT_GT(r.tensile_breaks, 2 * r.shear_breaks) << "sigma3 = " << c;
    EXPECT_GT(r.tensile_breaks, 10u);
    EXPECT_GT(r.youngs_modulus, 5e9);
    EXPECT_LT(r.youngs_modulus, 100e9);
    // The peak is an interior point of the record (the test went past it).
    EXPECT_LT(r.peak_strain, r.curve.back().axial_strain);
    if (c > 0) {
      EXPECT_NEAR(r.confining_stress, c, 0.25 * c);  // servo holds σ_3 (chatter of a few contacts)
    }
  }
  EXPECT_GT(s1[1], s1[0] + 0.5 * (s3[1] - s3[0]));  // friction: dσ_1/dσ_3 well above 1
  // Unconfined ν from the width averaged over the height: 0.385 here against 0.294 at 10 MPa (the
  // unbonded contacts across the sample open without σ_3, docs/validation/dem.md). The overall
  // extent of the discs, used before, gave 0.68. Tolerance 0.15: twice the spread of ν over σ_3 =
  // 5–20 MPa in the validation series (0.34–0.27).
  EXPECT_LT(nu[0], nu[1] + 0.15);
  EXPECT_GT(nu[0], 0.0);
  const auto mc = fit_mohr_coulomb(s3, s1);
  EXPECT_TRUE(mc.valid);
  EXPECT_GT(mc.friction_angle, 10.0);
  EXPECT_LT(mc.friction_angle, 60.0);
}

TEST(DemRegression, AcousticEmissionAcceleratesBeforePeak) {
  LabTestSpec spec = small_lab();
  spec.confining_stress = 5e6;
  const BondedSample sample = build_bonded_sample(spec.packing, spec.material);
  DemSolver solver;
  const auto r = run_lab_test(spec, sample, solver);
  std::size_t ipk = 0;
  for (std::size_t k = 0; k < r.curve.size(); ++k)
    if (r.curve[k].axial_stress > r.curve[ipk].axial_stress) ipk = k;
  // Breaks in the first half of the pre-peak record vs the second half.
  std::size_t first = 0, second = 0;
  for (std::size_t k = 0; k <= ipk; ++k) (k < ipk / 2 ? first : second) += r.curve[k].ae_count;
  std::printf("AE before peak: first half %zu, second half %zu\n", first, second);
  EXPECT_GT(second, 2 * first + 1);
}

TEST(DemRegression, ModulusScalesWithMicroModuliAndNotWithDiscSize) {
  const LabTestSpec base = small_lab();
  const double E1 = elastic_modulus(base);
  LabTestSpec stiff = base;
  stiff.material.law = LinearSpringCoulomb{2 * 40e9, 2 * 40e9 / 2.5};
  stiff.material.bond.modulus = 40e9;
  const double E2 = elastic_modulus(stiff);
  // Linear elasticity of the contact/bond network: doubling every micro-modulus doubles E.
  std::printf("E = %.3g Pa, doubled moduli: %.3g Pa\n", E1, E2);
  EXPECT_NEAR(E2 / E1, 2.0, 0.1);
  // PFC2D scaling k_n = 2E_c, k̄_n = Ē_c/(R_A + R_B): E does not depend on the disc size (±15 %,
  // different packings of 170 and 400 discs).
  const double Esmall = elastic_modulus(small_lab(0.8e-3));
  std::printf("E with R_min 0.8 mm: %.3g Pa (R_min 1.2 mm: %.3g Pa)\n", Esmall, E1);
  EXPECT_NEAR(Esmall / E1, 1.0, 0.15);
}

TEST(DemRegression, PeakStrengthScalesWithBondStrength) {
  // Unconfined: the strength comes from the bonds, so doubling σ̄_c and τ̄_c (means and standard
  // deviations, same sample) nearly doubles the UCS; contact friction adds a little, so ratio < 2.
  LabTestSpec spec = small_lab();
  spec.confining_stress = 0;
  const BondedSample sample = build_bonded_sample(spec.packing, spec.material);
  DemSolver s1;
  const double p1 = run_lab_test(spec, sample, s1).peak_stress;
  BondedSample strong = sample;
  for (std::size_t b = 0; b < strong.bonds.size(); ++b) {
    strong.bonds.tensile_strength[b] *= 2;
    strong.bonds.shear_strength[b] *= 2;
  }
  DemSolver s2;
  const double p2 = run_lab_test(spec, strong, s2).peak_stress;
  std::printf("UCS %.3g Pa, with doubled bond strengths %.3g Pa\n", p1, p2);
  EXPECT_GT(p2 / p1, 1.6);
  EXPECT_LT(p2 / p1, 2.2);
}

TEST(DemRegression, AngleOfReposeRisesWithRollingResistance) {
  auto repose = [](double mu_r) {
    DemSolver s;
    s.law = LinearSpringCoulomb{5e6, 2.5e6};
    s.contact.friction = 0.5;
    s.contact.rolling_friction = mu_r;
    s.contact.restitution = 0.3;
    s.settings.local_damping = 0.1;
    std::int64_t id = 0;
    const double r = 0.005;
    for (int a = 0; a < 12; ++a)
      for (int b = 0; b < 25; ++b)
        add_disc(s.discs, Vec2(0.0105 * a + 0.0052 * (b % 2), 0.0055 + 0.0095 * b),
                 r * (0.8 + 0.05 * ((a * 7 + b * 3) % 5)), 2650, id++);
    WallSegment floor;
    floor.a = Vec2(-1, 0);
    floor.b = Vec2(1, 0);
    floor.friction = 0.5;
    s.walls.push_back(floor);
    WallSegment left = floor;
    left.a = Vec2(0 - r, 0);
    left.b = Vec2(-r, 1);
    s.walls.push_back(left);  // a column against a wall on the left collapses to the right
    s.initialise();
    s.run_until(1.0);
    // Angle of the free surface: the slope of the highest disc top against x over the pile.
    const auto& x = s.discs.get<Position<2>>();
    double xmax = 0;
    for (std::size_t i = 0; i < s.discs.size(); ++i) xmax = std::max(xmax, x[i].x());
    return geohaz::dem::testing::surface_angle(s.discs, xmax, 10, 1, 9);
  };
  const double a0 = repose(0.0), a1 = repose(0.3);
  RecordProperty("repose_angle_mu_r_0", std::to_string(a0));
  RecordProperty("repose_angle_mu_r_0.3", std::to_string(a1));
  std::printf("angle of repose: mu_r = 0: %.1f deg, mu_r = 0.3: %.1f deg\n", a0, a1);
  EXPECT_GT(a0, 2.0);       // a pile, not a monolayer
  EXPECT_GT(a1, a0 + 3.0);  // rolling resistance steepens the pile (e.g. Zhou et al. 2002)
}

TEST(DemRegression, ColumnCollapseFollowsTheExperimentalScaling) {
  // The validation column (docs/validation/column_collapse.md) at half the width, L0 = 30 mm
  // (15 mean diameters, 116 and 678 discs), μ = 0.5, μ_r = 0.3. Band: 0.7–1.6 × Lube et al. (2005)
  // (1.2 a for a ≲ 1.8, 1.9 a^{2/3} for a ≳ 2.8). Upper 1.6: glass beads in a channel run ≈ 1.5×
  // further than Lube's sand (Lajeunesse et al. 2005) and a 2D disc packing is round-grained;
  // lower 0.7: seed scatter (±5 % at 1800 discs, more here) and the size effect at 15 diameters.
  // Without rolling resistance (μ_r = 0) the a = 3 column runs 7.0 L0 (1.8×) and the a = 0.5 one
  // spreads to a monolayer, so the band fails where the physics is wrong.
  geohaz::dem::testing::ColumnSpec c;
  c.width = 0.03;
  c.rolling_friction = 0.3;
  double r05 = 0, r3 = 0;
  for (double a : {0.5, 3.0}) {
    c.aspect_ratio = a;
    DemSolver s;
    const auto r = geohaz::dem::testing::run_column(c, s);
    const double law = r.a < 1.8 ? 1.2 * r.a : 1.9 * std::pow(r.a, 2.0 / 3.0);
    std::printf("column a = %.2f: (Linf - L0)/L0 = %.2f (Lube 2005: %.2f), Hinf/H0 = %.2f\n", r.a, r.runout(), law,
                r.height / r.H0);
    EXPECT_GT(r.runout(), 0.7 * law) << "a = " << a;
    EXPECT_LT(r.runout(), 1.6 * law) << "a = " << a;
    (a < 1 ? r05 : r3) = r.runout();
    // Lube et al. (2005): for small a the failure does not reach the top, H∞ = H0.
    if (a < 1) {
      EXPECT_GT(r.height / r.H0, 0.95);
    }
  }
  EXPECT_GT(r3, 4.0 * r05);  // run-out grows faster than a^{2/3} from 0.5 to 3 (6^{2/3} = 3.3)
}

// ---------------------------------------------------------------------------------------------
// The app

namespace {

const fs::path kApp = fs::path(GEOHAZ_BINARY_DIR) / "apps" / "dem-avalanche" / "dem-avalanche";
const fs::path kData = fs::path(GEOHAZ_SOURCE_DIR) / "data" / "dem";

int run_app(const std::string& args) {
  return geohaz::testing::run_command(kApp.string() + " " + args).code;
}

fs::path fresh_dir(const std::string& name) {
  const fs::path d = fs::path(GEOHAZ_BINARY_DIR) / "tests" / "dem" / name;
  fs::remove_all(d);
  return d;
}

nlohmann::json read_json(const fs::path& p) {
  std::ifstream in(p);
  const auto j = nlohmann::json::parse(in);
  if (p.filename() == "summary.json") EXPECT_SUMMARY_KEYS_DECLARED(j, geohaz::dem::summary_keys());  // issue #33
  return j;
}

const std::string kTinyLab =
    " --set sample.r_min=1.2e-3 --set sample.r_max=2e-3 --set sample.expansion_steps=1000"
    " --set sample.relax_steps=3000 --set output.snapshot_every=5 --threads 1 --quiet";

}  // namespace

TEST(DemApp, BiaxialCompressionTinyConfig) {
  const fs::path out = fresh_dir("app_compression");
  ASSERT_EQ(run_app("--config " + (kData / "biaxial_compression.toml").string() + kTinyLab +
                    " --set 'biaxial.confining_stresses=[0.0, 10e6]' --out " + out.string()),
            0);
  for (const char* f : {"summary.json", "config.resolved.toml", "curve_sigma3_0MPa.csv", "curve_sigma3_10MPa.csv",
                        "ae_sigma3_10MPa.csv", "cracks_sigma3_10MPa.png", "snapshots_sigma3_10MPa.h5",
                        "snapshots_sigma3_10MPa.xmf", "sample_cells.vtk", "sample_triangulation.vtk"})
    EXPECT_TRUE(fs::exists(out / f)) << f;
  // The crack picture is framed by numbered axes in metres with their titles (core's plotter).
  EXPECT_EQ(geohaz::check_plot_png(out / "cracks_sigma3_10MPa.png"), std::vector<std::string>{});
  const auto j = read_json(out / "summary.json");
  ASSERT_EQ(j["tests"].size(), 2u);
  const double p0 = j["tests"][0]["peak_stress_Pa"], p1 = j["tests"][1]["peak_stress_Pa"];
  EXPECT_GT(p1, p0);
  EXPECT_TRUE(j["mohr_coulomb"]["valid"].get<bool>());
  // Stored values (this build, 22 Nov 2026). The sample is fixed by the seed (184 discs, 362
  // bonds since the disc–wall dashpot reproduces its restitution, 1 Dec 2026: the packing's servo
  // walls shape the sample; 355 before); the peaks may move with compiler / library rounding,
  // amplified near the peak by bond breaking, so they are compared within 10 %.
  EXPECT_EQ(j["sample"]["discs"].get<int>(), 184);
  EXPECT_EQ(j["sample"]["bonds"].get<int>(), 362);
  EXPECT_NEAR(p0, 47.2e6, 4.7e6);
  EXPECT_NEAR(p1, 76.5e6, 7.6e6);
  // Snapshots: several time levels, the documented fields, intact bonds as line cells.
  SnapshotReader snap(out / "snapshots_sigma3_10MPa.h5");
  ASSERT_GE(snap.snapshot_count(), 2u);
  EXPECT_EQ(snap.model(), "dem-avalanche");
  for (const char* f : {"position", "velocity", "rotation", "radius", "broken_bonds", "intact_bonds"})
    EXPECT_TRUE(snap.has_field(0, f)) << f;
  const auto first = snap.lines(0), last = snap.lines(snap.snapshot_count() - 1);
  EXPECT_GT(first.size(), 0u);
  EXPECT_EQ(first.size() % 2, 0u);
  EXPECT_LT(last.size(), first.size());  // bonds broke during the test
  const auto broken = snap.read(snap.snapshot_count() - 1, "broken_bonds");
  double nb = 0;
  for (double v : broken.values) nb += v;
  EXPECT_GT(nb, 0.0);
  // Same seed, same sample: the numbers are reproducible run to run (serial run, same build).
  const fs::path out2 = fresh_dir("app_compression_again");
  ASSERT_EQ(run_app("--config " + (kData / "biaxial_compression.toml").string() + kTinyLab +
                    " --set 'biaxial.confining_stresses=[0.0, 10e6]' --out " + out2.string()),
            0);
  EXPECT_EQ(read_json(out2 / "summary.json")["tests"][1]["peak_stress_Pa"].get<double>(), p1);
}

TEST(DemApp, BiaxialTensionTinyConfig) {
  const fs::path out = fresh_dir("app_tension");
  ASSERT_EQ(run_app("--config " + (kData / "biaxial_tension.toml").string() + kTinyLab + " --out " + out.string()), 0);
  const auto j = read_json(out / "summary.json");
  const double st = j["tests"][0]["peak_stress_Pa"];
  // Stored value (this build; 17.0 MPa on the 355-bond sample before the disc–wall dashpot
  // change, 18.8 MPa on today's 362-bond sample), 10 % as for the compression peaks.
  EXPECT_NEAR(st, 18.8e6, 1.9e6);
  // Macro tensile strength of a BPM is a fraction of the mean bond strength (50 MPa here).
  EXPECT_GT(st, 2e6);
  EXPECT_LT(st, 50e6);
  EXPECT_GT(j["tests"][0]["tensile_breaks"].get<int>(), j["tests"][0]["shear_breaks"].get<int>());
}

TEST(DemApp, AvalancheTinyConfig) {
  const fs::path out = fresh_dir("app_avalanche");
  ASSERT_EQ(run_app("--config " + (kData / "avalanche.toml").string() +
                    " --set sample.r_min=1.2 --set sample.r_max=2.0 --set avalanche.runout_time=4"
                    " --set avalanche.settle_time=0.5 --set output.snapshot_every=4 --threads 1 --quiet --out " +
                    out.string()),
            0);
  for (const char* f : {"summary.json", "runout.csv", "ae.csv", "deposit.csv", "fragments.csv", "deposit.png",
                        "snapshots.h5", "snapshots.xmf"})
    EXPECT_TRUE(fs::exists(out / f)) << f;
  for (const char* f : {"deposit.png", "deposit_thickness.png"})  // numbered, titled axes
    EXPECT_EQ(geohaz::check_plot_png(out / f), std::vector<std::string>{}) << f;
  const auto j = read_json(out / "summary.json");
  std::printf("tiny avalanche: %d discs, toe x = %.1f m\n", j["discs"].get<int>(), j["toe"][0].get<double>());
  // After 4 s on a 35° slope the mass has moved down-slope: the toe is beyond the source.
  EXPECT_GT(j["toe"][0].get<double>(), 60.0);
  EXPECT_GT(j["fall_height_H_m"].get<double>(), 0.0);
  EXPECT_GT(j["runout_L_m"].get<double>(), 0.0);
  EXPECT_GT(j["discontinuities"]["bonds_cut"].get<int>(), 0);
  // Cut off at 4 s with the mass still moving: the summary says so.
  EXPECT_FALSE(j["at_rest"].get<bool>());
  ASSERT_EQ(j["warnings"].size(), 1u);
  EXPECT_NE(j["warnings"][0].get<std::string>().find("avalanche.runout_time"), std::string::npos);
  EXPECT_GT(j["moving_mass_fraction_at_end"].get<double>(), 0.5);
}

TEST(DemApp, AvalancheRunsToRest) {
  // The same tiny mass with the default time limit stops on the stop criterion (kinetic energy
  // below 10⁻³ of its peak and no disc faster than 0.1 m/s), about 40 s after release.
  const fs::path out = fresh_dir("app_avalanche_rest");
  ASSERT_EQ(run_app("--config " + (kData / "avalanche.toml").string() +
                    " --set sample.r_min=1.2 --set sample.r_max=2.0 --set avalanche.settle_time=0.5"
                    " --set output.snapshot_every=0 --threads 1 --quiet --out " +
                    out.string()),
            0);
  const auto j = read_json(out / "summary.json");
  EXPECT_TRUE(j["at_rest"].get<bool>());
  EXPECT_TRUE(j["warnings"].empty());
  EXPECT_LE(j["max_speed_at_end_m_per_s"].get<double>(), 0.1);
  EXPECT_EQ(j["moving_mass_fraction_at_end"].get<double>(), 0.0);
  EXPECT_LT(j["runout_duration_s"].get<double>(), 300.0);
}

TEST(DemApp, AvalancheOnAProfileCutFromADsm) {
  // A synthetic DSM: a 35°-ish plane z = max(0, 280 − 0.7 x) on a 5 m grid, no CRS (metres).
  const fs::path dir = fresh_dir("app_dsm");
  fs::create_directories(dir);
  Raster r;
  r.nx = 200;
  r.ny = 20;
  r.geotransform = {0.0, 5.0, 0.0, 100.0, 0.0, -5.0};
  r.data.resize(static_cast<std::size_t>(r.nx * r.ny));
  for (int row = 0; row < r.ny; ++row)
    for (int col = 0; col < r.nx; ++col) r.at(col, row) = std::max(0.0, 280.0 - 0.7 * r.cell_centre(col, row).x());
  write_geotiff(dir / "dsm.tif", r);
  const std::string toml = R"(test = "avalanche"
seed = 2
[sample]
r_min = 1.2
r_max = 2.0
[material]
contact_modulus = 1e9
[bond]
modulus = 1e9
tensile_strength = 1e6
shear_strength = 1e6
[avalanche]
dsm = "dsm.tif"
section_x = [10.0, 990.0]
section_y = [50.0, 50.0]
section_spacing = 5.0
source_x = [20.0, 50.0, 50.0, 20.0]
source_z = [260.0, 239.0, 252.0, 273.0]
settle_time = 0.3
runout_time = 2.0
)";
  std::ofstream(dir / "case.toml") << toml;
  const fs::path out = dir / "out";
  ASSERT_EQ(run_app("--config " + (dir / "case.toml").string() + " --threads 1 --quiet --out " + out.string()), 0);
  const auto j = read_json(out / "summary.json");
  EXPECT_GT(j["discs"].get<int>(), 10);
  // The profile starts at s = 0 at z(10) = 273 m; after 2 s the mass has moved down-slope.
  EXPECT_GT(j["toe"][0].get<double>(), 50.0);
  EXPECT_LT(j["toe"][1].get<double>(), 250.0);
}

TEST(DemApp, BlowUpStopsWithExitCode1AndKeepsSnapshots) {
  // A speed limit far below the run-out speeds makes the blow-up check fire deterministically.
  const fs::path out = fresh_dir("app_blowup");
  EXPECT_EQ(run_app("--config " + (kData / "avalanche.toml").string() +
                    " --set sample.r_min=1.2 --set sample.r_max=2.0 --set avalanche.settle_time=0.2"
                    " --set numerics.max_speed=5 --set output.snapshot_every=1 --threads 1 --quiet --out " +
                    out.string()),
            1);
  EXPECT_TRUE(fs::exists(out / "snapshots.h5"));  // what was written is kept
  EXPECT_TRUE(fs::exists(out / "snapshots.xmf"));
  EXPECT_FALSE(fs::exists(out / "summary.json"));
  const std::string cmd = kApp.string() + " --config " + (kData / "avalanche.toml").string() +
                          " --set sample.r_min=1.2 --set sample.r_max=2.0 --set avalanche.settle_time=0.2"
                          " --set numerics.max_speed=5 --threads 1 --quiet --out " +
                          out.string();
  const std::string msg = geohaz::testing::run_command(cmd).output;
  // The diagnosis names the disc, its position and the step.
  EXPECT_NE(msg.find("disc id"), std::string::npos) << msg;
  EXPECT_NE(msg.find("at step"), std::string::npos) << msg;
}

TEST(DemApp, BadInputExitsWithCode2AndWritesNothing) {
  const fs::path out = fresh_dir("app_bad");
  // Out-of-range value.
  EXPECT_EQ(run_app("--config " + (kData / "biaxial_compression.toml").string() + " --set sample.porosity=0.9 --out " +
                    out.string()),
            2);
  EXPECT_FALSE(fs::exists(out));
  // Unknown key.
  EXPECT_EQ(run_app("--config " + (kData / "biaxial_compression.toml").string() + " --set sample.radius=1 --out " +
                    out.string()),
            2);
  EXPECT_FALSE(fs::exists(out));
  // Inconsistent radii.
  EXPECT_EQ(run_app("--config " + (kData / "biaxial_compression.toml").string() + " --set sample.r_max=0.5e-3 --out " +
                    out.string()),
            2);
  EXPECT_FALSE(fs::exists(out));
  // Unknown test.
  EXPECT_EQ(run_app("--config " + (kData / "biaxial_compression.toml").string() + " --set test=shear-box --out " +
                    out.string()),
            2);
  EXPECT_FALSE(fs::exists(out));
  // A profile running uphill.
  EXPECT_EQ(run_app("--config " + (kData / "avalanche.toml").string() +
                    " --set 'avalanche.terrain_z=[0.0, 200.0, 200.0]' --out " + out.string()),
            2);
  EXPECT_FALSE(fs::exists(out));
  // A source polygon too small for the discs, and one below the terrain.
  EXPECT_EQ(run_app("--config " + (kData / "avalanche.toml").string() +
                    " --set sample.r_min=10 --set sample.r_max=16 --out " + out.string()),
            2);
  EXPECT_FALSE(fs::exists(out));
  EXPECT_EQ(run_app("--config " + (kData / "avalanche.toml").string() +
                    " --set 'avalanche.source_z=[100.0, 80.0, 90.0, 110.0]' --out " + out.string()),
            2);
  EXPECT_FALSE(fs::exists(out));
  // Stop fraction and speed, restitution, rolling resistance and its damping out of range: the message
  // names the key and the allowed range.
  for (const char* set :
       {"avalanche.stop_kinetic_fraction=1.0", "avalanche.stop_kinetic_fraction=0", "avalanche.terrain_restitution=1.5",
        "avalanche.terrain_restitution=0", "material.restitution=0", "material.restitution=1.5",
        "material.rolling_friction=-0.1", "avalanche.terrain_rolling_friction=-0.2",
        "avalanche.stop_kinetic_fraction=-0.5", "avalanche.stop_speed=-1", "material.rolling_damping=1.5",
        "material.tangential_damping=1.5", "material.tangential_damping=-0.1", "material.terrain_damping_mass=wheel",
        "material.terrain_rolling=wheel", "material.rolling_friction=2.5", "avalanche.terrain_rolling_friction=3"}) {
    const auto r = geohaz::testing::run_command(kApp.string() + " --config " + (kData / "avalanche.toml").string() +
                                                " --set " + set + " --out " + out.string());
    EXPECT_EQ(r.code, 2) << set;
    const std::string key(set, std::string(set).find('='));
    EXPECT_NE(r.output.find(key), std::string::npos) << r.output;
    EXPECT_NE(r.output.find("allowed"), std::string::npos) << r.output;  // the message states the range
    EXPECT_FALSE(fs::exists(out));
  }
  // Missing config file and help/version.
  EXPECT_EQ(run_app("--config /nonexistent.toml --out " + out.string()), 2);
  EXPECT_EQ(run_app("--help"), 0);
  EXPECT_EQ(run_app("--version"), 0);
  EXPECT_EQ(run_app("--help-config"), 0);
  EXPECT_FALSE(fs::exists(out));
}
