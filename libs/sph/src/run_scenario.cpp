// The particles, solver settings and reported structures of an sph-slope config: the scenarios of
// scenario.hpp (the builders) made from RunConfig, clamped regions, the water table's saturation,
// and the map geometry of a DSM section.
#include <algorithm>
#include <cmath>
#include <functional>
#include <sstream>
#include <string>
#include <vector>

#include "geohaz/core/errors.hpp"
#include "run_support.hpp"

namespace geohaz::sph {

const char* scenario_name(ScenarioType t) {
  switch (t) {
    case ScenarioType::Slope:
      return "slope";
    case ScenarioType::Column:
      return "column";
    case ScenarioType::Biaxial:
      return "biaxial";
    case ScenarioType::Section:
      return "section";
    case ScenarioType::Block:
      return "block";
  }
  return "?";
}

double strip_width(const RunConfig& c) {
  return static_cast<double>(std::lround(c.width / c.numerics.spacing)) * c.numerics.spacing;
}

namespace {

/// The clamped regions (clamp.boxes) of a config; a box whose corners are not ordered is bad input.
template <int Dim>
struct ClampBoxes {
  std::vector<Vec<Dim>> lo, hi;
  std::vector<std::string> text;  // as the config gives it, for messages
  std::vector<std::size_t> held;  // soil particles made inside, kept or not (counted by visit)

