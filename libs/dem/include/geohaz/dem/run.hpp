#pragma once
/// \file run.hpp
/// A complete dem-avalanche run, callable from C++ without a subprocess (the app and the Python
/// module geohaz.dem both go through it). Three steps, each with one job:
///
///  1. `read_config(reader, false)` (config.hpp): every key read and checked, the avalanche's DSM
///     profile cut; InputError (file, key, value); writes nothing.
///  2. `DemSimulation sim(config)`; `sim.run(observer)`: the lab tests (the bonded sample built
///     once, then one test per confining stress, or the tension test) or the rock avalanche. The
///     observer sees every record of the drivers (progress, snapshots). SimulationError on a
///     blow-up, with the tests finished so far kept in the object.
///  3. `write_outputs(sim, out)`: the CSV tables, PNGs, tessellation and summary.json into an
///     existing directory. The summary and the tables come from `summary_json` and `csv_tables`,
///     which the Python module returns as they are.
///
/// `run_case(config, options, observer)` chains 2 and 3 the way `dem-avalanche` does (output folder
/// and resolved config created only now; snapshots and progress during the run) and returns the
/// run: the app and the Python module call only it. The same front end as runout's and sph's
/// run.hpp: `RunOptions`, `RunObserver`, `CaseRun run_case(config, options, observer)`.

#include <filesystem>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "geohaz/dem/config.hpp"
#include "geohaz/dem/experiments.hpp"
#include "geohaz/dem/solver.hpp"

namespace geohaz::dem {

/// One finished laboratory test.
struct LabRun {
  std::string name;                   ///< "sigma3_5MPa" or "tension": the stem of its output files
  double confining_stress = 0.0;      ///< σ_3 (Pa); 0 for the tension test
  LabTestResult result;               ///< curve, peak, moduli, AE catalogue
  std::unique_ptr<DemSolver> solver;  ///< the discs and bonds in their final state
};

class DemSimulation;

/// Sees a run as it goes (progress bars, snapshot writers, a Python callback). Default: nothing.
/// Called once per record of the drivers (every few tens of steps), never per disc or pair.
class RunObserver {
 public:
  virtual ~RunObserver() = default;
  /// A test starts: a lab test by its name, or "avalanche"; `expected_time` is the simulated time
  /// it should last (s; lab: max strain × height / (2 × loading velocity); avalanche: settle +
  /// run-out time).
  virtual void started(const DemSimulation&, const std::string& /*test*/, double /*expected_time*/) {}
  /// A record of the driver in `phase` ("consolidation", "loading", "settling", "runout").
  virtual void recorded(const DemSimulation&, const DemSolver&, const std::string& /*phase*/) {}
  /// The test ended; `solver` is in its final state (lab: `sim.lab_runs().back()` holds its result).
  virtual void finished(const DemSimulation&, const std::string& /*test*/, const DemSolver& /*solver*/) {}
};

/// Several observers called in turn (null entries skipped).
class RunObservers : public RunObserver {
 public:
  explicit RunObservers(std::vector<RunObserver*> list) : list_(std::move(list)) {}
  void started(const DemSimulation& sim, const std::string& test, double t) override;
  void recorded(const DemSimulation& sim, const DemSolver& s, const std::string& phase) override;
  void finished(const DemSimulation& sim, const std::string& test, const DemSolver& s) override;

 private:
  std::vector<RunObserver*> list_;
};

/// One dem-avalanche run: the lab tests of one bonded sample, or one rock avalanche.
class DemSimulation {
 public:
  /// Takes a config that read_config has checked; nothing runs yet.
  explicit DemSimulation(RunConfig config);

  /// Build the sample and run every test (lab) or the avalanche. SimulationError on a blow-up.
  void run(RunObserver* observer = nullptr);

  const RunConfig& config() const noexcept { return config_; }
  /// A lab run (biaxial compression or tension), not an avalanche.
  bool is_lab() const noexcept { return config_.kind != TestKind::Avalanche; }
  /// The lab sample (valid once run() has built it).
  const BondedSample& sample() const noexcept { return sample_; }
  /// The lab tests finished so far, in the order of biaxial.confining_stresses.
  const std::vector<LabRun>& lab_runs() const noexcept { return lab_runs_; }
  /// The avalanche's result (valid after run()).
  const AvalancheResult& avalanche() const noexcept { return avalanche_; }
  /// The avalanche's discs and bonds in their final state.
  const DemSolver& avalanche_solver() const noexcept { return *avalanche_solver_; }

 private:
  void run_lab(RunObserver& observer);
  void run_avalanche_case(RunObserver& observer);

  RunConfig config_;
  BondedSample sample_;
  std::vector<LabRun> lab_runs_;
  AvalancheResult avalanche_;
  std::unique_ptr<DemSolver> avalanche_solver_;
};

/// File-name stem of the compression test at confining stress `sigma3` (Pa): "sigma3_5MPa".
std::string lab_test_name(double sigma3);

/// The warnings of a finished run (an avalanche still moving at avalanche.runout_time).
std::vector<std::string> run_warnings(const DemSimulation& sim);

/// The key figures of `sim` as the JSON text of summary.json (the app and geohaz.dem read the same).
std::string summary_json(const DemSimulation& sim);

/// The CSV tables of `sim` as (file stem, CSV text) in the app's order: per lab test
/// curve_<name> and ae_<name>; avalanche runout, ae, deposit, fragments. Numbers with 9
/// significant digits.
std::vector<std::pair<std::string, std::string>> csv_tables(const DemSimulation& sim);

/// Write the tables, PNGs, tessellation (output.tessellation) and summary.json of `sim` into the
/// existing directory `out`.
void write_outputs(const DemSimulation& sim, const std::filesystem::path& out);

/// How run_case runs (the fields of runout's RunOptions but its thread count, which only the runout
/// summary records).
struct RunOptions {
  std::filesystem::path out;  ///< folder of the outputs (created by run_case); empty: none (the run only)
  bool quiet = false;         ///< no progress, sample or result lines on stderr (the warnings still)
};

/// A run that has ended: the discs, bonds, tests and figures in their final state.
struct CaseRun {
  std::unique_ptr<DemSimulation> simulation;
};

/// The whole `dem-avalanche` run of a checked config (read_config). With `options.out`: create it,
/// write config.resolved.toml, run with snapshots (snapshots[_<test>].h5) and progress on stderr
/// (unless quiet; the warnings always), call `observer` too (may be null), and write the outputs;
/// on a SimulationError the lab tests finished so far still get their tables and pictures (no
/// summary), then it goes on. Without: the run only, `observer` its only witness (nothing written
/// or printed; the Python module's in-memory run). Returns the run.
CaseRun run_case(RunConfig config, const RunOptions& options, RunObserver* observer = nullptr);

}  // namespace geohaz::dem
