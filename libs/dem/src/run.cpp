// A dem-avalanche run (run.hpp): the simulation object running the lab tests or the avalanche,
// the one summary builder, the tables and the outputs, and run_case as the app and Python run it.
#include "geohaz/dem/run.hpp"

#include <cmath>
#include <iomanip>
#include <iostream>
#include <nlohmann/json.hpp>
#include <numbers>
#include <sstream>

#include "geohaz/core/errors.hpp"
#include "geohaz/core/output.hpp"
#include "geohaz/core/progress.hpp"
#include "geohaz/core/snapshot.hpp"
#include "geohaz/dem/output.hpp"
#include "geohaz/dem/tessellation.hpp"

namespace geohaz::dem {

using json = nlohmann::json;
namespace fs = std::filesystem;

namespace {

constexpr const char* kModel = "dem-avalanche";

}  // namespace

// ------------------------------------------------------------------------------------------
// Observers

void RunObservers::started(const DemSimulation& sim, const std::string& test, double t) {
  for (auto* o : list_)
    if (o) o->started(sim, test, t);
}

void RunObservers::recorded(const DemSimulation& sim, const DemSolver& s, const std::string& phase) {
  for (auto* o : list_)
    if (o) o->recorded(sim, s, phase);
}

void RunObservers::finished(const DemSimulation& sim, const std::string& test, const DemSolver& s) {
  for (auto* o : list_)
    if (o) o->finished(sim, test, s);
}

// ------------------------------------------------------------------------------------------
// The simulation

std::string lab_test_name(double sigma3) {
  std::ostringstream o;
  o << "sigma3_" << std::setprecision(4) << sigma3 / 1e6 << "MPa";
  return o.str();
}

DemSimulation::DemSimulation(RunConfig config) : config_(std::move(config)) {}

void DemSimulation::run(RunObserver* observer) {
  RunObserver none;
  RunObserver& obs = observer ? *observer : none;
  if (is_lab())
    run_lab(obs);
  else
    run_avalanche_case(obs);
}

void DemSimulation::run_lab(RunObserver& observer) {
  const RunConfig& c = config_;
  const bool tension = c.kind == TestKind::Tension;
  const std::vector<double> conf = tension ? std::vector<double>{0.0} : c.confining;
  lab_runs_.clear();
  sample_ = build_bonded_sample(c.lab.packing, c.lab.material);
  for (double sig3 : conf) {
    LabTestSpec spec = c.lab;
    spec.confining_stress = sig3;
    LabRun run;
    run.name = tension ? "tension" : lab_test_name(sig3);
    run.confining_stress = sig3;
    run.solver = std::make_unique<DemSolver>();
    run.solver->settings = c.numerics;
    // The loading ends at about max strain × H / (2 v).
    observer.started(*this, run.name, spec.max_axial_strain * sample_.packed.height / (2.0 * spec.loading_velocity));
    auto record = [&](const DemSolver& s, const std::string& phase) { observer.recorded(*this, s, phase); };
    run.result = run_lab_test(spec, sample_, *run.solver, record);
    const DemSolver& final_state = *run.solver;
    lab_runs_.push_back(std::move(run));
    observer.finished(*this, lab_runs_.back().name, final_state);
  }
}

void DemSimulation::run_avalanche_case(RunObserver& observer) {
  avalanche_solver_ = std::make_unique<DemSolver>();
  avalanche_solver_->settings = config_.numerics;
  observer.started(*this, "avalanche", config_.avalanche.settle_time + config_.avalanche.runout_time);
  auto record = [&](const DemSolver& s, const std::string& phase) { observer.recorded(*this, s, phase); };
  avalanche_ = run_avalanche(config_.avalanche, *avalanche_solver_, record);
  observer.finished(*this, "avalanche", *avalanche_solver_);
}

// ------------------------------------------------------------------------------------------
// Summary

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

json lab_summary(const DemSimulation& sim) {
  const bool tension = sim.config().kind == TestKind::Tension;
  const BondedSample& sample = sim.sample();
  json summary = {{"model", kModel},
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
  for (const LabRun& run : sim.lab_runs()) {
    json j = lab_json(run.result);
    j["name"] = run.name;
    j["confining_stress_Pa"] = run.confining_stress;
    tests.push_back(j);
    if (!tension) {
      s3.push_back(run.confining_stress);
      s1.push_back(run.result.peak_stress);
    }
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
  return summary;
}

/// The run-out, H/L and travel angle of the mass quantiles (the headline toe is the 0.99 one).
json quantiles_json(const AvalancheResult& r) {
  json quantiles = json::array();
  for (const auto& q : r.quantiles)
    quantiles.push_back({{"mass_fraction", q.fraction},
                         {"toe", {q.x, q.z}},
                         {"runout_L_m", q.runout},
                         {"fall_height_H_m", q.fall_height},
                         {"H_over_L", q.h_over_l}});
  return quantiles;
}

json avalanche_summary(const DemSimulation& sim) {
  const AvalancheResult& r = sim.avalanche();
  const DemSolver& s = sim.avalanche_solver();
  std::size_t tens = 0, shear = 0;
  for (const auto& e : r.events) (e.mode == FailureMode::Tensile ? tens : shear) += 1;
  std::size_t multi = 0;
  for (auto n : r.fragment_sizes) multi += n >= 2;
  double mass_total = 0;
  for (const auto& f : r.fragments) mass_total += f.mass;
  const double largest_fraction = r.fragments.empty() ? 0.0 : r.fragments.front().mass / mass_total;
  json summary = {{"model", kModel},
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
                  {"runout_by_mass_quantile", quantiles_json(r)},
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
                  {"max_speed_at_end_m_per_s", r.max_speed_at_end},
                  {"moving_mass_fraction_at_end", r.moving_fraction_at_end},
                  {"peak_kinetic_energy_J_per_m", r.peak_kinetic_energy},
                  {"steps", s.step_count()}};
  summary["warnings"] = run_warnings(sim);
  return summary;
}

/// Fragments, largest first: size, mass, equivalent-area diameter, centre of mass, travel.
std::string fragments_csv(const AvalancheResult& r, double density) {
  std::ostringstream o;
  o << std::setprecision(9) << "fragment,discs,mass_kg_per_m,equivalent_diameter_m,x_m,z_m,travel_m\n";
  for (std::size_t k = 0; k < r.fragments.size(); ++k) {
    const auto& f = r.fragments[k];
    const double d = 2.0 * std::sqrt(f.mass / density / std::numbers::pi);
    o << k << ',' << f.discs << ',' << f.mass << ',' << d << ',' << f.x << ',' << f.z << ',' << f.travel << '\n';
  }
  return o.str();
}

}  // namespace

std::vector<std::string> run_warnings(const DemSimulation& sim) {
  std::vector<std::string> warnings;
  if (sim.is_lab()) return warnings;
  const AvalancheResult& r = sim.avalanche();
  if (!r.at_rest) {
    std::ostringstream w;
    w << "the run reached avalanche.runout_time (" << sim.config().avalanche.runout_time << " s) with "
      << 100.0 * r.moving_fraction_at_end << " % of the mass still moving (fastest disc " << r.max_speed_at_end
      << " m/s): run-out, H/L and the deposit are not final; raise avalanche.runout_time";
    warnings.push_back(w.str());
  }
  return warnings;
}

std::string summary_json(const DemSimulation& sim) {
  return (sim.is_lab() ? lab_summary(sim) : avalanche_summary(sim)).dump(2) + "\n";
}

std::vector<std::pair<std::string, std::string>> csv_tables(const DemSimulation& sim) {
  std::vector<std::pair<std::string, std::string>> t;
  if (sim.is_lab()) {
    for (const LabRun& run : sim.lab_runs()) {
      t.emplace_back("curve_" + run.name, curve_csv(run.result.curve));
      t.emplace_back("ae_" + run.name, ae_csv(run.result.events));
    }
    return t;
  }
  const AvalancheResult& r = sim.avalanche();
  t.emplace_back("runout", avalanche_csv(r.series));
  t.emplace_back("ae", ae_csv(r.events));
  t.emplace_back("deposit", deposit_csv(r.deposit));
  t.emplace_back("fragments", fragments_csv(r, sim.config().avalanche.packing.density));
  return t;
}

// ------------------------------------------------------------------------------------------
// Outputs

namespace {

void write_lab_pictures(const DemSimulation& sim, const fs::path& out) {
  const bool tension = sim.config().kind == TestKind::Tension;
  if (sim.config().write_tessellation && sim.sample().packed.discs.size() > 0) {
    const auto& packed = sim.sample().packed;
    const auto& x = packed.discs.get<Position<2>>();
    const auto t = tessellate(x, packed.discs.get<Radius>(), Vec2(0, 0), Vec2(packed.width, packed.height));
    write_tessellation_vtk(out / "sample", t, x);
  }
  for (const LabRun& run : sim.lab_runs()) {
    std::ostringstream title;
    title << (tension ? "tension test" : "biaxial test, confining stress sigma3 = ") << std::setprecision(4);
    if (!tension) title << run.confining_stress / 1e6 << " MPa";
    write_sample_png(out / ("cracks_" + run.name + ".png"), *run.solver, title.str());
  }
}

void write_avalanche_pictures(const DemSimulation& sim, const fs::path& out) {
  const AvalancheSpec& a = sim.config().avalanche;
  write_deposit_png(out / "deposit_thickness.png", sim.avalanche().deposit);
  write_avalanche_png(out / "deposit.png", sim.avalanche_solver(), a.terrain, a.source);
}

/// The snapshots (HDF5 + XDMF) and the progress line of a run into `out`, as dem-avalanche writes
/// them: lab tests one file each (snapshots_<test>.h5: the first loading record, every
/// output.snapshot_every-th, and the final state); the avalanche one file (snapshots.h5: the first
/// record, every snapshot_every-th of the run-out, and the final state).
class OutputObserver : public RunObserver {
 public:
  OutputObserver(fs::path out, bool quiet) : out_(std::move(out)), quiet_(quiet) {}

  void started(const DemSimulation& sim, const std::string& test, double expected_time) override {
    const RunConfig& c = sim.config();
    const std::string file = sim.is_lab() ? "snapshots_" + test + ".h5" : "snapshots.h5";
    snapshots_ = std::make_unique<SnapshotWriter>(out_ / file, kModel, 2, c.resolved);
    snapshots_->set_attribute("units", "SI; discs of unit thickness (forces N/m, energies J/m)");
    progress_ = std::make_unique<ProgressReporter>(sim.is_lab() ? std::string(kModel) + " " + test : kModel,
                                                   expected_time, quiet_);
    records_ = 0;
    first_ = true;
  }

  void recorded(const DemSimulation& sim, const DemSolver& s, const std::string& phase) override {
    const int every = sim.config().snapshot_every;
    if (sim.is_lab()) {
      if (phase == "loading") {
        if (records_ == 0 || (every > 0 && records_ % every == 0)) write_snapshot(*snapshots_, s);
        ++records_;
      }
    } else {
      if (first_) {
        write_snapshot(*snapshots_, s);
        first_ = false;
      }
      if (phase == "runout") {
        if (every > 0 && records_ % every == 0) write_snapshot(*snapshots_, s);
        ++records_;
      }
    }
    progress_->update(s.time(), s.step_count(), s.discs.size());
  }

  void finished(const DemSimulation& sim, const std::string& test, const DemSolver& s) override {
    write_snapshot(*snapshots_, s);
    snapshots_.reset();  // closes the file
    progress_->finish(s.time(), s.step_count(), s.discs.size());
    if (!quiet_ && sim.is_lab()) {
      const LabTestResult& r = sim.lab_runs().back().result;
      std::cerr << kModel << ": " << test << ": peak " << r.peak_stress / 1e6 << " MPa at strain " << r.peak_strain
                << ", E = " << r.youngs_modulus / 1e9 << " GPa, nu = " << r.poisson_ratio << ", breaks "
                << r.tensile_breaks << " tensile / " << r.shear_breaks << " shear\n";
    }
  }

 private:
  fs::path out_;
  bool quiet_;
  std::unique_ptr<SnapshotWriter> snapshots_;
  std::unique_ptr<ProgressReporter> progress_;
  int records_ = 0;
  bool first_ = true;
};

}  // namespace

namespace {

/// Everything but the summary: the tables and pictures (lab: of the tests finished so far).
void write_tables_and_pictures(const DemSimulation& sim, const fs::path& out) {
  for (const auto& [stem, text] : csv_tables(sim)) write_text_file(out / (stem + ".csv"), text);
  if (sim.is_lab())
    write_lab_pictures(sim, out);
  else
    write_avalanche_pictures(sim, out);
}

}  // namespace

void write_outputs(const DemSimulation& sim, const fs::path& out) {
  write_tables_and_pictures(sim, out);
  write_text_file(out / "summary.json", summary_json(sim));
}

CaseRun run_case(RunConfig config, const RunOptions& options, RunObserver* observer) {
  CaseRun run;
  run.simulation = std::make_unique<DemSimulation>(std::move(config));
  DemSimulation& sim = *run.simulation;
  if (options.out.empty()) {
    sim.run(observer);
    return run;
  }
  const fs::path& out = options.out;
  const bool quiet = options.quiet;
  make_output_dir(out);
  write_text_file(out / "config.resolved.toml", sim.config().resolved);
  if (!quiet && sim.is_lab()) std::cerr << kModel << ": building the bonded sample\n";
  OutputObserver files(out, quiet);
  RunObservers observers({&files, observer});
  try {
    sim.run(&observers);
  } catch (const SimulationError&) {
    // As the app always did: the lab tests finished before the blow-up keep their tables and
    // pictures (and the sample its tessellation); no summary. An avalanche keeps its snapshots.
    if (sim.is_lab()) write_tables_and_pictures(sim, out);
    throw;
  }
  write_outputs(sim, out);
  for (const auto& w : run_warnings(sim)) std::cerr << kModel << ": warning: " << w << "\n";
  if (!quiet && !sim.is_lab()) {
    const AvalancheResult& r = sim.avalanche();
    std::cerr << kModel << ": run-out L = " << r.runout << " m, H = " << r.fall_height << " m, H/L = " << r.h_over_l
              << " (Scheidegger 1973: " << r.scheidegger_h_over_l << " for V = " << r.volume << " m^3)\n";
  }
  return run;
}

}  // namespace geohaz::dem
