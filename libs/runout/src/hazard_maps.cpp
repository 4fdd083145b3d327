#include "geohaz/runout/hazard_maps.hpp"

#include <omp.h>

#include <algorithm>
#include <cmath>
#include <numbers>

#include "geohaz/core/kernels.hpp"
#include "geohaz/core/parallel.hpp"

namespace geohaz::runout {

HazardMaps::HazardMaps(GridGeometry grid, double d0, double density, double sparse_min_depth)
    : g_(grid),
      d0_(d0),
      density_(density),
      radius_(std::max({0.5 * d0, grid.dx, grid.dy})),
      self_weight_(CubicSpline<2>::value(0.0, d0)),
      sparse_min_depth_(sparse_min_depth),
      max_depth_(grid.cells(), 0.0),
      max_speed_(grid.cells(), 0.0),
      max_momentum_(grid.cells(), 0.0),
      arrival_(grid.cells(), std::numeric_limits<double>::quiet_NaN()) {}

std::vector<double> HazardMaps::painted_depth(const RunoutStore& store) {
  const auto& x = store.get<Position<2>>();
  const auto& h = store.get<FlowDepth>();
  const auto& vol = store.get<Volume>();
  const std::size_t n = store.size();
  double total = 0.0;
  for (double v : vol) total += v;
  std::vector<double> depth(h.begin(), h.end());
  // Alone within the support: no neighbour added a positive kernel weight (1e-9: the rounding).
  std::vector<std::size_t> lone;
  double reach = 0.0;  // the farthest a nearest particle can be and still give sparse_min_depth
  for (std::size_t i = 0; i < n; ++i)
    if (h[i] <= vol[i] * self_weight_ * (1.0 + 1e-9) && vol[i] < kDetachedShare * total) {
      lone.push_back(i);
      reach = std::max(reach, std::sqrt(vol[i] / sparse_min_depth_));
    }
  if (lone.empty()) return depth;
  // Nearest particle within `reach`: particles bucketed by cells of side `reach` over their bounding
  // box (counting sort), the 3 × 3 cells around each lone particle searched.
  Vec2 lo = x[0], hi = x[0];
  for (std::size_t i = 1; i < n; ++i) {
    lo = lo.cwiseMin(x[i]);
    hi = hi.cwiseMax(x[i]);
  }
  const double cs = std::max(reach, 2.0 * d0_);
  const auto ncx = static_cast<std::int64_t>((hi.x() - lo.x()) / cs) + 1,
             ncy = static_cast<std::int64_t>((hi.y() - lo.y()) / cs) + 1;
  const auto cell_of = [&](const Vec2& p, std::int64_t& cx, std::int64_t& cy) {
    cx = std::min(ncx - 1, static_cast<std::int64_t>((p.x() - lo.x()) / cs));
    cy = std::min(ncy - 1, static_cast<std::int64_t>((p.y() - lo.y()) / cs));
  };
  bucket_start_.assign(static_cast<std::size_t>(ncx * ncy + 1), 0);
  std::int64_t cx, cy;
  for (std::size_t i = 0; i < n; ++i) {
    cell_of(x[i], cx, cy);
    ++bucket_start_[static_cast<std::size_t>(cy * ncx + cx + 1)];
  }
  for (std::size_t k = 1; k < bucket_start_.size(); ++k) bucket_start_[k] += bucket_start_[k - 1];
  bucket_items_.assign(n, 0);
  std::vector<std::int64_t> fill(bucket_start_.begin(), bucket_start_.end() - 1);
  for (std::size_t i = 0; i < n; ++i) {
    cell_of(x[i], cx, cy);
    bucket_items_[static_cast<std::size_t>(fill[static_cast<std::size_t>(cy * ncx + cx)]++)] = i;
  }
  for (std::size_t i : lone) {
    cell_of(x[i], cx, cy);
    double s2 = std::numeric_limits<double>::infinity();
    for (std::int64_t y = std::max<std::int64_t>(0, cy - 1); y <= std::min(ncy - 1, cy + 1); ++y)
      for (std::int64_t xx = std::max<std::int64_t>(0, cx - 1); xx <= std::min(ncx - 1, cx + 1); ++xx) {
        const auto b = static_cast<std::size_t>(y * ncx + xx);
        for (auto k = bucket_start_[b]; k < bucket_start_[b + 1]; ++k) {
          const std::size_t j = bucket_items_[static_cast<std::size_t>(k)];
          if (j != i) s2 = std::min(s2, (x[j] - x[i]).squaredNorm());
        }
      }
    // Never more than its kernel depth (a neighbour just outside the support).
    const double d = std::min(h[i], vol[i] / s2);
    depth[i] = d > sparse_min_depth_ ? d : 0.0;
  }
  return depth;
}

void HazardMaps::record(const RunoutStore& store, double t) {
  const auto& x = store.get<Position<2>>();
  const auto& s = store.get<Speed>();
  const auto& moving = store.get<Moving>();
  const auto& id = store.get<ParticleId>();
  const auto& vol = store.get<Volume>();
  // Serial tally by id (store order does not matter): who is detached now, where they were.
  paint_ = painted_depth(store);
  detached_now_.assign(store.size(), 0);
  for (std::size_t i = 0; i < store.size(); ++i) {
    const auto k = static_cast<std::size_t>(id[i]);
    if (k >= seen_.size()) {
      const std::size_t n = std::max<std::size_t>(k + 1, 2 * seen_.size());
      seen_.resize(n, 0);
      was_detached_.resize(n, 0);
      detached_at_.resize(n, Vec2::Zero());
      last_seen_.resize(n, Vec2::Zero());
      id_volume_.resize(n, 0.0);
    }
    seen_[k] = 1;
    last_seen_[k] = x[i];
    id_volume_[k] = vol[i];
    if (paint_[i] > 0.0) continue;
    detached_now_[i] = 1;
    if (!was_detached_[k]) {
      was_detached_[k] = 1;
      detached_at_[k] = x[i];
    }
  }
  const int rc = static_cast<int>(std::ceil(radius_ / g_.dx)), rr = static_cast<int>(std::ceil(radius_ / g_.dy));
  const double r2 = radius_ * radius_;
  const std::int64_t n = static_cast<std::int64_t>(store.size());
  // Threads own bands of grid rows, split so that each has about as many particles; every thread
  // runs over all particles and paints only the rows of its band. Maxima and the first arrival
  // (one t per call) do not depend on the order of painting, so the maps are the same for any
  // number of threads, and no two threads write the same cell.
  const int threads = parallel_worth(n) ? omp_get_max_threads() : 1;
  band_start_.assign(static_cast<std::size_t>(threads) + 1, 0);
  band_start_.back() = g_.ny;
  if (threads > 1) {
    row_count_.assign(static_cast<std::size_t>(g_.ny), 0);
    int c0, r0;
    for (std::int64_t i = 0; i < n; ++i)
      if (g_.cell_of(x[static_cast<std::size_t>(i)], c0, r0)) ++row_count_[static_cast<std::size_t>(r0)];
    std::int64_t seen = 0;
    int band = 1;
    for (int r = 0; r < g_.ny && band < threads; ++r) {
      seen += row_count_[static_cast<std::size_t>(r)];
      while (band < threads && seen * threads >= n * band) band_start_[static_cast<std::size_t>(band++)] = r + 1;
    }
    for (; band < threads; ++band) band_start_[static_cast<std::size_t>(band)] = g_.ny;
  }
#pragma omp parallel num_threads(threads) if (threads > 1)
  {
    const auto b = static_cast<std::size_t>(omp_get_thread_num());
    const int row_lo = band_start_[b], row_hi = band_start_[b + 1] - 1;  // inclusive
    for (std::int64_t ii = 0; ii < n && row_lo <= row_hi; ++ii) {
      const auto i = static_cast<std::size_t>(ii);
      int c0, r0;
      if (detached_now_[i] || !g_.cell_of(x[i], c0, r0)) continue;
      const int r_first = std::max(row_lo, r0 - rr), r_last = std::min(row_hi, r0 + rr);
      if (r_first > r_last) continue;
      const double hi = paint_[i], si = s[i];
      const bool arrives = moving[i] || t == 0.0;
      for (int r = r_first; r <= r_last; ++r)
        for (int c = std::max(0, c0 - rc); c <= std::min(g_.nx - 1, c0 + rc); ++c) {
          if (!paints(x[i], c0, r0, c, r, r2)) continue;
          const std::size_t k = g_.index(c, r);
          max_depth_[k] = std::max(max_depth_[k], hi);
          max_speed_[k] = std::max(max_speed_[k], si);
          max_momentum_[k] = std::max(max_momentum_[k], hi * si);
          if (arrives && std::isnan(arrival_[k])) arrival_[k] = t;
        }
    }
  }
}

void HazardMaps::painted_at(const RunoutStore& store, const std::vector<std::size_t>& cells, std::vector<double>& depth,
                            std::vector<double>& speed) const {
  depth.assign(cells.size(), 0.0);
  speed.assign(cells.size(), 0.0);
  const auto& x = store.get<Position<2>>();
  const auto& s = store.get<Speed>();
  if (paint_.size() != store.size()) return;  // no record() of this state
  if (cells.empty()) return;
  const int rc = static_cast<int>(std::ceil(radius_ / g_.dx)), rr = static_cast<int>(std::ceil(radius_ / g_.dy));
  // The cells' bounding box grown by the painting reach: a particle outside it paints none of them.
  const auto nx = static_cast<std::size_t>(g_.nx);
  int c_lo = g_.nx, c_hi = -1, r_lo = g_.ny, r_hi = -1;
  for (std::size_t cell : cells) {
    c_lo = std::min(c_lo, static_cast<int>(cell % nx));
    c_hi = std::max(c_hi, static_cast<int>(cell % nx));
    r_lo = std::min(r_lo, static_cast<int>(cell / nx));
    r_hi = std::max(r_hi, static_cast<int>(cell / nx));
  }
  for (std::size_t i = 0; i < store.size(); ++i) {
    int c0, r0;
    if (detached_now_[i] || !g_.cell_of(x[i], c0, r0)) continue;
    if (c0 < c_lo - rc || c0 > c_hi + rc || r0 < r_lo - rr || r0 > r_hi + rr) continue;
    for (std::size_t k = 0; k < cells.size(); ++k) {
      const int c = static_cast<int>(cells[k] % nx), r = static_cast<int>(cells[k] / nx);
      if (std::abs(c - c0) > rc || std::abs(r - r0) > rr || !paints(x[i], c0, r0, c, r, radius_ * radius_)) continue;
      depth[k] = std::max(depth[k], paint_[i]);
      speed[k] = std::max(speed[k], s[i]);
    }
  }
}

DetachedReport HazardMaps::detached_report(const RunoutStore& store) const {
  DetachedReport r;
  std::vector<std::uint8_t> present(seen_.size(), 0);
  for (auto k : store.get<ParticleId>())
    if (static_cast<std::size_t>(k) < present.size()) present[static_cast<std::size_t>(k)] = 1;
  // The raster's extent less 2·d0 and a cell: a particle last seen outside it left by the edge.
  const double margin = 2.0 * d0_ + std::max(g_.dx, g_.dy);
  const double xmin = g_.x0 + margin, xmax = g_.x0 + g_.nx * g_.dx - margin;
  const double ymax = g_.y0 - margin, ymin = g_.y0 - g_.ny * g_.dy + margin;
  for (std::size_t k = 0; k < seen_.size(); ++k) {
    if (!seen_[k]) continue;
    const bool gone = !present[k];
    if (gone) {
      const Vec2& p = last_seen_[k];
      r.exits.push_back(
          {p, id_volume_[k], was_detached_[k] != 0, p.x() < xmin || p.x() > xmax || p.y() < ymin || p.y() > ymax});
    }
    if (!was_detached_[k]) continue;
    r.volume += id_volume_[k];
    ++r.particles;
    if (gone) {
      r.lost_volume += id_volume_[k];
      ++r.lost_particles;
    } else {
      r.in_domain_volume += id_volume_[k];
    }
    const double dist = (last_seen_[k] - detached_at_[k]).norm();
    if (dist >= r.farthest_distance) {
      r.farthest_distance = dist;
      r.farthest = last_seen_[k];
    }
  }
  return r;
}

std::vector<double> HazardMaps::max_pressure() const {
  // ρ S² is increasing in S ≥ 0 and rounding is monotone, so the maximum over time of ρ·S·S
  // painted every step equals ρ·S_max·S_max exactly: the map is derived from max_speed.
  std::vector<double> p(max_speed_.size());
  for (std::size_t k = 0; k < p.size(); ++k) p[k] = density_ * max_speed_[k] * max_speed_[k];
  return p;
}

double HazardMaps::affected_area() const {
  std::size_t n = 0;
  for (double d : max_depth_)
    if (d > 0.0) ++n;
  return static_cast<double>(n) * g_.cell_area();
}

std::vector<double> HazardMaps::deposit(const RunoutStore& store, ParticleSelection which) const {
  std::vector<double> t(g_.cells(), 0.0);
  const auto& x = store.get<Position<2>>();
  const auto& vol = store.get<Volume>();
  const auto& moving = store.get<Moving>();
  const double support = 2.0 * d0_;
  const int rc = static_cast<int>(std::ceil(support / g_.dx)) + 1,
            rr = static_cast<int>(std::ceil(support / g_.dy)) + 1;
  for (std::size_t i = 0; i < store.size(); ++i) {
    if ((which == ParticleSelection::Resting && moving[i]) || (which == ParticleSelection::Moving && !moving[i]))
      continue;
    const double fc = (x[i].x() - g_.x0) / g_.dx, fr = (g_.y0 - x[i].y()) / g_.dy;
    const int c0 = static_cast<int>(std::floor(fc)), r0 = static_cast<int>(std::floor(fr));
    for (int r = std::max(0, r0 - rr); r <= std::min(g_.ny - 1, r0 + rr); ++r)
      for (int c = std::max(0, c0 - rc); c <= std::min(g_.nx - 1, c0 + rc); ++c) {
        const double d = (g_.centre(c, r) - x[i]).norm();
        if (d < support) t[g_.index(c, r)] += vol[i] * CubicSpline<2>::value(d, d0_);
      }
  }
  return t;
}

SeriesRow series_row(const RunoutStore& store, const VolumeBudget& budget, double t, std::int64_t step) {
  SeriesRow row;
  row.time = t;
  row.step = step;
  row.particles = store.size();
  row.volumes = budget;
  const auto& x = store.get<Position<2>>();
  const auto& path = store.get<PathLength>();
  const auto& s = store.get<Speed>();
  const auto& vol = store.get<Volume>();
  const auto& moving = store.get<Moving>();
  const auto& z = store.get<Elevation>();
  const auto& z0 = store.get<StartElevation>();
  double sv = 0.0, v = 0.0;
  std::size_t front = store.size();
  for (std::size_t i = 0; i < store.size(); ++i) {
    if (front == store.size() || path[i] > path[front]) front = i;
    row.max_speed = std::max(row.max_speed, s[i]);
    if (moving[i]) {
      sv += vol[i] * s[i];
      v += vol[i];
    }
  }
  if (v > 0.0) row.mean_speed = sv / v;
  if (front < store.size()) {
    row.front = x[front];
    row.front_travel = path[front];
    row.front_drop = z0[front] - z[front];
  }
  return row;
}

ReleaseTop release_top(const RunoutStore& store) {
  ReleaseTop top;
  const auto& z0 = store.get<StartElevation>();
  const auto& x0 = store.get<StartPosition>();
  for (std::size_t i = 0; i < store.size(); ++i)
    if (z0[i] > top.elevation) {
      top.elevation = z0[i];
      top.position = x0[i];
    }
  return top;
}

RunoutSummary summarise(const RunoutStore& store, const ReleaseTop& top) {
  RunoutSummary s;
  if (store.empty()) return s;
  const auto& path = store.get<PathLength>();
  const auto& x = store.get<Position<2>>();
  const auto& x0 = store.get<StartPosition>();
  const auto& z = store.get<Elevation>();
  const auto& z0 = store.get<StartElevation>();
  const auto& vol = store.get<Volume>();
  std::size_t toe = 0;
  double v = 0.0, zc = 0.0, zc0 = 0.0, pc = 0.0;
  for (std::size_t i = 0; i < store.size(); ++i) {
    if (path[i] > path[toe]) toe = i;
    v += vol[i];
    zc += vol[i] * z[i];
    zc0 += vol[i] * z0[i];
    pc += vol[i] * path[i];
  }
  s.runout_length = path[toe];
  s.toe = x[toe];
  s.drop_height = top.elevation - z[toe];
  s.reach = path[toe] + (x0[toe] - top.position).norm();
  if (s.reach > 0.0) {
    s.fahrboeschung = s.drop_height / s.reach;
    s.fahrboeschung_deg = std::atan(s.fahrboeschung) * 180.0 / std::numbers::pi;
  }
  s.com_drop = (zc0 - zc) / v;
  s.com_travel = pc / v;
  if (s.com_travel > 0.0) s.com_angle_deg = std::atan2(s.com_drop, s.com_travel) * 180.0 / std::numbers::pi;
  return s;
}

const char* to_string(IntensityScheme s) noexcept {
  return s == IntensityScheme::Pressure ? "pressure" : "depth_speed";
}

std::vector<double> intensity_classes(const std::vector<double>& depth, const std::vector<double>& speed,
                                      double density, const IntensityTable& t) {
  std::vector<double> c(depth.size(), 0.0);
  for (std::size_t k = 0; k < c.size(); ++k) {
    if (!(depth[k] > t.min_depth)) continue;  // not reached
    if (t.scheme == IntensityScheme::DepthSpeed) {
      c[k] = (depth[k] > t.strong_depth && speed[k] > t.strong_speed) ? 3.0 : 2.0;
    } else {
      const double p = density * speed[k] * speed[k];
      c[k] = p >= t.strong_pressure ? 3.0 : p >= t.medium_pressure ? 2.0 : 1.0;
    }
  }
  return c;
}

std::vector<double> intensity_classes(const HazardMaps& maps, const IntensityTable& t) {
  return intensity_classes(maps.max_depth(), maps.max_speed(), maps.density(), t);
}

}  // namespace geohaz::runout
