// dem-avalanche: bonded-disc DEM (libs/dem, docs/dem.md) — biaxial compression and tension tests of
// a bonded rock sample, and rock avalanches of a bonded, jointed rock mass on a terrain profile.
// This file turns the command line and the TOML config into typed specs, validates everything
// before writing anything, then runs and writes the outputs.
#include <cmath>
#include <fstream>
#include <iomanip>
#include <iostream>
#include <nlohmann/json.hpp>
#include <numbers>
#include <sstream>

#include "geohaz/core/app.hpp"
#include "geohaz/core/config.hpp"
#include "geohaz/core/errors.hpp"
#include "geohaz/core/output.hpp"
#include "geohaz/core/progress.hpp"
#include "geohaz/core/raster.hpp"
#include "geohaz/core/resources.hpp"
#include "geohaz/core/snapshot.hpp"
#include "geohaz/dem/experiments.hpp"
#include "geohaz/dem/output.hpp"
#include "geohaz/dem/tessellation.hpp"

using namespace geohaz;
using namespace geohaz::dem;
using json = nlohmann::json;

namespace {

template <class... F>
struct Overloaded : F... {
  using F::operator()...;
};

enum class TestKind { Compression, Tension, Avalanche };

struct RunConfig {
  TestKind kind = TestKind::Compression;
  std::string source;
  std::string resolved;
  PackingSpec packing;
  MaterialSpec material;
  SolverSettings numerics;
  // lab tests
  LabTestSpec lab;
  std::vector<double> confining;
  // avalanche
  AvalancheSpec avalanche;
  // outputs
  int snapshot_every = 20;  ///< records between snapshots (0: first and last only)
  bool write_tessellation = true;
};

std::vector<Vec2> points(ConfigReader& r, const char* kx, const char* kz, const char* what, bool required,
                         std::size_t min_points) {
  std::vector<double> x, z;
  if (required) {
    x = r.require_array(kx, Range{}, {"m", what});
    z = r.require_array(kz, Range{}, {"m", what});
  } else {
    x = r.get_array(kx, {}, Range{}, {"m", what});
    z = r.get_array(kz, {}, Range{}, {"m", what});
  }
  if (x.size() != z.size())
    throw InputError("must have as many values as " + std::string(kz) + " (" + std::to_string(z.size()) + ")",
                     r.source(), kx, std::to_string(x.size()) + " values");
  if ((required || !x.empty()) && x.size() < min_points)
    throw InputError("needs at least " + std::to_string(min_points) + " points", r.source(), kx,
                     std::to_string(x.size()) + " values");
  std::vector<Vec2> p;
  for (std::size_t k = 0; k < x.size(); ++k) p.emplace_back(x[k], z[k]);
  return p;
}

/// The discs a packing of `area` (m², unit thickness) asks for, checked against the memory available
/// before anything is packed (sample.r_min = 1e-9 m would otherwise end in std::bad_alloc).
void check_disc_memory(double area, const PackingSpec& p, const std::string& source, const std::string& what) {
  const double r = 0.5 * (p.r_min + p.r_max);
  const double discs = (1.0 - p.porosity) * area / (3.141592653589793 * r * r);
  // A lower bound per disc: its fields, a few contacts and bonds, the neighbour cells and the
  // triangulation used to place the bonds.
  const double per_disc = 1000.0;
  std::ostringstream est;
  est << std::setprecision(3) << discs << " discs × " << per_disc << " B for the " << what << " with radii " << p.r_min
      << "–" << p.r_max << " m";
  std::ostringstream value;
  value << p.r_min;
  check_memory(discs * per_disc, est.str(), source, "sample.r_min", value.str());
}

RunConfig read_config(ConfigReader& r, bool describe) {
  RunConfig c;
  c.source = r.source();
  const auto test = r.get_choice("test", "biaxial-compression", {"biaxial-compression", "biaxial-tension", "avalanche"},
                                 {"",
                                  "what to run: biaxial compression at one or more confining stresses, direct "
                                  "(biaxial) tension, or a rock avalanche on a terrain profile"});
  c.kind = test == "biaxial-compression" ? TestKind::Compression
           : test == "biaxial-tension"   ? TestKind::Tension
                                         : TestKind::Avalanche;
  const auto seed = r.get_int("seed", 1, Range::non_negative(), {"1", "random seed of packing, strengths and joints"});

  // [sample]: packing
  PackingSpec& p = c.packing;
  p.seed = static_cast<std::uint64_t>(seed);
  p.width = r.get("sample.width", 0.03, Range::positive(), {"m", "sample width (lab tests)"});
  p.height = r.get("sample.height", 0.06, Range::positive(), {"m", "sample height (lab tests)"});
  p.r_min = r.get("sample.r_min", 0.8e-3, Range::positive(), {"m", "smallest disc radius"});
  p.r_max = r.get("sample.r_max", 1.66 * 0.8e-3, Range::positive(),
                  {"m", "largest disc radius (R_max/R_min = 1.66 in Potyondy & Cundall 2004)"});
  p.porosity =
      r.get("sample.porosity", 0.18, Range::closed(0.1, 0.4), {"1", "target porosity of the radius expansion"});
  p.locked_in_stress = r.get("sample.locked_in_stress", 1e6, Range::non_negative(),
                             {"Pa", "isotropic stress installed by servo walls before bonding (0: none)"});
  p.expansion_steps = static_cast<int>(
      r.get_int("sample.expansion_steps", 2000, Range::closed(10, 1e7), {"1", "radius-expansion steps"}));
  p.max_relax_steps = static_cast<int>(
      r.get_int("sample.relax_steps", 6000, Range::closed(100, 1e8), {"1", "cap on each packing equilibrium stage"}));
  if (!describe && p.r_max < p.r_min)
    throw InputError("must be ≥ sample.r_min (" + std::to_string(p.r_min) + " m)", r.source(), "sample.r_max",
                     std::to_string(p.r_max));

  // [material]
  MaterialSpec& m = c.material;
  p.density = m.density =
      r.get("material.density", m.density, Range::positive(), {"kg/m^3", "disc density (discs are 1 m thick)"});
  {  // the choices and their sentences come from the one name table (contact_laws.hpp)
    std::vector<std::string> names;
    std::string help = "contact law:";
    for (std::size_t k = 0; k < contact_law_names.size(); ++k) {
      names.emplace_back(contact_law_names[k]);
      help += (k ? "; " : " ") + names.back() + " = " + std::string(contact_law_summaries[k]);
    }
    m.law = *contact_law_from_name(r.get_choice("material.contact_law", "linear", names, {"", help}));
  }
  const double Ec = r.get("material.contact_modulus", 20e9, Range::positive(),
                          {"Pa", "linear law: contact modulus E_c, k_n = 2 E_c (PFC2D, unit thickness)"});
  const double kratio = r.get("material.stiffness_ratio", 2.5, Range::positive(), {"1", "linear law: k_n/k_s"});
  const double E =
      r.get("material.youngs_modulus", 20e9, Range::positive(), {"Pa", "Hertz-Mindlin: particle Young's modulus"});
  const double nu = r.get("material.poisson_ratio", 0.25, Range::closed_open(0.0, 0.5),
                          {"1", "Hertz-Mindlin: particle Poisson's ratio"});
  // One case per law and no generic one: a law added to ContactLaw without its case fails to compile.
  std::visit(Overloaded{[&](LinearSpringCoulomb& l) {
                          l.kn = 2 * Ec;
                          l.ks = 2 * Ec / kratio;
                        },
                        [&](HertzMindlin& h) {
                          h.youngs = E;
                          h.poisson = nu;
                        }},
             m.law);
  m.contact.friction = r.get("material.friction", 0.5, Range::non_negative(), {"1", "contact friction coefficient mu"});
  m.contact.restitution =
      r.get("material.restitution", 0.5, Range::open_closed(0.0, 1.0), {"1", "normal restitution coefficient e"});
  m.contact.rolling_friction = r.get("material.rolling_friction", 0.0, Range::non_negative(),
                                     {"1", "rolling-resistance coefficient mu_r (Ai et al. 2011, model C)"});
  m.contact.rolling_damping =
      r.get("material.rolling_damping", 0.3, Range::closed(0.0, 1.0), {"1", "rolling viscous damping ratio eta_r"});
  // [bond]
  ParallelBondProperties& b = m.bond;  // defaults: the struct's (bonds.hpp)
  b.radius_multiplier = r.get("bond.radius_multiplier", b.radius_multiplier, Range::open_closed(0.0, 1.0),
                              {"1", "lambda: bond radius = lambda min(R_A, R_B)"});
  b.modulus =
      r.get("bond.modulus", b.modulus, Range::positive(), {"Pa", "bond modulus E_c-bar: k_n-bar = E_c-bar/(R_A+R_B)"});
  b.stiffness_ratio = r.get("bond.stiffness_ratio", b.stiffness_ratio, Range::positive(), {"1", "k_n-bar/k_s-bar"});
  b.tensile_strength = r.get("bond.tensile_strength", b.tensile_strength, Range::positive(),
                             {"Pa", "mean bond tensile strength sigma_c-bar"});
  b.tensile_strength_std = r.get("bond.tensile_strength_std", b.tensile_strength_std, Range::non_negative(),
                                 {"Pa", "standard deviation of sigma_c-bar"});
  b.shear_strength =
      r.get("bond.shear_strength", b.shear_strength, Range::positive(), {"Pa", "mean bond shear strength tau_c-bar"});
  b.shear_strength_std = r.get("bond.shear_strength_std", b.shear_strength_std, Range::non_negative(),
                               {"Pa", "standard deviation of tau_c-bar"});
  m.bond_gap_tolerance =
      r.get("bond.gap_tolerance", m.bond_gap_tolerance, Range::non_negative(),
            {"1", "bond triangulation edges whose gap is below this fraction of the smaller radius"});
  // [joints]
  m.joint_friction = r.get("joints.friction", m.joint_friction, Range::non_negative(),
                           {"1", "friction coefficient of joint contacts"});
  for (auto& js : r.tables("joints.set", {"", "joint sets: dip, spacing, persistence, trace_length"})) {
    JointSet s;
    s.dip = js.get("dip", 45.0, Range::closed(-180, 180), {"deg", "trace angle from +x, counter-clockwise"});
    s.spacing = js.require("spacing", Range::positive(), {"m", "normal spacing of the traces"});
    s.persistence =
        js.get("persistence", 1.0, Range::open_closed(0.0, 1.0), {"1", "jointed fraction of each trace line"});
    s.trace_length = js.get("trace_length", 1.0, Range::positive(), {"m", "length of one joint when persistence < 1"});
    m.joint_sets.push_back(s);
  }
  for (auto& jt : r.tables("joints.trace", {"", "explicit joint traces: from = [x, z], to = [x, z] (m)"})) {
    const auto a = jt.require_array("from", Range{}, {"m", "first end point [x, z]"}, 2);
    const auto bb = jt.require_array("to", Range{}, {"m", "second end point [x, z]"}, 2);
    m.traces.push_back({Vec2(a[0], a[1]), Vec2(bb[0], bb[1]), -1});
  }
  // [numerics]
  c.numerics.safety_factor = r.get("numerics.safety_factor", 0.25, Range::open_closed(0.0, 1.0),
                                   {"1", "time step = safety factor x critical time step sqrt(m/k)"});
  c.numerics.max_speed =
      r.get("numerics.max_speed", 500.0, Range::positive(), {"m/s", "a disc faster than this is a blow-up"});
  // [output]
  c.snapshot_every = static_cast<int>(r.get_int("output.snapshot_every", 20, Range::closed(0, 1e9),
                                                {"1", "records between HDF5 snapshots (0: first and last only)"}));
  c.write_tessellation = r.get_bool("output.tessellation", true, {"", "write the power cells and triangulation (VTK)"});

  if (c.kind != TestKind::Avalanche || describe) {
    LabTestSpec& l = c.lab;
    l.test = c.kind == TestKind::Tension ? LabTest::BiaxialTension : LabTest::BiaxialCompression;
    c.confining = r.get_array("biaxial.confining_stresses", {0.0, 5e6, 10e6}, Range::non_negative(),
                              {"Pa", "confining stresses sigma_3 of the compression tests (one test each)"});
    l.loading_velocity =
        r.get("biaxial.loading_velocity", 0.25, Range::closed(1e-3, 100.0),
              {"m/s",
               "speed of each platen / grip (quasi-static tests: 0.01-1; the test lasts strain·height/speed "
               "at a step of ~1e-7 s, so slower is impractically long)"});
    l.max_axial_strain = r.get("biaxial.max_axial_strain", l.max_axial_strain, Range::open_closed(0.0, 0.5),
                               {"1", "stop at this axial strain"});
    l.post_peak_stop = r.get("biaxial.post_peak_stop", l.post_peak_stop, Range::closed(0.0, 1.0),
                             {"1", "stop once the stress falls below this fraction of the peak"});
    l.local_damping = r.get("biaxial.local_damping", l.local_damping, Range::closed_open(0.0, 1.0),
                            {"1", "Cundall local damping alpha"});
    l.grip_fraction = r.get("biaxial.grip_fraction", l.grip_fraction, Range::open_closed(0.0, 0.3),
                            {"1", "tension: gripped fraction of the height at each end"});
    l.record_interval = static_cast<int>(r.get_int("biaxial.record_interval", l.record_interval, Range::closed(1, 1e9),
                                                   {"1", "steps between curve points"}));
    l.packing = p;
    l.material = m;
    if (!describe && p.width < 8 * p.r_max)
      throw InputError("the sample must be at least 8 R_max wide", r.source(), "sample.width", std::to_string(p.width));
    if (!describe && p.height < 8 * p.r_max)
      throw InputError("the sample must be at least 8 R_max high", r.source(), "sample.height",
                       std::to_string(p.height));
    // An element test needs a specimen of element shape (height/width 2 is usual); a slender column
    // buckles instead of shearing, and its loading time grows with the height (fuzz case 255: a
    // 3.5 m × 3 cm "sample" ran for hours).
    if (!describe && !(p.height >= 0.5 * p.width && p.height <= 4.0 * p.width))
      throw InputError("the lab sample's height/width must be in [0.5, 4] (2 is usual for a biaxial test)", r.source(),
                       "sample.height", std::to_string(p.height) + " with sample.width " + std::to_string(p.width));
    if (!describe) check_disc_memory(p.width * p.height, p, r.source(), "sample.width × sample.height");
  }
  if (c.kind == TestKind::Avalanche || describe) {
    AvalancheSpec& a = c.avalanche;
    const auto dsm = r.get_string("avalanche.dsm", "",
                                  {"",
                                   "elevation raster (GeoTIFF, projected CRS): the profile is cut "
                                   "along avalanche.section_x/y instead of terrain_x/z"});
    if (!dsm.empty() || describe) {
      const auto sx =
          r.get_array("avalanche.section_x", {}, Range{}, {"m", "section polyline x (map CRS), uphill first"});
      const auto sy = r.get_array("avalanche.section_y", {}, Range{}, {"m", "section polyline y (map CRS)"});
      const double spacing =
          r.get("avalanche.section_spacing", 5.0, Range::positive(), {"m", "profile sampling interval"});
      if (!describe) {
        if (sx.size() != sy.size() || sx.size() < 2)
          throw InputError("section_x and section_y need the same number (≥ 2) of values", r.source(),
                           "avalanche.section_x");
        const auto path = std::filesystem::path(dsm).is_absolute() ? std::filesystem::path(dsm) : r.base_dir() / dsm;
        Terrain terrain(read_raster(path));
        std::vector<Vec2> pl;
        double length = 0.0;
        for (std::size_t k = 0; k < sx.size(); ++k) {
          pl.emplace_back(sx[k], sy[k]);
          if (k > 0) length += (pl.back() - pl[k - 1]).norm();
        }
        check_memory(length / spacing * sizeof(ProfilePoint),
                     "a profile of " + std::to_string(length) + " m sampled every avalanche.section_spacing",
                     r.source(), "avalanche.section_spacing", std::to_string(spacing));
        std::vector<ProfilePoint> profile;
        try {
          profile = extract_profile(terrain, pl, spacing);
        } catch (const InputError& e) {  // name the DSM and the key the profile comes from
          throw InputError(e.reason() + " (" + path.string() + ")", r.source(), "avalanche.section_x");
        }
        for (const auto& q : profile)
          if (a.terrain.empty() || q.s > a.terrain.back().x() + 1e-9) a.terrain.emplace_back(q.s, q.z);  // no repeats
      }
    }
    if (dsm.empty() || describe) {
      auto t = points(r, "avalanche.terrain_x", "avalanche.terrain_z",
                      "terrain profile: distance along the section (downhill in +x) and elevation", !describe, 2);
      if (dsm.empty()) a.terrain = t;
    }
    a.source = points(r, "avalanche.source_x", "avalanche.source_z", "rock-mass polygon vertices (profile coordinates)",
                      !describe, 3);
    if (!describe) {
      const std::string tkey = dsm.empty() ? "avalanche.terrain_x" : "avalanche.section_x";
      for (std::size_t k = 1; k < a.terrain.size(); ++k)
        if (!(a.terrain[k].x() > a.terrain[k - 1].x()))
          throw InputError("the terrain profile must advance in +x (distance along the section)", r.source(), tkey,
                           "point " + std::to_string(k));
      if (!(a.terrain.front().y() > a.terrain.back().y()))
        throw InputError("the profile must run downhill in +x (give the section uphill first)", r.source(), tkey);
      for (const auto& q : a.source)
        if (q.x() <= a.terrain.front().x() || q.x() >= a.terrain.back().x())
          throw InputError("the source polygon must lie within the profile's x-range [" +
                               std::to_string(a.terrain.front().x()) + ", " + std::to_string(a.terrain.back().x()) +
                               "] m",
                           r.source(), "avalanche.source_x", std::to_string(q.x()));
    }
    a.support = points(r, "avalanche.support_x", "avalanche.support_z",
                       "optional support wall (2 points) holding the mass until release", false, 2);
    if (!a.support.empty() && a.support.size() != 2)
      throw InputError("the support wall takes exactly 2 points", r.source(), "avalanche.support_x");
    a.terrain_friction = r.get("avalanche.terrain_friction", a.terrain_friction, Range::non_negative(),
                               {"1", "friction coefficient of disc-terrain contacts"});
    a.terrain_restitution = r.get("avalanche.terrain_restitution", a.terrain_restitution, Range::open_closed(0.0, 1.0),
                                  {"1", "restitution of disc-terrain contacts"});
    a.terrain_rolling_friction = r.get(
        "avalanche.terrain_rolling_friction", m.contact.rolling_friction, Range::non_negative(),
        {"1", "rolling-resistance coefficient mu_r of disc-terrain contacts (default: material.rolling_friction)"});
    a.settle_time = r.get("avalanche.settle_time", a.settle_time, Range::non_negative(),
                          {"s", "settling under gravity before release"});
    a.settle_damping = r.get("avalanche.settle_damping", a.settle_damping, Range::closed_open(0.0, 1.0),
                             {"1", "local damping while settling"});
    a.strength_factor =
        r.get("avalanche.strength_factor", a.strength_factor, Range::closed(0.0, 1.0),
              {"1", "bond strengths are multiplied by this at release (weathering / weakening trigger)"});
    const auto trig =
        r.get_array("avalanche.trigger_acceleration", {0.0, 0.0}, Range{},
                    {"m/s^2", "extra acceleration [ax, az] applied during the trigger (earthquake-like push)"}, 2);
    a.trigger_acceleration = Vec2(trig[0], trig[1]);
    a.trigger_duration = r.get("avalanche.trigger_duration", a.trigger_duration, Range::non_negative(),
                               {"s", "duration of the trigger acceleration"});
    a.runout_time = r.get("avalanche.runout_time", a.runout_time, Range::positive(),
                          {"s",
                           "longest simulated time after release; the run ends earlier once the mass is at rest "
                           "(stop_kinetic_fraction, stop_speed), and warns if it is still moving at this time"});
    a.stop_kinetic_fraction =
        r.get("avalanche.stop_kinetic_fraction", a.stop_kinetic_fraction, Range{0.0, 1.0, true, true},
              {"1",
               "at rest when the kinetic energy is below this fraction of its peak after release (and no disc "
               "is faster than stop_speed)"});
    a.stop_speed = r.get("avalanche.stop_speed", a.stop_speed, Range::non_negative(),
                         {"m/s", "at rest when no disc is faster than this (0: kinetic-energy criterion alone)"});
    a.runout_damping = r.get("avalanche.runout_damping", a.runout_damping, Range::closed_open(0.0, 1.0),
                             {"1", "local damping during the run-out"});
    a.record_interval =
        r.get("avalanche.record_interval", a.record_interval, Range::positive(), {"s", "time-series interval"});
    a.volume_width = r.get("avalanche.volume_width", a.volume_width, Range::non_negative(),
                           {"m", "out-of-plane width turning the 2D source area into a volume (0: source length)"});
    a.packing = p;
    a.packing.locked_in_stress = r.get("avalanche.locked_in_stress", 0.0, Range::non_negative(),
                                       {"Pa", "isotropic stress of the packing box before the mass is cut out"});
    a.material = m;
    if (!describe) {
      double x0 = 1e300, x1 = -1e300, z0 = 1e300, z1 = -1e300;
      for (const auto& q : a.source) {
        x0 = std::min(x0, q.x());
        x1 = std::max(x1, q.x());
        z0 = std::min(z0, q.y());
        z1 = std::max(z1, q.y());
      }
      check_disc_memory((x1 - x0) * (z1 - z0), p, r.source(), "source polygon's bounding box");
      try {
        check_avalanche_spec(a);
      } catch (const InputError& e) {  // add the file name
        throw InputError(e.reason(), r.source(), e.key());
      }
    }
  }
  return c;
}

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

std::string fmt_stress_name(double s) {
  std::ostringstream o;
  o << "sigma3_" << std::setprecision(4) << s / 1e6 << "MPa";
  return o.str();
}

int run_lab(const RunConfig& c, const std::filesystem::path& out, bool quiet) {
  const bool tension = c.kind == TestKind::Tension;
  std::vector<double> conf = tension ? std::vector<double>{0.0} : c.confining;
  make_output_dir(out);
  write_text_file(out / "config.resolved.toml", c.resolved);
  if (!quiet) std::cerr << "dem-avalanche: building the bonded sample\n";
  const BondedSample sample = build_bonded_sample(c.lab.packing, c.lab.material);
  if (c.write_tessellation) {
    const auto& x = sample.packed.discs.get<Position<2>>();
    const auto t =
        tessellate(x, sample.packed.discs.get<Radius>(), Vec2(0, 0), Vec2(sample.packed.width, sample.packed.height));
    write_tessellation_vtk(out / "sample", t, x);
  }
  json summary = {{"model", "dem-avalanche"},
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
  for (double sig3 : conf) {
    LabTestSpec spec = c.lab;
    spec.confining_stress = sig3;
    const std::string name = tension ? "tension" : fmt_stress_name(sig3);
    DemSolver s;
    s.settings = c.numerics;
    SnapshotWriter snaps(out / ("snapshots_" + name + ".h5"), "dem-avalanche", 2, c.resolved);
    snaps.set_attribute("units", "SI; discs of unit thickness (forces N/m, energies J/m)");
    // Progress in simulated time; the loading ends at about max strain × H / (2 v).
    ProgressReporter progress("dem-avalanche " + name,
                              spec.max_axial_strain * sample.packed.height / (2.0 * spec.loading_velocity), quiet);
    int records = 0;
    auto observe = [&](const DemSolver& sv, const std::string& phase) {
      if (phase != "loading") return;
      if (records == 0 || (c.snapshot_every > 0 && records % c.snapshot_every == 0)) write_snapshot(snaps, sv);
      ++records;
    };
    auto observe_progress = [&](const DemSolver& sv, const std::string& phase) {
      observe(sv, phase);
      progress.update(sv.time(), sv.step_count(), sv.discs.size());
    };
    LabTestResult r = run_lab_test(spec, sample, s, observe_progress);
    write_snapshot(snaps, s);
    progress.finish(s.time(), s.step_count(), s.discs.size());
    write_curve_csv(out / ("curve_" + name + ".csv"), r.curve);
    write_ae_csv(out / ("ae_" + name + ".csv"), r.events);
    {
      std::ostringstream title;
      title << (tension ? "tension test" : "biaxial test, confining stress sigma3 = ") << std::setprecision(4);
      if (!tension) title << sig3 / 1e6 << " MPa";
      write_sample_png(out / ("cracks_" + name + ".png"), s, title.str());
    }
    json j = lab_json(r);
    j["name"] = name;
    j["confining_stress_Pa"] = sig3;
    tests.push_back(j);
    if (!tension) {
      s3.push_back(sig3);
      s1.push_back(r.peak_stress);
    }
    if (!quiet)
      std::cerr << "dem-avalanche: " << name << ": peak " << r.peak_stress / 1e6 << " MPa at strain " << r.peak_strain
                << ", E = " << r.youngs_modulus / 1e9 << " GPa, nu = " << r.poisson_ratio << ", breaks "
                << r.tensile_breaks << " tensile / " << r.shear_breaks << " shear\n";
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
  write_text_file(out / "summary.json", summary.dump(2) + "\n");
  return kExitOk;
}

int run_avalanche_case(const RunConfig& c, const std::filesystem::path& out, bool quiet) {
  make_output_dir(out);
  write_text_file(out / "config.resolved.toml", c.resolved);
  DemSolver s;
  s.settings = c.numerics;
  SnapshotWriter snaps(out / "snapshots.h5", "dem-avalanche", 2, c.resolved);
  snaps.set_attribute("units", "SI; discs of unit thickness (forces N/m, energies J/m)");
  const double t_end = c.avalanche.settle_time + c.avalanche.runout_time;
  ProgressReporter progress("dem-avalanche", t_end, quiet);
  int records = 0;
  bool first = true;
  auto observe = [&](const DemSolver& sv, const std::string& phase) {
    if (first) {
      write_snapshot(snaps, sv);
      first = false;
    }
    if (phase == "runout") {
      if (c.snapshot_every > 0 && records % c.snapshot_every == 0) write_snapshot(snaps, sv);
      ++records;
    }
    progress.update(sv.time(), sv.step_count(), sv.discs.size());
  };
  AvalancheResult r = run_avalanche(c.avalanche, s, observe);
  write_snapshot(snaps, s);
  progress.finish(s.time(), s.step_count(), s.discs.size());
  write_avalanche_csv(out / "runout.csv", r.series);
  write_ae_csv(out / "ae.csv", r.events);
  write_deposit_csv(out / "deposit.csv", r.deposit);
  write_deposit_png(out / "deposit_thickness.png", r.deposit);
  {
    // Fragments, largest first: size, mass, equivalent-area diameter, centre of mass, travel.
    std::ostringstream o;
    o << std::setprecision(9) << "fragment,discs,mass_kg_per_m,equivalent_diameter_m,x_m,z_m,travel_m\n";
    for (std::size_t k = 0; k < r.fragments.size(); ++k) {
      const auto& f = r.fragments[k];
      const double d = 2.0 * std::sqrt(f.mass / c.avalanche.packing.density / std::numbers::pi);
      o << k << ',' << f.discs << ',' << f.mass << ',' << d << ',' << f.x << ',' << f.z << ',' << f.travel << '\n';
    }
    write_text_file(out / "fragments.csv", o.str());
  }
  write_avalanche_png(out / "deposit.png", s, c.avalanche.terrain, c.avalanche.source);
  std::size_t tens = 0, shear = 0;
  for (const auto& e : r.events) (e.mode == FailureMode::Tensile ? tens : shear) += 1;
  std::size_t multi = 0;
  for (auto n : r.fragment_sizes) multi += n >= 2;
  json quantiles = json::array();
  for (const auto& q : r.quantiles)
    quantiles.push_back({{"mass_fraction", q.fraction},
                         {"toe", {q.x, q.z}},
                         {"runout_L_m", q.runout},
                         {"fall_height_H_m", q.fall_height},
                         {"H_over_L", q.h_over_l}});
  double mass_total = 0;
  for (const auto& f : r.fragments) mass_total += f.mass;
  const double largest_fraction = r.fragments.empty() ? 0.0 : r.fragments.front().mass / mass_total;
  json summary = {{"model", "dem-avalanche"},
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
                  {"runout_by_mass_quantile", quantiles},
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
                  {"max_speed_at_end_m_s", r.max_speed_at_end},
                  {"moving_mass_fraction_at_end", r.moving_fraction_at_end},
                  {"peak_kinetic_energy_J_per_m", r.peak_kinetic_energy},
                  {"steps", s.step_count()}};
  json warnings = json::array();
  if (!r.at_rest) {
    std::ostringstream w;
    w << "the run reached avalanche.runout_time (" << c.avalanche.runout_time << " s) with "
      << 100.0 * r.moving_fraction_at_end << " % of the mass still moving (fastest disc " << r.max_speed_at_end
      << " m/s): run-out, H/L and the deposit are not final; raise avalanche.runout_time";
    warnings.push_back(w.str());
    std::cerr << "dem-avalanche: warning: " << w.str() << "\n";
  }
  summary["warnings"] = warnings;
  write_text_file(out / "summary.json", summary.dump(2) + "\n");
  if (!quiet)
    std::cerr << "dem-avalanche: run-out L = " << r.runout << " m, H = " << r.fall_height << " m, H/L = " << r.h_over_l
              << " (Scheidegger 1973: " << r.scheidegger_h_over_l << " for V = " << r.volume << " m^3)\n";
  return kExitOk;
}

}  // namespace

int main(int argc, char** argv) {
  ConfigApp app;
  app.name = "dem-avalanche";
  app.summary =
      "bonded-disc DEM (parallel bonds, Potyondy & Cundall 2004) of rock: biaxial compression "
      "and tension tests of a bonded sample, and rock avalanches of a jointed rock mass on a "
      "terrain profile.\n"
      "Usage: dem-avalanche --config case.toml [--set key=value ...] [--out DIR] [--threads N] [--quiet]\n"
      "Example: dem-avalanche --config data/dem/biaxial_compression.toml --set bond.tensile_strength=40e6 "
      "--out biaxial-out";
  app.options_caption =
      "Options (SI units throughout: m, s, kg, Pa; discs are 1 m thick, so forces are N/m and energies J/m; "
      "angles in the config in degrees)";
  app.describe = [](ConfigReader& r) { (void)read_config(r, true); };
  app.run = [](ConfigReader& reader, const CommonOptions& opts) {
    RunConfig cfg = read_config(reader, false);
    reader.finish();
    cfg.resolved = reader.resolved();
    // Everything is validated before the output directory is created.
    return run_in_output_dir(opts.out, "dem-avalanche", {}, [&] {
      return cfg.kind == TestKind::Avalanche ? run_avalanche_case(cfg, opts.out, opts.quiet)
                                             : run_lab(cfg, opts.out, opts.quiet);
    });
  };
  return run_config_app(argc, argv, app);
}
