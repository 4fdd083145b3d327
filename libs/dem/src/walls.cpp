#include "geohaz/dem/walls.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

namespace geohaz::dem {

double WallSegment::normal_stress(double loaded_length) const noexcept {
  const double L = loaded_length > 0 ? loaded_length : length();
  return L > 0 ? -force.dot(servo_normal) / L : 0.0;
}

void TerrainSegments::add_polyline(const std::vector<Vec2>& pts, double friction, double restitution,
                                   double rolling_friction) {
  for (std::size_t k = 0; k + 1 < pts.size(); ++k) {
    WallSegment s;
    s.a = pts[k];
    s.b = pts[k + 1];
    s.friction = friction;
    s.restitution = restitution;
    s.rolling_friction = rolling_friction;
    s.joined_prev = k > 0;
    s.joined_next = k + 2 < pts.size();
    segs_.push_back(s);
  }
}

void TerrainSegments::build(double reach) {
  start_.clear();
  index_.clear();
  if (segs_.empty()) return;
  double lo = std::numeric_limits<double>::max(), hi = std::numeric_limits<double>::lowest();
  for (const auto& s : segs_) {
    lo = std::min({lo, s.a.x(), s.b.x()});
    hi = std::max({hi, s.a.x(), s.b.x()});
  }
  lo -= reach;
  hi += reach;
  const std::size_t nb = std::clamp<std::size_t>(segs_.size(), 1, 1 << 16);
  x0_ = lo;
  dx_ = std::max((hi - lo) / static_cast<double>(nb), 1e-12);
  std::vector<std::vector<std::uint32_t>> bins(nb);
  for (std::size_t k = 0; k < segs_.size(); ++k) {
    const double a = std::min(segs_[k].a.x(), segs_[k].b.x()) - reach;
    const double b = std::max(segs_[k].a.x(), segs_[k].b.x()) + reach;
    const auto c0 = static_cast<std::size_t>(std::clamp((a - x0_) / dx_, 0.0, static_cast<double>(nb - 1)));
    const auto c1 = static_cast<std::size_t>(std::clamp((b - x0_) / dx_, 0.0, static_cast<double>(nb - 1)));
    for (std::size_t c = c0; c <= c1; ++c) bins[c].push_back(static_cast<std::uint32_t>(k));
  }
  start_.assign(nb + 1, 0);
  for (std::size_t c = 0; c < nb; ++c) {
    start_[c + 1] = start_[c] + static_cast<std::uint32_t>(bins[c].size());
    index_.insert(index_.end(), bins[c].begin(), bins[c].end());
  }
}

std::pair<const std::uint32_t*, const std::uint32_t*> TerrainSegments::candidates(double x) const noexcept {
  if (start_.empty()) return {nullptr, nullptr};
  const double u = (x - x0_) / dx_;
  if (!(u >= 0) || u >= static_cast<double>(start_.size() - 1)) return {nullptr, nullptr};
  const auto c = static_cast<std::size_t>(u);
  return {index_.data() + start_[c], index_.data() + start_[c + 1]};
}

bool TerrainSegments::near(const Vec2& p, double dx, double reach) const noexcept {
  if (start_.empty()) return false;
  const double nb = static_cast<double>(start_.size() - 1);
  const double u0 = (p.x() - dx - x0_) / dx_, u1 = (p.x() + dx - x0_) / dx_;
  if (!(u1 >= 0) || !(u0 < nb)) return false;  // candidates() is empty along the whole interval
  const auto c0 = static_cast<std::size_t>(std::max(u0, 0.0));
  const auto c1 = static_cast<std::size_t>(std::min(u1, nb - 1.0));
  const double g = reach + dx;
  for (std::uint32_t q = start_[c0]; q < start_[c1 + 1]; ++q) {
    const WallSegment& s = segs_[index_[q]];
    if (p.x() >= std::min(s.a.x(), s.b.x()) - g && p.x() <= std::max(s.a.x(), s.b.x()) + g &&
        p.y() >= std::min(s.a.y(), s.b.y()) - g && p.y() <= std::max(s.a.y(), s.b.y()) + g)
      return true;
  }
  return false;
}

double TerrainSegments::elevation(double x) const noexcept {
  double z = std::numeric_limits<double>::quiet_NaN();
  for (const auto& s : segs_) {
    const double a = std::min(s.a.x(), s.b.x()), b = std::max(s.a.x(), s.b.x());
    if (x < a || x > b || b == a) continue;
    const double t = (x - s.a.x()) / (s.b.x() - s.a.x());
    const double zz = s.a.y() + t * (s.b.y() - s.a.y());
    if (!(zz <= z)) z = zz;
  }
  return z;
}

}  // namespace geohaz::dem
