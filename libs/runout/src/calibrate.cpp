// Back-analysis of debris-runout against an observed event (calibrate.hpp, docs/calibration.md):
// misfit and the search (design + Morris + lockstep NLopt local searches); the configuration is
// read in calibrate_config.cpp.
#include "geohaz/runout/calibrate.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <condition_variable>
#include <deque>
#include <fstream>
#include <iomanip>
#include <iostream>
#include <map>
#include <mutex>
#include <nlohmann/json.hpp>
#include <nlopt.hpp>
#include <optional>
#include <set>
#include <sstream>
#include <thread>

#include "case_support.hpp"
#include "geohaz/core/config.hpp"
#include "geohaz/core/errors.hpp"
#include "geohaz/core/output.hpp"
#include "geohaz/core/raster.hpp"
#include "geohaz/runout/run.hpp"

namespace fs = std::filesystem;

namespace geohaz::runout {

using detail::fmt;
using detail::numeric_case_keys;
using detail::origin;
using detail::resolve_path;

namespace {

std::string slurp(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

}  // namespace

double CalibrationParameter::value(double u) const noexcept {
  u = std::clamp(u, 0.0, 1.0);
  if (log_scale) return lower * std::pow(upper / lower, u);
  return lower + u * (upper - lower);
}

double CalibrationParameter::unit(double v) const noexcept {
  if (upper == lower) return 0.0;
  if (log_scale) return std::log(v / lower) / std::log(upper / lower);
  return (v - lower) / (upper - lower);
}

double Observation::footprint_area() const noexcept {
  std::size_t n = 0;
  for (auto f : footprint) n += f;
  return static_cast<double>(n) * grid.cell_area();
}

double along_thalweg(const std::vector<Vec2>& t, const Vec2& p) noexcept {
  double best_d2 = std::numeric_limits<double>::infinity(), best_s = 0.0, s0 = 0.0;
  for (std::size_t k = 1; k < t.size(); ++k) {
    const Vec2 a = t[k - 1], ab = t[k] - a;
    const double len2 = ab.squaredNorm(), len = std::sqrt(len2);
    const double f = len2 > 0.0 ? std::clamp((p - a).dot(ab) / len2, 0.0, 1.0) : 0.0;
    const double d2 = (a + ab * f - p).squaredNorm();
    if (d2 < best_d2) best_d2 = d2, best_s = s0 + f * len;
    s0 += len;
  }
  return best_s;
}

Misfit compute_misfit(const Observation& obs, const ScoreSettings& s, const std::vector<double>& max_depth,
                      const std::vector<double>& deposit, double volume) {
  Misfit m;
  const double a = obs.grid.cell_area();
  double s_max = 0.0;
  double sq = 0.0, obs_sum = 0.0;
  std::size_t n_union = 0, n_obs = 0;
  const bool depth = !obs.deposit.empty();
  for (std::size_t k = 0; k < obs.footprint.size(); ++k) {
    const bool mod = std::isfinite(max_depth[k]) && max_depth[k] > s.depth_threshold;
    const bool ob = obs.footprint[k] != 0;
    if (mod && ob) m.tp += a;
    if (mod && !ob) m.fp += a;
    if (!mod && ob) m.fn += a;
    if (mod) s_max = std::max(s_max, obs.s[k]);
    if (depth) {
      const double o = obs.deposit[k], d = std::isfinite(deposit[k]) ? deposit[k] : 0.0;
      if (o > 0.0 || d > 0.0) sq += (d - o) * (d - o), ++n_union;
      if (o > 0.0) obs_sum += o, ++n_obs;
    }
  }
  const double denom = m.tp + s.alpha * m.fp + s.beta * m.fn;
  m.tversky = denom > 0.0 ? m.tp / denom : 0.0;
  m.runout_s = s_max;
  m.runout_diff = s_max - obs.runout_s;
  m.volume = volume;
  m.term_footprint = s.w_footprint * (1.0 - m.tversky);
  m.term_runout = obs.runout_s > 0.0 ? s.w_runout * std::abs(m.runout_diff) / obs.runout_s : 0.0;
  if (depth && n_union > 0 && n_obs > 0) {
    m.depth_rmse = std::sqrt(sq / static_cast<double>(n_union));
    m.term_depth = s.w_depth * m.depth_rmse / (obs_sum / static_cast<double>(n_obs));
  }
  if (obs.volume > 0.0) m.term_volume = s.w_volume * std::abs(volume - obs.volume) / obs.volume;
  m.score = m.term_footprint + m.term_runout + m.term_depth + m.term_volume;
  return m;
}

// ---- members --------------------------------------------------------------------------------

namespace {

nlohmann::json misfit_json(const Misfit& m) {
  return {{"tp_m2", m.tp},
          {"fp_m2", m.fp},
          {"fn_m2", m.fn},
          {"tversky", m.tversky},
          {"runout_s_m", m.runout_s},
          {"runout_diff_m", m.runout_diff},
          {"depth_rmse_m", m.depth_rmse},
          {"volume_m3", m.volume},
          {"term_footprint", m.term_footprint},
          {"term_runout", m.term_runout},
          {"term_depth", m.term_depth},
          {"term_volume", m.term_volume},
          {"score", m.score}};
}

Misfit parse_misfit(const nlohmann::json& j) {
  Misfit m;
  m.tp = j.at("tp_m2"), m.fp = j.at("fp_m2"), m.fn = j.at("fn_m2"), m.tversky = j.at("tversky");
  m.runout_s = j.at("runout_s_m"), m.runout_diff = j.at("runout_diff_m"), m.depth_rmse = j.at("depth_rmse_m");
  m.volume = j.at("volume_m3"), m.term_footprint = j.at("term_footprint"), m.term_runout = j.at("term_runout");
  m.term_depth = j.at("term_depth"), m.term_volume = j.at("term_volume"), m.score = j.at("score");
  return m;
}

/// The deposit of a member, cropped like its peaks (depth = deposit, the other two fields zero).
MemberPeaks crop(const GridGeometry& g, const std::vector<double>& v) {
  MemberPeaks p;
  p.nx = g.nx, p.ny = g.ny;
  int c0 = g.nx, c1 = -1, r0 = g.ny, r1 = -1;
  for (int r = 0; r < g.ny; ++r)
    for (int c = 0; c < g.nx; ++c)
      if (v[g.index(c, r)] > 0.0)
        c0 = std::min(c0, c), c1 = std::max(c1, c), r0 = std::min(r0, r), r1 = std::max(r1, r);
  if (c1 < 0) return p;
  p.c0 = c0, p.r0 = r0, p.w = c1 - c0 + 1, p.h = r1 - r0 + 1;
  const std::size_t n = static_cast<std::size_t>(p.w) * p.h;
  p.depth.resize(n), p.speed.assign(n, 0.0), p.pressure.assign(n, 0.0);
  for (int r = 0; r < p.h; ++r)
    for (int c = 0; c < p.w; ++c) p.depth[static_cast<std::size_t>(r) * p.w + c] = v[g.index(c0 + c, r0 + r)];
  return p;
}

}  // namespace

std::unique_ptr<MemberRunner> make_calibration_runner(const CalibrationSetup& s) {
  auto runner = std::make_unique<MemberRunner>(s.members);
  runner->set_finished_hook([&s](const RunoutSimulation& sim, const MemberRecord& rec, const fs::path& dir) {
    const std::vector<double> deposit = sim.deposit();
    write_member_peaks(dir / "deposit.bin", crop(s.observation.grid, deposit));
    // The deposited volume is that of the deposit raster: a run stopped by the kinetic-energy
    // criterion deposits every particle (RunoutSimulation::deposit), which the volume budget still
    // counts as mobile.
    (void)rec;
    double volume = 0.0;
    for (double d : deposit) volume += std::isfinite(d) ? d : 0.0;
    volume *= s.observation.grid.cell_area();
    const Misfit m = compute_misfit(s.observation, s.score, sim.maps().max_depth(), deposit, volume);
    write_text_file(dir / "misfit.json", misfit_json(m).dump(2) + "\n");
  });
  return runner;
}

Evaluation read_evaluation(const CalibrationSetup& s, const fs::path& out, int i) {
  const fs::path d = member_dir(out, i);
  const MemberRecord r = parse_member_json(slurp(d / "member.json"));
  Evaluation e;
  e.index = i;
  e.values = r.values;
  e.ok = r.ok;
  e.diagnosis = r.diagnosis;
  if (e.ok) {
    e.misfit = parse_misfit(nlohmann::json::parse(slurp(d / "misfit.json")));
  } else {
    e.misfit.score = s.score.failed_penalty;
  }
  return e;
}

void prepare_calibration_output(const CalibrationSetup& s, const fs::path& out) {
  if (fs::exists(out / "calibration.resolved.toml") && (slurp(out / "calibration.resolved.toml") != s.resolved_config ||
                                                        slurp(out / "base.resolved.toml") != s.members.base_resolved))
    throw InputError(
        "the output folder holds another calibration (calibration.resolved.toml or base.resolved.toml differ): "
        "choose another --out or delete it",
        "command line", "--out", out.string());
  make_output_dir(out);
  fs::create_directories(out / "members");
  for (const auto& e : fs::directory_iterator(out / "members"))
    if (e.path().filename().string().find(".partial") != std::string::npos) fs::remove_all(e.path());
  write_text_file(out / "calibration.resolved.toml", s.resolved_config);
  write_text_file(out / "base.resolved.toml", s.members.base_resolved);
}

// ---- Morris trajectories --------------------------------------------------------------------

std::vector<std::vector<double>> morris_trajectory(std::uint64_t seed, int t, int parameters, int levels) {
  // Morris (1991) with the step Δ = p / (2 (p − 1)) on the grid {0, 1/(p−1), …, 1}: each factor
  // moves once, up or down (a random direction per factor and trajectory, Campolongo et al. 2007),
  // in a random order; the base level is drawn among those from which the move stays on [0, 1].
  const double delta = levels / (2.0 * (levels - 1));
  const int base_levels = levels / 2;  // levels 0 … p/2 − 1 can move up by Δ; p/2 … p − 1 down
  const auto u = [&](std::uint64_t stream, int j) {
    return counter_uniform(seed, 3 + stream, static_cast<std::uint64_t>(t), static_cast<std::uint64_t>(j));
  };
  std::vector<double> x(static_cast<std::size_t>(parameters));
  std::vector<int> dir(static_cast<std::size_t>(parameters)), order(static_cast<std::size_t>(parameters));
  for (int j = 0; j < parameters; ++j) {
    dir[static_cast<std::size_t>(j)] = u(0, j) < 0.5 ? 1 : -1;
    const int lvl = std::min(base_levels - 1, static_cast<int>(u(1, j) * base_levels));
    const int level = dir[static_cast<std::size_t>(j)] > 0 ? lvl : levels - 1 - lvl;
    x[static_cast<std::size_t>(j)] = static_cast<double>(level) / (levels - 1);
    order[static_cast<std::size_t>(j)] = j;
  }
  for (int j = parameters - 1; j > 0; --j)
    std::swap(order[static_cast<std::size_t>(j)],
              order[static_cast<std::size_t>(std::min(j, static_cast<int>(u(2, j) * (j + 1))))]);
  std::vector<std::vector<double>> pts{x};
  for (int j : order) {
    x[static_cast<std::size_t>(j)] =
        std::clamp(x[static_cast<std::size_t>(j)] + dir[static_cast<std::size_t>(j)] * delta, 0.0, 1.0);
    pts.push_back(x);
  }
  return pts;
}

// ---- the search -----------------------------------------------------------------------------

namespace {

/// Assigns member indices to points (a point met before keeps its member: no member is run twice)
/// and runs the new ones as one batch.
class Evaluator {
 public:
  Evaluator(CalibrationSetup& s, const fs::path& out, const BatchRunner& run, CalibrationResult& r, bool quiet)
      : s_(s), out_(out), run_(run), r_(r), quiet_(quiet) {}

