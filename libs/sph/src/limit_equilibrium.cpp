#include "geohaz/sph/limit_equilibrium.hpp"

#include <algorithm>
#include <cmath>
#include <string>

#include "geohaz/core/errors.hpp"

namespace geohaz::sph {

SlopeSection SlopeSection::from_profile(const ProfileDomain& d, std::vector<LimitEquilibriumSoil> soils) {
  if (d.surface_layer_depth > 0.0 || d.bedrock_depth > 0.0 || d.surface_xy)
    throw InputError(
        "the limit-equilibrium check needs a section with layers by elevation on a flat rigid bottom (no surface "
        "layer, bedrock or 3D terrain)");
  SlopeSection s;
  s.surface = d.surface;
  s.x_left = d.x_left;
  s.x_right = d.x_right;
  s.z_bottom = d.z_bottom;
  s.layer_tops = d.layer_tops;
  s.layer_materials = d.layer_materials;
  s.soils = std::move(soils);
  for (int m : s.layer_materials)
    if (m < 0 || static_cast<std::size_t>(m) >= s.soils.size())
      throw InputError("layer material " + std::to_string(m) + " has no soil for the limit-equilibrium check");
  if (s.soils.empty()) throw InputError("the limit-equilibrium check needs at least one soil");
  return s;
}

int SlopeSection::material_at(double z) const noexcept {
  if (layer_materials.empty()) return 0;
  for (std::size_t k = 0; k < layer_tops.size(); ++k)
    if (z < layer_tops[k]) return layer_materials[k];
  return layer_materials.back();
}

namespace {

/// ∫ γ(z) dz over [z0, z1] with γ piecewise constant between the layer tops (N/m²).
double weight_of_column(const SlopeSection& s, double z0, double z1) {
  if (!(z1 > z0)) return 0.0;
  if (s.layer_materials.empty()) return s.soils[0].unit_weight * (z1 - z0);
  double w = 0.0, lo = -1e300;
  for (std::size_t k = 0; k <= s.layer_tops.size(); ++k) {
    const double hi = k < s.layer_tops.size() ? s.layer_tops[k] : 1e300;
    const double a = std::max(lo, z0), b = std::min(hi, z1);
    if (b > a) w += s.soils[static_cast<std::size_t>(s.layer_materials[k])].unit_weight * (b - a);
    lo = hi;
  }
  return w;
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
  if (arc_at(c, std::clamp(c.xc, x0, x1)) < s.z_bottom - 1e-9 * c.radius) return r;  // through the rigid bottom
  const double b = (x1 - x0) / slices;
  struct Slice {
    double w, sin_a, cos_a, cb, tan_phi;
  };
  std::vector<Slice> sl;
  sl.reserve(static_cast<std::size_t>(slices));
  double moment = 0.0;
  for (int i = 0; i < slices; ++i) {
    const double x = x0 + (i + 0.5) * b;
    const double zb = arc_at(c, x), zt = surface_at(s.surface, x);
    if (!(zt > zb)) continue;
    const double w = b * weight_of_column(s, zb, zt);
    const auto& soil = s.soils[static_cast<std::size_t>(s.material_at(zb))];
    const double sa = (c.xc - x) / c.radius;
    const double ca = std::sqrt(std::max(0.0, 1.0 - sa * sa));
    // c b = c ℓ cos α with the slice's exact arc length ℓ: the mid-point b/cos α misses most of a
    // steep base's length where the arc turns vertical.
    const double arc = c.radius * std::abs(std::asin(std::clamp((x + 0.5 * b - c.xc) / c.radius, -1.0, 1.0)) -
                                           std::asin(std::clamp((x - 0.5 * b - c.xc) / c.radius, -1.0, 1.0)));
    sl.push_back({w, sa, ca, soil.cohesion * arc * ca, std::tan(soil.friction)});
    moment += w * sa;
    r.weight += w;
  }
  if (sl.empty() || moment == 0.0) return r;
  const double sign = moment > 0.0 ? 1.0 : -1.0;  // the mass moves down the slope
  const double driving = std::abs(moment);
  double F = 1.0;
  for (int it = 1; it <= 200; ++it) {
    double resisting = 0.0;
    for (const auto& q : sl) {
      const double sa = sign * q.sin_a;
      const double ma = q.cos_a + sa * q.tan_phi / F;
      if (sa < 0.0 && ma < kMinMAlpha) return r;
      resisting += (q.cb + q.w * q.tan_phi) / ma;
    }
    const double Fn = resisting / driving;
    r.iterations = it;
    if (std::abs(Fn - F) < 1e-9 * Fn) {
      r.factor = Fn;
      return r;
    }
    F = Fn;
  }
  r.factor = F;  // not converged to 1e-9 in 200 iterations: the last iterate (never seen in the tests)
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
      const double x0 = refine(xs(first), 0.5 * (xs(first) + xs(first + 1)));
      const double x1 = refine(xs(k), 0.5 * (xs(k - 1) + xs(k)));
      const auto q = bishop_mass(s, c, x0, x1, slices);
      if (q.factor < best.factor) best = q;
      first = -1;
    }
  }
  return best;
}

