#include "geohaz/sph/limit_equilibrium.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>

#include "geohaz/core/errors.hpp"
#include "geohaz/sph/infinite_slope.hpp"

namespace geohaz::sph {

SlopeSection SlopeSection::from_profile(const ProfileDomain& d, std::vector<LimitEquilibriumSoil> soils) {
  if (d.surface_xy) throw InputError("the limit-equilibrium check needs a 2D section (not a terrain across the width)");
  SlopeSection s;
  s.surface = d.surface;
  s.x_left = d.x_left;
  s.x_right = d.x_right;
  s.z_bottom = d.z_bottom;
  s.layer_tops = d.layer_tops;
  s.layer_materials = d.layer_materials;
  s.surface_layer_depth = d.surface_layer_depth;
  s.surface_material = d.surface_material;
  s.bedrock_depth = d.bedrock_depth;
  s.soils = std::move(soils);
  if (s.soils.empty()) throw InputError("the limit-equilibrium check needs at least one soil");
  auto check = [&](int m) {
    if (m < 0 || static_cast<std::size_t>(m) >= s.soils.size())
      throw InputError("layer material " + std::to_string(m) + " has no soil for the limit-equilibrium check");
  };
  for (int m : s.layer_materials) check(m);
  if (s.surface_layer_depth > 0.0) check(s.surface_material);
  return s;
}

int SlopeSection::material_at(double x, double z) const noexcept {
  if (surface_layer_depth > 0.0 && z > surface_at(surface, x) - surface_layer_depth) return surface_material;
  if (layer_materials.empty()) return 0;
  for (std::size_t k = 0; k < layer_tops.size(); ++k)
    if (z < layer_tops[k]) return layer_materials[k];
  return layer_materials.back();
}

double SlopeSection::bottom_at(double x) const noexcept {
  return bedrock_depth > 0.0 ? surface_at(surface, x) - bedrock_depth : z_bottom;
}

double PoreWater::level_at(double x) const noexcept {
  if (x <= phreatic.front()[0]) return phreatic.front()[1];
  if (x >= phreatic.back()[0]) return phreatic.back()[1];
  const auto it = std::upper_bound(phreatic.begin(), phreatic.end(), x,
                                   [](double v, const std::array<double, 2>& p) { return v < p[0]; });
  const auto& a = *(it - 1);
  const auto& b = *it;
  return b[0] > a[0] ? a[1] + (b[1] - a[1]) * (x - a[0]) / (b[0] - a[0]) : b[1];
}

double PoreWater::pressure_at(double x, double z) const noexcept {
  const double h = level_at(x) - z;
  if (!(h > 0.0)) return 0.0;
  double cos2 = 1.0;
  if (head_loss_correction && phreatic.size() > 1 && x > phreatic.front()[0] && x < phreatic.back()[0]) {
    // Inclination of the segment under x (a vertex takes the segment to its right).
    const auto it = std::upper_bound(phreatic.begin(), phreatic.end(), x,
                                     [](double v, const std::array<double, 2>& p) { return v < p[0]; });
    const double dx = (*it)[0] - (*(it - 1))[0], dz = (*it)[1] - (*(it - 1))[1];
    cos2 = dx > 0.0 ? dx * dx / (dx * dx + dz * dz) : 0.0;
  }
  return unit_weight * h * cos2;
}

void SlopeSection::validate_water(const std::string& prefix) const {
  if (!(water.ru >= 0.0 && water.ru < 1.0))
    throw InputError("r_u must lie in [0, 1)", "", prefix + "ru", std::to_string(water.ru));
  if (!(water.unit_weight > 0.0))
    throw InputError("the unit weight of water must be positive", "", prefix + "unit_weight",
                     std::to_string(water.unit_weight));
  if (!water.phreatic.empty()) {
    if (water.ru > 0.0)
      throw InputError("give either a phreatic surface or r_u, not both", "", prefix + "ru", std::to_string(water.ru));
    for (std::size_t i = 1; i < water.phreatic.size(); ++i)
      if (water.phreatic[i][0] < water.phreatic[i - 1][0])
        throw InputError("the phreatic surface's x must not decrease", "", prefix + "phreatic",
                         std::to_string(water.phreatic[i][0]));
    // Above the ground everywhere: the section would be a lake bed, not a slope with a water table.
    bool below_somewhere = false;
    const int n = 400;
    for (int k = 0; k <= n && !below_somewhere; ++k) {
      const double x = x_left + (x_right - x_left) * k / n;
      below_somewhere = water.level_at(x) < surface_at(surface, x);
    }
    if (!below_somewhere)
      throw InputError("the phreatic surface lies above the ground over the whole section", "", prefix + "phreatic");
  }
  for (std::size_t m = 0; m < soils.size(); ++m) {
    const auto& q = soils[m];
    if (q.saturated_unit_weight > 0.0 && q.saturated_unit_weight < q.unit_weight)
      throw InputError(
          "material " + std::to_string(m) + ": the saturated unit weight must not be below the moist unit weight", "",
          prefix + "saturated_unit_weight", std::to_string(q.saturated_unit_weight));
  }
}

namespace {

/// Weight per width ∫ γ dz over [z0, z1] (N/m²) and its first moment ∫ γ z dz (N/m), γ piecewise
/// constant between the layer tops and, below the phreatic surface z_w, saturated.
struct Column {
  double w = 0.0, wz = 0.0;
};

Column column_of(const SlopeSection& s, double x, double z0, double z1, double zw) {
  Column c;
  if (!(z1 > z0)) return c;
  auto add = [&](const LimitEquilibriumSoil& soil, double a, double b) {  // a < b within one soil
    const double mid = std::clamp(zw, a, b);
    const double ws = soil.unit_weight_below_water() * (mid - a), wm = soil.unit_weight * (b - mid);
    c.w += ws + wm;
    c.wz += ws * 0.5 * (a + mid) + wm * 0.5 * (mid + b);
  };
  // The surface layer by depth above z_s(x) − its depth, the layers by elevation below.
  double top = z1;
  if (s.surface_layer_depth > 0.0) {
    const double zl = surface_at(s.surface, x) - s.surface_layer_depth;
    if (z1 > std::max(z0, zl)) add(s.soils[static_cast<std::size_t>(s.surface_material)], std::max(z0, zl), z1);
    top = std::min(z1, zl);
    if (!(top > z0)) return c;
  }
  if (s.layer_materials.empty()) {
    add(s.soils[0], z0, top);
    return c;
  }
  double lo = -1e300;
  for (std::size_t k = 0; k <= s.layer_tops.size(); ++k) {
    const double hi = k < s.layer_tops.size() ? s.layer_tops[k] : 1e300;
    const double a = std::max(lo, z0), b = std::min(hi, top);
    if (b > a) add(s.soils[static_cast<std::size_t>(s.layer_materials[k])], a, b);
    lo = hi;
  }
  return c;
}

double arc_at(const SlipCircle& c, double x) {
  const double d = c.radius * c.radius - (x - c.xc) * (x - c.xc);
  return c.zc - std::sqrt(std::max(d, 0.0));
}

constexpr double kMinMAlpha = 0.2;  // Whitman & Bailey (1967)

/// Bishop's factor of the mass between the circle and the surface from x0 to x1.
BishopResult bishop_mass(const SlopeSection& s, const SlipCircle& c, double x0, double x1, int slices) {
  BishopResult r;
  r.circle = c;
  r.x_entry = x0;
  r.x_exit = x1;
  const bool bedrock = s.bedrock_depth > 0.0;
  if (!bedrock && arc_at(c, std::clamp(c.xc, x0, x1)) < s.z_bottom - 1e-9 * c.radius)
    return r;  // through the rigid bottom
  const double b = (x1 - x0) / slices;
  const bool phreatic = !s.water.phreatic.empty();
  const double kh = s.seismic.kh, kv = s.seismic.kv, gw = s.water.unit_weight;
  struct Slice {
    double v;        // vertical load (1 − k_v) W + W_w (N/m)
    double sin_a;    // (x_c − x)/R
    double cos_a;    // cos α
    double cb;       // c′ ℓ cos α (N/m)
    double ub;       // u ℓ cos α (N/m)
    double tan_phi;  // tan φ′
  };
  std::vector<Slice> sl;
  sl.reserve(static_cast<std::size_t>(slices));
  double moment = 0.0;   // Σ V (x_c − x)/R, signed
  double seismic = 0.0;  // Σ W (z_c − z_g)/R: the horizontal force's arm per unit k_h
  for (int i = 0; i < slices; ++i) {
    const double x = x0 + (i + 0.5) * b;
    const double zb = arc_at(c, x), zt = surface_at(s.surface, x);
    if (!(zt > zb)) continue;
    if (bedrock && zb < zt - s.bedrock_depth - 1e-9 * c.radius) return r;  // through the bedrock
    const double zw = phreatic ? s.water.level_at(x) : -1e300;
    const Column col = column_of(s, x, zb, zt, zw);
    const double w = b * col.w;
    const double ww = zw > zt ? b * gw * (zw - zt) : 0.0;  // ponded water on the slice
    const auto& soil = s.soils[static_cast<std::size_t>(s.material_at(x, zb))];
    const double sa = (c.xc - x) / c.radius;
    const double ca = std::sqrt(std::max(0.0, 1.0 - sa * sa));
    // c b = c ℓ cos α with the slice's exact arc length ℓ: the mid-point b/cos α misses most of a
    // steep base's length where the arc turns vertical.
    const double arc = c.radius * std::abs(std::asin(std::clamp((x + 0.5 * b - c.xc) / c.radius, -1.0, 1.0)) -
                                           std::asin(std::clamp((x - 0.5 * b - c.xc) / c.radius, -1.0, 1.0)));
    double u = 0.0;
    if (s.water.pressure_field)
      u = s.water.pressure_field(x, zb);
    else if (phreatic)
      u = s.water.pressure_at(x, zb);
    else if (s.water.ru > 0.0)
      u = s.water.ru * col.w;  // r_u = u / (γ h), γ h the soil column's weight per area
    const double v = (1.0 - kv) * w + ww;
    sl.push_back({v, sa, ca, soil.cohesion * arc * ca, u * arc * ca, std::tan(soil.friction)});
    moment += v * sa;
    seismic += w * (c.zc - col.wz / col.w) / c.radius;
    r.weight += w;
  }
  if (sl.empty() || moment == 0.0) return r;
  const int sign = moment > 0.0 ? 1 : -1;  // the mass moves down the slope
  r.direction = sign;
  // Ponded water: the hydrostatic thrusts on the vertical faces of the water above the mass at its
  // ends (with the water's weight on the slices, the water's whole load on the ground), d²γ_w/2 at
  // d/3 above the ground, pushing towards the mass; their moment about the centre per R, in the
  // direction of sliding.
  double water_moment = 0.0;
  if (phreatic)
    for (const auto& [xe, push] : {std::pair{x0, 1.0}, std::pair{x1, -1.0}}) {
      const double zg = surface_at(s.surface, xe), d = s.water.level_at(xe) - zg;
      if (d > 0.0) water_moment += sign * push * 0.5 * gw * d * d * (c.zc - (zg + d / 3.0)) / c.radius;
    }
  const double driving_static = std::abs(moment) + water_moment;
  const double driving = driving_static + kh * seismic;
  // Σ [c′b + (V − ub) tan φ′]/m_α at F, and the smallest m_α of the slices whose base rises in the
  // direction of sliding (+∞ if none).
  auto resisting_at = [&](double F, double& min_ma) {
    double res = 0.0;
    min_ma = std::numeric_limits<double>::infinity();
    for (const auto& q : sl) {
      const double sa = sign * q.sin_a;
      const double ma = q.cos_a + sa * q.tan_phi / F;
      if (sa < 0.0) min_ma = std::min(min_ma, ma);
      // Effective normal force never negative: a slice whose pore pressure exceeds its load carries
      // no friction (its base is open), not a negative one.
      res += (q.cb + std::max(q.v - q.ub, 0.0) * q.tan_phi) / ma;
    }
    return res;
  };
  if (!(driving > 0.0)) return r;
  double min_ma = 0.0;
  double F = 1.0;
  for (int it = 1; it <= 200; ++it) {
    const double res = resisting_at(F, min_ma);
    r.iterations = it;
    if (min_ma < 0.05) {  // the iterate is far below the factor: m_α near 0 or negative; try higher
      F *= 2.0;
      if (F > 1e6) return r;
      continue;
    }
    const double Fn = res / driving;
    if (std::abs(Fn - F) < 1e-9 * Fn) {
      F = Fn;
      break;
    }
    F = Fn;  // after 200 iterations the last iterate (never seen in the tests)
  }
  // Whitman & Bailey's limit at the factor found (not at the iterates on the way).
  (void)resisting_at(F, min_ma);
  if (min_ma < kMinMAlpha) return r;
  r.factor = F;
  // Yield coefficient: F = 1 ⇔ k_h Σ W (z_c − z_g)/R = resisting(1) − static driving.
  // Not determined (+∞) where a toe slice's m_α falls below the limit at F = 1.
  const double res1 = resisting_at(1.0, min_ma);
  if (min_ma >= kMinMAlpha && seismic > 0.0) r.yield_coefficient = std::max(0.0, (res1 - driving_static) / seismic);
  return r;
}

}  // namespace

BishopResult bishop_factor(const SlopeSection& s, const SlipCircle& c, int slices) {
  BishopResult r;
  r.circle = c;
  if (!(c.radius > 0.0)) return r;
  const double xa = std::max(c.xc - c.radius, s.x_left), xb = std::min(c.xc + c.radius, s.x_right);
  if (!(xb > xa)) return r;
  auto depth = [&](double x) { return surface_at(s.surface, x) - arc_at(c, x); };
  // A mass cut by an end of the section is not a slip of the section, and one reaching the side of
  // the circle (the surface above z_c there) is not bounded by the circle.
  if (depth(xa) > 0.0 || depth(xb) > 0.0) return r;
  // Entries and exits: the changes of sign of the depth on a fine sampling, refined by bisection.
  // Each stretch between an entry and the next exit is a sliding mass of its own (a toe circle that
  // dips under the ground in front of the toe leaves the slope at the toe; the soil it cuts beyond is
  // another mass), and the circle's factor is that of its weakest mass.
  const int m = 400;
  auto xs = [&](int k) { return xa + (xb - xa) * k / m; };
  auto refine = [&](double out, double in) {  // depth(out) ≤ 0 < depth(in)
    for (int it = 0; it < 60; ++it) {
      const double mid = 0.5 * (out + in);
      (depth(mid) > 0.0 ? in : out) = mid;
    }
    return 0.5 * (out + in);
  };
  BishopResult best = r;
  int first = -1;
  for (int k = 0; k <= m; ++k) {
    const bool inside = k < m && depth(0.5 * (xs(k) + xs(k + 1))) > 0.0;
    if (inside && first < 0) first = k;
    if (!inside && first >= 0) {
      // The crossings lie between the mid-points sampled outside and inside (the ends xa, xb are
      // outside: checked above).
      auto mid = [&](int j) { return 0.5 * (xs(j) + xs(j + 1)); };
      const double x0 = refine(first > 0 ? mid(first - 1) : xa, mid(first));
      const double x1 = refine(k < m ? mid(k) : xb, mid(k - 1));
      const auto q = bishop_mass(s, c, x0, x1, slices);
      if (q.factor < best.factor) best = q;
      first = -1;
    }
  }
  return best;
}

namespace {

/// A circle search: `eval` maps a point of the search's own coordinates to a Bishop result (+∞ where
/// not admissible); `grid` lists the grid stage's points. The best `refine_starts` grid circles are
/// refined by a compass search: try ± step along each coordinate, move to the best improvement,
/// halve the steps when none improves, until step[0] is below `stop`.
/// `key` is the objective: the factor, or the yield coefficient (+∞ where not determined).
template <class Eval, class Key>
BishopResult search_circles(const std::vector<std::array<double, 3>>& grid, const std::array<double, 3>& step0,
                            double stop, int refine_starts, const Eval& eval, const Key& key, bool yield) {
  std::vector<std::pair<double, std::array<double, 3>>> found;
  for (const auto& p : grid) {
    const auto r = eval(p);
    if (r.admissible() && key(r) < std::numeric_limits<double>::infinity()) found.push_back({key(r), p});
  }
  if (found.empty())
    throw InputError(yield ? "the limit-equilibrium search found no slip circle with a yield coefficient"
                           : "the limit-equilibrium search found no admissible slip circle");
  std::sort(found.begin(), found.end(), [](const auto& a, const auto& b) { return a.first < b.first; });
  BishopResult best;
  for (int start = 0; start < std::min<int>(refine_starts, static_cast<int>(found.size())); ++start) {
    std::array<double, 3> p = found[static_cast<std::size_t>(start)].second, step = step0;
    BishopResult cur = eval(p);
    while (step[0] > stop) {
      bool moved = false;
      for (std::size_t a = 0; a < 3; ++a)
        for (double sgn : {-1.0, 1.0}) {
          auto q = p;
          q[a] += sgn * step[a];
          const auto r = eval(q);
          if (key(r) < key(cur)) {
            cur = r;
            p = q;
            moved = true;
          }
        }
      if (!moved)
        for (auto& d : step) d *= 0.5;
    }
    if (key(cur) < key(best)) best = cur;
  }
  return best;
}

/// Deepest point of a circle's mass below the surface (m), sampled at 21 points.
double mass_depth(const SlopeSection& s, const BishopResult& r) {
  double dmax = 0.0;
  for (int k = 0; k <= 20; ++k) {
    const double x = r.x_entry + (r.x_exit - r.x_entry) * k / 20.0;
    dmax = std::max(dmax, surface_at(s.surface, x) - arc_at(r.circle, x));
  }
  return dmax;
}

/// The circle through the surface points at x1 and x1 + chord (chord measured along x) whose arc lies
/// `sagitta` below the straight chord at its middle, the centre above the chord.
SlipCircle circle_through(const SlopeSection& s, double x1, double chord, double sagitta) {
  const double x2 = x1 + chord;
  const double z1 = surface_at(s.surface, x1), z2 = surface_at(s.surface, x2);
  const double dx = x2 - x1, dz = z2 - z1, L = std::hypot(dx, dz);
  const double R = (0.25 * L * L + sagitta * sagitta) / (2.0 * sagitta);
  // Unit normal of the chord pointing up (n_z = dx / L > 0).
  const double nx = -dz / L, nz = dx / L;
  return {0.5 * (x1 + x2) + (R - sagitta) * nx, 0.5 * (z1 + z2) + (R - sagitta) * nz, R};
}

}  // namespace

BishopResult bishop_critical_circle(const SlopeSection& s, const BishopSearchSettings& set) {
  const int n = std::max(set.grid, 2);
  const double length = s.x_right - s.x_left;
  // The objective: the factor of safety, or the yield coefficient (+∞ where not determined).
  auto key = [&](const BishopResult& r) {
    return set.minimise_yield_coefficient && r.admissible() ? r.yield_coefficient : r.factor;
  };
  const bool yield = set.minimise_yield_coefficient;
  auto depth_ok = [&](const BishopResult& r) {
    return !r.admissible() || !(set.min_depth > 0.0) || mass_depth(s, r) >= set.min_depth;
  };
  if (s.bedrock_depth > 0.0) {
    // Entry x1, log chord, log sagitta.
    const double D = s.bedrock_depth;
    const double c_lo = 2.0 * D, c_hi = std::min(60.0 * D, length), s_lo = 0.05 * D, s_hi = 1.5 * D;
    auto eval = [&](const std::array<double, 3>& p) {
      const double chord = std::exp(p[1]), sag = std::exp(p[2]);
      if (!(p[0] >= s.x_left) || !(p[0] + chord <= s.x_right) || !(sag > 0.0)) return BishopResult{};
      const auto r = bishop_factor(s, circle_through(s, p[0], chord, sag), set.slices);
      return depth_ok(r) ? r : BishopResult{};
    };
    std::vector<std::array<double, 3>> grid;
    const int entries = std::max(2, static_cast<int>(length / D));
    const double dlc = std::log(c_hi / c_lo) / (n - 1), dls = std::log(s_hi / s_lo) / (n - 1);
    for (int i = 0; i < entries; ++i)
      for (int j = 0; j < n; ++j)
        for (int k = 0; k < n; ++k)
          grid.push_back({s.x_left + length * i / entries, std::log(c_lo) + dlc * j, std::log(s_lo) + dls * k});
    return search_circles(grid, {D, dlc, dls}, 1e-5 * length, set.refine_starts, eval, key, yield);
  }
  double ztop = -1e300;
  for (const auto& p : s.surface) ztop = std::max(ztop, p[1]);
  const double height = ztop - s.z_bottom;
  const double zc_hi = ztop + std::max(2.0 * height, 0.5 * length);
  // A circle as (x_c, z_c, bottom elevation z_c − R).
  auto eval = [&](const std::array<double, 3>& p) {
    const double xc = p[0], zc = p[1], zlow = p[2];
    BishopResult r;
    if (!(zlow >= s.z_bottom - height) || !(zc > zlow)) return r;
    r = bishop_factor(s, {xc, zc, zc - zlow}, set.slices);
    return depth_ok(r) ? r : BishopResult{};
  };
  std::vector<std::array<double, 3>> grid;
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < n; ++j)
      for (int k = 0; k < n; ++k)
        grid.push_back({s.x_left + length * (i + 0.5) / n, ztop + (zc_hi - ztop) * (j + 0.5) / n,
                        s.z_bottom - height + 2.0 * height * k / n});
  return search_circles(grid, {length / n, (zc_hi - ztop) / n, height / n}, 1e-5 * length, set.refine_starts, eval, key,
                        yield);
}