  std::vector<double> values_of(const std::vector<double>& u) const {
    std::vector<double> v(u.size());
    for (std::size_t d = 0; d < u.size(); ++d) v[d] = s_.parameters[d].value(u[d]);
    return v;
  }

  /// Scores of the points (u in the unit cube), in order.
  std::vector<double> evaluate(const std::vector<std::vector<double>>& us, const std::vector<std::string>& stages) {
    std::vector<int> idx;
    std::vector<int> fresh;
    const int first_new = next_;
    for (std::size_t k = 0; k < us.size(); ++k) {
      const std::vector<double> v = values_of(us[k]);
      const auto it = known_.find(v);
      if (it != known_.end()) {
        idx.push_back(it->second);
        continue;
      }
      const int i = next_++;
      known_[v] = i;
      idx.push_back(i);
      auto& values = s_.members.values;
      if (values.size() <= static_cast<std::size_t>(i)) values.resize(static_cast<std::size_t>(i) + 1);
      values[static_cast<std::size_t>(i)] = v;
      stage_[i] = stages[k];
      batch_[i] = batches_;
      if (member_done(out_, i)) {
        // A member of an earlier (killed) run: it must be the same point, or the folder is another search's.
        const MemberRecord rec = parse_member_json(slurp(member_dir(out_, i) / "member.json"));
        if (rec.values != v)
          throw InputError("member " + std::to_string(i) +
                               " on disk has other parameter values than this search asks for (the folder holds "
                               "another calibration): choose another --out or delete it",
                           "command line", "--out", out_.string());
        ++resumed_;
      } else {
        fresh.push_back(i);
      }
    }
    if (!fresh.empty()) run_(fresh);
    if (next_ > first_new) ++batches_;
    std::vector<double> f;
    for (int i : idx) {
      if (r_.evaluations.size() <= static_cast<std::size_t>(i)) r_.evaluations.resize(static_cast<std::size_t>(i) + 1);
      Evaluation& e = r_.evaluations[static_cast<std::size_t>(i)];
      if (e.stage.empty()) {
        e = read_evaluation(s_, out_, i);
        e.stage = stage_[i];
        e.batch = batch_[i];
        if (!quiet_) {
          std::ostringstream o;
          o << "geohaz-calibrate: member " << i << " (" << e.stage << ")";
          for (std::size_t d = 0; d < e.values.size(); ++d) o << ' ' << s_.parameters[d].key << '=' << fmt(e.values[d]);
          if (e.ok)
            o << ": score " << fmt(e.misfit.score, 4) << " (T " << fmt(e.misfit.tversky, 4) << ", run-out "
              << fmt(e.misfit.runout_diff, 4) << " m)";
          else
            o << ": FAILED (score " << fmt(e.misfit.score) << "): " << e.diagnosis;
          std::cerr << o.str() << "\n";
        }
      }
      f.push_back(e.misfit.score);
    }
    return f;
  }
  /// Whether the point (u in the unit cube) has a member already.
  bool known(const std::vector<double>& u) const { return known_.count(values_of(u)) > 0; }
  int resumed() const noexcept { return resumed_; }
  int members() const noexcept { return next_; }