BishopResult bishop_critical_circle(const SlopeSection& s, const BishopSearchSettings& set) {
  double ztop = -1e300;
  for (const auto& p : s.surface) ztop = std::max(ztop, p[1]);
  const double height = ztop - s.z_bottom, length = s.x_right - s.x_left;
  const double zc_hi = ztop + std::max(2.0 * height, 0.5 * length);
  // A circle as (x_c, z_c, bottom elevation z_c − R).
  auto eval = [&](double xc, double zc, double zlow) {
    BishopResult r;
    if (!(zlow >= s.z_bottom - height) || !(zc > zlow)) return r;
    r = bishop_factor(s, {xc, zc, zc - zlow}, set.slices);
    if (r.admissible() && set.min_depth > 0.0) {
      double dmax = 0.0;
      for (int k = 0; k <= 20; ++k) {
        const double x = r.x_entry + (r.x_exit - r.x_entry) * k / 20.0;
        dmax = std::max(dmax, surface_at(s.surface, x) - arc_at(r.circle, x));
      }
      if (dmax < set.min_depth) return BishopResult{};
    }
    return r;
  };
  const int n = std::max(set.grid, 2);
  std::vector<std::pair<double, std::array<double, 3>>> found;
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < n; ++j)
      for (int k = 0; k < n; ++k) {
        const double xc = s.x_left + length * (i + 0.5) / n;
        const double zc = ztop + (zc_hi - ztop) * (j + 0.5) / n;
        const double zlow = s.z_bottom - height + 2.0 * height * k / n;
        const auto r = eval(xc, zc, zlow);
        if (r.admissible()) found.push_back({r.factor, {xc, zc, zlow}});
      }
  if (found.empty()) throw InputError("the limit-equilibrium search found no admissible slip circle");
  std::sort(found.begin(), found.end(), [](const auto& a, const auto& b) { return a.first < b.first; });
  BishopResult best;
  const std::array<double, 3> step0{length / n, (zc_hi - ztop) / n, height / n};
  for (int start = 0; start < std::min<int>(set.refine_starts, static_cast<int>(found.size())); ++start) {
    std::array<double, 3> p = found[static_cast<std::size_t>(start)].second, step = step0;
    BishopResult cur = eval(p[0], p[1], p[2]);
    // Compass search: try ± step along each coordinate, move to the best improvement, halve the steps
    // when none improves, until the steps are 1e-5 of the section.
    while (step[0] > 1e-5 * length) {
      bool moved = false;
      for (int a = 0; a < 3; ++a)
        for (double sgn : {-1.0, 1.0}) {
          auto q = p;
          q[static_cast<std::size_t>(a)] += sgn * step[static_cast<std::size_t>(a)];
          const auto r = eval(q[0], q[1], q[2]);
          if (r.factor < cur.factor) {
            cur = r;
            p = q;
            moved = true;
          }
        }
      if (!moved)
        for (auto& d : step) d *= 0.5;
    }
    if (cur.factor < best.factor) best = cur;
  }
  return best;
}

}  // namespace geohaz::sph
