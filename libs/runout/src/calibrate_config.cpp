// The calibration's configuration (calibrate.hpp, docs/calibration.md): every key declared once
// (Keys: describe mode for --help-config and reading go through the same calls), and
// read_calibration, which reads and checks the observation against the DSM before anything is
// written. Split from calibrate.cpp (the misfit and the search) to keep each under 1000 lines.
#include <algorithm>
#include <cctype>
#include <cmath>
#include <set>
#include <string>
#include <vector>

#include "case_support.hpp"
#include "geohaz/core/config.hpp"
#include "geohaz/core/errors.hpp"
#include "geohaz/core/raster.hpp"
#include "geohaz/runout/calibrate.hpp"
#include "geohaz/runout/run.hpp"

namespace fs = std::filesystem;

namespace geohaz::runout {

using detail::fmt;
using detail::numeric_case_keys;
using detail::origin;
using detail::resolve_path;

namespace {

bool is_vector_file(const fs::path& p) {
  std::string e = p.extension().string();
  std::transform(e.begin(), e.end(), e.begin(), [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return e == ".shp" || e == ".geojson" || e == ".json" || e == ".gpkg" || e == ".kml" || e == ".gml";
}

/// A raster of the observation must lie on the DSM's grid in the DSM's CRS (no silent resampling:
/// a footprint shifted by half a cell would bias every area).
void check_same_grid(const Raster& r, const Raster& dsm, const std::string& src, const std::string& key,
                     const std::string& file) {
  if (!r.crs_wkt.empty() && !dsm.crs_wkt.empty() && !crs_equal(r.crs_wkt, dsm.crs_wkt))
    throw InputError(
        "the raster is in another CRS than the DSM (reproject it onto the DSM grid, e.g. gdalwarp "
        "-t_srs <DSM CRS> -te <DSM extent> -tr <DSM cell size>)",
        src, key, file);
  const double tol = 1e-6 * std::abs(dsm.cell_size_x());
  bool same = r.nx == dsm.nx && r.ny == dsm.ny;
  for (int k = 0; k < 6 && same; ++k)
    same = std::abs(r.geotransform[static_cast<std::size_t>(k)] - dsm.geotransform[static_cast<std::size_t>(k)]) <= tol;
  if (!same)
    throw InputError("the raster is on another grid than the DSM (" + std::to_string(r.nx) + " x " +
                         std::to_string(r.ny) + " cells of " + fmt(r.cell_size_x()) + " m against " +
                         std::to_string(dsm.nx) + " x " + std::to_string(dsm.ny) + " of " + fmt(dsm.cell_size_x()) +
                         " m; resample it onto the DSM grid, e.g. gdalwarp -te <DSM extent> -tr <DSM cell size>)",
                     src, key, file);
}

bool inside(const Raster& dsm, const Vec2& p) {
  const auto e = dsm.extent();
  return p.x() >= e[0].x() && p.x() <= e[1].x() && p.y() >= e[0].y() && p.y() <= e[1].y();
}

const char* const kParamKeys = "calibration.parameter";

}  // namespace

// ---- configuration --------------------------------------------------------------------------

namespace {

/// The observation's keys as read (paths resolved), before the files are read.
struct ObservationKeys {
  std::string footprint;
  double threshold = 0.0;
  std::string deposit;
  std::vector<double> point;
  std::string line, thalweg;
};

struct Keys {
  // Every key declared once: describe mode (--help-config) and reading go through these calls.
  static void calibration(ConfigReader& cfg, CalibrationSetup& s) {
    SearchSettings& q = s.search;
    s.members.base_config = resolve_path(
        cfg, cfg.require_string("calibration.base",
                                {"", "the debris-runout config of the base case (DSM, release, law, numerics)"}));
    q.seed = static_cast<std::uint64_t>(cfg.get_int("calibration.seed", 1, Range::closed(0, 9.0e15),
                                                    {"1", "seed of the design and the Morris trajectories"}));
    q.global_members = static_cast<int>(
        cfg.get_int("calibration.global_members", q.global_members, Range::closed(1, 100000),
                    {"1", "members of the global stage: a Latin hypercube in the unit cube of the scaled parameters",
                     "members of the design"}));
    q.morris_trajectories =
        static_cast<int>(cfg.get_int("calibration.morris_trajectories", q.morris_trajectories, Range::closed(0, 1000),
                                     {"1", "Morris elementary-effect trajectories (P + 1 members each); 0: none"}));
    q.morris_levels = static_cast<int>(cfg.get_int("calibration.morris_levels", q.morris_levels, Range::closed(2, 64),
                                                   {"1", "Morris grid levels p (step p / (2 (p - 1)) in u)"}));
    if (q.morris_levels % 2 != 0)
      throw InputError("Morris levels must be even (the step p / (2 (p - 1)) stays on the grid)", origin(cfg),
                       "calibration.morris_levels", std::to_string(q.morris_levels));
    q.local_starts =
        static_cast<int>(cfg.get_int("calibration.local_starts", q.local_starts, Range::closed(0, 1000),
                                     {"1",
                                      "local searches, started from the best distinct members (run in lockstep: "
                                      "one member per search and iteration, so this many ranks stay busy)",
                                      "local searches"}));
    q.local_evaluations =
        static_cast<int>(cfg.get_int("calibration.local_evaluations", q.local_evaluations, Range::closed(1, 100000),
                                     {"1", "members per local search at most"}));
    q.local_restarts = cfg.get_bool(
        "calibration.local_restarts", q.local_restarts,
        {"",
         "a local search that ends hands its slot to a new search from the best member at least an initial step "
         "away from every start and every search's best, while local_starts x local_evaluations local members are "
         "not spent (keeps local_starts ranks busy)",
         "local searches restarted when one ends"});
    q.local_xtol = cfg.get("calibration.local_xtol", q.local_xtol, Range::open_closed(0.0, 1.0),
                           {"1", "a local search stops when a step moves u (unit cube) by less than this"});
    q.local_step = cfg.get("calibration.local_step", q.local_step, Range::closed(0.0, 1.0),
                           {"1", "initial step of the local searches in u; 0: 1 / global_members"});
    q.local_algorithm =
        cfg.get_choice("calibration.local_algorithm", q.local_algorithm, {"sbplx", "bobyqa", "neldermead"},
                       {"",
                        "NLopt derivative-free bounded local method: sbplx (Rowan 1990), bobyqa "
                        "(Powell 2009; needs 2 or more parameters), neldermead",
                        "local search algorithm"});
    for (double v : cfg.get_array("calibration.inject_failure", {}, Range::closed(0, 1e9),
                                  {"1", "test hook: these member indices fail on purpose"}))
      s.members.inject_failure.push_back(static_cast<int>(v));
  }

  static void parameter(ConfigReader& t, CalibrationParameter& p) {
    p.key = t.require_string("key", {"",
                                     "numeric debris-runout key (model.n, model.icr, model.mu, ...) or "
                                     "release.thickness_factor"});
    const Range any = Range::closed(-1e12, 1e12);
    p.lower = t.require("min", any, {"key's unit", "lower bound"});
    p.upper = t.require("max", any, {"key's unit", "upper bound (> min)"});
    p.log_scale =
        t.get_choice("scale", "linear", {"linear", "log"},
                     {"", "linear, or log (searched in ln: for coefficients spanning decades, min > 0)"}) == "log";
  }

  static void observation(ConfigReader& cfg, ObservationKeys& o, double& volume) {
    auto& [footprint, threshold, deposit, point, line, thalweg] = o;
    footprint = resolve_path(
        cfg, cfg.require_string("observation.footprint", {"",
                                                          "mapped footprint: polygons (Shapefile, GeoJSON, GPKG) or a "
                                                          "raster on the DSM grid (affected where > threshold)"}));
    threshold = cfg.get("observation.footprint_threshold", 0.0, Range::closed(-1e12, 1e12),
                        {"raster's unit", "a footprint raster cell is affected when its value exceeds this"});
    deposit = resolve_path(cfg, cfg.get_string("observation.deposit", "",
                                               {"",
                                                "observed deposit depth raster (m, vertical) on the DSM grid "
                                                "(optional)"}));
    point = cfg.get_array("observation.runout_point", {}, Range::closed(-1e8, 1e8),
                          {"m",
                           "observed run-out point [x, y] in the DSM's CRS (optional; default: the footprint's "
                           "farthest cell along the thalweg)"});
    line = resolve_path(cfg, cfg.get_string("observation.runout_line", "",
                                            {"",
                                             "observed run-out as a line file (e.g. the mapped deposit front, any "
                                             "CRS); its vertex farthest along the thalweg sets the run-out "
                                             "(optional; not with runout_point)"}));
    volume = cfg.get("observation.volume", 0.0, Range::non_negative(),
                     {"m^3", "observed deposit volume (optional; 0: not used)"});
    thalweg = resolve_path(
        cfg, cfg.require_string("observation.thalweg",
                                {"",
                                 "the thalweg (flow path) as a line file: the along-path coordinate of the "
                                 "AIMEC-style comparison, starting at the release"}));
  }

  static void score(ConfigReader& cfg, ScoreSettings& s) {
    s.depth_threshold = cfg.get(
        "score.depth_threshold", s.depth_threshold, Range::non_negative(),
        {"m", "a modelled cell is affected when its peak flow depth exceeds this", "affected above the peak depth"});
    s.alpha = cfg.get("score.tversky_alpha", s.alpha, Range::non_negative(),
                      {"1", "Tversky weight of false positives (over-prediction); 0.5 with beta 0.5: Dice",
                       "Tversky α (weight of false positives)"});
    s.beta =
        cfg.get("score.tversky_beta", s.beta, Range::non_negative(),
                {"1", "Tversky weight of false negatives (under-prediction)", "Tversky β (weight of false negatives)"});
    s.w_footprint = cfg.get("score.w_footprint", s.w_footprint, Range::non_negative(),
                            {"1", "weight of 1 - T", "weight of the footprint term"});
    s.w_runout = cfg.get(
        "score.w_runout", s.w_runout, Range::non_negative(),
        {"1", "weight of |run-out difference| / observed run-out (along the thalweg)", "weight of the run-out term"});
    s.w_depth = cfg.get("score.w_depth", s.w_depth, Range::non_negative(),
                        {"1", "weight of the deposit RMSE / mean observed deposit (with observation.deposit)",
                         "weight of the deposit term"});
    s.w_volume = cfg.get("score.w_volume", s.w_volume, Range::non_negative(),
                         {"1", "weight of |volume difference| / observed volume (with observation.volume)",
                          "weight of the volume term"});
    s.failed_penalty = cfg.get("score.failed_penalty", s.failed_penalty, Range::positive(),
                               {"1", "score of a member whose run failed", "score of a failed member"});
    s.acceptable_tolerance = cfg.get("score.acceptable_tolerance", s.acceptable_tolerance, Range::non_negative(),
                                     {"1", "acceptable set: members whose score is at most the best score + this",
                                      "acceptable within this score of the best"});
    s.profile_bin = cfg.get("score.profile_bin", s.profile_bin, Range::non_negative(),
                            {"m", "bin length of thalweg_profile.csv along the thalweg; 0: two DSM cells"});
  }
};

}  // namespace

void describe_calibration(ConfigReader& cfg) {
  CalibrationSetup s;
  Keys::calibration(cfg, s);
  for (ConfigReader& t : cfg.tables(kParamKeys, {"", "the parameters to fit: key, min, max, scale"})) {
    CalibrationParameter p;
    Keys::parameter(t, p);
  }
  ObservationKeys o;
  double v = 0;
  Keys::observation(cfg, o, v);
  Keys::score(cfg, s.score);
}

namespace {

/// The observed run-out along the thalweg (ob.runout_s, ob.runout_from): from the run-out point,
/// the farthest vertex of the run-out line, or else the farthest footprint cell.
void observed_runout(Observation& ob, const Raster& dsm, const std::vector<double>& point, const std::string& line,
                     const std::string& src) {
  const std::size_t cells = ob.grid.cells();
  if (!point.empty() && !line.empty())
    throw InputError("give the observed run-out as a point or as a line, not both", src, "observation.runout_line",
                     line);
  if (!point.empty()) {
    if (point.size() != 2)
      throw InputError("the run-out point is [x, y]", src, "observation.runout_point",
                       std::to_string(point.size()) + " numbers");
    const Vec2 p(point[0], point[1]);
    if (!inside(dsm, p))
      throw InputError("the run-out point lies outside the DSM", src, "observation.runout_point",
                       fmt(p.x(), 10) + ", " + fmt(p.y(), 10));
    ob.runout_s = along_thalweg(ob.thalweg, p);
    ob.runout_from = "runout_point";
  } else if (!line.empty()) {
    if (!fs::exists(line)) throw InputError("run-out line file not found", src, "observation.runout_line", line);
    ob.runout_s = 0.0;
    for (const auto& l : read_lines(line, "", dsm.crs_wkt))
      for (const Vec2& v : l.vertices) {
        if (!inside(dsm, v))
          throw InputError("the run-out line leaves the DSM (vertex " + fmt(v.x(), 10) + ", " + fmt(v.y(), 10) + ")",
                           src, "observation.runout_line", line);
        ob.runout_s = std::max(ob.runout_s, along_thalweg(ob.thalweg, v));
      }
    ob.runout_from = "runout_line";
  } else {
    for (std::size_t k = 0; k < cells; ++k)
      if (ob.footprint[k]) ob.runout_s = std::max(ob.runout_s, ob.s[k]);
  }
}

}  // namespace

CalibrationSetup read_calibration(ConfigReader& cfg) {
  CalibrationSetup s;
  const std::string src = origin(cfg);
  Keys::calibration(cfg, s);
  const std::set<std::string> numeric = numeric_case_keys();
  auto tables = cfg.tables(kParamKeys, {"", "the parameters to fit"});
  if (tables.empty())
    throw InputError("no parameter to fit: add [[calibration.parameter]] tables (key, min, max)", src, kParamKeys);
  for (std::size_t k = 0; k < tables.size(); ++k) {
    const std::string where = std::string(kParamKeys) + "[" + std::to_string(k) + "]";
    CalibrationParameter p;
    Keys::parameter(tables[k], p);
    if (p.key != kThicknessFactorKey && !numeric.count(p.key)) {
      std::string list = kThicknessFactorKey;
      for (const auto& n : numeric) list += ", " + n;
      throw InputError("unknown parameter name (a numeric debris-runout key or " + std::string(kThicknessFactorKey) +
                           "); allowed: " + list,
                       src, where + ".key", p.key);
    }
    for (const auto& q : s.parameters)
      if (q.key == p.key) throw InputError("parameter given twice", src, where + ".key", p.key);
    if (!(p.lower < p.upper))
      throw InputError(
          "bounds reversed or empty: min must be < max (min = " + fmt(p.lower) + ", max = " + fmt(p.upper) + ")", src,
          where + ".min", fmt(p.lower));
    if (p.log_scale && !(p.lower > 0.0))
      throw InputError("a log scale needs min > 0", src, where + ".min", fmt(p.lower));
    if (p.key == kThicknessFactorKey && !(p.lower > 0.0))
      throw InputError("the release thickness factor must be > 0", src, where + ".min", fmt(p.lower));
    s.parameters.push_back(p);
  }
  if (s.search.local_algorithm == "bobyqa" && s.parameters.size() < 2 && s.search.local_starts > 0)
    throw InputError("bobyqa needs two or more parameters (use sbplx or neldermead for one)", src,
                     "calibration.local_algorithm", "bobyqa");
  ObservationKeys keys;
  Keys::observation(cfg, keys, s.observation.volume);
  const auto& [footprint, threshold, deposit, point, line, thalweg] = keys;
  Keys::score(cfg, s.score);
  cfg.finish();
  s.resolved_config = cfg.resolved();

  // The base case, and the case at every corner of the box (a bound outside its key's range is an
  // input error naming the parameter, before anything is written).
  EnsembleSetup& e = s.members;
  e.resolved_config = s.resolved_config;
  if (!fs::exists(e.base_config))
    throw InputError("base case config not found", src, "calibration.base", e.base_config.string());
  {
    ConfigReader base = ConfigReader::from_file(e.base_config);
    const RunConfig c = read_config(base);
    base.finish();
    e.base_resolved = base.resolved();
    e.dsm = c.dsm;
  }
  for (std::size_t k = 0; k < s.parameters.size(); ++k) {
    const auto& p = s.parameters[k];
    ParameterDistribution d;
    d.key = p.key, d.kind = DistributionKind::Uniform, d.a = p.lower, d.b = p.upper;
    e.plan.parameters.push_back(d);
    if (p.key == kThicknessFactorKey) continue;
    for (const double v : {p.lower, p.upper}) {
      ConfigReader m = ConfigReader::from_file(e.base_config);
      std::ostringstream o;
      o << p.key << '=' << std::setprecision(17) << v;
      m.apply_override(o.str(),
                       src + " (" + kParamKeys + "[" + std::to_string(k) + "]." + (v == p.lower ? "min" : "max") + ")");
      (void)read_config(m);
    }
  }
  e.plan.members = 0;
  e.plan.seed = s.search.seed;

  // The observation on the DSM grid.
  const Raster dsm = read_raster(e.dsm);
  s.dsm_crs_wkt = dsm.crs_wkt;
  Observation& ob = s.observation;
  ob.grid = geometry_of(dsm);
  const std::size_t cells = ob.grid.cells();
  if (!fs::exists(thalweg)) throw InputError("thalweg file not found", src, "observation.thalweg", thalweg);
  {
    const auto lines = read_lines(thalweg, "", dsm.crs_wkt);
    ob.thalweg = lines.front().vertices;
    if (ob.thalweg.size() < 2)
      throw InputError("the thalweg needs two or more vertices", src, "observation.thalweg", thalweg);
    for (const Vec2& v : ob.thalweg)
      if (!inside(dsm, v))
        throw InputError("the thalweg leaves the DSM (vertex " + fmt(v.x(), 10) + ", " + fmt(v.y(), 10) + ")", src,
                         "observation.thalweg", thalweg);
  }
  ob.s.resize(cells);
  for (int r = 0; r < ob.grid.ny; ++r)
    for (int c = 0; c < ob.grid.nx; ++c) ob.s[ob.grid.index(c, r)] = along_thalweg(ob.thalweg, ob.grid.centre(c, r));

  if (!fs::exists(footprint)) throw InputError("footprint file not found", src, "observation.footprint", footprint);
  ob.footprint.assign(cells, 0);
  if (is_vector_file(footprint)) {
    const auto polys = read_polygons(footprint, "", dsm.crs_wkt);
    for (const auto& poly : polys)
      for (const Vec2& v : poly.outer)
        if (!inside(dsm, v))
          throw InputError(
              "the footprint polygon leaves the DSM (vertex " + fmt(v.x(), 10) + ", " + fmt(v.y(), 10) + ")", src,
              "observation.footprint", footprint);
    for (int r = 0; r < ob.grid.ny; ++r)
      for (int c = 0; c < ob.grid.nx; ++c)
        for (const auto& poly : polys)
          if (poly.contains(ob.grid.centre(c, r))) {
            ob.footprint[ob.grid.index(c, r)] = 1;
            break;
          }
  } else {
    const Raster f = read_raster(footprint, CrsPolicy::Any);
    check_same_grid(f, dsm, src, "observation.footprint", footprint);
    for (std::size_t k = 0; k < cells; ++k) ob.footprint[k] = !f.is_nodata(f.data[k]) && f.data[k] > threshold;
  }
  for (std::size_t k = 0; k < cells; ++k)
    if (dsm.is_nodata(dsm.data[k])) ob.footprint[k] = 0;
  if (ob.footprint_area() <= 0.0)
    throw InputError("the observed footprint covers no DSM cell (outside the DSM?)", src, "observation.footprint",
                     footprint);
  if (!deposit.empty()) {
    if (!fs::exists(deposit)) throw InputError("deposit raster not found", src, "observation.deposit", deposit);
    const Raster d = read_raster(deposit, CrsPolicy::Any);
    check_same_grid(d, dsm, src, "observation.deposit", deposit);
    ob.deposit.assign(cells, 0.0);
    for (std::size_t k = 0; k < cells; ++k)
      ob.deposit[k] = d.is_nodata(d.data[k]) || !std::isfinite(d.data[k]) ? 0.0 : std::max(0.0, d.data[k]);
  }
  observed_runout(ob, dsm, point, line, src);
  return s;
}

}  // namespace geohaz::runout