namespace {

/// The infinite-slope factor of the cover at x with the section's pore water (infinite_slope.hpp, the
/// formula of slope-stability) on the plane at the cover's depth t: the pressure head there from a
/// phreatic surface h_w = m t above the plane (m ≤ 1, the table clipped to the ground), slope-parallel
/// seepage: ψ = m t cos²β; from r_u: ψ = r_u γ t / γ_w (and no saturated weight); from a prescribed
/// field (rain): ψ = u / γ_w.
double wet_infinite_slope(const SlopeSection& s, const LimitEquilibriumSoil& soil, double x, double beta) {
  const double t = s.surface_layer_depth, gw = s.water.unit_weight;
  const double zs = surface_at(s.surface, x), cos2 = std::cos(beta) * std::cos(beta);
  InfiniteSlopeSoil q{soil.cohesion, soil.friction, soil.unit_weight, soil.unit_weight_below_water(), gw, false};
  double psi = 0.0;
  if (s.water.pressure_field) {
    psi = s.water.pressure_field(x, zs - t) / gw;
  } else if (!s.water.phreatic.empty()) {
    psi = cos2 * std::clamp(std::min(s.water.level_at(x), zs) - (zs - t), 0.0, t);
  } else {
    psi = s.water.ru * soil.unit_weight * t / gw;
    q.unit_weight_saturated = soil.unit_weight;
  }
  return infinite_slope_fs(beta, t, psi, cos2, q);
}

}  // namespace

