// dem-avalanche: bonded-disc DEM (libs/dem, docs/dem.md) — biaxial compression and tension tests of
// a bonded rock sample, and rock avalanches of a bonded, jointed rock mass on a terrain profile.
// The config reader is libs/dem (config.hpp); this file validates everything
// before writing anything, then runs and writes the outputs.
#include <cmath>
#include <fstream>
#include <iomanip>
#include <iostream>
#include <nlohmann/json.hpp>
#include <numbers>
#include <sstream>

#include "geohaz/core/app.hpp"
#include "geohaz/core/config.hpp"
#include "geohaz/core/errors.hpp"
#include "geohaz/core/output.hpp"
#include "geohaz/core/progress.hpp"
#include "geohaz/core/snapshot.hpp"
#include "geohaz/dem/config.hpp"
#include "geohaz/dem/experiments.hpp"
#include "geohaz/dem/output.hpp"
#include "geohaz/dem/tessellation.hpp"

using namespace geohaz;
using namespace geohaz::dem;
using json = nlohmann::json;

namespace {

json lab_json(const LabTestResult& r) {
  return {{"peak_stress_Pa", r.peak_stress},
          {"peak_axial_strain", r.peak_strain},
          {"deviator_at_peak_Pa", r.deviator_at_peak},
          {"confining_stress_measured_Pa", r.confining_stress},
          {"youngs_modulus_Pa", r.youngs_modulus},
          {"poisson_ratio", r.poisson_ratio},
          {"crack_band_inclination_deg", r.crack_plane_angle},
          {"tensile_breaks", r.tensile_breaks},
          {"shear_breaks", r.shear_breaks},
          {"bonds", r.bonds},
          {"discs", r.discs},
          {"porosity", r.porosity},
          {"width_m", r.width},
          {"height_m", r.height}};
}

json discontinuity_json(const DiscontinuityReport& d) {
  json sets = json::array();
  for (std::size_t k = 0; k < d.set_dip.size(); ++k)
    sets.push_back({{"dip_deg", d.set_dip[k]}, {"traces", d.set_traces[k]}, {"length_m", d.set_length[k]}});
  return {{"traces", d.traces},
          {"total_length_m", d.total_length},
          {"intensity_P21_per_m", d.intensity_p21},
          {"bonds_cut", d.bonds_cut},
          {"sets", sets}};
}

std::string fmt_stress_name(double s) {
  std::ostringstream o;
  o << "sigma3_" << std::setprecision(4) << s / 1e6 << "MPa";
  return o.str();
}

int run_lab(const RunConfig& c, const std::filesystem::path& out, bool quiet) {
  const bool tension = c.kind == TestKind::Tension;
  std::vector<double> conf = tension ? std::vector<double>{0.0} : c.confining;
  make_output_dir(out);
  write_text_file(out / "config.resolved.toml", c.resolved);
  if (!quiet) std::cerr << "dem-avalanche: building the bonded sample\n";
  const BondedSample sample = build_bonded_sample(c.lab.packing, c.lab.material);
  if (c.write_tessellation) {
    const auto& x = sample.packed.discs.get<Position<2>>();
    const auto t =
        tessellate(x, sample.packed.discs.get<Radius>(), Vec2(0, 0), Vec2(sample.packed.width, sample.packed.height));
    write_tessellation_vtk(out / "sample", t, x);
  }
  json summary = {{"model", "dem-avalanche"},
                  {"version", GEOHAZ_VERSION},
                  {"test", tension ? "biaxial-tension" : "biaxial-compression"},
                  {"sample",
                   {{"discs", sample.packed.discs.size()},
                    {"bonds", sample.bonds.intact_count()},
                    {"porosity", sample.packed.porosity},
                    {"coordination_number", sample.packed.coordination},
                    {"width_m", sample.packed.width},
                    {"height_m", sample.packed.height},
                    {"locked_in_stress_Pa", {sample.packed.stress_x, sample.packed.stress_y}}}},
                  {"discontinuities", discontinuity_json(sample.discontinuities)}};
  json tests = json::array();
  std::vector<double> s3, s1;
  for (double sig3 : conf) {
    LabTestSpec spec = c.lab;
    spec.confining_stress = sig3;
    const std::string name = tension ? "tension" : fmt_stress_name(sig3);
    DemSolver s;
    s.settings = c.numerics;
    SnapshotWriter snaps(out / ("snapshots_" + name + ".h5"), "dem-avalanche", 2, c.resolved);
    snaps.set_attribute("units", "SI; discs of unit thickness (forces N/m, energies J/m)");
    // Progress in simulated time; the loading ends at about max strain × H / (2 v).
    ProgressReporter progress("dem-avalanche " + name,
                              spec.max_axial_strain * sample.packed.height / (2.0 * spec.loading_velocity), quiet);
    int records = 0;
    auto observe = [&](const DemSolver& sv, const std::string& phase) {
      if (phase != "loading") return;
      if (records == 0 || (c.snapshot_every > 0 && records % c.snapshot_every == 0)) write_snapshot(snaps, sv);
      ++records;
    };
    auto observe_progress = [&](const DemSolver& sv, const std::string& phase) {
      observe(sv, phase);
      progress.update(sv.time(), sv.step_count(), sv.discs.size());
    };
    LabTestResult r = run_lab_test(spec, sample, s, observe_progress);
    write_snapshot(snaps, s);
    progress.finish(s.time(), s.step_count(), s.discs.size());
    write_curve_csv(out / ("curve_" + name + ".csv"), r.curve);
    write_ae_csv(out / ("ae_" + name + ".csv"), r.events);
    {
      std::ostringstream title;
      title << (tension ? "tension test" : "biaxial test, confining stress sigma3 = ") << std::setprecision(4);
      if (!tension) title << sig3 / 1e6 << " MPa";
      write_sample_png(out / ("cracks_" + name + ".png"), s, title.str());
    }
    json j = lab_json(r);
    j["name"] = name;
    j["confining_stress_Pa"] = sig3;
    tests.push_back(j);
    if (!tension) {
      s3.push_back(sig3);
      s1.push_back(r.peak_stress);
    }
    if (!quiet)
      std::cerr << "dem-avalanche: " << name << ": peak " << r.peak_stress / 1e6 << " MPa at strain " << r.peak_strain
                << ", E = " << r.youngs_modulus / 1e9 << " GPa, nu = " << r.poisson_ratio << ", breaks "
                << r.tensile_breaks << " tensile / " << r.shear_breaks << " shear\n";
  }
  summary["tests"] = tests;
  if (s3.size() >= 2) {
    const auto mc = fit_mohr_coulomb(s3, s1);
    summary["mohr_coulomb"] = {{"valid", mc.valid},
                               {"cohesion_Pa", mc.cohesion},
                               {"friction_angle_deg", mc.friction_angle},
                               {"intercept_Pa", mc.intercept},
                               {"slope", mc.slope},
                               {"failure_plane_angle_deg", mc.failure_plane_angle}};
  }
  write_text_file(out / "summary.json", summary.dump(2) + "\n");
  return kExitOk;
}

int run_avalanche_case(const RunConfig& c, const std::filesystem::path& out, bool quiet) {
  make_output_dir(out);
  write_text_file(out / "config.resolved.toml", c.resolved);
  DemSolver s;
  s.settings = c.numerics;
  SnapshotWriter snaps(out / "snapshots.h5", "dem-avalanche", 2, c.resolved);
  snaps.set_attribute("units", "SI; discs of unit thickness (forces N/m, energies J/m)");
  const double t_end = c.avalanche.settle_time + c.avalanche.runout_time;
  ProgressReporter progress("dem-avalanche", t_end, quiet);
  int records = 0;
  bool first = true;
  auto observe = [&](const DemSolver& sv, const std::string& phase) {
    if (first) {
      write_snapshot(snaps, sv);
      first = false;
    }
    if (phase == "runout") {
      if (c.snapshot_every > 0 && records % c.snapshot_every == 0) write_snapshot(snaps, sv);
      ++records;
    }
    progress.update(sv.time(), sv.step_count(), sv.discs.size());
  };
  AvalancheResult r = run_avalanche(c.avalanche, s, observe);
  write_snapshot(snaps, s);
  progress.finish(s.time(), s.step_count(), s.discs.size());
  write_avalanche_csv(out / "runout.csv", r.series);
  write_ae_csv(out / "ae.csv", r.events);
  write_deposit_csv(out / "deposit.csv", r.deposit);
  write_deposit_png(out / "deposit_thickness.png", r.deposit);
  {
    // Fragments, largest first: size, mass, equivalent-area diameter, centre of mass, travel.
    std::ostringstream o;
    o << std::setprecision(9) << "fragment,discs,mass_kg_per_m,equivalent_diameter_m,x_m,z_m,travel_m\n";
    for (std::size_t k = 0; k < r.fragments.size(); ++k) {
      const auto& f = r.fragments[k];
      const double d = 2.0 * std::sqrt(f.mass / c.avalanche.packing.density / std::numbers::pi);
      o << k << ',' << f.discs << ',' << f.mass << ',' << d << ',' << f.x << ',' << f.z << ',' << f.travel << '\n';
    }
    write_text_file(out / "fragments.csv", o.str());
  }
  write_avalanche_png(out / "deposit.png", s, c.avalanche.terrain, c.avalanche.source);
  std::size_t tens = 0, shear = 0;
  for (const auto& e : r.events) (e.mode == FailureMode::Tensile ? tens : shear) += 1;
  std::size_t multi = 0;
  for (auto n : r.fragment_sizes) multi += n >= 2;
  json quantiles = json::array();
  for (const auto& q : r.quantiles)
    quantiles.push_back({{"mass_fraction", q.fraction},
                         {"toe", {q.x, q.z}},
                         {"runout_L_m", q.runout},
                         {"fall_height_H_m", q.fall_height},
                         {"H_over_L", q.h_over_l}});
  double mass_total = 0;
  for (const auto& f : r.fragments) mass_total += f.mass;
  const double largest_fraction = r.fragments.empty() ? 0.0 : r.fragments.front().mass / mass_total;
  json summary = {{"model", "dem-avalanche"},
                  {"version", GEOHAZ_VERSION},
                  {"test", "avalanche"},
                  {"discs", r.discs},
                  {"bonds_initial", r.bonds},
                  {"bonds_intact_final", s.bonds.intact_count()},
                  {"bond_breaks", {{"tensile", tens}, {"shear", shear}, {"before_release", r.events_before_release}}},
                  {"release_time_s", r.release_time},
                  {"discontinuities", discontinuity_json(r.discontinuities)},
                  {"source_area_m2", r.area},
                  {"volume_m3", r.volume},
                  {"crown", {r.crown_x, r.crown_z}},
                  {"toe", {r.toe_x, r.toe_z}},
                  {"runout_L_m", r.runout},
                  {"fall_height_H_m", r.fall_height},
                  {"H_over_L", r.h_over_l},
                  {"toe_definition", "x below which 99 % of the mass lies"},
                  {"runout_by_mass_quantile", quantiles},
                  {"centre_of_mass",
                   {{"start", {r.com_start.x(), r.com_start.y()}},
                    {"end", {r.com_end.x(), r.com_end.y()}},
                    {"H_over_L", r.com_h_over_l}}},
                  {"fragment_mass_fraction_of_largest", largest_fraction},
                  {"scheidegger_1973_H_over_L", r.scheidegger_h_over_l},
                  {"fragments_final", r.fragment_sizes.size()},
                  {"fragments_with_2_or_more_discs", multi},
                  {"largest_fragment_discs", r.fragment_sizes.empty() ? 0 : r.fragment_sizes.front()},
                  {"simulated_time_s", s.time()},
                  {"runout_duration_s", r.duration},
                  {"at_rest", r.at_rest},
                  {"max_speed_at_end_m_s", r.max_speed_at_end},
                  {"moving_mass_fraction_at_end", r.moving_fraction_at_end},
                  {"peak_kinetic_energy_J_per_m", r.peak_kinetic_energy},
                  {"steps", s.step_count()}};
  json warnings = json::array();
  if (!r.at_rest) {
    std::ostringstream w;
    w << "the run reached avalanche.runout_time (" << c.avalanche.runout_time << " s) with "
      << 100.0 * r.moving_fraction_at_end << " % of the mass still moving (fastest disc " << r.max_speed_at_end
      << " m/s): run-out, H/L and the deposit are not final; raise avalanche.runout_time";
    warnings.push_back(w.str());
    std::cerr << "dem-avalanche: warning: " << w.str() << "\n";
  }
  summary["warnings"] = warnings;
  write_text_file(out / "summary.json", summary.dump(2) + "\n");
  if (!quiet)
    std::cerr << "dem-avalanche: run-out L = " << r.runout << " m, H = " << r.fall_height << " m, H/L = " << r.h_over_l
              << " (Scheidegger 1973: " << r.scheidegger_h_over_l << " for V = " << r.volume << " m^3)\n";
  return kExitOk;
}

}  // namespace

