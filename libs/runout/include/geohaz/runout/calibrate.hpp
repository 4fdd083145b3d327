#pragma once
/// \file calibrate.hpp
/// Back-analysis of debris-runout against an observed event (issue #31, docs/calibration.md).
/// MPI-free like ensemble.hpp: the `geohaz-calibrate` app spreads each batch of members over MPI
/// ranks exactly as `geohaz-ensemble` does; the Python module runs the same code on one rank.
///
///  1. `read_calibration`: the base debris-runout case, the parameters (key, bounds, linear or log
///     scale; `release.thickness_factor` too), the observation (footprint polygons or raster,
///     optional deposit-depth raster, run-out point, deposit volume, the thalweg) and the score
///     settings, every one checked before anything is written.
///  2. The misfit of a run (`compute_misfit`), AIMEC-style (Fischer 2013; AvaFrame ana3AIMEC): every
///     DSM cell carries its coordinate s along the thalweg (projection on the nearest segment);
///     modelled affected cells (peak depth > depth_threshold) against observed ones give the areas
///     TP, FP, FN, and the run-out is the largest s of an affected cell. The score (0 = perfect)
///       J = w_f (1 − T) + w_r |s_mod − s_obs| / s_obs + w_d RMSE(deposit) / mean(observed deposit)
///           + w_v |V_mod − V_obs| / V_obs,
///     with T the Tversky index TP / (TP + α FP + β FN) (Tversky 1977; α = β = ½ is the Dice/F1
///     score). T does not count true negatives, so J does not depend on how much of the DSM lies
///     outside the event (MCC does); α, β weigh over- against under-prediction.
///  3. The search (`run_calibration`): a Latin-hypercube design in the unit cube of the scaled
///     parameters (the ensemble's sampler) plus Morris trajectories (Morris 1991; μ* of Campolongo
///     et al. 2007) as one batch, then derivative-free local searches (NLopt: Sbplx, BOBYQA or
///     Nelder–Mead, bounded) from the best distinct members, run in lockstep: every iteration is a
///     batch of one point per live search, so `local_starts` searches keep that many ranks busy; the
///     slot of a search that ends is refilled by a restart from the best distinct member while the
///     local budget (`local_starts` x `local_evaluations` members) lasts.
///     Every evaluation is a member (members/<i>/, ensemble.hpp) whose index is fixed by the
///     sequence alone: a rerun replays the searches and finds finished members on disk.
///  4. The outputs (`write_calibration_outputs`): best.toml (a ready-to-run debris-runout config),
///     members.csv, acceptable.csv and acceptable.svg, sensitivity.csv, comparison.tif/.png
///     (TP/FP/FN over the hillshade), thalweg_profile.csv, the best member's long profile along
///     the thalweg with the observed run-out marked beside the modelled one (profile.csv,
///     profile.png) and summary.json.

#include <array>
#include <cstdint>
#include <filesystem>
#include <functional>
#include <limits>
#include <memory>
#include <string>
#include <vector>

#include "geohaz/core/terrain.hpp"
#include "geohaz/core/vec.hpp"
#include "geohaz/runout/ensemble.hpp"

namespace geohaz {
class ConfigReader;
}