 private:
  CalibrationSetup& s_;
  const fs::path& out_;
  const BatchRunner& run_;
  CalibrationResult& r_;
  bool quiet_;
  std::map<std::vector<double>, int> known_;
  std::map<int, std::string> stage_;
  std::map<int, int> batch_;
  int next_ = 0, resumed_ = 0, batches_ = 0;
};

/// Local searches in lockstep: each NLopt search runs in its own thread and blocks in its objective
/// until the driver has evaluated one point of every live search as one batch. A search that ends
/// frees its slot; while the local budget (`local_starts` x `local_evaluations` members) has room,
/// the driver fills the slot with a new search from `next_start` (restarts), so the batches stay
/// `local_starts` wide and that many ranks stay busy. Every decision is taken at the barrier between
/// two batches from the scores alone, so the members do not depend on the number of ranks.
class LockstepSearches {
 public:
  struct Search {
    std::vector<double> x0;
    int max_evaluations = 0, used = 0;  ///< NLopt's budget for this search, points asked so far
    bool waiting = false, answered = false, done = false, restarted = false;
    std::vector<double> request, best_x;
    double answer = 0.0, best_f = std::numeric_limits<double>::infinity();
    std::string stop;
  };
  /// Gives the start of a new search (u in the unit cube), or nothing when no start is left.
  using NextStart = std::function<std::optional<std::vector<double>>(const std::deque<Search>&)>;

