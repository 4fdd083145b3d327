// Barriers across the flow: geometry for the particle loop and loading from a vector file
// (docs/runout.md, "Barriers").
#include "geohaz/runout/barriers.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <iostream>
#include <sstream>

#include "case_support.hpp"
#include "geohaz/core/errors.hpp"
#include "geohaz/core/kernels.hpp"
#include "geohaz/core/raster.hpp"
#include "geohaz/runout/run.hpp"

namespace geohaz::runout {

namespace {

double cross(const Vec2& a, const Vec2& b) noexcept {
  return a.x() * b.y() - a.y() * b.x();
}

/// F(s) on s = k/kTable·2, k = 0..kTable: ½ + ∫₀ˢ m(x) dx with m(x) = ∫ w(√(x² + y²)) dy the
/// marginal of the normalised 2D cubic spline (h = 1), by the midpoint rule on a fine grid.
constexpr int kTable = 400;
const std::array<double, kTable + 1>& fraction_table() {
  static const std::array<double, kTable + 1> table = [] {
    std::array<double, kTable + 1> t{};
    const auto marginal = [](double x) {
      constexpr int ny = 2000;
      const double ymax = std::sqrt(std::max(4.0 - x * x, 0.0));
      const double dy = 2.0 * ymax / ny;
      double m = 0.0;
      for (int k = 0; k < ny; ++k) {
        const double y = -ymax + (k + 0.5) * dy;
        m += CubicSpline<2>::value(std::sqrt(x * x + y * y), 1.0) * dy;
      }
      return m;
    };
    const double ds = 2.0 / kTable;
    t[0] = 0.5;
    for (int k = 1; k <= kTable; ++k) {
      // Simpson on [s_{k-1}, s_k].
      const double a = (k - 1) * ds, b = k * ds;
      t[k] = t[k - 1] + ds / 6.0 * (marginal(a) + 4.0 * marginal(0.5 * (a + b)) + marginal(b));
    }
    // The table's end is 1 up to the quadrature error; scale the increments so that it is exactly 1.
    const double scale = 0.5 / (t[kTable] - 0.5);
    for (int k = 1; k <= kTable; ++k) t[k] = 0.5 + (t[k] - 0.5) * scale;
    return t;
  }();
  return table;
}

/// G(q) = ∫_q^2 f(t) dt for the head-pressure shape f of head_pressure.hpp (closed form).
double shape_tail(double q) noexcept {
  if (q >= 2.0) return 0.0;
  if (q >= 1.0) {
    const double a = q * q * q / 3.0 - 1.5 * q * q + 2.0 * q;  // ∫ (t − 1)(t − 2) dt
    return 0.5 * (a - 2.0 / 3.0);
  }
  return 2.0 * std::log(2.0) - 1.0 - (2.0 * std::log(1.0 + q) - q) + 1.0 / 12.0;
}

/// M(s) on the same grid as the fraction table: ∫ G(√(s² + y²)) dy by the midpoint rule.
const std::array<double, kTable + 1>& push_table() {
  static const std::array<double, kTable + 1> table = [] {
    std::array<double, kTable + 1> t{};
    for (int k = 0; k <= kTable; ++k) {
      const double s = 2.0 * k / kTable;
      constexpr int ny = 4000;
      const double ymax = std::sqrt(std::max(4.0 - s * s, 0.0));
      const double dy = 2.0 * ymax / ny;
      double m = 0.0;
      for (int j = 0; j < ny; ++j) {
        const double y = -ymax + (j + 0.5) * dy;
        m += shape_tail(std::sqrt(s * s + y * y)) * dy;
      }
      t[static_cast<std::size_t>(k)] = m;
    }
    return t;
  }();
  return table;
}

double from_table(const std::array<double, kTable + 1>& t, double s) noexcept {
  const double f = s / 2.0 * kTable;
  const int k = std::min(static_cast<int>(f), kTable - 1);
  const double w = f - k;
  return t[static_cast<std::size_t>(k)] * (1.0 - w) + t[static_cast<std::size_t>(k) + 1] * w;
}

}  // namespace

double BarrierSet::mirror_push(double s) noexcept {
  if (s >= 2.0) return 0.0;
  return from_table(push_table(), std::max(s, 0.0));
}

bool BarrierSet::nearest_wall(const Vec2& p, WallProximity& w) const noexcept {
  double best = reach_;
  bool found = false, at_end = false;
  for (std::size_t b = 0; b < barriers_.size(); ++b) {
    const auto& v = barriers_[b].vertices;
    for (std::size_t k = 0; k + 1 < v.size(); ++k) {
      const Vec2 a = v[k], e = v[k + 1] - a;
      const double l2 = e.squaredNorm();
      const double u = std::clamp((p - a).dot(e) / l2, 0.0, 1.0);
      const Vec2 q = a + u * e;
      const double d = (p - q).norm();
      if (d >= best) continue;
      best = d;
      found = true;
      at_end = (k == 0 && u <= 0.0) || (k + 2 == v.size() && u >= 1.0);
      w.barrier = static_cast<int>(b);
      w.distance = d;
      w.point = q;
      const double el = std::sqrt(l2);
      Vec2 n(-e.y() / el, e.x() / el);  // left of a → b
      if (cross(e, p - a) < 0.0) n = -n;
      w.away = n;
      w.arclength = arclength_[b][k] + u * el;
    }
  }
  return found && !at_end;
}

std::size_t BarrierSet::bin_at(std::size_t b, double arclength) const noexcept {
  const std::size_t n = bin0_[b + 1] - bin0_[b];
  const auto k = static_cast<std::size_t>(std::max(0.0, arclength / bin_length_[b]));
  return bin0_[b] + std::min(k, n - 1);
}

double Barrier::length() const noexcept {
  double l = 0.0;
  for (std::size_t k = 1; k < vertices.size(); ++k) l += (vertices[k] - vertices[k - 1]).norm();
  return l;
}

double BarrierSet::kernel_fraction(double s) noexcept {
  if (!(s > 0.0)) return 0.5;
  if (s >= 2.0) return 1.0;
  return from_table(fraction_table(), s);
}

BarrierSet::BarrierSet(std::vector<Barrier> barriers, WallLaw law, double d0)
    : barriers_(std::move(barriers)), law_(law), reach_(2.0 * d0) {
  bin0_.push_back(0);
  lo_ = Vec2::Constant(std::numeric_limits<double>::infinity());
  hi_ = -lo_;
  for (const Barrier& b : barriers_) {
    std::vector<double> s{0.0};
    for (std::size_t k = 1; k < b.vertices.size(); ++k)
      s.push_back(s.back() + (b.vertices[k] - b.vertices[k - 1]).norm());
    for (const Vec2& v : b.vertices) {
      lo_ = lo_.cwiseMin(v);
      hi_ = hi_.cwiseMax(v);
    }
    const double len = s.back();
    const auto n = static_cast<std::size_t>(std::max(1.0, std::ceil(len / (0.5 * d0))));
    bin_length_.push_back(len / static_cast<double>(n));
    bin0_.push_back(bin0_.back() + n);
    arclength_.push_back(std::move(s));
  }
  fraction_table();  // built now, outside the particle loop
  push_table();
}

std::size_t BarrierSet::bin_of(const BarrierCrossing& c) const noexcept {
  return bin_at(static_cast<std::size_t>(c.barrier), c.arclength);
}

bool BarrierSet::crossing(const Vec2& x0, const Vec2& x1, BarrierCrossing& c) const noexcept {
  const Vec2 d = x1 - x0;
  double best = std::numeric_limits<double>::infinity();
  for (std::size_t b = 0; b < barriers_.size(); ++b) {
    const auto& v = barriers_[b].vertices;
    for (std::size_t k = 0; k + 1 < v.size(); ++k) {
      const Vec2 a = v[k], e = v[k + 1] - v[k];
      const double o0 = cross(e, x0 - a), o1 = cross(e, x1 - a);
      // Crossing: x0 strictly on one side, x1 on the other or on the line.
      if (o0 == 0.0 || (o0 > 0.0 && o1 > 0.0) || (o0 < 0.0 && o1 < 0.0)) continue;
      const double den = cross(d, e);
      if (den == 0.0) continue;
      const double t = cross(a - x0, e) / den;  // along the step
      const double u = cross(a - x0, d) / den;  // along the segment
      if (u < -1e-12 || u > 1.0 + 1e-12 || t < 0.0 || t > 1.0 || t >= best) continue;
      best = t;
      c.barrier = static_cast<int>(b);
      c.segment = k;
      c.t = t;
      c.point = x0 + t * d;
      const double el = e.norm();
      Vec2 n(e.y() / el, -e.x() / el);  // right of a → b
      if (o0 < 0.0) {
        // x0 is right of the segment: the normal into the other side points left.
        n = -n;
      }
      c.normal = n;
      c.arclength = arclength_[b][k] + std::clamp(u, 0.0, 1.0) * el;
      c.from_upstream = (o0 > 0.0) == barriers_[b].upstream_left;
    }
  }
  return best <= 1.0;
}

double BarrierSet::distance_to_segment(std::size_t b, std::size_t k, const Vec2& p) const noexcept {
  const Vec2 a = barriers_[b].vertices[k], e = barriers_[b].vertices[k + 1] - a;
  const double l2 = e.squaredNorm();
  const double u = l2 > 0.0 ? std::clamp((p - a).dot(e) / l2, 0.0, 1.0) : 0.0;
  return (p - a - u * e).norm();
}

double BarrierSet::distance(std::size_t b, const Vec2& p, bool& upstream) const noexcept {
  const auto& v = barriers_[b].vertices;
  double best = std::numeric_limits<double>::infinity();
  upstream = false;
  for (std::size_t k = 0; k + 1 < v.size(); ++k) {
    const double dist = distance_to_segment(b, k, p);
    if (dist < best) {
      best = dist;
      upstream = (cross(v[k + 1] - v[k], p - v[k]) > 0.0) == barriers_[b].upstream_left;
    }
  }
  return best;
}

bool BarrierSet::passes(std::int64_t id, std::size_t b) const noexcept {
  const double p = barriers_[b].permeability;
  if (!(p > 0.0)) return false;
  // splitmix64 of (id, b): a uniform number in [0, 1) per particle and barrier.
  std::uint64_t z = static_cast<std::uint64_t>(id) * 0x9E3779B97F4A7C15ull +
                    (static_cast<std::uint64_t>(b) + 1) * 0xD1B54A32D192ED03ull;
  z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
  z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
  z ^= z >> 31;
  return static_cast<double>(z >> 11) * 0x1.0p-53 < p;
}

std::vector<Barrier> load_barriers(const BarrierSpec& s, const Raster& dsm, const GridSurface& surface,
                                   const Vec2& upstream_point) {
  std::vector<Barrier> out;
  if (s.file.empty()) return out;
  const std::vector<std::string> fields = vector_field_names(s.file);
  const auto has = [&](const std::string& f) {
    return !f.empty() && std::find(fields.begin(), fields.end(), f) != fields.end();
  };
  const bool height_attr = has(s.height_attribute), perm_attr = has(s.permeability_attribute);
  if (!height_attr && !(s.height > 0.0))
    throw InputError("no crest height: the file has no attribute '" + s.height_attribute +
                         "' and barriers.height is not set (m, > 0)",
                     s.file, "barriers.height_attribute", s.height_attribute);
  // read_lines names a feature that is not a line (points, polygons): InputError.
  const auto lines = read_lines(s.file, height_attr ? s.height_attribute : "", dsm.crs_wkt);
  std::vector<Polyline> perm;
  if (perm_attr) perm = read_lines(s.file, s.permeability_attribute, dsm.crs_wkt);
  const GridGeometry g = surface.geometry();
  for (std::size_t k = 0; k < lines.size(); ++k) {
    const Polyline& l = lines[k];
    const std::string feature = "feature " + std::to_string(l.feature);
    Barrier b;
    b.feature = l.feature;
    b.name = "barrier_" + std::to_string(l.feature);
    // Parts of one multi-line feature get a suffix.
    if ((k > 0 && lines[k - 1].feature == l.feature) || (k + 1 < lines.size() && lines[k + 1].feature == l.feature)) {
      std::size_t part = 0;
      for (std::size_t m = 0; m < k; ++m) part += lines[m].feature == l.feature ? 1 : 0;
      b.name += '_';
      b.name += std::to_string(part);
    }
    b.vertices = l.vertices;
    b.height = std::isfinite(l.attribute) ? l.attribute : s.height;
    const std::string hkey = std::isfinite(l.attribute) ? s.height_attribute : "barriers.height";
    if (!(b.height > 0.0 && b.height <= 100.0))
      throw InputError(feature + ": the crest height must be in (0, 100] m (found " + detail::fmt(b.height) + " m)",
                       s.file, hkey, detail::fmt(b.height));
    b.permeability = s.permeability;
    std::string pkey = "barriers.permeability";
    if (perm_attr && std::isfinite(perm[k].attribute)) {
      b.permeability = perm[k].attribute;
      pkey = s.permeability_attribute;
    }
    if (!(b.permeability >= 0.0 && b.permeability < 1.0))
      throw InputError(feature + ": the permeability must be in [0, 1) (found " + detail::fmt(b.permeability) + ")",
                       s.file, pkey, detail::fmt(b.permeability));
    // The whole line on the terrain: the vertices and points every half cell between them.
    const double step = 0.5 * std::min(g.dx, g.dy);
    for (std::size_t v = 0; v + 1 < b.vertices.size(); ++v) {
      const Vec2 a = b.vertices[v], e = b.vertices[v + 1] - a;
      const int n = std::max(1, static_cast<int>(std::ceil(e.norm() / step)));
      for (int m = 0; m <= n; ++m) {
        const Vec2 p = a + e * (static_cast<double>(m) / n);
        SurfaceSample smp;
        if (!surface.sample(p, smp)) {
          std::ostringstream msg;
          msg << std::fixed;
          msg.precision(1);
          msg << feature << ": the barrier line leaves the DSM (or crosses nodata) at (" << p.x() << ", " << p.y()
              << "); the DSM extent is " << g.x0 << " … " << g.x0 + g.nx * g.dx << " × " << g.y0 - g.ny * g.dy << " … "
              << g.y0 << " (check the CRS of both files)";
          std::ostringstream val;
          val << std::fixed;
          val.precision(1);
          val << p.x() << ", " << p.y();
          throw InputError(msg.str(), s.file, "barriers.file", val.str());
        }
      }
    }
    if (!(b.length() > 0.0)) throw InputError(feature + ": the barrier line has no length", s.file, "barriers.file");
    // The flow comes from the release: its side of the line is upstream.
    bool left = true;
    double best = std::numeric_limits<double>::infinity();
    for (std::size_t v = 0; v + 1 < b.vertices.size(); ++v) {
      const Vec2 a = b.vertices[v], e = b.vertices[v + 1] - a;
      const double u = std::clamp((upstream_point - a).dot(e) / e.squaredNorm(), 0.0, 1.0);
      const double dist = (upstream_point - a - u * e).norm();
      if (dist < best) {
        best = dist;
        left = cross(e, upstream_point - a) >= 0.0;
      }
    }
    b.upstream_left = left;
    out.push_back(std::move(b));
  }
  return out;
}

}  // namespace geohaz::runout
