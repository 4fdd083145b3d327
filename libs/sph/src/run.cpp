#include "geohaz/sph/run.hpp"

#include <memory>
#include <optional>
#include <string_view>

#include "geohaz/core/errors.hpp"
#include "geohaz/core/output.hpp"
#include "geohaz/core/progress.hpp"
#include "geohaz/core/snapshot.hpp"
#include "run_support.hpp"

// The simulation object of sph-slope and the files of a run. The analyses are in run_dynamic.cpp,
// run_strength_reduction.cpp and limit_equilibrium_run.cpp; what they share in run_support.hpp.

namespace geohaz::sph {

struct SphSimulation::Impl {
  std::unique_ptr<SimulationModel> model;
  std::shared_ptr<const Communicator> comm;  // over several ranks; null on one process
};

SphSimulation::SphSimulation(const RunConfig& cfg, bool quiet, std::shared_ptr<const Communicator> comm)
    : cfg_(cfg), impl_(std::make_unique<Impl>()) {
  if (comm) check_distributable(cfg);
  impl_->comm = comm;
  // The limit-equilibrium analysis has no particles: every rank computes it (a few milliseconds), rank
  // 0 writes it.
  if (cfg.analysis == Analysis::LimitEquilibrium)
    impl_->model = make_limit_equilibrium_run(cfg, quiet);
  else if (cfg.analysis == Analysis::StrengthReduction)
    impl_->model = make_strength_reduction_run(cfg, quiet, std::move(comm));
  else
    impl_->model = make_dynamic_run(cfg, quiet, std::move(comm));
}

SphSimulation::~SphSimulation() = default;

void SphSimulation::run(RunObserver* observer) {
  impl_->model->run(*this, observer);
}
double SphSimulation::time() const {
  return impl_->model->time();
}
std::int64_t SphSimulation::step_count() const {
  return impl_->model->step_count();
}
std::size_t SphSimulation::particle_count() const {
  return impl_->model->particle_count();
}
bool SphSimulation::main_phase_started() const {
  return impl_->model->main_phase_started();
}
std::string SphSimulation::summary_json() const {
  return impl_->model->summary().dump(2) + "\n";
}
std::vector<NamedTable> SphSimulation::tables() const {
  return impl_->model->tables();
}
ParticleFields SphSimulation::particles() const {
  return impl_->model->particles();
}

/// The files of a run made during it (the output folder, the resolved config, the snapshots and
/// the velocity PNGs) and the progress lines on stderr; passes every event on to `next`. Over several
/// ranks every rank has one with the same folder: rank 0 makes the folder and writes the files, every
/// rank its part of the snapshots (the writer is collective, and so are the model's snapshot and
/// picture calls), in the same order on every rank.
class SphRunFiles final : public RunObserver {
 public:
  SphRunFiles(const SphSimulation& sim, std::filesystem::path out, bool quiet, RunObserver* next)
      : model_(*sim.impl_->model), cfg_(sim.config()), out_(std::move(out)), quiet_(quiet), next_(next) {
    if (out_.empty()) return;
    const auto& comm = sim.impl_->comm;
    if (!comm || comm->rank() == 0) {
      make_output_dir(out_);
      write_text_file(out_ / "config.resolved.toml", cfg_.resolved_config);
    }
    if (cfg_.analysis == Analysis::LimitEquilibrium) return;  // no particles
    snaps_ = std::make_unique<SnapshotWriter>(out_ / "snapshots.h5", "sph-slope", cfg_.dimension, cfg_.resolved_config,
                                              comm);
    snaps_->set_attribute("scenario", scenario_name(cfg_.scenario));
    snaps_->set_attribute("units", "SI: m, s, kg, Pa");
    if (cfg_.analysis == Analysis::StrengthReduction)
      snaps_->set_attribute("contents",
                            "snapshot 0: geostatic state; snapshot 1: the failed trial at the critical factor");
    else if (cfg_.scenario == ScenarioType::Section && !cfg_.section.crs_wkt.empty())
      snaps_->set_attribute("crs_wkt", cfg_.section.crs_wkt);
  }
  void progress(const SphSimulation& sim, const RunProgress& p) override {
    if (std::string_view(p.phase) == "geostatic") {
      if (!geostatic_) geostatic_.emplace("sph-slope geostatic", p.end_time, quiet_);
      if (p.done)
        geostatic_->finish(p.time, p.steps, p.particles);
      else if (p.steps > 0)
        geostatic_->update(p.time, p.steps, p.particles);
    }
    if (next_) next_->progress(sim, p);
  }
  // The snapshot points are the same on every rank of a distributed run (the writer is collective).
  void started(const SphSimulation& sim) override {
    if (snaps_) model_.write_snapshot(*snaps_);
    next_snap_ = sim.time() + cfg_.snapshot_interval;
    if (cfg_.analysis == Analysis::Dynamic) main_.emplace("sph-slope", cfg_.end_time, quiet_);
    if (next_) next_->started(sim);
  }
  void before_step(const SphSimulation& sim) override {
    if (!out_.empty()) model_.draw_due_pngs(out_);
    if (next_) next_->before_step(sim);
  }
  void stepped(const SphSimulation& sim) override {
    if (main_) main_->update(sim.time(), sim.step_count(), sim.particle_count());
    if (cfg_.snapshot_interval > 0.0 && sim.time() >= next_snap_ - 1e-12) {
      if (snaps_) model_.write_snapshot(*snaps_);
      next_snap_ += cfg_.snapshot_interval;
    }
    if (next_) next_->stepped(sim);
  }
  void finished(const SphSimulation& sim) override {
    if (main_) main_->finish(sim.time(), sim.step_count(), sim.particle_count());
    if (snaps_) model_.write_snapshot(*snaps_);
    if (next_) next_->finished(sim);
  }
  /// Close the snapshot file.
  void close() { snaps_.reset(); }
  SimulationModel& model() { return model_; }

 private:
  SimulationModel& model_;
  const RunConfig& cfg_;
  std::filesystem::path out_;
  bool quiet_;
  RunObserver* next_;
  std::unique_ptr<SnapshotWriter> snaps_;
  std::optional<ProgressReporter> geostatic_, main_;
  double next_snap_ = 0.0;
};

void write_outputs(const SphSimulation& sim, const std::filesystem::path& out) {
  sim.impl_->model->write_outputs(out);
}

void run_with_outputs(SphSimulation& sim, const std::filesystem::path& out, bool quiet, RunObserver* observer) {
  // Over several ranks the files are rank 0's (SphRunFiles); every rank runs the collective parts.
  const bool writes = !out.empty() && (!sim.impl_->comm || sim.impl_->comm->rank() == 0);
  SphRunFiles files(sim, out, quiet, observer);
  try {
    sim.run(&files);
  } catch (const SimulationError&) {
    if (writes && sim.main_phase_started()) files.model().write_partial(out);
    throw;
  }
  files.close();
  if (writes) write_outputs(sim, out);
}

CaseRun run_case(const RunConfig& cfg, const RunOptions& options, RunObserver* observer) {
  CaseRun run;
  run.simulation = std::make_unique<SphSimulation>(cfg, options.quiet, options.comm);
  run_with_outputs(*run.simulation, options.out, options.quiet, observer);
  return run;
}

}  // namespace geohaz::sph
