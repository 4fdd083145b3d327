// The sph-slope configuration keys: declared once here (unit, default, range, help), read into
// RunConfig. Defaults come from the structs (solver.hpp, constitutive.hpp, config.hpp) where they have one.
#include "geohaz/sph/config.hpp"

#include <cmath>
#include <filesystem>
#include <memory>
#include <numbers>
#include <string>
#include <utility>
#include <variant>
#include <vector>

#include "geohaz/core/config.hpp"
#include "geohaz/core/errors.hpp"
#include "geohaz/core/raster.hpp"
#include "geohaz/core/resources.hpp"

namespace geohaz::sph {

namespace {

constexpr double kDeg = std::numbers::pi / 180.0;

WallType wall(ConfigReader& r, const char* key, const char* def) {
  const auto s =
      r.get_choice(key, def, {"fixed", "roller", "none"},
                   {"", "boundary condition of this wall: fixed (full fixity, no slip), roller (free slip), none"});
  return s == "fixed" ? WallType::Fixed : (s == "roller" ? WallType::Roller : WallType::None);
}

/// [run] and [strength_reduction]: dimension, scenario, analysis, times, restart.
void read_run(ConfigReader& r, RunConfig& c) {
  // [run]
  c.dimension = static_cast<int>(
      r.get_int("run.dimension", c.dimension, Range::closed(2, 3), {"1", "2 (plane strain) or 3", "dimension"}));
  const auto sc = r.get_choice("run.scenario", "slope", {"slope", "column", "biaxial", "section", "block"},
                               {"",
                                "scenario type: parametric slope, granular column collapse, biaxial specimen, "
                                "DSM cross-section, block (a rectangle of soil, e.g. an elastic beam with "
                                "clamp.boxes)",
                                "scenario"});
  c.scenario = sc == "slope"     ? ScenarioType::Slope
               : sc == "column"  ? ScenarioType::Column
               : sc == "biaxial" ? ScenarioType::Biaxial
               : sc == "block"   ? ScenarioType::Block
                                 : ScenarioType::Section;
  const auto analysis =
      r.get_choice("run.analysis", "dynamic", {"dynamic", "strength_reduction", "limit_equilibrium"},
                   {"",
                    "dynamic: the main phase in time; strength_reduction: the factor of safety by "
                    "strength reduction from the geostatic state, with Bishop's factor beside it "
                    "([strength_reduction]); limit_equilibrium: Bishop's method only (2D slope), with "
                    "[water] and [seismic], the yield coefficient k_y and, with an [earthquake], the Newmark "
                    "displacement",
                    "analysis"});
  c.analysis = analysis == "dynamic"              ? Analysis::Dynamic
               : analysis == "strength_reduction" ? Analysis::StrengthReduction
                                                  : Analysis::LimitEquilibrium;
  {  // read whatever the analysis, so that --set run.analysis=... works on any config
    const StrengthReductionSettings d;
    auto& q = c.srm;
    q.f_min =
        r.get("strength_reduction.f_min", d.f_min, Range::positive(), {"1", "lower end of the initial F bracket"});
    q.f_max = r.get("strength_reduction.f_max", d.f_max, Range::positive(),
                    {"1", "upper end of the initial F bracket (> f_min)"});
    q.tolerance = r.get(
        "strength_reduction.tolerance", d.tolerance, Range::positive(),
        {"1", "bisection stops when the bracket of F is narrower than this", "strength reduction: bracket tolerance"});
    q.damping = r.get(
        "strength_reduction.damping", d.damping, Range::closed_open(0.0, 1.0),
        {"1", "Cundall local damping zeta of the quasi-static trials", "strength reduction: damping of the trials"});
    q.trial_duration =
        r.get("strength_reduction.trial_duration", d.trial_duration, Range::non_negative(),
              {"s", "simulated time of each trial (0: 30 H / c_p)", "strength reduction: duration of a trial"});
    q.knee_ratio = r.get("strength_reduction.knee_ratio", d.knee_ratio, Range::open_closed(1.0, 1e6),
                         {"1",
                          "a trial fails when its largest displacement exceeds this multiple of that of the "
                          "f_min trial (the knee of the F-displacement curve)",
                          "strength reduction: knee ratio"});
    q.growth_ratio = r.get("strength_reduction.growth_ratio", d.growth_ratio, Range::open_closed(0.0, 1.0),
                           {"1",
                            "a trial fails when its largest displacement grew by more than this fraction of its "
                            "final value over the last quarter of the trial",
                            "strength reduction: displacement growth ratio of failure"});
  }
  c.end_time = r.get("run.end_time", c.end_time, Range::positive(), {"s", "simulated time of the main phase"});
  c.output_interval = r.get("run.output_interval", c.output_interval, Range::positive(), {"s", "time-series interval"});
  c.snapshot_interval = r.get("run.snapshot_interval", c.snapshot_interval, Range::non_negative(),
                              {"s", "HDF5 snapshot interval (0: first and last only)"});
  c.velocity_png_times = r.get_array("run.velocity_png_times", {}, Range::non_negative(),
                                     {"s", "times of quick-look PNGs of the speed field"});
  c.rest_speed = r.get("run.rest_speed", c.rest_speed, Range::positive(),
                       {"m/s", "max speed below which the mass is at rest", "at rest below the speed"});
  c.stop_at_rest =
      r.get_bool("run.stop_at_rest", c.stop_at_rest,
                 {"", "stop when max speed < rest_speed (after max(0.05 s, end_time/10) and any shaking)"});
  const auto restart = r.get_string("run.restart", "",
                                    {"",
                                     "snapshot file (snapshots.h5) to restart from; "
                                     "skips the geostatic phase",
                                     "restarted from"});
  if (!restart.empty())
    c.restart = std::filesystem::path(restart).is_absolute() ? std::filesystem::path(restart) : r.base_dir() / restart;
}

/// [model] and [[material]].
void read_model_and_materials(ConfigReader& r, RunConfig& c) {
  // [model]
  {  // the choices and their sentences come from the one name table (constitutive.hpp)
    const auto model = r.get_choice("model.constitutive", std::string(constitutive_model_name(c.model)),
                                    ConstitutiveModelNames::choices(),
                                    {"", ConstitutiveModelNames::help("constitutive model of all soil materials")});
    c.model = *constitutive_model_from_name(model);  // get_choice has checked the name
  }
  const auto fit = r.get_choice(
      "model.dp_fit", "auto", {"auto", "plane_strain_flow_rule", "plane_strain", "compression_3d"},
      {"",
       "Drucker-Prager constants from (cohesion, friction, dilatancy): plane_strain_flow_rule = plane strain "
       "matched to Mohr-Coulomb for the flow rule in use (alpha = sin(phi)/3, k = c cos(phi) for dilatancy 0; "
       "equal to plane_strain for dilatancy = friction; docs/sph.md); plane_strain = Bui et al. 2010, eqs. "
       "18-19 (matches Mohr-Coulomb in plane strain for associated flow only); compression_3d = SPH-slope "
       "paper 2020, eq. 21; auto = plane_strain_flow_rule in 2D, compression_3d in 3D"});
  const DruckerPragerFit dpfit = fit == "plane_strain"             ? DruckerPragerFit::PlaneStrain
                                 : fit == "plane_strain_flow_rule" ? DruckerPragerFit::PlaneStrainFlowRule
                                 : fit == "compression_3d"         ? DruckerPragerFit::Compression3D
                                                           : (c.dimension == 2 ? DruckerPragerFit::PlaneStrainFlowRule
                                                                               : DruckerPragerFit::Compression3D);
  // [[material]]
  auto mats = r.tables("material", {"", "soil materials, indexed from 0 in order (base layer first)"});
  for (auto& m : mats) {
    MaterialParams p;  // defaults from the struct (constitutive.hpp), except the friction angle below
    c.material_names.push_back(m.get_string("name", "soil", {"", "label"}));
    // Bounded to real materials: the time step scales with √(ρ/E), so a density of a few kg/m³
    // (a slip of the unit) would make a run of seconds take hours (fuzz case 116).
    p.density = m.get("density", p.density, Range::closed(100.0, 30000.0),
                      {"kg/m^3", "density rho0 (soils 1500-2300, water 1000, rock 2500-3000)"});
    p.young = m.get("young", p.young, Range::positive(), {"Pa", "Young's modulus E"});
    p.poisson = m.get("poisson", p.poisson, Range::closed_open(0.0, 0.5), {"1", "Poisson's ratio"});
    // The models' own keys (constitutive.hpp, `parameters`): every model's keys are read (so
    // --help-config and the resolved config list them); a key of a model that is not chosen is
    // refused (exit 2), as in the runout and DEM families. The other models' values are their
    // defaults (the shared keys: the values read); they land in p and pass their rules as before.
    const auto all = ConstitutiveModelParameters::read_all(
        m, {"", "model.constitutive", "set model.constitutive", true, "material."}, constitutive_model_name(c.model));
    for (const std::string_view name : ConstitutiveModelNames::names) {
      const ParamValues v = ConstitutiveModelParameters::values_of(all, name);
      ConstitutiveModelParameters::check(name, v, r.source(), "material.");
      set_model_parameters(*constitutive_model_from_name(name), p, v);
    }
    p.fit = dpfit;
    const double sat = m.get("saturated_density", 0.0, Range::closed(0.0, 30000.0),
                             {"kg/m^3",
                              "density below the phreatic surface ([water]; 0: density); at least density "
                              "(limit-equilibrium analysis)"});
    if (sat > 0.0 && sat < p.density)
      throw InputError("must not be below the material's density (" + std::to_string(p.density) + " kg/m^3)",
                       r.source(), "material.saturated_density", std::to_string(sat));
    c.saturated_densities.push_back(sat);
    c.materials.push_back(p);
  }
}

/// [numerics]: defaults from NumericalSettings (solver.hpp).
void read_numerics(ConfigReader& r, RunConfig& c) {
  // [numerics]
  auto& n = c.numerics;
  const NumericalSettings d;  // the defaults (solver.hpp)
  n.spacing =
      r.get("numerics.spacing", d.spacing, Range::positive(), {"m", "initial particle spacing dx", "particle spacing"});
  n.h_factor =
      r.get("numerics.h_factor", d.h_factor, Range::closed(1.0, 2.0), {"1", "smoothing length h = h_factor dx"});
  {  // from the kernels' name table (solver.hpp)
    std::vector<std::string> names;
    std::string def;
    for (const auto& [name, k] : kernel_names) {
      names.emplace_back(name);
      if (k == d.kernel) def = name;
    }
    const auto kernel = r.get_choice("numerics.kernel", def, names, {"", "SPH kernel"});
    for (const auto& [name, k] : kernel_names)
      if (name == kernel) n.kernel = k;
  }
  n.gravity = r.get("numerics.gravity", d.gravity, Range::non_negative(), {"m/s^2", "gravitational acceleration"});
  n.cfl = r.get("numerics.cfl", d.cfl, Range::open_closed(0.0, 1.0), {"1", "CFL number on (c_p + |v|max)"});
  n.force_factor =
      r.get("numerics.force_factor", d.force_factor, Range::open_closed(0.0, 1.0), {"1", "dt <= f sqrt(h/|a|max)"});
  n.dt_max = r.get("numerics.dt_max", d.dt_max, Range::positive(), {"s", "largest time step"});
  n.dt_min = r.get("numerics.dt_min", d.dt_min, Range::positive(), {"s", "a smaller step stops the run (collapse)"});
  n.viscosity_alpha = r.get("numerics.viscosity_alpha", d.viscosity_alpha, Range::non_negative(),
                            {"1", "Monaghan artificial viscosity alpha"});
  n.viscosity_beta = r.get("numerics.viscosity_beta", d.viscosity_beta, Range::non_negative(),
                           {"1", "Monaghan artificial viscosity beta"});
  n.artificial_stress = r.get("numerics.artificial_stress", d.artificial_stress, Range::closed(0.0, 1.0),
                              {"1", "Gray-Monaghan artificial stress epsilon (0: off)"});
  n.artificial_stress_n = r.get("numerics.artificial_stress_n", d.artificial_stress_n, Range::non_negative(),
                                {"1", "artificial-stress exponent n (0: W(0)/W(dx))"});
  n.xsph = r.get("numerics.xsph", d.xsph, Range::closed(0.0, 1.0),
                 {"1", "XSPH velocity-correction factor epsilon (SWJTU lecture 2010)"});
  n.damping = r.get("numerics.damping", d.damping, Range::closed_open(0.0, 1.0),
                    {"1", "Cundall local damping zeta in the main phase (Bui et al. 2010 uses 0.2 under shaking)"});
  n.stress_free_fraction = r.get("numerics.stress_free_fraction", d.stress_free_fraction, Range::closed_open(0.0, 1.0),
                                 {"1", "stress vanishes where the kernel-sum density < fraction rho0 (0: off)"});
  if (r.has("numerics.reorder_every"))  // counted steps until Dec 2026; now list rebuilds, as in every model
    throw InputError("renamed to numerics.reorder_every_rebuilds (it counts neighbour-list rebuilds, not steps)",
                     r.source(), "numerics.reorder_every");
  n.reorder_every = static_cast<int>(
      r.get_int("numerics.reorder_every_rebuilds", d.reorder_every, Range::closed(0, 1e6),
                {"1", "sort the particles by cell at every N-th neighbour-list rebuild (memory locality; 0: never)"}));
  n.wall_repulsion = r.get("numerics.wall_repulsion", d.wall_repulsion, Range::closed(0.0, 1.0),
                           {"1", "soil closer than this x dx to a wall particle is pushed back (0: off)"});
  {  // auto: the solver's default (off) except for linear_elastic, where it was validated (docs/sph.md)
    const auto kc = r.get_choice(
        "numerics.kernel_correction", "auto", {"auto", "on", "off", "quadratic"},
        {"",
         "consistent kernel gradients in the strain-rate and momentum sums: on = exact for linear fields "
         "(Bonet & Lok 1999), quadratic = also for quadratic fields at free surfaces (bending; unstable at "
         "fine resolution without a cure, docs/validation/sph.md), auto = on for model.constitutive = "
         "linear_elastic, off for the other models"});
    n.kernel_correction = kc == "on" || kc == "quadratic" ||
                          (kc == "auto" && (d.kernel_correction || std::holds_alternative<LinearElastic>(c.model)));
    n.quadratic_correction = kc == "quadratic";
  }
  {  // total_lagrangian: elastic bodies only (the solver checks the particles: no walls, no periodic axes)
    const auto f = r.get_choice(
        "numerics.formulation", "updated_lagrangian", {"updated_lagrangian", "total_lagrangian"},
        {"",
         "updated_lagrangian = the SPH solver for flow and failure (neighbours and gradients in the current "
         "configuration); total_lagrangian = for elastic bodies in small-to-moderate deformation (beams, piles): "
         "gradients in the configuration at the start of the main phase, St Venant-Kirchhoff stress, "
         "hourglass control (docs/sph.md); needs model.constitutive = linear_elastic, no walls, no geostatic "
         "phase"});
    n.total_lagrangian = f == "total_lagrangian";
    if (n.total_lagrangian && !std::holds_alternative<LinearElastic>(c.model))
      throw InputError("total_lagrangian is only for elastic bodies: it needs model.constitutive = linear_elastic",
                       r.source(), "numerics.formulation", f);
  }
  n.hourglass = r.get("numerics.hourglass", d.hourglass, Range::closed(0.0, 100.0),
                      {"1",
                       "hourglass-control coefficient alpha of the total-Lagrangian formulation (Ganzenmueller "
                       "2015; 0: off; its stiffness is in the time step; at most 1 with kernel_correction = "
                       "quadratic, where a larger one drives a growing mode, docs/sph.md); unused by "
                       "updated_lagrangian"});
  if (n.total_lagrangian && n.quadratic_correction && n.hourglass > 1.0)
    throw InputError(
        "must be at most 1 with numerics.kernel_correction = quadratic (a larger hourglass force "
        "drives a growing mode with the quadratic-complete gradient, docs/sph.md)",
        r.source(), "numerics.hourglass", std::to_string(n.hourglass));
  n.neighbour_skin = r.get("numerics.neighbour_skin", d.neighbour_skin, Range::closed(0.0, 1.0),
                           {"1", "Verlet skin in units of h (0: rebuild the neighbour list every step)"});
}

/// [geostatic] and [earthquake] (an accelerogram file is read here).
void read_geostatic_and_earthquake(ConfigReader& r, RunConfig& c) {
  auto& n = c.numerics;
  // [geostatic]
  c.geostatic = r.get_bool("geostatic.enabled", c.geostatic, {"", "apply gravity gradually before the main phase"});
  c.geostatic_duration = r.get("geostatic.duration", c.geostatic_duration, Range::non_negative(),
                               {"s", "0: 20 H / c_p", "geostatic phase: duration"});
  c.geostatic_damping = r.get("geostatic.damping", c.geostatic_damping, Range::closed_open(0.0, 1.0),
                              {"1", "Cundall zeta while loading"});
  c.geostatic_elastic = r.get_bool("geostatic.elastic", c.geostatic_elastic, {"", "linear-elastic soil while loading"});
  if (c.geostatic && n.total_lagrangian)
    throw InputError(
        "total_lagrangian takes no geostatic phase (its reference configuration is the start of the "
        "main phase): set geostatic.enabled = false and load with numerics.gravity and numerics.damping",
        r.source(), "numerics.formulation", "total_lagrangian");
  c.rest_tolerance =
      r.get("geostatic.rest_tolerance", c.rest_tolerance, Range::positive(), {"1", "at rest: max|v| < tol sqrt(g H)"});

  // [earthquake]
  const auto eq = r.get_choice("earthquake.type", "none", {"none", "sine", "record"},
                               {"", "earthquake acceleration applied to every particle (Bui et al. 2010, eqs. 25-26)"});
  {  // all keys are read whatever the type, so that --set earthquake.type=none works on any config
    const double A =
        r.get("earthquake.amplitude", 5.0, Range::non_negative(), {"m/s^2", "sine amplitude (500 gal = 5)"});
    const double f = r.get("earthquake.frequency", 1.0, Range::positive(), {"Hz", "sine frequency"});
    const double t0 = r.get("earthquake.start", 0.0, Range::non_negative(), {"s", "start time"});
    const double d = r.get("earthquake.duration", 5.0, Range::positive(), {"s", "duration"});
    const double ramp = r.get("earthquake.ramp", 0.5, Range::non_negative(), {"s", "linear ramp at both ends"});
    if (eq == "sine") n.earthquake = EarthquakeLoading::sine(A, f, t0, d, ramp);
  }
  {
    const auto file =
        r.get_string("earthquake.file", "", {"", "CSV accelerogram: time (s), a_h (m/s^2), optional a_v (m/s^2)"});
    if (eq == "record") {
      if (file.empty())
        throw InputError("earthquake.type = record needs earthquake.file", r.source(), "earthquake.file");
      const auto p = std::filesystem::path(file).is_absolute() ? std::filesystem::path(file) : r.base_dir() / file;
      n.earthquake = EarthquakeLoading::read_csv(p);
    }
  }
}

/// [output].
/// [water], [rain], [hydrology] and [seismic]: the pore water, the rain and the pseudo-static
/// coefficients (docs/sph.md, "Pore pressure and seismic coefficients").
void read_water_and_seismic(ConfigReader& r, RunConfig& c) {
  auto& w = c.water;
  const auto line = r.get_array("water.phreatic", {}, {},
                                {"m",
                                 "phreatic surface x0, z0, x1, z1, ... (x non-decreasing, level beyond the ends); "
                                 "u = water density g h_w below it; empty: none",
                                 "phreatic surface (x, z)"});
  if (line.size() % 2 || line.size() == 2)
    throw InputError("needs pairs x, z of at least two points", r.source(), "water.phreatic",
                     std::to_string(line.size()) + " numbers");
  for (std::size_t k = 0; k + 1 < line.size(); k += 2) w.phreatic.push_back({line[k], line[k + 1]});
  w.ru = r.get("water.ru", w.ru, Range::closed_open(0.0, 1.0),
               {"1",
                "pore-pressure ratio r_u = u / (gamma h): u = r_u times the vertical overburden stress on Bishop's "
                "slice bases and at every SPH particle (slope, DSM section: the column of its cover and base; 2D "
                "and 3D; not with water.phreatic)",
                "pore pressure ratio r_u"});
  const double rho_w = r.get("water.density", 1000.0, Range::closed(900.0, 1300.0), {"kg/m^3", "density of water"});
  w.unit_weight = rho_w * c.numerics.gravity;
  w.head_loss_correction =
      r.get_choice("water.pore_pressure", "vertical_head", {"vertical_head", "head_loss_corrected"},
                   {"",
                    "vertical_head: u = gamma_w h_w (h_w the depth below the phreatic surface, hydrostatic); "
                    "head_loss_corrected: u = gamma_w h_w cos^2(theta), theta the phreatic surface's inclination "
                    "(steady seepage parallel to it; Slide's automatic H_u)",
                    "pore pressure"}) == "head_loss_corrected";
  c.water_history_times =
      r.get_array("water.history_times", {}, Range::non_negative(),
                  {"s", "main-phase times of the water-table history (increasing; SPH runs with water.phreatic)",
                   "water level history: times"});
  c.water_history_offsets =
      r.get_array("water.history_offsets", {}, {},
                  {"m", "rise of the phreatic surface at those times (linear between, held after; + up)",
                   "water level history: rise of the phreatic surface"});
  {
    const auto table = r.get_string("water.table_raster", "",
                                    {"",
                                     "raster of the water table's elevation (m) in the DSM's CRS: a DSM section's "
                                     "phreatic surface, cut along the section (2D) or sampled over the strip (3D); "
                                     "clipped to the ground; not with water.phreatic, water.ru or rain",
                                     "water-table raster"});
    if (!table.empty())
      c.water_table_raster = std::filesystem::path(table).is_absolute() ? table : (r.base_dir() / table).string();
    const auto pore = r.get_string(
        "water.pore_pressure_raster", c.pore_pressure_raster,
        {"",
         "raster of the pore pressure u_b (Pa) at the base of a DSM section's soil cover (section.soil_thickness "
         "below the ground; e.g. gamma_w times a pressure head of slope-stability) in the DSM's CRS: the "
         "piezometric level z_g - D + u_b / (rho_w g) above and below (hydrostatic in the vertical), clipped to "
         "the ground; not with another source of pore water",
         "pore-pressure raster (at the base of the cover)"});
    if (!pore.empty())
      c.pore_pressure_raster = std::filesystem::path(pore).is_absolute() ? pore : (r.base_dir() / pore).string();
  }
  // [rain] and [hydrology]: the keys and reader of slope-stability (infiltration.hpp), here a loading history.
  c.rain.enabled = r.get_bool("rain.enabled", c.rain.enabled,
                              {"",
                               "rain infiltration (Iverson 2000, as slope-stability: [rain], [hydrology]) as the "
                               "pore pressure: over time in a dynamic run, at rain.evaluate_at in the strength "
                               "reduction and limit equilibrium (slope, DSM section; 2D and 3D; not with "
                               "water.phreatic or water.ru)"});
  c.rain.infiltration = read_infiltration_keys(r);
  c.rain.evaluate_at = c.rain.infiltration.rain.end();
  c.rain.evaluate_at = r.get("rain.evaluate_at", c.rain.evaluate_at, Range::non_negative(),
                             {"s",
                              "the rain's time t_rain whose pore pressure the strength reduction and the "
                              "limit-equilibrium analysis take (a dynamic run follows rain.clock_times); default: "
                              "the end of the rain",
                              "rain time of the pore pressure (strength reduction, limit equilibrium)"});
  const auto clock = r.get_array("rain.clock_times", {}, Range::non_negative(),
                                 {"s",
                                  "the rain's clock: pairs t, t_rain of main-phase time t and the rain's time t_rain "
                                  "there, linear between, held beyond (e.g. [0, 0, 10, 86400]: a day of rain in 10 s "
                                  "of SPH); empty: t_rain = t",
                                  "rain: clock (run time, rain time) pairs"});
  if (clock.size() % 2 || clock.size() == 2)
    throw InputError("needs pairs t, t_rain of at least two points", r.source(), "rain.clock_times",
                     std::to_string(clock.size()) + " numbers");
  for (std::size_t k = 0; k + 1 < clock.size(); k += 2) {
    if (k > 0 && !(clock[k] > clock[k - 2]))
      throw InputError("the main-phase times t must increase", r.source(), "rain.clock_times",
                       std::to_string(clock[k]));
    if (k > 0 && clock[k + 1] < clock[k - 1])
      throw InputError("the rain's times t_rain must not decrease", r.source(), "rain.clock_times",
                       std::to_string(clock[k + 1]));
    c.rain.clock.push_back({clock[k], clock[k + 1]});
  }
  c.seismic.kh = r.get("seismic.kh", c.seismic.kh, Range::closed_open(0.0, 1.0),
                       {"1",
                        "horizontal pseudo-static coefficient: a force k_h W in the direction of sliding "
                        "(limit-equilibrium analysis and strength-reduction trials)",
                        "horizontal seismic coefficient k_h"});
  c.seismic.kv = r.get("seismic.kv", c.seismic.kv, Range::closed(-0.5, 0.5),
                       {"1", "vertical pseudo-static coefficient, positive upward: the weight becomes (1 - k_v) W",
                        "vertical seismic coefficient k_v"});
}

void read_output(ConfigReader& r, RunConfig& c) {
  // [output]
  c.failed_threshold = r.get("output.failed_threshold", c.failed_threshold, Range::positive(),
                             {"m", "displacement above which soil counts as failed (failed mass, slip surface)",
                              "failed above the displacement"});
  c.front_thickness =
      r.get("output.front_thickness", c.front_thickness, Range::non_negative(),
            {"m", "deposit thickness that defines the front (0: 2 spacings); fix it to compare resolutions",
             "front thickness"});
  c.bulking_factor =
      r.get("output.bulking_factor", c.bulking_factor, Range::closed(1.0, 3.0), {"1", "volume factor for release.h5"});
  c.write_release = r.get_bool("output.release", c.write_release,
                               {"", "section scenario: write release.h5 and release_thickness.tif"});
  c.structure_forces =
      r.get_bool("output.structure_forces", c.structure_forces,
                 {"",
                  "sum the force the soil exerts on each wall and pile: structure_forces.csv (N/m and N m/m per unit "
                  "thickness in 2D, N and N m in 3D), peaks in summary.json, structure_forces.png"});
  {
    const auto names = r.get_string("output.structures", "",
                                    {"",
                                     "comma-separated names of the structures to report (empty: all): bottom or "
                                     "bedrock, left_wall, right_wall, side_y0, side_y1 (3D roller sides), pile_1, "
                                     "pile_2, ... (3D pile row), bottom_platen, top_platen (biaxial)"});
    std::size_t a = 0;
    while (a <= names.size()) {
      std::size_t e = names.find(',', a);
      if (e == std::string::npos) e = names.size();
      std::string n = names.substr(a, e - a);
      n.erase(0, n.find_first_not_of(" \t"));
      n.erase(n.find_last_not_of(" \t") + 1);
      if (!n.empty()) c.structures.push_back(n);
      a = e + 1;
    }
  }
}

/// Geometry of the chosen scenario (every scenario's keys in describe mode): [slope], [piles],
/// [column], [biaxial], [geometry].
void read_geometry(ConfigReader& r, RunConfig& c, bool describe) {
  // Geometry of the chosen scenario.
  const bool is3d = c.dimension == 3;
  if (c.scenario == ScenarioType::Slope || describe) {
    auto& g = c.slope;
    g.height = r.get("slope.height", g.height, Range::positive(), {"m", "slope height above the base"});
    g.gradient = r.get("slope.gradient", g.gradient, Range::non_negative(), {"1", "face gradient H:V (1.5 = 1.5H:1V)"});
    g.crest_length =
        r.get("slope.crest_length", g.crest_length, Range::non_negative(), {"m", "flat crest behind the face"});
    g.front_length =
        r.get("slope.front_length", g.front_length, Range::non_negative(), {"m", "flat ground in front of the toe"});
    g.base_thickness = r.get("slope.base_thickness", g.base_thickness, Range::non_negative(),
                             {"m", "soil base under everything (at most 10 slope heights)"});
    // A deeper base does not change a slope's mechanism (Taylor's 1937 chart reaches a depth factor
    // of 4, beyond which it is the infinitely deep case) but multiplies the particle count: fuzz
    // case 119 (base 50 m under a 0.25 m slope at 1 cm spacing) asked for 640,000 particles.
    if (!describe && g.base_thickness > 10.0 * g.height)
      throw InputError("must be at most 10 slope heights (10 x slope.height = " + std::to_string(10.0 * g.height) +
                           " m): a deeper base does not change the slope's mechanism",
                       r.source(), "slope.base_thickness", std::to_string(g.base_thickness));
    g.cut_depth = r.get("slope.cut_depth", g.cut_depth, Range::non_negative(),
                        {"m", "upper cut: depth below the crest (0: none)"});
    g.cut_gradient = r.get("slope.cut_gradient", g.cut_gradient, Range::positive(), {"1", "upper cut gradient H:V"});
    c.layer_tops =
        r.get_array("slope.layer_tops", {}, Range::non_negative(), {"m", "layer tops (elevations, ascending)"});
    const auto lm = r.get_array("slope.layer_materials", {}, Range::closed(0, 1000),
                                {"1", "material index per layer, bottom first (one more than layer_tops)"});
    for (double v : lm) c.layer_materials.push_back(static_cast<int>(v));
    c.piles.enabled = r.get_bool("piles.enabled", c.piles.enabled, {"", "a row of rigid piles across the width (3D)"});
    {  // read even when disabled, so that --set piles.enabled=false works on a config with piles
      const auto pos = r.get_choice("piles.position", "middle", {"lower", "middle", "upper"},
                                    {"", "row position on the face: lower 1/4, middle 1/2, upper 3/4 of the face"});
      c.piles.position = pos == "lower" ? 0.25 : (pos == "middle" ? 0.5 : 0.75);
      c.piles.diameter = r.get("piles.diameter", c.piles.diameter, Range::positive(), {"m", "pile diameter"});
      c.piles.spacing =
          r.get("piles.spacing", c.piles.spacing, Range::positive(), {"m", "centre spacing across the width"});
    }
  }
  if (c.scenario == ScenarioType::Column || describe) {
    c.column_width =
        r.get("column.width", c.column_width, Range::positive(), {"m", "column width L0 (against the left wall)"});
    c.column_height =
        r.get("column.height", c.column_height, Range::positive(), {"m", "column height H0 (aspect ratio a = H0/L0)"});
    c.floor_length = r.get("column.floor_length", c.floor_length, Range::positive(), {"m", "floor beyond the column"});
  }
  if (c.scenario == ScenarioType::Biaxial || describe) {
    c.biaxial.width = r.get("biaxial.width", c.biaxial.width, Range::positive(), {"m", "specimen width"});
    c.biaxial.height = r.get("biaxial.height", c.biaxial.height, Range::positive(), {"m", "specimen height"});
    c.biaxial_strain_rate = r.get("biaxial.strain_rate", c.biaxial_strain_rate, {},
                                  {"1/s", "axial strain rate (> 0 compression, < 0 tension)"});
    if (!describe && c.biaxial_strain_rate == 0.0)
      throw InputError("must be non-zero", r.source(), "biaxial.strain_rate", "0");
    // An element test needs a specimen of element shape (height/width 2 is usual); a slender column
    // buckles instead of shearing (fuzz case 151: a 100 m × 5 cm specimen, 1.25 million particles).
    if (!describe && !(c.biaxial.height >= 0.5 * c.biaxial.width && c.biaxial.height <= 4.0 * c.biaxial.width))
      throw InputError("the specimen's height/width must be in [0.5, 4] (2 is usual for a biaxial test)", r.source(),
                       "biaxial.height",
                       std::to_string(c.biaxial.height) + " with biaxial.width " + std::to_string(c.biaxial.width));
  }
  if (is3d || describe) {
    c.width = r.get("geometry.width", c.width, Range::positive(),
                    {"m", "3D width (axis y); a 3D DSM section: the strip width, centred on the polyline"});
    c.periodic_width = r.get_bool(
        "geometry.periodic", c.scenario != ScenarioType::Section,
        {"", "3D: periodic across the width (SPH-slope paper 2020), else roller walls (default for a DSM section)"});
  }
}

/// [walls], [block], [clamp] and [initial_velocity].
void read_walls_clamp_and_initial_velocity(ConfigReader& r, RunConfig& c, bool describe) {
  const bool block = c.scenario == ScenarioType::Block;
  const char* left_default = block ? "none" : "fixed";
  const char* right_default = c.scenario == ScenarioType::Column || block ? "none" : "fixed";
  c.left_wall = wall(r, "walls.left", left_default);
  c.right_wall = wall(r, "walls.right", right_default);
  c.bottom_wall = wall(r, "walls.bottom", block ? "none" : "fixed");
  if (block || describe) {
    c.block_length = r.get("block.length", c.block_length, Range::positive(), {"m", "block scenario: length along x"});
    c.block_height = r.get("block.height", c.block_height, Range::positive(), {"m", "block scenario: height along z"});
  }
  // [clamp] and [initial_velocity]: any scenario.
  c.clamp_boxes = r.get_array("clamp.boxes", {}, {},
                              {"m",
                               "clamped regions, 2*dimension numbers per box: x_lo, [y_lo,] z_lo, x_hi, [y_hi,] "
                               "z_hi; soil particles inside are held at rest in place (each box must hold soil)"});
  {
    auto& iv = c.initial_velocity;
    const auto type = r.get_choice("initial_velocity.type", "none", {"none", "uniform", "cantilever_mode"},
                                   {"",
                                    "velocity of the soil at the start of the main phase: none, uniform "
                                    "(initial_velocity.value) or cantilever_mode (v_z = amplitude phi1((x - root)/"
                                    "length), the first bending mode of a clamped-free beam, 1 at the free end)"});
    iv.type = type == "uniform"           ? InitialVelocity::Type::Uniform
              : type == "cantilever_mode" ? InitialVelocity::Type::CantileverMode
                                          : InitialVelocity::Type::None;
    iv.value = r.get_array("initial_velocity.value", {}, {}, {"m/s", "uniform: one component per axis"});
    iv.amplitude =
        r.get("initial_velocity.amplitude", iv.amplitude, {}, {"m/s", "cantilever_mode: v_z at the free end"});
    iv.root = r.get("initial_velocity.root", iv.root, {}, {"m", "cantilever_mode: x of the clamped end"});
    iv.length = r.get("initial_velocity.length", iv.length, Range::positive(), {"m", "cantilever_mode: free length"});
  }
}

/// A raster of a DSM section's pore water (water.table_raster, water.pore_pressure_raster under
/// `key`): readable, in the DSM's CRS.
std::shared_ptr<const Terrain> read_water_raster(const ConfigReader& r, const std::string& path, const Raster& dsm,
                                                 const char* key) {
  Raster t;
  try {
    t = read_raster(path);
  } catch (const InputError& e) {  // name the key the raster comes from
    throw InputError(e.reason() + " (" + path + ")", r.source(), key, path);
  }
  if (!crs_equal(t.crs_wkt, dsm.crs_wkt))
    throw InputError("must be in the DSM's CRS (" + crs_label(dsm.crs_wkt) + "; it is in " + crs_label(t.crs_wkt) + ")",
                     r.source(), key, path);
  try {
    return std::make_shared<const Terrain>(std::move(t));
  } catch (const InputError& e) {
    throw InputError(e.reason() + " (" + path + ")", r.source(), key, path);
  }
}

/// [section]: the DSM is read and the profile extracted here (not in describe mode).
void read_section(ConfigReader& r, RunConfig& c, bool describe) {
  const auto& n = c.numerics;
  if (c.scenario == ScenarioType::Section || describe) {
    const auto dsm = r.get_string("section.dsm", "", {"", "DSM raster (GeoTIFF, projected CRS)"});
    const auto poly = r.get_array("section.polyline", {}, {}, {"m", "x0, y0, x1, y1, ... in the DSM CRS"});
    c.section.soil_thickness = r.get("section.soil_thickness", c.section.soil_thickness, Range::positive(),
                                     {"m", "soil layer thickness below the surface"});
    c.section.bedrock = r.get_choice("section.base", "bedrock", {"bedrock", "fill"},
                                     {"",
                                      "bedrock: soil and base layers follow the surface on fixed bedrock "
                                      "particles; fill: the base fills down to a flat bottom"}) == "bedrock";
    c.section.base_thickness = r.get("section.base_thickness", c.section.base_thickness, Range::positive(),
                                     {"m",
                                      "base layer under the soil (bedrock: parallel to the surface; fill: "
                                      "below the lowest soil)"});
    c.section.soil_material =
        static_cast<int>(r.get_int("section.soil_material", c.section.soil_material, Range::closed(0, 1000),
                                   {"1", "material index of the soil layer"}));
    c.section.base_material = static_cast<int>(r.get_int("section.base_material", c.section.base_material,
                                                         Range::closed(0, 1000), {"1", "material index of the base"}));
    c.section.release_width = r.get("section.release_width", c.section.release_width, Range::positive(),
                                    {"m", "width W over which the plane-strain failed mass is spread for release.h5"});
    if (!describe) {
      if (dsm.empty()) throw InputError("the section scenario needs section.dsm", r.source(), "section.dsm");
      if (poly.size() < 4 || poly.size() % 2)
        throw InputError("needs an even number (>= 4) of coordinates x0, y0, x1, y1, ...", r.source(),
                         "section.polyline");
      const auto path = std::filesystem::path(dsm).is_absolute() ? std::filesystem::path(dsm) : r.base_dir() / dsm;
      auto raster = std::make_shared<Raster>(read_raster(path));
      std::vector<Vec2> line;
      double length = 0.0;
      for (std::size_t k = 0; k < poly.size(); k += 2) {
        line.emplace_back(poly[k], poly[k + 1]);
        if (k > 0) length += (line.back() - line[line.size() - 2]).norm();
      }
      // The profile has one point per spacing: checked before it is sampled (spacing 1e-6 m).
      check_memory(length / n.spacing * sizeof(ProfilePoint),
                   "a profile of " + std::to_string(length) + " m sampled every numerics.spacing", r.source(),
                   "numerics.spacing", std::to_string(n.spacing));
      Terrain terrain(*raster);
      try {
        c.section.profile = extract_profile(terrain, line, n.spacing);
      } catch (const InputError& e) {  // name the DSM and the key the profile comes from
        throw InputError(e.reason() + " (" + path.string() + ")", r.source(), "section.polyline");
      }
      c.section.crs_wkt = raster->crs_wkt;
      c.section.dsm = raster;
      c.section.terrain = std::make_shared<const Terrain>(*raster);
      if (!c.water_table_raster.empty())
        c.section.water_table = read_water_raster(r, c.water_table_raster, *raster, "water.table_raster");
      if (!c.pore_pressure_raster.empty())
        c.section.pore_pressure = read_water_raster(r, c.pore_pressure_raster, *raster, "water.pore_pressure_raster");
    }
  }
}

}  // namespace

RunConfig read_config(ConfigReader& r, bool describe) {
  RunConfig c;
  c.config_source = r.source();
  // The order of the calls is the order of the keys in --help-config and config.resolved.toml.
  read_run(r, c);
  read_model_and_materials(r, c);
  read_numerics(r, c);
  read_geostatic_and_earthquake(r, c);
  read_water_and_seismic(r, c);
  read_output(r, c);
  read_geometry(r, c, describe);
  read_walls_clamp_and_initial_velocity(r, c, describe);
  read_section(r, c, describe);
  return c;
}

}  // namespace geohaz::sph