  explicit ClampBoxes(const RunConfig& c) {
    const std::size_t per = 2 * Dim;
    if (c.clamp_boxes.size() % per != 0)
      throw InputError("needs " + std::to_string(per) + " numbers per box (lower corner, then upper corner, m)",
                       c.config_source, "clamp.boxes", std::to_string(c.clamp_boxes.size()) + " numbers");
    for (std::size_t b = 0; b < c.clamp_boxes.size(); b += per) {
      Vec<Dim> l, h;
      for (int d = 0; d < Dim; ++d) {
        l[d] = c.clamp_boxes[b + d];
        h[d] = c.clamp_boxes[b + Dim + d];
      }
      std::ostringstream box;
      for (std::size_t k = 0; k < per; ++k) box << (k ? ", " : "[") << csv_number(c.clamp_boxes[b + k]);
      box << "]";
      if (!(l.array() < h.array()).all())
        throw InputError(
            "box " + std::to_string(b / per) + ": every lower corner coordinate must be below the upper one",
            c.config_source, "clamp.boxes", box.str());
      lo.push_back(l);
      hi.push_back(h);
      text.push_back(box.str());
    }
    held.assign(lo.size(), 0);
  }
  bool inside(std::size_t b, const Vec<Dim>& x) const {
    return (x.array() >= lo[b].array()).all() && (x.array() <= hi[b].array()).all();
  }
  /// The builder's visitor: counts every soil particle made in each box.
  std::function<void(const Vec<Dim>&, Kind)> counter() {
    if (lo.empty()) return {};
    return [this](const Vec<Dim>& x, Kind k) {
      if (k != Kind::Soil) return;
      for (std::size_t b = 0; b < lo.size(); ++b)
        if (inside(b, x)) ++held[b];
    };
  }
  /// Mark the kept soil particles inside the boxes; a box without soil in the whole scenario is bad input.
  void apply(const RunConfig& c, SphStore<Dim>& S) const {
    const auto& x = S.template get<Position<Dim>>();
    const auto& kind = S.template get<ParticleKind>();
    auto& cl = S.template get<Clamped>();
    for (std::size_t b = 0; b < lo.size(); ++b) {
      for (std::size_t i = 0; i < S.size(); ++i)
        if (kind[i] == kSoil && inside(b, x[i])) cl[i] = 1;
      if (held[b] == 0)
        throw InputError("box " + std::to_string(b) + " holds no soil particle: a clamped region must overlap the body",
                         c.config_source, "clamp.boxes", text[b]);
    }
  }
};

}  // namespace

namespace {

/// The configured end and bottom walls and the 3D width on a profile domain.
void apply_walls(ProfileDomain& d, const RunConfig& c) {
  d.left = c.left_wall;
  d.right = c.right_wall;
  d.bottom = c.bottom_wall;
  d.width = c.width;
  d.periodic_width = c.periodic_width;
}

}  // namespace

void apply_layers(ProfileDomain& d, const RunConfig& c) {
  if (!c.layer_materials.empty()) {
    d.layer_tops = c.layer_tops;
    d.layer_materials = c.layer_materials;
  } else {
    d.layer_tops.clear();
    d.layer_materials.clear();
  }
}

ProfileDomain section_profile(const RunConfig& c) {
  const auto& P = c.section.profile;
  if (P.size() < 2)
    throw InputError("the cross-section profile has fewer than 2 points", c.config_source, "section.polyline");
  ProfileDomain d;
  double zmin = 1e300;
  for (const auto& p : P) {
    d.surface.push_back({p.s, p.z});
    zmin = std::min(zmin, p.z);
  }
  d.x_left = P.front().s;
  d.x_right = P.back().s;
  d.z_bottom = zmin - c.section.soil_thickness - c.section.base_thickness;
  d.layer_tops.clear();
  d.layer_materials = {c.section.base_material};
  d.surface_layer_depth = c.section.soil_thickness;
  d.surface_material = c.section.soil_material;
  if (c.section.bedrock) d.bedrock_depth = c.section.soil_thickness + c.section.base_thickness;
  return d;
}

template <int Dim>
Built<Dim> build(const RunConfig& c, const Share& share) {
  ClampBoxes<Dim> clamp(c);
  BuildShare<Dim> keep{share.part, share.parts, share.count_only, clamp.counter()};
  std::vector<double> rho;
  for (const auto& m : c.materials) rho.push_back(m.density);
  const double dx = c.numerics.spacing, hf = c.numerics.h_factor;
  Built<Dim> b;
  switch (c.scenario) {
    case ScenarioType::Slope: {
      ProfileDomain d = c.slope.profile();
      apply_walls(d, c);
      apply_layers(d, c);
      if (c.piles.enabled) {
        if (Dim != 3)
          throw InputError("pile rows need dimension = 3 (a pile row in plane strain is a wall)", c.config_source,
                           "piles.enabled", "true");
        const double xp = c.slope.toe_x() - c.piles.position * c.slope.gradient * c.slope.height;
        for (double y = 0.5 * c.piles.spacing; y < c.width; y += c.piles.spacing)
          d.piles.push_back({xp, y, c.piles.diameter});
        d.pile_top_margin = 2.0 * dx;
      }
      b.sc = build_profile<Dim>(d, dx, rho, hf, keep);
      b.frame.toe_x = c.slope.toe_x();
      b.frame.base_length = c.slope.base_length();
      b.frame.base_top = c.slope.base_thickness;
      break;
    }
    case ScenarioType::Column: {
      ProfileDomain d;
      const double a = c.column_width, H = c.column_height;
      d.surface = {{0.0, H}, {a, H}, {a, 0.0}, {a + c.floor_length, 0.0}};
      d.x_left = 0.0;
      d.x_right = a + c.floor_length;
      apply_walls(d, c);
      b.sc = build_profile<Dim>(d, dx, rho, hf, keep);
      b.frame.toe_x = a;
      b.frame.base_length = a;
      b.frame.base_top = 0.0;
      break;
    }
    case ScenarioType::Block: {
      ProfileDomain d;
      d.surface = {{0.0, c.block_height}, {c.block_length, c.block_height}};
      d.x_left = 0.0;
      d.x_right = c.block_length;
      apply_walls(d, c);
      b.sc = build_profile<Dim>(d, dx, rho, hf, keep);
      b.frame.toe_x = c.block_length;
      b.frame.base_length = c.block_length;
      b.frame.base_top = -1e300;
      break;
    }
    case ScenarioType::Biaxial: {
      b.sc = build_biaxial<Dim>(c.biaxial, dx, rho.front(), hf, keep);
      b.frame.toe_x = c.biaxial.width;
      b.frame.base_length = c.biaxial.width;
      b.frame.base_top = -1e300;
      break;
    }
    case ScenarioType::Section: {
      const auto& P = c.section.profile;
      ProfileDomain d = section_profile(c);
      d.left = c.left_wall;
      d.right = c.right_wall;
      d.bottom = c.bottom_wall;
      if constexpr (Dim == 3) {
        if (!c.section.bedrock)
          throw InputError("a 3D DSM section needs section.base = \"bedrock\"", c.config_source, "section.base",
                           "fill");
        if (c.periodic_width)
          throw InputError("a 3D DSM section cannot be periodic across: the terrain differs on both sides",
                           c.config_source, "geometry.periodic", "true");
        if (!c.section.terrain) throw InputError("the 3D section has no terrain", c.config_source, "section.dsm");
        d.width = c.width;
        d.periodic_width = false;
        const Terrain* terrain = c.section.terrain.get();
        const double half = 0.5 * strip_width(c);
        d.surface_xy = [terrain, &P, half, &c](double s, double y) {
          const Vec2 q = section_map_point(P, s, y - half);
          const double z = terrain->elevation(q.x(), q.y());
          if (!std::isfinite(z))
            throw InputError("the 3D section strip leaves the DSM's data at (" + std::to_string(q.x()) + ", " +
                                 std::to_string(q.y()) + "): narrow geometry.width or move the polyline",
                             c.config_source, "geometry.width", std::to_string(c.width));
          return z;
        };
      }
      b.sc = build_profile<Dim>(d, dx, rho, hf, keep);
      b.frame.toe_x = d.x_left;  // run-out on a section: reported as the largest horizontal displacement
      b.frame.base_length = d.x_right - d.x_left;
      b.frame.base_top = 1e300;  // no particle counts for the front
      break;
    }
  }
  b.frame.spacing = dx;
  b.frame.front_thickness = c.front_thickness;
  clamp.apply(c, b.sc.store);
  saturate_below_water_table<Dim>(c, b.sc.store);
  return b;
}

template <int Dim>
SolverSettings<Dim> settings_for(const RunConfig& c, const Scenario<Dim>& sc) {
  SolverSettings<Dim> s;
  static_cast<NumericalSettings&>(s) = c.numerics;
  if (c.scenario == ScenarioType::Biaxial) s.gravity = 0.0;
  s.periodic = sc.periodic;
  s.domain_lo = sc.domain_lo;
  s.domain_hi = sc.domain_hi;
  s.pore_water = pore_water_settings(c);
  return s;
}

template <int Dim>
std::vector<std::size_t> reported_structures(const RunConfig& c, const std::vector<Structure<Dim>>& table) {
  std::vector<std::size_t> shown;
  if (!c.structure_forces) return shown;
  if (c.structures.empty()) {
    for (std::size_t k = 0; k < table.size(); ++k) shown.push_back(k);
    return shown;
  }
  for (const auto& name : c.structures) {
    std::size_t k = 0;
    while (k < table.size() && table[k].name != name) ++k;
    if (k == table.size()) {
      std::string names;
      for (const auto& s : table) names += (names.empty() ? "" : ", ") + s.name;
      throw InputError("no structure of this name in the scenario; it has: " + (names.empty() ? "none" : names),
                       c.config_source, "output.structures", name);
    }
    if (std::find(shown.begin(), shown.end(), k) != shown.end())
      throw InputError("structure named twice", c.config_source, "output.structures", name);
    shown.push_back(k);
  }
  return shown;
}

Vec2 section_map_point(const std::vector<ProfilePoint>& P, double s, double t) {
  s = std::clamp(s, P.front().s, P.back().s);
  std::size_t seg = 1;
  while (seg + 1 < P.size() && P[seg].s < s) ++seg;
  const double ds = P[seg].s - P[seg - 1].s;
  const double w = ds > 0 ? (s - P[seg - 1].s) / ds : 0.0;
  const Vec2 a(P[seg - 1].x, P[seg - 1].y), b(P[seg].x, P[seg].y);
  Vec2 tan = b - a;
  tan = tan.norm() > 0 ? Vec2(tan / tan.norm()) : Vec2(1.0, 0.0);
  return a + w * (b - a) + t * Vec2(-tan.y(), tan.x());
}

double cantilever_mode_shape(double xi) {
  constexpr double k = 1.8751040687119611;  // first root of 1 + cos k cosh k = 0
  const double s = (std::cosh(k) + std::cos(k)) / (std::sinh(k) + std::sin(k));
  auto phi = [&](double z) { return std::cosh(k * z) - std::cos(k * z) - s * (std::sinh(k * z) - std::sin(k * z)); };
  return phi(std::clamp(xi, 0.0, 1.0)) / phi(1.0);
}

template Built<2> build<2>(const RunConfig&, const Share&);
template Built<3> build<3>(const RunConfig&, const Share&);
template SolverSettings<2> settings_for<2>(const RunConfig&, const Scenario<2>&);
template SolverSettings<3> settings_for<3>(const RunConfig&, const Scenario<3>&);
template std::vector<std::size_t> reported_structures<2>(const RunConfig&, const std::vector<Structure<2>>&);
template std::vector<std::size_t> reported_structures<3>(const RunConfig&, const std::vector<Structure<3>>&);

}  // namespace geohaz::sph