InfiniteSlopeResult infinite_slope_minimum(const SlopeSection& s, double window) {
  InfiniteSlopeResult r;
  const double t = s.surface_layer_depth;
  if (!(t > 0.0)) return r;
  r.window = window > 0.0 ? window : 10.0 * t;
  const auto& soil = s.soils[static_cast<std::size_t>(s.surface_material)];
  const double w = r.window, length = s.x_right - s.x_left;
  const int n = std::max(1, static_cast<int>(std::floor(10.0 * (length - w) / w)));
  for (int k = 0; k <= n; ++k) {
    const double x = length > w ? s.x_left + 0.5 * w + (length - w) * k / n : 0.5 * (s.x_left + s.x_right);
    const double h = std::min(0.5 * w, 0.5 * length);
    const double beta = std::atan(std::abs(surface_at(s.surface, x + h) - surface_at(s.surface, x - h)) / (2.0 * h));
    if (!(beta > 0.0)) continue;
    const double f = s.water.active() ? wet_infinite_slope(s, soil, x, beta)
                                      : soil.cohesion / (soil.unit_weight * t * std::sin(beta) * std::cos(beta)) +
                                            std::tan(soil.friction) / std::tan(beta);
    if (f < r.factor) {
      r.factor = f;
      r.x = x;
      r.angle = beta;
    }
  }
  return r;
}

}  // namespace geohaz::sph
