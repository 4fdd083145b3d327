// run.analysis = strength_reduction: the factor of safety of a slope by strength reduction, trials
// from the geostatic state (or a restart) bisecting F, the Bishop circle beside it (docs/sph.md,
// "Factor of safety by strength reduction").
#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <nlohmann/json.hpp>
#include <optional>

#include "geohaz/core/errors.hpp"
#include "geohaz/core/output.hpp"
#include "geohaz/core/plot.hpp"
#include "run_support.hpp"

namespace geohaz::sph {

namespace {

template <int Dim>
double max_soil_displacement(const SphStore<Dim>& s, std::size_t n) {
  double u = 0.0;
  const auto& d = s.template get<Displacement<Dim>>();
  const auto& k = s.template get<ParticleKind>();
  for (std::size_t i = 0; i < n; ++i)
    if (k[i] == kSoil) u = std::max(u, d[i].norm());
  return u;
}
template <int Dim>
double max_soil_displacement(const SphStore<Dim>& s) {
  return max_soil_displacement(s, s.size());
}

/// Over every rank of a distributed solver (collective): its owned particles' largest displacement.
template <int Dim>
double max_soil_displacement(const SphSolver<Dim>& s) {
  std::array<double, 1> u{max_soil_displacement(s.store(), s.owned_count())};
  if (s.domain()) s.domain()->comm().max_all(u);
  return u[0];
}

/// One strength-reduction trial: its factor and what decided it.
struct SrmTrial {
  double factor = 1.0;
  double displacement = 0.0;  ///< largest soil displacement at the end (m)
  double growth = 0.0;        ///< its growth over the last quarter of the trial (m)
  bool failed = false;
  bool blew_up = false;  ///< the trial stopped with a SimulationError (counted as failed)
  std::int64_t steps = 0;
};

/// The settings of the geostatic phase and the trials of a strength reduction: gravity only, the
/// trials' damping.
template <int Dim>
SolverSettings<Dim> trial_settings(const RunConfig& c, const Scenario<Dim>& sc) {
  auto s = settings_for<Dim>(c, sc);
  s.earthquake = EarthquakeLoading{};
  if (c.seismic.kh != 0.0 || c.seismic.kv != 0.0) {
    // Pseudo-static coefficients: a constant body acceleration k_h g towards +x (the slope scenario's
    // face descends towards +x, SlopeGeometry) and k_v g upward, in the trials only (the geostatic
    // phase turns the earthquake off), as Bishop's k_h W and k_v W.
    const double g = c.numerics.gravity, ah = c.seismic.kh * g, av = c.seismic.kv * g;
    s.earthquake = EarthquakeLoading::record({0.0, 1e12}, {ah, ah}, {av, av});
  }
  s.damping = c.srm.damping;
  return s;
}

/// Factor of safety by strength reduction (docs/sph.md, "Factor of safety by strength reduction"):
/// the geostatic state (or a restart), trials bisecting F, the Bishop circle beside it.
template <int Dim>
class StrengthReductionRun final : public SimulationModel {
 public:
  StrengthReductionRun(const RunConfig& c, bool quiet, std::shared_ptr<const Communicator> comm);
  void run(const SphSimulation& self, RunObserver* obs) override;
  double time() const override { return 0.0; }
  std::int64_t step_count() const override { return trial_steps_; }
  std::size_t particle_count() const override { return b_.sc.soil_count + b_.sc.boundary_count; }
  bool main_phase_started() const override { return false; }
  nlohmann::json summary() const override;
  std::vector<NamedTable> tables() const override;
  ParticleFields particles() const override { return mechanism_ ? fields_of(*mechanism_) : ParticleFields{}; }
  /// Before the trials the geostatic state (snapshot 0), after them the failed trial at the
  /// critical factor (snapshot 1). Over several ranks every rank writes its block of the geostatic
  /// state by id (joined in rank order: the id order); rank 0 alone holds the failed trial, gathered
  /// there (its pictures are drawn from it), and writes it.
  void write_snapshot(SnapshotWriter& w) const override {
    const std::size_t all = comm_ && comm_->rank() != 0 ? 0 : static_cast<std::size_t>(-1);
    if (!finished_)
      write_fields<Dim>(w, *initial_, 0.0, 0, settings_.pore_water.active());
    else if (mechanism_)
      write_fields<Dim>(w, *mechanism_, trial_duration_, 1, settings_.pore_water.active(), all);
  }
  void draw_due_pngs(const std::filesystem::path&) override {}
  void write_outputs(const std::filesystem::path& out) const override;
  void write_partial(const std::filesystem::path&) const override {}