namespace geohaz::runout {

/// A parameter searched between bounds, on a linear or logarithmic scale (the search works on
/// u ∈ [0, 1]: v = lo + u (hi − lo), or v = lo (hi/lo)^u).
struct CalibrationParameter {
  std::string key;  ///< a numeric debris-runout key or release.thickness_factor
  double lower = 0.0, upper = 1.0;
  bool log_scale = false;
  double value(double u) const noexcept;  ///< u ∈ [0, 1] → key's unit
  double unit(double v) const noexcept;   ///< inverse of value()
};

/// How a run is compared with the observation (the weights and what "affected" means).
struct ScoreSettings {
  double depth_threshold = 0.1;        ///< m: a modelled cell is affected when its peak depth exceeds this
  double alpha = 0.5, beta = 0.5;      ///< Tversky weights of FP (over-) and FN (under-prediction)
  double w_footprint = 1.0;            ///< weight of 1 − T
  double w_runout = 1.0;               ///< weight of |Δs| / s_obs
  double w_depth = 1.0;                ///< weight of the deposit RMSE / mean observed deposit (with a deposit raster)
  double w_volume = 1.0;               ///< weight of |ΔV| / V_obs (with an observed volume)
  double failed_penalty = 10.0;        ///< score of a failed member
  double acceptable_tolerance = 0.02;  ///< members with J ≤ J_best + this are acceptable
  double profile_bin = 0.0;            ///< m, bin of the thalweg profile (0: two cells)
};

/// The observed event on the DSM grid, with each cell's coordinate along the thalweg.
struct Observation {
  GridGeometry grid;
  std::vector<std::uint8_t> footprint;  ///< 1 = affected (per DSM cell)
  std::vector<double> deposit;          ///< m, vertical (empty: none observed)
  double runout_s = 0.0;  ///< m along the thalweg (run-out point or line, or the footprint's farthest cell)
  std::string runout_from = "footprint";  ///< where runout_s comes from: "runout_point", "runout_line", "footprint"
  double volume = 0.0;                    ///< m³ deposited (0: none observed)
  std::vector<Vec2> thalweg;              ///< polyline in the DSM's CRS
  std::vector<double> s;                  ///< m along the thalweg of every cell centre
  double footprint_area() const noexcept;
};

/// Along-thalweg coordinate of p: arc length to its projection on the nearest segment.
double along_thalweg(const std::vector<Vec2>& thalweg, const Vec2& p) noexcept;

/// The comparison of one run with the observation.
struct Misfit {
  double tp = 0.0, fp = 0.0, fn = 0.0;       ///< m²
  double tversky = 0.0;                      ///< T (1)
  double runout_s = 0.0, runout_diff = 0.0;  ///< m: modelled run-out along the thalweg, minus the observed
  double depth_rmse = 0.0;                   ///< m (0 without a deposit raster)
  double volume = 0.0;                       ///< m³ deposited in the model
  double term_footprint = 0.0, term_runout = 0.0, term_depth = 0.0, term_volume = 0.0;
  double score = 0.0;  ///< J
};

/// Misfit of a run: `max_depth` and `deposit` on the DSM grid (m), `volume` its deposited m³ (the
/// integral of `deposit`).
Misfit compute_misfit(const Observation& obs, const ScoreSettings& s, const std::vector<double>& max_depth,
                      const std::vector<double>& deposit, double volume);

/// The search settings.
struct SearchSettings {
  int global_members = 16;                ///< Latin-hypercube members
  int morris_trajectories = 4;            ///< Morris trajectories (P + 1 members each); 0: no sensitivity
  int morris_levels = 4;                  ///< grid levels p (step Δ = p / (2 (p − 1)))
  int local_starts = 2;                   ///< local searches from the best distinct members
  int local_evaluations = 30;             ///< members per local search at most
  bool local_restarts = true;             ///< refill the slot of an ended search while the budget lasts
  double local_xtol = 1e-3;               ///< stop when a step changes u by less than this (unit cube)
  std::string local_algorithm = "sbplx";  ///< sbplx, bobyqa (P ≥ 2), neldermead
  double local_step = 0.0;                ///< initial step in u (0: 1 / global_members)
  std::uint64_t seed = 1;
};

/// Everything every rank needs: the members' ensemble setup (its values grow as the search goes),
/// the parameters, the observation, the settings.
struct CalibrationSetup {
  EnsembleSetup members;  ///< base case, plan (the parameters as keys), values per member index
  std::vector<CalibrationParameter> parameters;
  Observation observation;
  ScoreSettings score;
  SearchSettings search;
  std::string resolved_config;  ///< the calibration config, resolved (TOML)
  std::string dsm_crs_wkt;
};

/// Read and check the calibration keys (InputError naming file, key, value: bounds reversed or
/// outside the key's range, unknown key, observation outside the DSM or on another grid or CRS).
/// Calls cfg.finish(). Writes nothing.
CalibrationSetup read_calibration(ConfigReader& cfg);
/// The keys in describe mode (for --help-config).
void describe_calibration(ConfigReader& cfg);

/// One evaluated member as the search sees it.
struct Evaluation {
  int index = 0;
  std::string stage;  ///< "design", "morris", "local<k>"
  int batch = 0;      ///< the batch it was run in (0: the global stage), fixed by the search alone
  std::vector<double> values;
  bool ok = false;
  std::string diagnosis;
  Misfit misfit;  ///< score = failed_penalty when !ok
};

/// Run the listed members (values already in setup.members.values) so that each is on disk when
/// it returns; members already on disk are skipped.
using BatchRunner = std::function<void(const std::vector<int>& indices)>;

/// Prepare the output folder (new, or the same calibration to resume: another one is an InputError,
/// left untouched): members/, the resolved configs.
void prepare_calibration_output(const CalibrationSetup& s, const std::filesystem::path& out);

/// A MemberRunner for the setup that also writes each member's misfit (misfit.json) and deposit.
std::unique_ptr<MemberRunner> make_calibration_runner(const CalibrationSetup& s);

/// The evaluations of member i from disk (after it finished).
Evaluation read_evaluation(const CalibrationSetup& s, const std::filesystem::path& out, int i);

/// Member i's deposit and peak flow depth on the full DSM grid (m), from its folder.
std::vector<double> read_member_deposit(const std::filesystem::path& out, int i);
std::vector<double> read_member_max_depth(const std::filesystem::path& out, int i);
/// Member i's peak depth (m), speed (m/s) and pressure (Pa) on the full DSM grid.
std::array<std::vector<double>, 3> read_member_peak_maps(const std::filesystem::path& out, int i);

/// The result of a search.
struct CalibrationResult {
  std::vector<Evaluation> evaluations;  ///< every member, in index order
  int best = -1;                        ///< index of the best member
  int design_members = 0, morris_members = 0;
  std::vector<std::string> local_stops;  ///< why each local search ended
};

/// The search (rank 0 or a lone process): design + Morris batch, then the lockstep local searches.
/// Grows setup.members.values as it goes.
CalibrationResult run_calibration(CalibrationSetup& s, const std::filesystem::path& out, const BatchRunner& run_batch,
                                  bool quiet);

/// Write best.toml (+ best_release.tif when the thickness factor is searched), members.csv,
/// acceptable.csv/.svg, sensitivity.csv, comparison.tif/.qml/.png, thalweg_profile.csv, profile.csv
/// and profile.png (when the best member ran), summary.json.
void write_calibration_outputs(const CalibrationSetup& s, const CalibrationResult& r, const std::filesystem::path& out,
                               int ranks, int threads, double wall_time_s, bool quiet);

/// All of it on one rank (the Python module, the app without MPI); `observer` sees each member
/// (planned: the design, Morris and local members at most).
void run_calibration_serial(CalibrationSetup& s, const std::filesystem::path& out, int threads, bool quiet,
                            MemberObserver* observer = nullptr);

/// Morris elementary effects of one parameter: μ* (mean |EE|), μ, σ (1/unit of u).
struct MorrisEffect {
  std::string key;
  double mu_star = 0.0, mu = 0.0, sigma = 0.0;
  int effects = 0;
};
/// Base point and order of Morris trajectory t (u values of its P + 1 points).
std::vector<std::vector<double>> morris_trajectory(std::uint64_t seed, int t, int parameters, int levels);

}  // namespace geohaz::runout