  LockstepSearches(const SearchSettings& q, int dims) : q_(q), dims_(dims) {}

  void run(const std::vector<std::vector<double>>& starts,
           const std::function<std::vector<double>(const std::vector<std::vector<double>>&,
                                                   const std::vector<std::size_t>&)>& evaluate,
           const std::function<bool(const std::vector<double>&)>& known, const NextStart& next_start) {
    nlopt::srand(q_.seed);
    budget_ = static_cast<long>(starts.size()) * q_.local_evaluations;
    for (const auto& x0 : starts) launch(x0, q_.local_evaluations);
    try {
      for (;;) {
        std::vector<std::size_t> live;
        std::vector<std::vector<double>> pts;
        {
          std::unique_lock lock(m_);
          cv_.wait(lock, [&] {
            return std::all_of(searches_.begin(), searches_.end(), [](const Search& s) { return s.waiting || s.done; });
          });
        }
        refill(next_start);
        {
          std::unique_lock lock(m_);
          cv_.wait(lock, [&] {
            return std::all_of(searches_.begin(), searches_.end(), [](const Search& s) { return s.waiting || s.done; });
          });
          for (std::size_t k = 0; k < searches_.size(); ++k)
            if (searches_[k].waiting) live.push_back(k), pts.push_back(searches_[k].request);
        }
        if (live.empty()) break;
        // Points met before cost nothing: they are answered at once, and the searches that asked
        // for them ask again, so that a batch holds only new members and stays as wide as the
        // searches that need one (a repeated point would otherwise leave a rank idle).
        std::vector<std::size_t> seen;
        for (std::size_t j = 0; j < live.size(); ++j)
          if (known(pts[j])) seen.push_back(j);
        if (!seen.empty()) {
          std::vector<std::size_t> l;
          std::vector<std::vector<double>> p;
          for (std::size_t j : seen) l.push_back(live[j]), p.push_back(pts[j]);
          live = std::move(l), pts = std::move(p);
        }
        const std::vector<double> f = evaluate(pts, live);
        {
          std::lock_guard lock(m_);
          for (std::size_t j = 0; j < live.size(); ++j) {
            Search& s = searches_[live[j]];
            s.answer = f[j], s.waiting = false, s.answered = true, ++s.used;
            if (f[j] < s.best_f) s.best_f = f[j], s.best_x = s.request;
          }
        }
        cv_.notify_all();
      }
    } catch (...) {
      {
        std::lock_guard lock(m_);
        abort_ = true;
      }
      cv_.notify_all();
      for (auto& t : threads_) t.join();
      throw;
    }
    for (auto& t : threads_) t.join();
  }
  const std::deque<Search>& searches() const noexcept { return searches_; }

