// run.analysis = dynamic: the geostatic phase (or a restart), then the main phase in time with its
// series, structure loads, quick-looks, the release handed to debris-runout and the summary's
// figures (docs/sph.md).
#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <iomanip>
#include <limits>
#include <nlohmann/json.hpp>
#include <numbers>
#include <optional>
#include <span>
#include <sstream>

#include "geohaz/core/errors.hpp"
#include "geohaz/core/handoff.hpp"
#include "geohaz/core/output.hpp"
#include "geohaz/core/raster.hpp"
#include "run_support.hpp"
#include "structure_report.hpp"

namespace geohaz::sph {

namespace {

/// What a material means under the model of the run, for summary.json and the log: the model's
/// declared figures (constitutive.hpp, MaterialFigure), key and value.
nlohmann::json model_parameters(const ConstitutiveModel& model, const MaterialParams& m) {
  nlohmann::json j = nlohmann::json::object();
  for (const MaterialFigure& f : material_figures(model)) j[std::string(f.key)] = f.value(m);
  return j;
}

/// The initial velocity of the main phase (initial_velocity.*); clamped particles stay at rest.
template <int Dim>
void set_initial_velocity(const RunConfig& c, SphStore<Dim>& S) {
  const auto& iv = c.initial_velocity;
  if (iv.type == InitialVelocity::Type::None) return;
  const auto& x = S.template get<Position<Dim>>();
  auto& v = S.template get<Velocity<Dim>>();
  for (std::size_t i = 0; i < S.size(); ++i) {
    if (S.template get<ParticleKind>()[i] != kSoil || S.template get<Clamped>()[i]) continue;
    if (iv.type == InitialVelocity::Type::Uniform) {
      for (int d = 0; d < Dim; ++d) v[i][d] = iv.value[static_cast<std::size_t>(d)];
    } else {
      v[i].setZero();
      v[i][Dim - 1] = iv.amplitude * cantilever_mode_shape((x[i][0] - iv.root) / iv.length);
    }
  }
}

/// The failed mass handed to debris-runout (docs/handoff.md) and, on the DSM grid, its thickness.
struct ReleaseOutput {
  Handoff handoff;
  double total = 0.0, width = 0.0;  ///< m³, m
  std::optional<Raster> thickness;  ///< release_thickness.tif (when the DSM is known)
  double binned = 0.0, max_thickness = 0.0;
};

/// A run in time: the geostatic phase (or a restart), then the main phase with its series,
/// structure loads, quick-looks and the summary's figures (docs/sph.md).
template <int Dim>
class DynamicRun final : public SimulationModel {
 public:
  DynamicRun(const RunConfig& c, bool quiet, std::shared_ptr<const Communicator> comm);
  void run(const SphSimulation& self, RunObserver* obs) override;
  double time() const override { return solver_.time(); }
  std::int64_t step_count() const override { return solver_.step_count(); }
  std::size_t particle_count() const override { return soil_count_ + boundary_count_; }
  bool main_phase_started() const override { return main_started_; }
  nlohmann::json summary() const override { return summary_with(release()); }
  std::vector<NamedTable> tables() const override;
  ParticleFields particles() const override { return fields_of(state()); }
  void write_snapshot(SnapshotWriter& w) const override {
    sph::write_snapshot<Dim>(w, solver_, step_offset_ + solver_.step_count());
  }
  void draw_due_pngs(const std::filesystem::path& out) override;
  void write_outputs(const std::filesystem::path& out) const override;
  void write_partial(const std::filesystem::path& out) const override;

 private:
  void print_header() const;
  void load_restart_state();
  void geostatic_phase(const SphSimulation& self, RunObserver* obs);
  void move_platens();
  void mark_free_end();
  double tip_displacement() const;
  void start_main_phase();
  void main_phase(const SphSimulation& self, RunObserver* obs);
  SeriesRow record();
  void record_biaxial();
  void write_pictures(const std::filesystem::path& out) const;
  ReleaseOutput release() const;
  void write_release(const std::filesystem::path& out, const ReleaseOutput& r) const;
  nlohmann::json summary_with(const ReleaseOutput& r) const;
  /// The whole state the pictures, the release and particles() read: the solver's store on one
  /// process; over several ranks, on rank 0, the copy gathered there by the last refresh_view()
  /// (every picture point and the end call it on every rank; the other ranks' copy is empty).
  const SphStore<Dim>& state() const { return solver_.domain() ? view_ : solver_.store(); }
  void refresh_view(bool force = false);
  /// What the diagnostics reduce over: this rank's owned particles and the ranks (one process:
  /// the whole store).
  OverRanks over() const {
    const auto* d = solver_.domain();
    return d ? OverRanks{&d->comm(), d->owned()} : OverRanks{};
  }
  /// The maximum, and the sums in rank order, of every rank's values (collective over several
  /// ranks; the values themselves on one process).
  double max_over_ranks(double v) const;
  std::vector<double> sum_over_ranks(std::vector<double> v) const;
  /// The final state's profiles and figures (collective over several ranks: reductions over the
  /// ranks, at the end of the main phase; on one process made from the store when asked).
  struct Finals {
    std::vector<std::array<double, 2>> surface, slip;
    FailedMass failed;
    double max_displacement = 0.0, max_plastic_strain = 0.0;
  };
  Finals make_finals() const;
  Finals finals() const { return solver_.domain() ? finals_ : make_finals(); }
  /// This process writes the files (one process, or rank 0 of several).
  bool root() const { return !solver_.domain() || solver_.domain()->rank() == 0; }
  void record_decomposition();

