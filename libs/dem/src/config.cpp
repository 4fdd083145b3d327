// The dem-avalanche config reader (config.hpp): TOML keys → RunConfig, every check before any
// output exists.
#include "geohaz/dem/config.hpp"

#include <cmath>
#include <filesystem>
#include <iomanip>
#include <sstream>

#include "geohaz/core/config.hpp"
#include "geohaz/core/errors.hpp"
#include "geohaz/core/raster.hpp"
#include "geohaz/core/resources.hpp"

namespace geohaz::dem {

namespace {

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

/// [sample]: the packing (seed from the top-level key).
void read_sample(ConfigReader& r, RunConfig& c, std::int64_t seed, bool describe) {
  // [sample]: packing
  PackingSpec& p = c.packing;
  p.seed = static_cast<std::uint64_t>(seed);
  p.width = r.get("sample.width", p.width, Range::positive(), {"m", "sample width (lab tests)"});
  p.height = r.get("sample.height", p.height, Range::positive(), {"m", "sample height (lab tests)"});
  p.r_min = r.get("sample.r_min", p.r_min, Range::positive(), {"m", "smallest disc radius"});
  p.r_max = r.get("sample.r_max", p.r_max, Range::positive(),
                  {"m", "largest disc radius (R_max/R_min = 1.66 in Potyondy & Cundall 2004)"});
  p.porosity =
      r.get("sample.porosity", p.porosity, Range::closed(0.1, 0.4), {"1", "target porosity of the radius expansion"});
  p.locked_in_stress = r.get("sample.locked_in_stress", p.locked_in_stress, Range::non_negative(),
                             {"Pa", "isotropic stress installed by servo walls before bonding (0: none)"});
  p.expansion_steps = static_cast<int>(
      r.get_int("sample.expansion_steps", p.expansion_steps, Range::closed(10, 1e7), {"1", "radius-expansion steps"}));
  p.max_relax_steps = static_cast<int>(r.get_int("sample.relax_steps", p.max_relax_steps, Range::closed(100, 1e8),
                                                 {"1", "cap on each packing equilibrium stage"}));
  if (!describe && p.r_max < p.r_min)
    throw InputError("must be ≥ sample.r_min (" + std::to_string(p.r_min) + " m)", r.source(), "sample.r_max",
                     std::to_string(p.r_max));
}

/// [material], [bond] and [joints]: the contact law, the parallel bonds, the joint sets and traces.
void read_material(ConfigReader& r, RunConfig& c) {
  PackingSpec& p = c.packing;
  // [material]
  MaterialSpec& m = c.material;
  p.density = m.density =
      r.get("material.density", m.density, Range::positive(), {"kg/m^3", "disc density (discs are 1 m thick)"});
  // the choices and their sentences come from the one name table (contact_laws.hpp)
  const std::string law = r.get_choice("material.contact_law", std::string(contact_law_name(m.law)),
                                       ContactLawNames::choices(), {"", ContactLawNames::help("contact law")});
  // The law's own coefficients (contact_laws.hpp, `parameters`); another law's key is an error.
  m.law = ContactLawParameters::read(r, {"material.", "material.contact_law", "set material.contact_law"}, law);
  m.contact.friction =
      r.get("material.friction", m.contact.friction, Range::non_negative(), {"1", "contact friction coefficient mu"});
  m.contact.restitution = r.get("material.restitution", m.contact.restitution, Range::open_closed(0.0, 1.0),
                                {"1", "normal restitution coefficient e"});
  // μ_r is the tangent of a rolling angle: 1 is a square resting on a face (tan 45°), STONE's
  // largest tan β is 0.80; above 2 the rolling stiffness 2.25 μ_r² k_n R² makes the time step collapse.
  m.contact.rolling_friction = r.get("material.rolling_friction", m.contact.rolling_friction, Range::closed(0.0, 2.0),
                                     {"1", "rolling-resistance coefficient mu_r (Ai et al. 2011, model C), 0 to 2"});
  m.contact.rolling_damping = r.get("material.rolling_damping", m.contact.rolling_damping, Range::closed(0.0, 1.0),
                                    {"1", "rolling viscous damping ratio eta_r"});
  m.contact.tangential_damping =
      r.get("material.tangential_damping", m.contact.tangential_damping, Range::closed(0.0, 1.0),
            {"1",
             "tangential dashpot while sticking, as a fraction of the normal damping ratio (0: none, 1: the same "
             "ratio, Cundall & Strack 1979)"});
  m.contact.fragment_damping_mass =
      r.get_choice("material.terrain_damping_mass", m.contact.fragment_damping_mass ? "fragment" : "disc",
                   {"disc", "fragment"},
                   {"",
                    "mass of the disc-terrain and disc-wall dashpots: disc = the disc's own; fragment = the "
                    "effective mass of its bonded fragment at the contact point, 1/(1/M + (r x n)^2/I)"}) == "fragment";
  m.contact.fragment_rolling =
      r.get_choice("material.terrain_rolling", m.contact.fragment_rolling ? "fragment" : "disc", {"disc", "fragment"},
                   {"",
                    "lever arm of the disc-terrain rolling resistance: disc = the disc radius, moment on "
                    "the disc; fragment = the height of its bonded fragment's centre above the contact, moment on the "
                    "whole fragment (a rolling fragment loses mu_r N per metre, as a lumped rockfall block)"}) ==
      "fragment";
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
    s.dip = js.get("dip", s.dip, Range::closed(-180, 180), {"deg", "trace angle from +x, counter-clockwise"});
    s.spacing = js.require("spacing", Range::positive(), {"m", "normal spacing of the traces"});
    s.persistence = js.get("persistence", s.persistence, Range::open_closed(0.0, 1.0),
                           {"1", "jointed fraction of each trace line"});
    s.trace_length =
        js.get("trace_length", s.trace_length, Range::positive(), {"m", "length of one joint when persistence < 1"});
    m.joint_sets.push_back(s);
  }
  for (auto& jt : r.tables("joints.trace", {"", "explicit joint traces: from = [x, z], to = [x, z] (m)"})) {
    const auto a = jt.require_array("from", Range{}, {"m", "first end point [x, z]"}, 2);
    const auto bb = jt.require_array("to", Range{}, {"m", "second end point [x, z]"}, 2);
    m.traces.push_back({Vec2(a[0], a[1]), Vec2(bb[0], bb[1]), -1});
  }
}

/// [numerics] and [output].
void read_numerics_and_output(ConfigReader& r, RunConfig& c) {
  // [numerics]
  c.numerics.safety_factor = r.get("numerics.safety_factor", c.numerics.safety_factor, Range::open_closed(0.0, 1.0),
                                   {"1", "time step = safety factor x critical time step sqrt(m/k)"});
  c.numerics.max_speed = r.get("numerics.max_speed", c.numerics.max_speed, Range::positive(),
                               {"m/s", "a disc faster than this is a blow-up"});
  // [output]
  c.snapshot_every = static_cast<int>(r.get_int("output.snapshot_every", c.snapshot_every, Range::closed(0, 1e9),
                                                {"1", "records between HDF5 snapshots (0: first and last only)"}));
  c.write_tessellation =
      r.get_bool("output.tessellation", c.write_tessellation, {"", "write the power cells and triangulation (VTK)"});
}

/// [biaxial]: the lab tests, with the specimen checks (size, shape, memory).
void read_lab(ConfigReader& r, RunConfig& c, bool describe) {
  const PackingSpec& p = c.packing;
  const MaterialSpec& m = c.material;
  LabTestSpec& l = c.lab;
  l.test = c.kind == TestKind::Tension ? LabTest::BiaxialTension : LabTest::BiaxialCompression;
  c.confining = r.get_array("biaxial.confining_stresses", c.confining, Range::non_negative(),
                            {"Pa", "confining stresses sigma_3 of the compression tests (one test each)"});
  l.loading_velocity =
      r.get("biaxial.loading_velocity", l.loading_velocity, Range::closed(1e-3, 100.0),
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
    throw InputError("the sample must be at least 8 R_max high", r.source(), "sample.height", std::to_string(p.height));
  // An element test needs a specimen of element shape (height/width 2 is usual); a slender column
  // buckles instead of shearing, and its loading time grows with the height (fuzz case 255: a
  // 3.5 m × 3 cm "sample" ran for hours).
  if (!describe && !(p.height >= 0.5 * p.width && p.height <= 4.0 * p.width))
    throw InputError("the lab sample's height/width must be in [0.5, 4] (2 is usual for a biaxial test)", r.source(),
                     "sample.height", std::to_string(p.height) + " with sample.width " + std::to_string(p.width));
  if (!describe) check_disc_memory(p.width * p.height, p, r.source(), "sample.width × sample.height");
}

/// The avalanche's terrain profile (cut from avalanche.dsm along the section, or given as points)
/// and its source polygon, checked: the profile advances in +x and runs downhill, the source lies
/// within it.
void read_avalanche_profile(ConfigReader& r, AvalancheSpec& a, bool describe) {
  const auto dsm = r.get_string("avalanche.dsm", "",
                                {"",
                                 "elevation raster (GeoTIFF, projected CRS): the profile is cut "
                                 "along avalanche.section_x/y instead of terrain_x/z"});
  if (!dsm.empty() || describe) {
    const auto sx =
        r.get_array("avalanche.section_x", {}, Range{}, {"m", "section polyline x (map CRS), uphill first"});
    const auto sy = r.get_array("avalanche.section_y", {}, Range{}, {"m", "section polyline y (map CRS)"});
    const double spacing = a.section_spacing =
        r.get("avalanche.section_spacing", a.section_spacing, Range::positive(), {"m", "profile sampling interval"});
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
                   "a profile of " + std::to_string(length) + " m sampled every avalanche.section_spacing", r.source(),
                   "avalanche.section_spacing", std::to_string(spacing));
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
}

/// [avalanche]: profile, source, walls, terrain contacts, trigger, stop criterion, checks.
void read_avalanche(ConfigReader& r, RunConfig& c, bool describe) {
  const PackingSpec& p = c.packing;
  const MaterialSpec& m = c.material;
  AvalancheSpec& a = c.avalanche;
  read_avalanche_profile(r, a, describe);
  a.support = points(r, "avalanche.support_x", "avalanche.support_z",
                     "optional support wall (2 points) holding the mass until release", false, 2);
  if (!a.support.empty() && a.support.size() != 2)
    throw InputError("the support wall takes exactly 2 points", r.source(), "avalanche.support_x");
  a.terrain_friction = r.get("avalanche.terrain_friction", a.terrain_friction, Range::non_negative(),
                             {"1", "friction coefficient of disc-terrain contacts"});
  a.terrain_restitution = r.get("avalanche.terrain_restitution", a.terrain_restitution, Range::open_closed(0.0, 1.0),
                                {"1", "restitution of disc-terrain contacts"});
  a.terrain_rolling_friction =
      r.get("avalanche.terrain_rolling_friction", m.contact.rolling_friction, Range::closed(0.0, 2.0),
            {"1",
             "rolling-resistance coefficient mu_r of disc-terrain contacts, 0 to 2 (default: "
             "material.rolling_friction)"});
  a.settle_time = r.get("avalanche.settle_time", a.settle_time, Range::non_negative(),
                        {"s", "settling under gravity before release"});
  a.settle_damping = r.get("avalanche.settle_damping", a.settle_damping, Range::closed_open(0.0, 1.0),
                           {"1", "local damping while settling"});
  a.strength_factor = r.get("avalanche.strength_factor", a.strength_factor, Range::closed(0.0, 1.0),
                            {"1", "bond strengths are multiplied by this at release (weathering / weakening trigger)"});
  const auto trig =
      r.get_array("avalanche.trigger_acceleration", {a.trigger_acceleration.x(), a.trigger_acceleration.y()}, Range{},
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
  a.packing.locked_in_stress =
      r.get("avalanche.locked_in_stress", AvalancheSpec{}.packing.locked_in_stress, Range::non_negative(),
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

}  // namespace

RunConfig read_config(ConfigReader& r, bool describe) {
  RunConfig c;
  c.source = r.source();
  const auto test = r.get_choice("test", "biaxial-compression", {"biaxial-compression", "biaxial-tension", "avalanche"},
                                 {"",
                                  "what to run: biaxial compression at one or more confining stresses, direct "
                                  "(biaxial) tension, or a rock avalanche on a terrain profile",
                                  "test"});
  c.kind = test == "biaxial-compression" ? TestKind::Compression
           : test == "biaxial-tension"   ? TestKind::Tension
                                         : TestKind::Avalanche;
  const auto seed = r.get_int("seed", static_cast<std::int64_t>(PackingSpec{}.seed), Range::non_negative(),
                              {"1", "random seed of packing, strengths and joints"});
  read_sample(r, c, seed, describe);
  read_material(r, c);
  read_numerics_and_output(r, c);
  if (c.kind != TestKind::Avalanche || describe) read_lab(r, c, describe);
  if (c.kind == TestKind::Avalanche || describe) read_avalanche(r, c, describe);
  return c;
}

}  // namespace geohaz::dem
