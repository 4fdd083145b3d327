#pragma once
/// \file ensemble.hpp
/// Ensembles of debris-runout runs and their probability maps (issue #17, docs/ensemble.md). MPI-free:
/// the `geohaz-ensemble` app spreads members over MPI ranks; everything a member or the aggregation
/// does is here, so one rank, many ranks and the Python module compute the same numbers.
///
///  1. `EnsemblePlan`: distributions of base-case parameters and a sampling plan. `sample_plan`
///     gives member i's values from (seed, i) only: Latin hypercube (McKay, Beckman & Conover 1979)
///     stratifies each parameter into N equal-probability strata, one member per stratum, strata
///     paired by a random permutation per parameter; plain Monte Carlo draws independently. Values
///     are inverse-CDF transforms of the uniform numbers (own counter-based generator, SplitMix64,
///     Steele, Lea & Flood 2014), so the plan is identical on every machine and standard library.
///  2. `run_member`: member i's case (base config with its values), run in-process with OpenMP
///     threads, its peak maps (cropped to the cells reached) and key figures written to
///     `members/<i>/` under a temporary name and renamed: a finished member survives any later
///     crash and is skipped on a rerun. A SimulationError (blow-up) is recorded with its diagnosis.
///  3. `EnsembleAggregator`: streams over the members in index order (memory independent of N):
///     exceedance counts per threshold (exact), sums for the mean (exact), and per-cell log-binned
///     histograms for the percentiles (relative error below one bin ratio, see percentile()).

#include <cstdint>
#include <filesystem>
#include <functional>
#include <limits>
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "geohaz/core/raster.hpp"
#include "geohaz/runout/hazard_maps.hpp"
#include "geohaz/runout/run.hpp"

namespace geohaz {
class ConfigReader;
}

