#include "geohaz/dem/joints.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <random>

namespace geohaz::dem {

namespace {

double orient(const Vec2& a, const Vec2& b, const Vec2& c) noexcept {
  return (b.x() - a.x()) * (c.y() - a.y()) - (b.y() - a.y()) * (c.x() - a.x());
}

/// Clip the infinite line p + s·d to the box; returns false when it misses (Liang–Barsky).
bool clip_line(const Vec2& p, const Vec2& d, const Vec2& lo, const Vec2& hi, double& s0, double& s1) {
  s0 = -1e300;
  s1 = 1e300;
  for (int k = 0; k < 2; ++k) {
    if (std::abs(d[k]) < 1e-300) {
      if (p[k] < lo[k] || p[k] > hi[k]) return false;
      continue;
    }
    double a = (lo[k] - p[k]) / d[k], b = (hi[k] - p[k]) / d[k];
    if (a > b) std::swap(a, b);
    s0 = std::max(s0, a);
    s1 = std::min(s1, b);
  }
  return s1 > s0;
}

}  // namespace

bool segments_intersect(const Vec2& a, const Vec2& b, const Vec2& c, const Vec2& d) noexcept {
  const double o1 = orient(a, b, c), o2 = orient(a, b, d), o3 = orient(c, d, a), o4 = orient(c, d, b);
  return ((o1 > 0) != (o2 > 0)) && ((o3 > 0) != (o4 > 0)) && o1 != 0 && o2 != 0 && o3 != 0 && o4 != 0;
}

std::vector<JointTrace> generate_joint_traces(const std::vector<JointSet>& sets, const Vec2& lo, const Vec2& hi,
                                              std::uint64_t seed) {
  std::vector<JointTrace> out;
  std::mt19937_64 rng(seed ^ 0xA5A5A5A5ULL);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  const Vec2 centre = 0.5 * (lo + hi);
  const double diag = (hi - lo).norm();
  for (std::size_t k = 0; k < sets.size(); ++k) {
    const JointSet& js = sets[k];
    const double th = js.dip * std::numbers::pi / 180.0;
    const Vec2 d(std::cos(th), std::sin(th));
    const Vec2 nrm(-d.y(), d.x());
    const double offset = js.spacing * u(rng);
    const int nlines = static_cast<int>(std::ceil(diag / js.spacing)) + 1;
    for (int l = -nlines; l <= nlines; ++l) {
      const Vec2 p = centre + (l * js.spacing + offset - 0.5 * js.spacing) * nrm;
      double s0, s1;
      if (!clip_line(p, d, lo, hi, s0, s1)) continue;
      if (js.persistence >= 1.0) {
        out.push_back({p + s0 * d, p + s1 * d, static_cast<int>(k)});
        continue;
      }
      const double Lj = js.trace_length, Lb = Lj * (1.0 - js.persistence) / js.persistence;
      double s = s0 - (Lj + Lb) * u(rng);
      while (s < s1) {
        const double a = std::max(s, s0), b = std::min(s + Lj, s1);
        if (b > a) out.push_back({p + a * d, p + b * d, static_cast<int>(k)});
        s += Lj + Lb;
      }
    }
  }
  return out;
}

std::vector<JointPair> cut_bonds_by_traces(const DiscStore& discs, BondTable& bonds,
                                           const std::vector<JointTrace>& traces, DiscontinuityReport* report,
                                           double area) {
  const auto& x = discs.get<Position<2>>();
  const auto& ids = discs.get<ParticleId>();
  std::int64_t max_id = -1;
  for (auto id : ids) max_id = std::max(max_id, id);
  std::vector<std::uint32_t> index(static_cast<std::size_t>(max_id + 1), 0);
  for (std::size_t i = 0; i < ids.size(); ++i) index[static_cast<std::size_t>(ids[i])] = static_cast<std::uint32_t>(i);
  std::vector<JointPair> pairs;
  std::size_t cut = 0;
  for (std::size_t b = 0; b < bonds.size(); ++b) {
    if (bonds.state[b] != BondState::Intact) continue;
    const Vec2& xa = x[index[bonds.id_a[b]]];
    const Vec2& xb = x[index[bonds.id_b[b]]];
    for (const auto& t : traces) {
      if (!segments_intersect(xa, xb, t.a, t.b)) continue;
      bonds.state[b] = BondState::CutByJoint;
      const Vec2 d = (t.b - t.a).normalized();
      pairs.push_back({bonds.id_a[b], bonds.id_b[b], Vec2(-d.y(), d.x())});
      ++cut;
      break;
    }
  }
  if (report) {
    report->traces = traces.size();
    report->bonds_cut = cut;
    report->total_length = 0;
    int nsets = 0;
    for (const auto& t : traces) {
      report->total_length += (t.b - t.a).norm();
      nsets = std::max(nsets, t.set + 1);
    }
    report->intensity_p21 = area > 0 ? report->total_length / area : 0.0;
    report->set_dip.assign(static_cast<std::size_t>(nsets), 0.0);
    report->set_traces.assign(static_cast<std::size_t>(nsets), 0);
    report->set_length.assign(static_cast<std::size_t>(nsets), 0.0);
    for (const auto& t : traces) {
      if (t.set < 0) continue;
      const Vec2 d = t.b - t.a;
      report->set_dip[t.set] = std::atan2(d.y(), d.x()) * 180.0 / std::numbers::pi;
      report->set_traces[t.set] += 1;
      report->set_length[t.set] += d.norm();
    }
  }
  return pairs;
}

}  // namespace geohaz::dem