 private:
  void geostatic_state(const SphSimulation& self, RunObserver* obs);
  bool trial(double F, const SphSimulation& self, RunObserver* obs);
  void bracket(const SphSimulation& self, RunObserver* obs);
  void bishop_check();
  Table curve() const;
  void plot_curve(const std::filesystem::path& path) const;
  void write_mechanism(const std::filesystem::path& out) const;

  const RunConfig& c_;
  bool quiet_;
  std::chrono::steady_clock::time_point wall0_;
  Built<Dim> b_;
  SolverSettings<Dim> settings_;
  double href_;
  SphSolver<Dim> geo_;
  double cmax_;                                              // largest P-wave speed (m/s)
  nlohmann::json phase_summary_ = nlohmann::json::object();  // "restart" or "geostatic"
  std::optional<SphStore<Dim>> initial_;    // the geostatic state every trial starts from (a rank's block by id)
  double initial_max_pore_pressure_ = 0.0;  // of the geostatic state's soil, over every rank
  double trial_duration_ = 0.0;             // T, s
  double u_ref_ = -1.0;                     // largest displacement of the f_min trial (the stable reference), m
  std::vector<SrmTrial> trials_;
  std::int64_t trial_steps_ = 0;
  std::optional<SphStore<Dim>> mechanism_;  // the store of the failed trial at the upper end of the bracket
  double mechanism_factor_ = 0.0;           // F of that trial (the last that failed)
  double mechanism_time_ = 0.0;             // s: the time that trial reached (T, or its stop)
  double lo_ = 0.0, hi_ = 0.0;
  std::string outcome_ = "bracketed";
  BishopResult bishop_;
  std::string bishop_note_;
  std::vector<std::array<double, 2>> circle_;
  bool finished_ = false;
  std::shared_ptr<const Communicator> comm_;  // over several ranks: the geostatic phase and each trial
};

template <int Dim>
StrengthReductionRun<Dim>::StrengthReductionRun(const RunConfig& c, bool quiet,
                                                std::shared_ptr<const Communicator> comm)
    : c_(c),
      quiet_(quiet),
      wall0_(std::chrono::steady_clock::now()),
      b_(build<Dim>(c, share_of(comm.get()))),
      settings_(trial_settings<Dim>(c, b_.sc)),
      href_(b_.sc.reference_height),
      geo_(std::move(b_.sc.store), c.materials, c.model, settings_),
      cmax_(geo_.max_wave_speed()),
      comm_(std::move(comm)) {
  if (c_.restart.empty()) geostatic_duration(c_, href_, cmax_);  // checked before anything is written
}

template <int Dim>
void StrengthReductionRun<Dim>::run(const SphSimulation& self, RunObserver* obs) {
  geostatic_state(self, obs);
  trial_duration_ = c_.srm.trial_duration > 0.0 ? c_.srm.trial_duration : 30.0 * href_ / cmax_;
  if (obs) obs->started(self);
  bracket(self, obs);
  bishop_check();
  finished_ = true;
  if (obs) obs->finished(self);
}

template <int Dim>
void StrengthReductionRun<Dim>::geostatic_state(const SphSimulation& self, RunObserver* obs) {
  if (!c_.restart.empty()) {
    const Restart rs = load_restart<Dim>(c_.restart, geo_.store(), share_of(comm_.get()));
    for (auto& v : geo_.store().template get<Velocity<Dim>>()) v.setZero();
    for (auto& u : geo_.store().template get<Displacement<Dim>>()) u.setZero();
    phase_summary_["restart"] = {{"file", c_.restart.string()}, {"time_s", rs.time}};
  } else {
    if (comm_) geo_.distribute(comm_, true);  // built by share
    const double dur = geostatic_duration(c_, href_, cmax_);
    const auto rep = geostatic_with_progress(geo_, dur, c_, self, obs);
    phase_summary_["geostatic"] = {{"duration_s", dur}, {"steps", rep.steps}, {"max_speed_m_per_s", rep.max_speed}};
  }
  // Over several ranks every rank keeps its block of the state by particle id (the block a scatter
  // of the whole state would keep; a restart's block of rows): each trial starts from it.
  initial_ = geo_.domain() ? geo_.domain()->id_block(geo_.store()) : geo_.store();
  if (settings_.pore_water.active()) {  // the trials' pore pressure: that of the geostatic state
    std::vector<double> umax{0.0};
    for (std::size_t i = 0; i < initial_->size(); ++i)
      if (initial_->template get<ParticleKind>()[i] == kSoil)
        umax[0] = std::max(umax[0], initial_->template get<PorePressure>()[i]);
    if (comm_) comm_->max_all(umax);
    initial_max_pore_pressure_ = umax[0];
  }
}

/// One trial with every strength divided by F; true when it fails.
template <int Dim>
bool StrengthReductionRun<Dim>::trial(double F, const SphSimulation& self, RunObserver* obs) {
  const double T = trial_duration_;
  SrmTrial t;
  t.factor = F;
  SphSolver<Dim> s(*initial_, reduced_strength(c_.model, c_.materials, F), c_.model, settings_);
  if (comm_) s.distribute(comm_, true);
  RunProgress p{"trial", 0.0, T, 0, particle_count(), F, false};
  double u75 = -1.0;
  try {
    while (s.time() < T) {
      s.step();
      if (u75 < 0.0 && s.time() >= 0.75 * T) u75 = max_soil_displacement(s);
      if (obs && s.step_count() % 50 == 0) {
        p.time = s.time();
        p.steps = s.step_count();
        obs->progress(self, p);
      }
    }
    t.displacement = max_soil_displacement(s);
    t.growth = t.displacement - std::max(u75, 0.0);
    // Failure: the displacement has not converged, or (once the stable reference exists) it lies
    // beyond the knee of the F–displacement curve. SPH follows a failing mass to a new equilibrium
    // after it has slid, so a trial just above the critical F may have stopped again by T.
    t.failed = t.growth > c_.srm.growth_ratio * t.displacement ||
               (u_ref_ >= 0.0 && t.displacement > c_.srm.knee_ratio * std::max(u_ref_, 1e-3 * c_.numerics.spacing));
  } catch (const SimulationError& e) {
    // Over several ranks every rank stops at the same step (the state check is reduced over them).
    t.failed = t.blew_up = true;
    t.displacement = max_soil_displacement(s);
    if (!quiet_) std::fprintf(stderr, "sph-slope: trial F = %.4g stopped (%s): counted as failed\n", F, e.what());
  }
  t.steps = s.step_count();
  trial_steps_ += t.steps;
  if (obs) {
    p.time = s.time();
    p.steps = t.steps;
    p.done = true;
    obs->progress(self, p);
  }
  if (!quiet_)
    std::fprintf(stderr, "sph-slope: trial F = %.4f: max displacement %.4g m, last-quarter growth %.3g m -> %s\n", F,
                 t.displacement, t.growth, t.failed ? "fails" : "stable");
  trials_.push_back(t);
  if (t.failed) {
    mechanism_ = s.domain() ? s.gathered_store(true) : s.store();  // rank 0's outputs
    mechanism_factor_ = F;
    mechanism_time_ = s.time();
  }
  return t.failed;
}

/// f_min, f_max, then bisection until the bracket is narrower than the tolerance.
template <int Dim>
void StrengthReductionRun<Dim>::bracket(const SphSimulation& self, RunObserver* obs) {
  lo_ = c_.srm.f_min;
  hi_ = c_.srm.f_max;
  const bool low_fails = trial(lo_, self, obs);
  u_ref_ = trials_.back().displacement;
  if (low_fails) {
    outcome_ = "below_f_min";
  } else if (!trial(hi_, self, obs)) {
    outcome_ = "above_f_max";
  } else {
    auto best_failed = mechanism_;
    while (hi_ - lo_ > c_.srm.tolerance * (1.0 + 1e-9)) {
      const double mid = 0.5 * (lo_ + hi_);
      if (trial(mid, self, obs)) {
        hi_ = mid;
        best_failed = mechanism_;
      } else {
        lo_ = mid;
      }
    }
    mechanism_ = best_failed;
  }
}

template <int Dim>
void StrengthReductionRun<Dim>::bishop_check() {
  try {
    bishop_ = bishop_of(c_);
  } catch (const InputError& e) {
    bishop_note_ = e.reason();
  }
  if (!bishop_.admissible()) return;
  const auto& C = bishop_.circle;
  for (int k = 0; k <= 100; ++k) {
    const double x = bishop_.x_entry + (bishop_.x_exit - bishop_.x_entry) * k / 100.0;
    circle_.push_back({x, C.zc - std::sqrt(std::max(0.0, C.radius * C.radius - (x - C.xc) * (x - C.xc)))});
  }
}

/// The F–displacement curve: the trials sorted by F.
template <int Dim>
Table StrengthReductionRun<Dim>::curve() const {
  auto sorted = trials_;
  std::sort(sorted.begin(), sorted.end(), [](const auto& a, const auto& b) { return a.factor < b.factor; });
  Table t{{"factor", "max_displacement_m", "failed"}, {}, {false, false, true}};
  for (const auto& s : sorted) t.rows.push_back({s.factor, s.displacement, s.failed ? 1.0 : 0.0});
  return t;
}

template <int Dim>
std::vector<NamedTable> StrengthReductionRun<Dim>::tables() const {
  Table tr{{"trial", "factor", "max_displacement_m", "growth_last_quarter_m", "failed", "steps"},
           {},
           {true, false, false, false, true, true}};
  for (std::size_t k = 0; k < trials_.size(); ++k)
    tr.rows.push_back({static_cast<double>(k), trials_[k].factor, trials_[k].displacement, trials_[k].growth,
                       trials_[k].failed ? 1.0 : 0.0, static_cast<double>(trials_[k].steps)});
  std::vector<NamedTable> t{{"srm_trials", tr}, {"srm_curve", curve()}};
  if (bishop_.admissible()) t.push_back({"bishop_circle", xz_table(circle_)});
  if (mechanism_) {
    // The slip surface of the mechanism: the lower edge of the soil displaced by more than a tenth
    // of the largest displacement.
    t.push_back({"slip_surface",
                 xz_table(slip_surface(*mechanism_, c_.numerics.spacing, 0.1 * max_soil_displacement(*mechanism_)))});
  }
  return t;
}

/// Plot: F on x (f_min … f_max), displacement on y (logarithmic, 4 decades below the largest),
/// stable trials blue, failed red, the bracket as two grey verticals.
template <int Dim>
void StrengthReductionRun<Dim>::plot_curve(const std::filesystem::path& path) const {
  const Table t = curve();
  constexpr int W = 800, H = 500, ml = 90, mr = 30, mt = 40, mb = 84, s = 2;
  double umax = 0.0;
  for (const auto& r : t.rows) umax = std::max(umax, r[1]);
  const double u1 = std::max(umax, 1e-12);
  const PlotPanel f{c_.srm.f_min, c_.srm.f_max, 1e-4 * u1, u1, ml, mt, W - ml - mr, H - mt - mb, true};
  Image img(W, H);
  draw_axes(img, f, "strength reduction factor F", "largest displacement of a trial (m)", s);
  const std::array<std::uint8_t, 3> grey{170, 170, 170}, stable{40, 80, 210}, failed{210, 40, 40};
  for (const double F : {lo_, hi_})
    if (std::isfinite(F)) draw_polyline(img, f, {F, F}, {f.y0, f.y1}, grey);
  std::vector<double> F, u, Fs, us, Ff, uf;
  for (const auto& r : t.rows) {
    F.push_back(r[0]);
    u.push_back(r[1]);
    (r[2] != 0.0 ? Ff : Fs).push_back(r[0]);
    (r[2] != 0.0 ? uf : us).push_back(r[1]);
  }
  draw_polyline(img, f, F, u, {90, 90, 90});
  draw_markers(img, f, Fs, us, stable);
  draw_markers(img, f, Ff, uf, failed);
  draw_frame(img, f);  // over markers on an edge
  draw_legend(img, ml, H - 7 * s - 8, W - ml - mr,
              {{stable, "stable trial"}, {failed, "failed trial"}, {grey, "bracket of the factor of safety"}}, s);
  write_plot_png(path, img, {f}, s);
}

/// The mechanism drawn where the particles started (with the Bishop circle) and deformed.
template <int Dim>
void StrengthReductionRun<Dim>::write_mechanism(const std::filesystem::path& out) const {
  std::vector<double> u(mechanism_->size());
  double umax = 0.0;
  SphStore<Dim> reference = *mechanism_;
  for (std::size_t i = 0; i < u.size(); ++i) {
    u[i] = mechanism_->template get<Displacement<Dim>>()[i].norm();
    reference.template get<Position<Dim>>()[i] -= mechanism_->template get<Displacement<Dim>>()[i];
    if (mechanism_->template get<ParticleKind>()[i] == kSoil) umax = std::max(umax, u[i]);
  }
  const std::string trial = "displacement in the failed trial F = " + format_tick(mechanism_factor_) +
                            " at t = " + format_tick(mechanism_time_) + " s, on the ";
  const std::string red = circle_.empty() ? "" : "; red: Bishop's critical circle";
  draw_particles<Dim>(out / "mechanism.png", reference, u, umax, c_.numerics.spacing,
                      particle_picture(c_, trial + "initial positions" + red, "displacement (m)", circle_));
  draw_particles<Dim>(out / "mechanism_deformed.png", *mechanism_, u, umax, c_.numerics.spacing,
                      particle_picture(c_, trial + "deformed positions" + red, "displacement (m)", circle_));
}

template <int Dim>
void StrengthReductionRun<Dim>::write_outputs(const std::filesystem::path& out) const {
  for (const auto& [name, table] : tables()) write_text_file(out / (name + ".csv"), table.csv());
  plot_curve(out / "srm_curve.png");
  if (mechanism_) write_mechanism(out);
  write_text_file(out / "summary.json", summary().dump(2) + "\n");
  if (!quiet_) {
    if (outcome_ == "bracketed")
      std::fprintf(stderr, "sph-slope: factor of safety (strength reduction) %.4g, failed at %.4g", lo_, hi_);
    else
      std::fprintf(stderr, "sph-slope: factor of safety %s the range [%.4g, %.4g]",
                   outcome_ == "below_f_min" ? "below" : "above", c_.srm.f_min, c_.srm.f_max);
    if (bishop_.admissible()) std::fprintf(stderr, "; Bishop %.4g", bishop_.factor);
    std::fprintf(stderr, "; outputs in %s\n", out.string().c_str());
  }
}

template <int Dim>
nlohmann::json StrengthReductionRun<Dim>::summary() const {
  nlohmann::json s = summary_header<Dim>(c_, geo_, b_.sc.soil_count);
  s["analysis"] = "strength_reduction";
  s.update(phase_summary_);
  if (!bishop_note_.empty()) s["bishop_note"] = bishop_note_;
  if (bishop_.admissible()) {
    s["bishop"] = StaticBishop::circle_json(bishop_);
    if (std::isfinite(bishop_.yield_coefficient)) s["bishop"]["yield_coefficient"] = bishop_.yield_coefficient;
  }
  s["seismic"] = {{"kh", c_.seismic.kh}, {"kv", c_.seismic.kv}};
  if (settings_.pore_water.active()) {  // the trials' pore pressure: that of the geostatic state
    s["water"] = water_summary(c_, 0.0);
    s["water"]["max_pore_pressure_Pa"] = initial_max_pore_pressure_;
  }

  s["outcome"] = outcome_;
  s["factor_of_safety"] = outcome_ == "bracketed" ? nlohmann::json(lo_) : nlohmann::json();
  s["bracket"] = {lo_, hi_};
  s["tolerance"] = c_.srm.tolerance;
  s["trial_duration_s"] = trial_duration_;
  s["trial_damping"] = c_.srm.damping;
  s["growth_ratio"] = c_.srm.growth_ratio;
  s["knee_ratio"] = c_.srm.knee_ratio;
  s["reference_displacement_m"] = u_ref_;
  s["trials"] = trials_.size();
  s["wall_time_s"] = std::chrono::duration<double>(std::chrono::steady_clock::now() - wall0_).count();
  return s;
}

}  // namespace

std::unique_ptr<SimulationModel> make_strength_reduction_run(const RunConfig& c, bool quiet,
                                                             std::shared_ptr<const Communicator> comm) {
  if (c.dimension == 2) return std::make_unique<StrengthReductionRun<2>>(c, quiet, std::move(comm));
  return std::make_unique<StrengthReductionRun<3>>(c, quiet, std::move(comm));
}

}  // namespace geohaz::sph