  const RunConfig& c_;
  bool quiet_;
  std::chrono::steady_clock::time_point wall0_;
  Built<Dim> b_;
  SolverSettings<Dim> settings_;
  std::size_t soil_count_, boundary_count_;
  double href_;
  SphSolver<Dim> solver_;
  StructureReport<Dim> structures_;
  std::vector<double> rho0_;
  bool have_loads_ = false;  // the loads of a step exist (not before the first step of a restart)
  std::int64_t step_offset_ = 0;
  nlohmann::json phase_summary_ = nlohmann::json::object();  // "restart" or "geostatic"
  // With clamped regions: the free end's particles by id (tip_displacement_m).
  std::vector<std::uint8_t> free_end_;
  bool main_started_ = false, finished_ = false, stopped_at_rest_ = false;
  // With pore water: the largest pore pressure of the soil at the series' rows and its time.
  double max_pore_pressure_ = 0.0, max_pore_pressure_time_ = 0.0;
  Table series_, biaxial_;
  std::vector<double> png_times_;
  std::size_t next_png_ = 0;
  double next_out_ = 0.0, max_speed_run_ = 0.0, max_runout_ = 0.0, last_moving_ = 0.0, t_start_ = 0.0;
  SeriesRow last_;
  StaticBishop bishop_;
  // Over several ranks: the gathered state (state()), the step it was gathered at, and the
  // decomposition's figures for summary.json.
  SphStore<Dim> view_;
  std::int64_t view_step_ = -1;
  Finals finals_;
  nlohmann::json decomposition_;
  // Over several ranks: the ranks, until the solver is distributed at the start of run() (after a
  // restart file's block is read).
  std::shared_ptr<const Communicator> comm_;
};

template <int Dim>
DynamicRun<Dim>::DynamicRun(const RunConfig& c, bool quiet, std::shared_ptr<const Communicator> comm)
    : c_(c),
      quiet_(quiet),
      wall0_(std::chrono::steady_clock::now()),
      b_(build<Dim>(c, share_of(comm.get()))),
      settings_(settings_for<Dim>(c, b_.sc)),
      soil_count_(b_.sc.soil_count),
      boundary_count_(b_.sc.boundary_count),
      href_(b_.sc.reference_height),
      solver_(std::move(b_.sc.store), c.materials, c.model, settings_),
      // Loads on the structures, tracked from the geostatic phase on: the first row is the state at rest.
      structures_(b_.sc.structures, reported_structures(c, b_.sc.structures)) {
  if (!structures_.empty()) {
    std::vector<Vec<Dim>> bases;
    for (const auto& s : b_.sc.structures) bases.push_back(s.base);
    solver_.track_structures(std::move(bases));
  }
  comm_ = std::move(comm);
  for (const auto& m : solver_.materials()) rho0_.push_back(m.density);
  if (c_.geostatic && c_.restart.empty() && c_.scenario != ScenarioType::Biaxial)
    geostatic_duration(c_, href_, solver_.max_wave_speed());  // checked now
  bishop_ = StaticBishop::of(c);
  if (!quiet_) print_header();
}

template <int Dim>
void DynamicRun<Dim>::print_header() const {
  const auto& mats = solver_.materials();
  std::fprintf(stderr, "sph-slope: %dD %s, %zu soil + %zu boundary particles, h = %.4g m, model %s\n", Dim,
               scenario_name(c_.scenario), soil_count_, boundary_count_, solver_.smoothing_length(),
               solver_.model_name().c_str());
  for (std::size_t k = 0; k < mats.size(); ++k)
    std::fprintf(stderr, "  material %zu (%s): c_p = %.4g m/s, DP fit %s, %s %s\n", k,
                 k < c_.material_names.size() ? c_.material_names[k].c_str() : "", mats[k].p_wave_speed,
                 drucker_prager_fit_name(mats[k].fit), solver_.model_name().c_str(),
                 model_parameters(c_.model, mats[k]).dump().c_str());
  if (bishop_.peak.admissible()) {
    std::fprintf(stderr, "  Bishop's factor of safety (static, critical circle, x = %.4g to %.4g m): %.3f",
                 bishop_.peak.x_entry, bishop_.peak.x_exit, bishop_.peak.factor);
    if (bishop_.residual.admissible()) std::fprintf(stderr, "; at residual strength %.3f", bishop_.residual.factor);
    std::fprintf(stderr, "\n");
    if (std::isfinite(bishop_.cover.factor))
      std::fprintf(stderr,
                   "  infinite-slope factor of the soil cover (translational slide along its base): %.3f at x = %.4g m "
                   "(%.1f deg over %.3g m)\n",
                   bishop_.cover.factor, bishop_.cover.x, bishop_.cover.angle * 180.0 / std::numbers::pi,
                   bishop_.cover.window);
  } else if (!bishop_.note.empty()) {
    std::fprintf(stderr, "  Bishop's factor of safety: none (%s)\n", bishop_.note.c_str());
  }
}

template <int Dim>
void DynamicRun<Dim>::run(const SphSimulation& self, RunObserver* obs) {
  if (!c_.restart.empty()) {
    load_restart_state();
  } else {
    if (comm_) solver_.distribute(comm_, true);  // built by share
    if (c_.geostatic && c_.scenario != ScenarioType::Biaxial) geostatic_phase(self, obs);
  }
  if (c_.scenario == ScenarioType::Biaxial) move_platens();
  if (c_.restart.empty()) set_initial_velocity<Dim>(c_, solver_.store());
  mark_free_end();
  start_main_phase();
  if (obs) obs->started(self);
  main_phase(self, obs);
}

template <int Dim>
void DynamicRun<Dim>::load_restart_state() {
  // Every rank reads its block of the file's rows (written on any number of ranks).
  const Restart rs = load_restart<Dim>(c_.restart, solver_.store(), share_of(comm_.get()));
  if (comm_) solver_.distribute(comm_, true);
  // With the solver state the run continues exactly as the one that wrote the file (on as many
  // ranks; on another count within round-off: other pair-sum orders); without it (files of older
  // versions) from the snapshot's particles, with Δt from the wave speed and a fresh neighbour list:
  // the same physics, another round-off.
  if (rs.state)
    solver_.resume(*rs.state);
  else
    solver_.set_time(rs.time);
  step_offset_ = rs.state ? 0 : rs.step;
  phase_summary_["restart"] = {
      {"file", c_.restart.string()}, {"time_s", rs.time}, {"step", rs.step}, {"exact", rs.state.has_value()}};
}

template <int Dim>
void DynamicRun<Dim>::geostatic_phase(const SphSimulation& self, RunObserver* obs) {
  const double dur = geostatic_duration(c_, href_, solver_.max_wave_speed());
  const auto rep = geostatic_with_progress(solver_, dur, c_, self, obs);
  have_loads_ = rep.steps > 0;
  const double tol = c_.rest_tolerance * std::sqrt(c_.numerics.gravity * href_);
  const bool at_rest = rep.max_speed < tol;
  phase_summary_["geostatic"] = {{"duration_s", dur},
                                 {"steps", rep.steps},
                                 {"max_speed_m_per_s", rep.max_speed},
                                 {"rest_tolerance_m_per_s", tol},
                                 {"at_rest", at_rest}};
  if (!quiet_)
    std::fprintf(stderr, "sph-slope: geostatic phase %.4g s (%lld steps): max speed %.3g m/s -> %s\n", dur,
                 static_cast<long long>(rep.steps), rep.max_speed,
                 at_rest ? "at rest" : "NOT at rest (see summary.json)");
}

/// Biaxial test: the platens move towards each other (compression) or apart (tension) at ε̇ H / 2 each.
template <int Dim>
void DynamicRun<Dim>::move_platens() {
  auto& S = solver_.store();
  const double vp = 0.5 * c_.biaxial_strain_rate * c_.biaxial.height;
  for (std::size_t i = 0; i < S.size(); ++i) {
    if (S.template get<ParticleKind>()[i] == kSoil) continue;
    const bool top = S.template get<Position<Dim>>()[i][Dim - 1] > 0.5 * c_.biaxial.height;
    S.template get<Velocity<Dim>>()[i].setZero();
    S.template get<Velocity<Dim>>()[i][Dim - 1] = top ? -vp : vp;
  }
}

/// With clamped regions: the free end's particles (initial x within Δx/2 of the largest soil x,
/// not clamped), whose mean vertical displacement is the series' tip_displacement_m.
template <int Dim>
void DynamicRun<Dim>::mark_free_end() {
  if (c_.clamp_boxes.empty()) return;
  const auto& S = solver_.store();
  const std::size_t n = solver_.owned_count();
  const auto& x = S.template get<Position<Dim>>();
  const auto& u = S.template get<Displacement<Dim>>();
  const auto& id = S.template get<ParticleId>();
  double xmax = -1e300;
  std::int64_t idmax = 0;
  for (std::size_t i = 0; i < n; ++i) {
    idmax = std::max(idmax, id[i]);
    if (S.template get<ParticleKind>()[i] == kSoil) xmax = std::max(xmax, x[i][0] - u[i][0]);
  }
  xmax = max_over_ranks(xmax);
  idmax = static_cast<std::int64_t>(max_over_ranks(static_cast<double>(idmax)));
  std::vector<std::int64_t> mine;  // the free end's ids on this rank; over several ranks every rank's
  for (std::size_t i = 0; i < n; ++i)
    if (S.template get<ParticleKind>()[i] == kSoil && !S.template get<Clamped>()[i] &&
        x[i][0] - u[i][0] >= xmax - 0.5 * c_.numerics.spacing)
      mine.push_back(id[i]);
  if (const auto* d = solver_.domain()) mine = all_gather_values(d->comm(), std::span<const std::int64_t>(mine));
  free_end_.assign(static_cast<std::size_t>(idmax) + 1, 0);
  for (const std::int64_t k : mine) free_end_[static_cast<std::size_t>(k)] = 1;
}

template <int Dim>
double DynamicRun<Dim>::tip_displacement() const {
  const auto& S = solver_.store();
  const auto& id = S.template get<ParticleId>();
  std::vector<double> sum{0.0, 0.0};  // Σ u_z, count
  for (std::size_t i = 0; i < solver_.owned_count(); ++i)
    if (free_end_[static_cast<std::size_t>(id[i])]) {
      sum[0] += S.template get<Displacement<Dim>>()[i][Dim - 1];
      sum[1] += 1.0;
    }
  sum = sum_over_ranks(std::move(sum));
  return sum[0] / std::max(sum[1], 1.0);
}

template <int Dim>
double DynamicRun<Dim>::max_over_ranks(double v) const {
  if (!solver_.domain()) return v;
  std::array<double, 1> a{v};
  solver_.domain()->comm().max_all(a);
  return a[0];
}

template <int Dim>
std::vector<double> DynamicRun<Dim>::sum_over_ranks(std::vector<double> v) const {
  if (!solver_.domain()) return v;
  const std::vector<double> all = solver_.domain()->comm().all_gather(v);
  std::fill(v.begin(), v.end(), 0.0);
  for (std::size_t r = 0; r < all.size() / v.size(); ++r)
    for (std::size_t k = 0; k < v.size(); ++k) v[k] += all[r * v.size() + k];
  return v;
}

template <int Dim>
void DynamicRun<Dim>::start_main_phase() {
  series_.columns = {"time_s",
                     "front_m",
                     "tip_m",
                     "runout_m",
                     "normalised_runout",
                     "max_speed_m_per_s",
                     "mean_speed_m_per_s",
                     "kinetic_energy_J",
                     "plastic_fraction",
                     "max_displacement_m",
                     "earthquake_acceleration_m_per_s2"};
  if (!free_end_.empty()) series_.columns.emplace_back("tip_displacement_m");
  if (settings_.pore_water.active()) series_.columns.emplace_back("max_pore_pressure_Pa");
  if (settings_.pore_water.rain) series_.columns.emplace_back("rain_time_s");
  biaxial_.columns = {"time_s", "axial_strain", "sigma_axial_Pa", "sigma_lateral_Pa", "deviator_Pa"};
  png_times_ = c_.velocity_png_times;
  std::sort(png_times_.begin(), png_times_.end());
  next_out_ = solver_.time();
  last_moving_ = t_start_ = solver_.time();
  main_started_ = true;
}

template <int Dim>
void DynamicRun<Dim>::main_phase(const SphSimulation& self, RunObserver* obs) {
  while (solver_.time() < c_.end_time - 1e-12) {
    if (solver_.time() >= next_out_ - 1e-12) {
      record();
      next_out_ += c_.output_interval;
    }
    if (obs) obs->before_step(self);
    solver_.step();
    have_loads_ = true;
    if (!structures_.empty()) structures_.observe(solver_.time(), solver_.structure_loads());
    const double vmax = solver_.last_stats().max_speed;
    max_speed_run_ = std::max(max_speed_run_, vmax);
    if (vmax > c_.rest_speed) last_moving_ = solver_.time();
    if (obs) obs->stepped(self);
    if (c_.stop_at_rest && solver_.time() - t_start_ > std::max(0.05, 0.1 * c_.end_time) && vmax < c_.rest_speed &&
        solver_.time() > settings_.earthquake.end_time()) {
      stopped_at_rest_ = true;
      break;
    }
  }
  last_ = record();
  finished_ = true;
  record_decomposition();
  if (solver_.domain()) finals_ = make_finals();
  refresh_view(true);  // for rank 0's pictures and release
  if (obs) obs->finished(self);
}

/// Over several ranks (collective): the whole state at this step, unless it is already the view.
template <int Dim>
void DynamicRun<Dim>::refresh_view(bool force) {
  if (!solver_.domain() || (!force && view_step_ == solver_.step_count())) return;
  view_ = SphStore<Dim>{};
  view_ = solver_.gathered_store(true);
  view_step_ = solver_.step_count();
}

/// Over several ranks (collective): summary.json's domain_decomposition block, per rank.
template <int Dim>
void DynamicRun<Dim>::record_decomposition() {
  const auto* d = solver_.domain();
  if (!d) return;
  const auto& st = d->stats();
  const std::vector<double> mine{static_cast<double>(d->owned()), static_cast<double>(st.ghosts),
                                 static_cast<double>(st.migrated_out - st.first_migrated_out),
                                 static_cast<double>(st.partitions), static_cast<double>(st.rebuilds)};
  const std::vector<double> all = d->comm().all_gather(mine);
  nlohmann::json owned = nlohmann::json::array(), ghosts = nlohmann::json::array();
  double migrated = 0.0;
  for (std::size_t r = 0; r < all.size() / mine.size(); ++r) {
    owned.push_back(static_cast<std::int64_t>(all[r * mine.size()]));
    ghosts.push_back(static_cast<std::int64_t>(all[r * mine.size() + 1]));
    migrated += all[r * mine.size() + 2];
  }
  decomposition_ = {{"ranks", d->size()},
                    {"owned_particles", owned},
                    {"ghost_particles", ghosts},
                    {"migrated_particles", static_cast<std::int64_t>(migrated)},
                    {"partitions", static_cast<std::int64_t>(st.partitions)},
                    {"rebuilds", static_cast<std::int64_t>(st.rebuilds)}};
}

/// A row of the series (and of the structure loads, and of the biaxial curve).
template <int Dim>
SeriesRow DynamicRun<Dim>::record() {
  // Reductions over the ranks' owned particles: no rank holds the whole state.
  const auto& S = solver_.store();
  const std::size_t n = solver_.owned_count();
  const auto r = series_row(S, b_.frame, over());
  double runout = r.runout, nrun = r.normalised_runout;
  if (c_.scenario == ScenarioType::Section) {
    runout = 0.0;
    for (std::size_t i = 0; i < n; ++i) runout = std::max(runout, std::abs(S.template get<Displacement<Dim>>()[i][0]));
    runout = max_over_ranks(runout);
    nrun = runout / b_.frame.base_length;
  }
  max_runout_ = std::max(max_runout_, runout);
  if (have_loads_ && !structures_.empty()) structures_.record(solver_.time(), solver_.structure_loads());
  std::vector<double> row{solver_.time(),
                          r.front,
                          r.tip,
                          runout,
                          nrun,
                          r.max_speed,
                          r.mean_speed,
                          r.kinetic_energy,
                          r.plastic_fraction,
                          r.max_displacement,
                          settings_.earthquake.horizontal(solver_.time())};
  if (!free_end_.empty()) row.push_back(tip_displacement());
  if (settings_.pore_water.active()) {
    double umax = 0.0;
    for (std::size_t i = 0; i < n; ++i)
      if (S.template get<ParticleKind>()[i] == kSoil) umax = std::max(umax, S.template get<PorePressure>()[i]);
    umax = max_over_ranks(umax);
    if (umax > max_pore_pressure_) {
      max_pore_pressure_ = umax;
      max_pore_pressure_time_ = solver_.time();
    }
    row.push_back(umax);
  }
  if (settings_.pore_water.rain) row.push_back(settings_.pore_water.rain->rain_time(solver_.time()));
  series_.rows.push_back(std::move(row));
  if (c_.scenario == ScenarioType::Biaxial) record_biaxial();
  return r;
}

/// The mean axial and lateral stress of the specimen.
template <int Dim>
void DynamicRun<Dim>::record_biaxial() {
  const auto& S = solver_.store();
  std::vector<double> sum{0.0, 0.0, 0.0};  // Σ σ_axial, Σ σ_lateral, count
  for (std::size_t i = 0; i < solver_.owned_count(); ++i)
    if (S.template get<ParticleKind>()[i] == kSoil) {
      sum[0] += S.template get<Stress>()[i](Dim - 1, Dim - 1);
      sum[1] += S.template get<Stress>()[i](0, 0);
      sum[2] += 1.0;
    }
  sum = sum_over_ranks(std::move(sum));
  const double sa = sum[0] / std::max(sum[2], 1.0), sl = sum[1] / std::max(sum[2], 1.0);
  biaxial_.rows.push_back({solver_.time(), c_.biaxial_strain_rate * solver_.time(), sa, sl, sa - sl});
}

template <int Dim>
void DynamicRun<Dim>::draw_due_pngs(const std::filesystem::path& out) {
  while (next_png_ < png_times_.size() && solver_.time() >= png_times_[next_png_] - 1e-12) {
    refresh_view();  // over several ranks the whole state (collective), drawn by rank 0
    const auto& S = state();
    if (root()) {
      std::vector<double> v(S.size());
      for (std::size_t i = 0; i < v.size(); ++i) v[i] = S.template get<Velocity<Dim>>()[i].norm();
      const double vm = v.empty() ? 0.0 : *std::max_element(v.begin(), v.end());
      std::ostringstream name;
      name << "velocity_t" << std::fixed << std::setprecision(3) << png_times_[next_png_] << ".png";
      draw_particles<Dim>(
          out / name.str(), S, v, vm, c_.numerics.spacing,
          particle_picture(c_, "speed at t = " + format_tick(png_times_[next_png_]) + " s", "speed (m/s)"));
    }
    ++next_png_;
  }
}

template <int Dim>
std::vector<NamedTable> DynamicRun<Dim>::tables() const {
  std::vector<NamedTable> t{{"series", series_}};
  if (!structures_.empty()) t.push_back({"structure_forces", structures_.table()});
  if (c_.scenario == ScenarioType::Biaxial) t.push_back({"stress_strain", biaxial_});
  const Finals f = finals();
  t.push_back({"surface_final", xz_table(f.surface)});
  t.push_back({"slip_surface", xz_table(f.slip)});
  return t;
}

template <int Dim>
void DynamicRun<Dim>::write_partial(const std::filesystem::path& out) const {
  write_text_file(out / "series.csv", series_.csv());
  if (!structures_.empty()) write_text_file(out / "structure_forces.csv", structures_.table().csv());
}

template <int Dim>
void DynamicRun<Dim>::write_outputs(const std::filesystem::path& out) const {
  for (const auto& [name, table] : tables()) write_text_file(out / (name + ".csv"), table.csv());
  if (!structures_.empty()) structures_.plot(out / "structure_forces.png");
  write_pictures(out);
  const ReleaseOutput rel = release();
  write_release(out, rel);
  const nlohmann::json summary = summary_with(rel);
  write_text_file(out / "summary.json", summary.dump(2) + "\n");
  if (!quiet_) {
    const auto fm = finals().failed;
    std::fprintf(stderr, "sph-slope: t = %.4g s, run-out %.4g m (normalised %.4g), failed %s %.4g, outputs in %s\n",
                 solver_.time(), summary["runout_m"].get<double>(), summary["normalised_runout"].get<double>(),
                 Dim == 2 ? "area (m^2/m)" : "volume (m^3)", fm.volume, out.string().c_str());
  }
}

/// Quick-looks of the final state coloured by displacement and by plastic strain.
template <int Dim>
void DynamicRun<Dim>::write_pictures(const std::filesystem::path& out) const {
  const auto& S = state();
  std::vector<double> u(S.size());
  double umax = 0.0;
  for (std::size_t i = 0; i < u.size(); ++i) {
    u[i] = S.template get<Displacement<Dim>>()[i].norm();
    if (S.template get<ParticleKind>()[i] == kSoil) umax = std::max(umax, u[i]);
  }
  const std::string at = " at t = " + format_tick(solver_.time()) + " s (end of the run)";
  draw_particles<Dim>(out / "final_displacement.png", S, u, umax, c_.numerics.spacing,
                      particle_picture(c_, "displacement" + at, "displacement (m)"));
  const auto& ep = S.template get<PlasticStrain>();
  const double epmax = ep.empty() ? 0.0 : *std::max_element(ep.begin(), ep.end());
  draw_particles<Dim>(out / "final_plastic_strain.png", S, ep, epmax, c_.numerics.spacing,
                      particle_picture(c_, "accumulated plastic strain" + at, "accumulated plastic strain (1)"));
}

/// Failed mass for debris-runout (docs/handoff.md): only when the section is georeferenced.
/// 2D: each plane-strain particle of area A becomes k = W/Δx map points spread across the width W,
/// each of volume A·W/k. 3D: each particle is one map point (its position on the strip) carrying
/// its own volume m/ρ0.
template <int Dim>
ReleaseOutput DynamicRun<Dim>::release() const {
  ReleaseOutput r;
  if (c_.scenario != ScenarioType::Section || !c_.write_release) return r;
  const auto& P = c_.section.profile;
  const auto& S = state();
  std::vector<Vec2> pts;
  std::vector<double> vols;
  const double W = Dim == 2 ? c_.section.release_width : strip_width(c_);
  const int k = Dim == 2 ? std::max(1, static_cast<int>(std::lround(W / c_.numerics.spacing))) : 1;
  for (std::size_t i = 0; i < S.size(); ++i) {
    if (S.template get<ParticleKind>()[i] != kSoil) continue;
    if (S.template get<Displacement<Dim>>()[i].norm() <= c_.failed_threshold) continue;
    const Vec<Dim>& x = S.template get<Position<Dim>>()[i];
    const double vol = S.template get<Mass>()[i] / rho0_[static_cast<std::size_t>(S.template get<MaterialId>()[i])] *
                       (Dim == 2 ? W / k : 1.0) * c_.bulking_factor;
    for (int q = 0; q < k; ++q) {
      const double t = Dim == 2 ? -0.5 * W + (q + 0.5) * W / k : x[1] - 0.5 * W;
      pts.push_back(section_map_point(P, x[0], t));
      vols.push_back(vol);
      r.total += vol;
    }
  }
  r.width = W;
  std::ostringstream src;
  src << c_.config_source << "; " << Dim << "D section; displacement > " << c_.failed_threshold << " m; width " << W
      << " m";
  r.handoff =
      Handoff{pts, vols, c_.section.crs_wkt, src.str(), c_.bulking_factor, solver_.time(), solver_.step_count()};
  if (c_.section.dsm) {
    // Nodata where the DSM has none (-9999, as the debris-runout maps), a band description and
    // unit, and a QGIS style beside it, like every GeoTIFF geohaz writes (issue #16).
    constexpr double kNodata = -9999.0;
    const Raster& dsm = *c_.section.dsm;
    Raster th = dsm.like(0.0, kNodata);
    th.description = "release thickness: failed volume per cell area (sph-slope section)";
    th.unit = "m";
    for (std::size_t q = 0; q < th.data.size(); ++q)
      if (dsm.is_nodata(dsm.data[q])) th.data[q] = kNodata;
    const double cell = th.cell_size_x() * th.cell_size_y();
    for (std::size_t q = 0; q < pts.size(); ++q) {
      const Vec2 px = th.to_pixel(pts[q]);
      const int col = static_cast<int>(std::lround(px.x())), row = static_cast<int>(std::lround(px.y()));
      if (col < 0 || row < 0 || col >= th.nx || row >= th.ny || th.at(col, row) == kNodata) continue;
      th.at(col, row) += vols[q] / cell;
      r.binned += vols[q];
    }
    for (double v : th.data)
      if (v != kNodata) r.max_thickness = std::max(r.max_thickness, v);
    r.thickness = std::move(th);
  }
  return r;
}

template <int Dim>
void DynamicRun<Dim>::write_release(const std::filesystem::path& out, const ReleaseOutput& r) const {
  if (c_.scenario != ScenarioType::Section || !c_.write_release) return;
  write_handoff(out / "release.h5", r.handoff, c_.resolved_config);
  if (!r.thickness) return;
  write_geotiff(out / "release_thickness.tif", *r.thickness);
  write_qgis_ramp_style(out / "release_thickness.qml", ColourRamp::Viridis, 0.0,
                        r.max_thickness > 0.0 ? r.max_thickness : 1.0, "m", 0.0);
}

template <int Dim>
typename DynamicRun<Dim>::Finals DynamicRun<Dim>::make_finals() const {
  const auto& S = solver_.store();
  const std::size_t n = solver_.owned_count();
  const auto o = over();
  Finals f;
  f.surface = free_surface(S, c_.numerics.spacing, o);
  f.slip = slip_surface(S, c_.numerics.spacing, c_.failed_threshold, o);
  f.failed = failed_mass(S, rho0_, c_.failed_threshold, o);
  const auto& ep = S.template get<PlasticStrain>();
  double umax = 0.0, epmax = -std::numeric_limits<double>::infinity();
  for (std::size_t i = 0; i < n; ++i) {
    if (S.template get<ParticleKind>()[i] == kSoil)
      umax = std::max(umax, S.template get<Displacement<Dim>>()[i].norm());
    epmax = std::max(epmax, ep[i]);
  }
  f.max_displacement = max_over_ranks(umax);
  epmax = max_over_ranks(epmax);
  f.max_plastic_strain = std::isfinite(epmax) ? epmax : 0.0;
  return f;
}

template <int Dim>
nlohmann::json DynamicRun<Dim>::summary_with(const ReleaseOutput& rel) const {
  const auto& mats = solver_.materials();
  const Finals fin = finals();
  nlohmann::json s = summary_header<Dim>(c_, solver_, soil_count_);
  s["boundary_particles"] = boundary_count_;
  s["smoothing_length_m"] = solver_.smoothing_length();
  for (std::size_t k = 0; k < mats.size(); ++k) {
    nlohmann::json e = {{"name", k < c_.material_names.size() ? c_.material_names[k] : ""},
                        {"p_wave_speed_m_per_s", mats[k].p_wave_speed},
                        {"dp_fit", drucker_prager_fit_name(mats[k].fit)}};
    e.update(model_parameters(c_.model, mats[k]));
    s["materials"].push_back(e);
  }
  s.update(phase_summary_);
  if (!structures_.empty()) s["structures"] = structures_.summary();
  const double umax = fin.max_displacement;
  s["max_plastic_strain"] = fin.max_plastic_strain;
  const bool section = c_.scenario == ScenarioType::Section;
  s["end_time_s"] = solver_.time();
  s["steps"] = solver_.step_count();
  s["stopped_at_rest"] = stopped_at_rest_;
  s["runout_m"] = section ? max_runout_ : last_.runout;
  s["normalised_runout"] = section ? max_runout_ / b_.frame.base_length : last_.normalised_runout;
  s["front_m"] = last_.front;
  s["tip_m"] = last_.tip;
  s["max_runout_m"] = max_runout_;
  s["max_speed_m_per_s"] = max_speed_run_;
  s["final_max_speed_m_per_s"] = last_.max_speed;
  s["max_displacement_m"] = umax;
  s["failed_threshold_m"] = c_.failed_threshold;
  s["front_thickness_m"] =
      b_.frame.front_thickness > 0.0 ? b_.frame.front_thickness : b_.frame.front_min_layers * b_.frame.spacing;
  const auto& fm = fin.failed;
  s["failed_particles"] = fm.count;
  s[Dim == 2 ? "failed_area_m2_per_m" : "failed_volume_m3"] = fm.volume;
  s["time_to_rest_s"] = last_.max_speed < c_.rest_speed ? nlohmann::json(last_moving_ - t_start_) : nlohmann::json();
  s["rest_speed_m_per_s"] = c_.rest_speed;
  s["bytes_per_particle"] = solver_.bytes_per_particle();
  if (!decomposition_.is_null()) s["domain_decomposition"] = decomposition_;
  bishop_.add_to(s);
  if (settings_.pore_water.active()) {
    s["water"] = water_summary(c_, solver_.time());
    s["water"]["max_pore_pressure_Pa"] = max_pore_pressure_;
    s["water"]["max_pore_pressure_time_s"] = max_pore_pressure_time_;
  }
  if (section && c_.write_release) {
    s["release"] = {{"file", "release.h5"},
                    {"points", rel.handoff.points.size()},
                    {"total_volume_m3", rel.total},
                    {"width_m", rel.width}};
    if (rel.thickness) {
      s["release"]["thickness_style"] = "release_thickness.qml";
      s["release"]["thickness_raster"] = "release_thickness.tif";
      s["release"]["volume_on_raster_m3"] = rel.binned;
    }
  }
  if (Dim == 2 && c_.scenario == ScenarioType::Slope && c_.numerics.earthquake.active()) {
    // Beside the SPH run: Newmark's rigid block on the circle of the smallest yield coefficient.
    try {
      s["newmark"] = newmark_report(c_);
      s["newmark"]["sph_max_displacement_m"] = umax;
    } catch (const InputError& e) {
      s["newmark_note"] = e.reason();
    }
  }
  s["wall_time_s"] = std::chrono::duration<double>(std::chrono::steady_clock::now() - wall0_).count();
  return s;
}

}  // namespace

std::unique_ptr<SimulationModel> make_dynamic_run(const RunConfig& c, bool quiet,
                                                  std::shared_ptr<const Communicator> comm) {
  if (c.dimension == 2) return std::make_unique<DynamicRun<2>>(c, quiet, std::move(comm));
  return std::make_unique<DynamicRun<3>>(c, quiet, std::move(comm));
}

}  // namespace geohaz::sph