namespace geohaz::runout {

class RunObserver;
class RunoutSimulation;

/// Kinds of parameter distribution.
enum class DistributionKind {
  Uniform,    ///< on [min, max]
  Normal,     ///< mean, sd; optionally truncated to [lower, upper]
  LogNormal,  ///< ln X normal with median e^μ and σ of ln X; optionally truncated to [lower, upper]
  Discrete,   ///< values with weights (equal when none given)
  Fixed       ///< one value for every member (a setting of the base case changed for the ensemble)
};
const char* to_string(DistributionKind k) noexcept;

/// One uncertain parameter: a numeric key of the base debris-runout case, or one of the two
/// ensemble parameters `release.thickness_factor` (multiplies the release thickness) and
/// `release.alternative` (index into the alternative release files, discrete).
struct ParameterDistribution {
  std::string key;
  DistributionKind kind = DistributionKind::Uniform;
  double a = 0.0, b = 1.0;  ///< uniform: min, max; normal: mean, sd; log-normal: median, σ of ln; fixed: value
  double lower = -std::numeric_limits<double>::infinity();  ///< truncation (normal, log-normal)
  double upper = std::numeric_limits<double>::infinity();
  std::vector<double> values, weights;  ///< discrete
  /// The value whose cumulative probability is u ∈ (0, 1) (inverse CDF; truncation included).
  double quantile(double u) const;
};

/// The ensemble parameter that scales the release thickness (and so the volume).
inline constexpr const char* kThicknessFactorKey = "release.thickness_factor";
/// The ensemble parameter that picks one of the alternative release files.
inline constexpr const char* kReleaseAlternativeKey = "release.alternative";

/// A parameter key of an ensemble (or a calibration) with its label and unit from the
/// declarations: the two keys above as declared here (key_labels.cpp; unit "1"), any other as
/// case_key gives it (run.hpp). std::nullopt for a key neither declares.
std::optional<FrictionKey> parameter_key(std::string_view key);

enum class SamplingMethod { LatinHypercube, MonteCarlo };

/// What an ensemble varies and how it samples.
struct EnsemblePlan {
  std::vector<ParameterDistribution> parameters;
  std::vector<std::string> release_alternatives;  ///< release files chosen by release.alternative
  SamplingMethod sampling = SamplingMethod::LatinHypercube;
  std::uint64_t seed = 1;
  int members = 10;
};

/// Member i's values, one per parameter (N × P), from the plan's seed only.
std::vector<std::vector<double>> sample_plan(const EnsemblePlan& plan);

/// A uniform number in (0, 1) from (seed, a, b, c) only (SplitMix64 mixing of the four).
double counter_uniform(std::uint64_t seed, std::uint64_t a, std::uint64_t b, std::uint64_t c) noexcept;

/// Which products the aggregation makes.
struct AggregationSettings {
  std::vector<double> depth_thresholds{0.5};        ///< m: P(peak depth > t)
  std::vector<double> speed_thresholds;             ///< m/s: P(peak speed > t)
  std::vector<double> pressure_thresholds{30.0e3};  ///< Pa: P(peak pressure > t)
  std::vector<int> intensity_classes{2};            ///< P(intensity class ≥ k), k ∈ {1, 2, 3}
  std::vector<double> percentiles{10.0, 50.0, 90.0};
  int bins = 96;             ///< log-spaced histogram bins per field and cell
  IntensityTable intensity;  ///< class thresholds (those of the base case)
  /// The maps as the base case draws its own (run.hpp OutputSettings): depth, speed and pressure
  /// classes (m, m/s, Pa), margin around the affected area (m), attribution ("" : the DSM's
  /// metadata).
  std::vector<double> map_depth_classes{0.5, 1.0, 2.0};
  std::vector<double> map_speed_classes{1.0, 3.0, 10.0};
  std::vector<double> map_pressure_classes{3e3, 3e4, 1e5};
  double map_margin = 200.0;
  std::string attribution;
  double profile_half_width = 50.0;  ///< m: the base case's output.profile_half_width
};

/// Log-binned histogram ranges of the three fields (values below the low end go into one bin,
/// values above the high end into another; the percentile is clamped to the cell's exact extremes).
struct HistogramRange {
  double lo, hi;
};
inline constexpr HistogramRange kDepthRange{1e-3, 1e2};    ///< m
inline constexpr HistogramRange kSpeedRange{1e-2, 1e2};    ///< m/s
inline constexpr HistogramRange kPressureRange{1.0, 1e7};  ///< Pa

/// Percentile of a set of values from its histogram (nearest rank k = ⌈q·n/100⌉, 1-based): `zeros`
/// exact zeros first, then `below` values in (0, lo), then `counts[j]` in bin j of `bins` log-spaced
/// bins over [lo, hi), then `above` values ≥ hi. Inside a bin the value is placed geometrically at
/// the rank's mid-position; the result is clamped to [vmin, vmax] (the exact extremes of the
/// non-zero values). Error: less than a factor (hi/lo)^(1/bins) for values in [lo, hi); values
/// below lo come out as vmin (error < lo), above hi as vmax.
template <class Count>
double histogram_percentile(double q, std::uint32_t zeros, std::uint32_t below, const Count* counts, int bins,
                            std::uint32_t above, HistogramRange range, double vmin, double vmax);

/// Peak maps of one member cropped to the window of the cells it reached.
struct MemberPeaks {
  int nx = 0, ny = 0;                          ///< the full grid
  int c0 = 0, r0 = 0, w = 0, h = 0;            ///< window (w = h = 0: nothing reached)
  double density = 0.0;                        ///< kg/m³ of the member (intensity classes)
  std::vector<double> depth, speed, pressure;  ///< w·h each, row-major
};
void write_member_peaks(const std::filesystem::path& path, const MemberPeaks& p);
/// Read peaks written by write_member_peaks; `header_only` skips the maps.
MemberPeaks read_member_peaks(const std::filesystem::path& path, bool header_only = false);

/// Streaming aggregation over members (call add() in member order for bit-identical results).
class EnsembleAggregator {
 public:
  /// `window`: the union of the members' windows (c0, r0, w, h) on the grid `nx` × `ny`.
  EnsembleAggregator(int nx, int ny, int c0, int r0, int w, int h, AggregationSettings s);
  void add(const MemberPeaks& p);
  int members() const noexcept { return n_; }
  /// A product on the full grid (zero outside the window). Field 0 depth, 1 speed, 2 pressure.
  std::vector<double> mean(int field) const;
  std::vector<double> percentile(int field, double q) const;
  std::vector<double> exceedance(int field, double threshold) const;  ///< field 3: intensity ≥ class
  /// Bytes held per window cell (for the docs and the summary).
  std::size_t bytes_per_cell() const noexcept;