int main(int argc, char** argv) {
  ConfigApp app;
  app.name = "dem-avalanche";
  app.summary =
      "bonded-disc DEM (parallel bonds, Potyondy & Cundall 2004) of rock: biaxial compression "
      "and tension tests of a bonded sample, and rock avalanches of a jointed rock mass on a "
      "terrain profile.\n"
      "Usage: dem-avalanche --config case.toml [--set key=value ...] [--out DIR] [--threads N] [--quiet]\n"
      "Example: dem-avalanche --config data/dem/biaxial_compression.toml --set bond.tensile_strength=40e6 "
      "--out biaxial-out";
  app.options_caption =
      "Options (SI units throughout: m, s, kg, Pa; discs are 1 m thick, so forces are N/m and energies J/m; "
      "angles in the config in degrees)";
  app.describe = [](ConfigReader& r) { (void)read_config(r, true); };
  app.run = [](ConfigReader& reader, const CommonOptions& opts) {
    RunConfig cfg = read_config(reader, false);
    reader.finish();
    cfg.resolved = reader.resolved();
    // Everything is validated before the output directory is created.
    return run_in_output_dir(opts.out, "dem-avalanche", {}, [&] {
      return cfg.kind == TestKind::Avalanche ? run_avalanche_case(cfg, opts.out, opts.quiet)
                                             : run_lab(cfg, opts.out, opts.quiet);
    });
  };
  return run_config_app(argc, argv, app);
}