 private:
  struct Context {
    LockstepSearches* self;
    std::size_t k;
  };

  /// Starts a search (the lock is not held: the new thread takes it).
  void launch(const std::vector<double>& x0, int max_evaluations) {
    {
      std::lock_guard lock(m_);
      Search s;
      s.x0 = x0, s.max_evaluations = max_evaluations;
      searches_.push_back(std::move(s));  // a deque: the running threads' references stay valid
    }
    const std::size_t k = searches_.size() - 1;
    threads_.emplace_back([this, k] { search(k); });
  }

  /// At the barrier: every search that ended since the last one, in slot order, hands its slot to a
  /// new search while the budget has room for one of at least dims + 2 members (BOBYQA's 2 P + 1
  /// interpolation points need less than the budget of the first searches).
  void refill(const NextStart& next_start) {
    if (!q_.local_restarts) return;
    const std::size_t n = searches_.size();
    for (std::size_t k = 0; k < n; ++k) {
      Search& s = searches_[k];
      if (!s.done || s.restarted) continue;
      s.restarted = true;
      long committed = 0;  // members asked, plus the rest of every live search's budget
      for (const Search& o : searches_) committed += o.done ? o.used : o.max_evaluations;
      const long room = std::min<long>(q_.local_evaluations, budget_ - committed);
      if (room < dims_ + 2) continue;
      const auto x0 = next_start(searches_);
      if (!x0) return;
      launch(*x0, static_cast<int>(room));
    }
  }

  static double objective(const std::vector<double>& x, std::vector<double>& grad, void* data) {
    (void)grad;  // derivative-free methods only
    auto* c = static_cast<Context*>(data);
    LockstepSearches& L = *c->self;
    std::unique_lock lock(L.m_);
    Search& s = L.searches_[c->k];
    if (L.abort_) throw nlopt::forced_stop();
    s.request = x, s.waiting = true;
    L.cv_.notify_all();
    L.cv_.wait(lock, [&] { return s.answered || L.abort_; });
    if (L.abort_) throw nlopt::forced_stop();
    s.answered = false;
    return s.answer;
  }