 private:
  static HistogramRange range_of(int field);
  int bin_of(int field, double v) const;
  int nx_, ny_, c0_, r0_, w_, h_, n_ = 0;
  AggregationSettings s_;
  std::vector<double> sum_;                         // 3 per cell
  std::vector<double> vmin_, vmax_;                 // 3 per cell, non-zero values
  std::vector<std::uint32_t> zeros_;                // 3 per cell
  std::vector<std::uint16_t> hist_;                 // 3 × (bins + 2) per cell: below, bins, above
  std::vector<std::uint32_t> exceed_;               // per threshold (depth, speed, pressure, intensity) per cell
  std::vector<std::pair<int, double>> thresholds_;  // (field, threshold) in exceed_ order
};

/// A member's outcome, as written to members/<i>/member.json and members.csv.
struct MemberRecord {
  int index = 0;
  bool ok = false;
  std::string diagnosis;  ///< why it failed ("" when ok)
  std::vector<double> values;
  double runout_m = 0.0, drop_height_m = 0.0, reach_m = 0.0, hl = 0.0, hl_deg = 0.0;
  double release_m3 = 0.0, deposited_m3 = 0.0, mobile_m3 = 0.0, lost_m3 = 0.0;
  double max_speed = 0.0, affected_area_m2 = 0.0, simulated_time_s = 0.0, wall_time_s = 0.0;
  double cpu_time_s = 0.0;  ///< CPU time of the process during the member (all its threads)
  std::int64_t steps = 0;
  std::string ended_by;
  bool unfinished = false;
  int rank = 0, threads = 1;
};
std::string member_json(const MemberRecord& r, const EnsemblePlan& plan);
MemberRecord parse_member_json(const std::string& text);

/// The base case and the plan, checked: what every rank needs to run members.
struct EnsembleSetup {
  std::filesystem::path base_config;  ///< the debris-runout config of the base case
  EnsemblePlan plan;
  std::vector<std::vector<double>> values;  ///< sample_plan(plan)
  AggregationSettings aggregation;
  std::vector<int> inject_failure;  ///< members made to fail (tests of failure handling)
  std::string resolved_config;      ///< resolved ensemble config (TOML)
  std::string base_resolved;        ///< resolved base config (TOML)
  std::string dsm;                  ///< the base case's DSM
};

/// Read the ensemble keys (every one declared with unit, range and help), the base case and
/// sample the plan; every member's case is built and checked (InputError naming the key, and the
/// member when only some members are out of range). Calls cfg.finish(). Writes nothing.
EnsembleSetup read_ensemble(ConfigReader& cfg);
/// The ensemble keys in describe mode (for --help-config).
void describe_ensemble(ConfigReader& cfg);

/// The plan as CSV text (member, one column per parameter): written as plan.csv and compared on a
/// rerun (a folder of another ensemble is not resumed).
std::string plan_csv(const EnsembleSetup& s);

/// Prepare the output folder (rank 0, or a lone process): a folder of another ensemble (plan.csv or
/// base.resolved.toml differ) is an InputError and is left untouched; otherwise create it and
/// members/, remove the member folders a killed run left unfinished, write plan.csv and the
/// resolved configs. Returns the members still to run, in index order.
std::vector<int> prepare_output(const EnsembleSetup& s, const std::filesystem::path& out);

/// Sees the members of a run in one process (run_ensemble_serial, run_calibration_serial): the
/// Python module's progress callback and Cancel. An exception thrown from it, or from the
/// RunObserver it hands out, stops the whole run: the member being run leaves no folder, the
/// finished ones stay (a rerun into the folder resumes), no products are written.
class MemberObserver {
 public:
  virtual ~MemberObserver() = default;
  /// Before member i; `done` members of this run have finished, about `planned` will run in all
  /// (for a calibration an upper bound: the local searches may stop early). Returns the observer
  /// of the member's steps, or null.
  virtual RunObserver* member_started(int /*i*/, int /*done*/, int /*planned*/) { return nullptr; }
  /// After member i ran (ok or failed), with its record.
  virtual void member_finished(const MemberRecord& /*rec*/, int /*done*/, int /*planned*/) {}
};

/// Run every pending member in this process and aggregate (one rank; the Python module).
void run_ensemble_serial(const EnsembleSetup& s, const std::filesystem::path& out, int threads, bool quiet,
                         MemberObserver* observer = nullptr);

/// Folder of member i below the output folder.
std::filesystem::path member_dir(const std::filesystem::path& out, int i);
/// Whether member i has finished (ok or failed) in a previous or concurrent run.
bool member_done(const std::filesystem::path& out, int i);

/// Runs members of one setup, keeping the DSM and release loaded between members with the same
/// inputs.
class MemberRunner {
 public:
  explicit MemberRunner(const EnsembleSetup& s);
  ~MemberRunner();
  /// Run member i with `threads` OpenMP threads and write members/<i>/ (atomically); `observer`
  /// sees every step (the MPI app answers requests from there). A blow-up is recorded, not thrown.
  MemberRecord run(int i, const std::filesystem::path& out, int rank, int threads, RunObserver* observer = nullptr);
  /// Called after a member ran to its end, with its record and its folder before that is published
  /// (a caller's own files join the member atomically: the calibration's misfit, calibrate.hpp).
  using FinishedHook =
      std::function<void(const RunoutSimulation&, const MemberRecord&, const std::filesystem::path& folder)>;
  void set_finished_hook(FinishedHook hook) { hook_ = std::move(hook); }

 private:
  struct Cache;
  const EnsembleSetup& s_;
  std::unique_ptr<Cache> cache_;
  FinishedHook hook_;
};

/// Aggregate the members in index order and write the products, members.csv, the plots and
/// summary.json into `out`. `ranks`, `wall_time_s` go into the summary.
void aggregate_ensemble(const EnsembleSetup& s, const std::filesystem::path& out, int ranks, int threads,
                        double wall_time_s, bool quiet);

}  // namespace geohaz::runout