  void search(std::size_t k) {
    std::vector<double> x;
    int max_evaluations = 0;
    {
      std::lock_guard lock(m_);
      x = searches_[k].x0;
      max_evaluations = searches_[k].max_evaluations;
    }
    std::string stop;
    try {
      const nlopt::algorithm alg = q_.local_algorithm == "bobyqa"       ? nlopt::LN_BOBYQA
                                   : q_.local_algorithm == "neldermead" ? nlopt::LN_NELDERMEAD
                                                                        : nlopt::LN_SBPLX;
      nlopt::opt opt(alg, static_cast<unsigned>(dims_));
      opt.set_lower_bounds(std::vector<double>(static_cast<std::size_t>(dims_), 0.0));
      opt.set_upper_bounds(std::vector<double>(static_cast<std::size_t>(dims_), 1.0));
      Context ctx{this, k};
      opt.set_min_objective(&LockstepSearches::objective, &ctx);
      opt.set_maxeval(max_evaluations);
      opt.set_xtol_abs(q_.local_xtol);
      const double step = q_.local_step > 0.0 ? q_.local_step : 1.0 / std::max(1, q_.global_members);
      std::vector<double> steps(static_cast<std::size_t>(dims_));
      for (int d = 0; d < dims_; ++d) {
        // Step towards the interior when the start lies on a bound (BOBYQA needs x0 ± step inside).
        const double xd = x[static_cast<std::size_t>(d)];
        steps[static_cast<std::size_t>(d)] = std::min(step, std::max(std::max(xd, 1.0 - xd), 1e-3));
      }
      opt.set_initial_step(steps);
      double f = 0.0;
      const nlopt::result res = opt.optimize(x, f);
      stop = res == nlopt::MAXEVAL_REACHED   ? "maximum evaluations reached"
             : res == nlopt::XTOL_REACHED    ? "step below local_xtol"
             : res == nlopt::FTOL_REACHED    ? "score change below ftol"
             : res == nlopt::STOPVAL_REACHED ? "stop value reached"
                                             : "converged";
    } catch (const nlopt::forced_stop&) {
      stop = "aborted";
    } catch (const nlopt::roundoff_limited&) {
      stop = "round-off limited";
    } catch (const std::exception& e) {
      stop = std::string("stopped: ") + e.what();
    }
    std::lock_guard lock(m_);
    Search& s = searches_[k];
    s.stop = stop, s.done = true, s.waiting = false;
    cv_.notify_all();
  }

  const SearchSettings& q_;
  int dims_;
  long budget_ = 0;
  std::deque<Search> searches_;
  std::vector<std::thread> threads_;
  std::mutex m_;
  std::condition_variable cv_;
  bool abort_ = false;
};

}  // namespace

CalibrationResult run_calibration(CalibrationSetup& s, const fs::path& out, const BatchRunner& run_batch, bool quiet) {
  CalibrationResult r;
  const int P = static_cast<int>(s.parameters.size());
  Evaluator ev(s, out, run_batch, r, quiet);
  // 1. The global stage: a Latin hypercube in u (the ensemble's sampler on U(0, 1)) and the Morris
  //    trajectories, as one batch.
  EnsemblePlan unit;
  unit.seed = s.search.seed;
  unit.members = s.search.global_members;
  unit.sampling = SamplingMethod::LatinHypercube;
  for (const auto& p : s.parameters) {
    ParameterDistribution d;
    d.key = p.key, d.kind = DistributionKind::Uniform, d.a = 0.0, d.b = 1.0;
    unit.parameters.push_back(d);
  }
  std::vector<std::vector<double>> pts = sample_plan(unit);
  std::vector<std::string> stages(pts.size(), "design");
  for (int t = 0; t < s.search.morris_trajectories; ++t)
    for (auto& x : morris_trajectory(s.search.seed, t, P, s.search.morris_levels)) {
      pts.push_back(x);
      stages.push_back("morris");
    }
  ev.evaluate(pts, stages);
  r.design_members = s.search.global_members;
  r.morris_members = ev.members() - r.design_members;

  // 2. Local searches from the best distinct successful members, in lockstep; a slot whose search
  //    ended is refilled from the best member far enough from every start and every search's best.
  const auto unit_of = [&](const Evaluation& e) {
    std::vector<double> u(static_cast<std::size_t>(P));
    for (int d = 0; d < P; ++d)
      u[static_cast<std::size_t>(d)] =
          std::clamp(s.parameters[static_cast<std::size_t>(d)].unit(e.values[static_cast<std::size_t>(d)]), 0.0, 1.0);
    return u;
  };
  const auto ranked = [&] {
    std::vector<const Evaluation*> v;
    for (const auto& e : r.evaluations)
      if (e.ok) v.push_back(&e);
    std::stable_sort(v.begin(), v.end(),
                     [](const Evaluation* a, const Evaluation* b) { return a->misfit.score < b->misfit.score; });
    return v;
  };
  std::vector<std::vector<double>> starts;
  for (const Evaluation* e : ranked()) {
    if (static_cast<int>(starts.size()) >= s.search.local_starts) break;
    const std::vector<double> u = unit_of(*e);
    if (std::find(starts.begin(), starts.end(), u) == starts.end()) starts.push_back(u);
  }
  if (!starts.empty()) {
    // A restart keeps an initial step's distance (Chebyshev, in u) from where every search began
    // and from the best point each found, so it explores another part of the valley.
    const double sep = s.search.local_step > 0.0 ? s.search.local_step : 1.0 / std::max(1, s.search.global_members);
    const auto far_from = [&](const std::vector<double>& u, const std::vector<double>& v) {
      if (v.empty()) return true;
      double d = 0.0;
      for (std::size_t i = 0; i < u.size(); ++i) d = std::max(d, std::abs(u[i] - v[i]));
      return d >= sep;
    };
    LockstepSearches L(s.search, P);
    L.run(
        starts,
        [&](const std::vector<std::vector<double>>& us, const std::vector<std::size_t>& which) {
          std::vector<std::string> st;
          for (std::size_t k : which) st.push_back("local" + std::to_string(k));
          return ev.evaluate(us, st);
        },
        [&](const std::vector<double>& u) { return ev.known(u); },
        [&](const std::deque<LockstepSearches::Search>& searches) -> std::optional<std::vector<double>> {
          for (const Evaluation* e : ranked()) {
            const std::vector<double> u = unit_of(*e);
            if (std::all_of(searches.begin(), searches.end(), [&](const LockstepSearches::Search& q) {
                  return far_from(u, q.x0) && far_from(u, q.best_x);
                }))
              return u;
          }
          return std::nullopt;
        });
    for (const auto& q : L.searches()) r.local_stops.push_back(q.stop);
  }
  // 3. The best member (lowest score, then lowest index).
  for (const auto& e : r.evaluations)
    if (r.best < 0 || e.misfit.score < r.evaluations[static_cast<std::size_t>(r.best)].misfit.score) r.best = e.index;
  if (!quiet)
    std::cerr << "geohaz-calibrate: " << ev.members() << " members (" << ev.resumed() << " found on disk), best "
              << r.best << " with score " << fmt(r.evaluations[static_cast<std::size_t>(r.best)].misfit.score, 5)
              << "\n";
  return r;
}

void run_calibration_serial(CalibrationSetup& s, const fs::path& out, int threads, bool quiet,
                            MemberObserver* observer) {
  prepare_calibration_output(s, out);
  const auto wall0 = std::chrono::steady_clock::now();
  const std::unique_ptr<MemberRunner> runner = make_calibration_runner(s);
  const SearchSettings& q = s.search;
  const int planned = q.global_members + q.morris_trajectories * (static_cast<int>(s.parameters.size()) + 1) +
                      q.local_starts * q.local_evaluations;
  int done = 0;
  const CalibrationResult r = run_calibration(
      s, out,
      [&](const std::vector<int>& batch) {
        for (int i : batch) {
          if (member_done(out, i)) continue;
          RunObserver* steps = observer ? observer->member_started(i, done, std::max(planned, done + 1)) : nullptr;
          const MemberRecord rec = runner->run(i, out, 0, threads, steps);
          if (observer) observer->member_finished(rec, ++done, std::max(planned, done));
        }
      },
      quiet);
  const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - wall0).count();
  write_calibration_outputs(s, r, out, 1, threads, wall, quiet);
}

// Outputs, and the members' maps read back, are in calibrate_outputs.cpp.

}  // namespace geohaz::runout
