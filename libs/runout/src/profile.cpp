/// \file profile.cpp
/// The thalweg long profile (profile.hpp).

#include "geohaz/runout/profile.hpp"

#include <algorithm>
#include <cmath>
#include <iomanip>
#include <sstream>
#include <string>

#include "geohaz/core/errors.hpp"
#include "geohaz/core/output.hpp"
#include "geohaz/core/plot.hpp"

namespace geohaz::runout {

namespace {

/// The value of the map cell holding (x, y); 0 outside, for nodata and NaN.
double cell_value(const Raster& r, double x, double y) {
  const int c = static_cast<int>(std::floor((x - r.geotransform[0]) / r.geotransform[1]));
  const int row = static_cast<int>(std::floor((y - r.geotransform[3]) / r.geotransform[5]));
  if (c < 0 || row < 0 || c >= r.nx || row >= r.ny) return 0.0;
  const double v = r.at(c, row);
  return std::isfinite(v) && !r.is_nodata(v) ? v : 0.0;
}

}  // namespace

std::vector<Vec2> flow_centreline(const Vec2& start, const std::vector<Vec2>& fronts, double min_spacing) {
  std::vector<Vec2> out{start};
  double reach = 0.0;  // distance from the start of the last point kept
  for (const Vec2& p : fronts) {
    if (!std::isfinite(p.x()) || !std::isfinite(p.y())) continue;
    const double d = (p - start).norm();
    if (d >= reach + min_spacing) {
      out.push_back(p);
      reach = d;
    }
  }
  return out;
}

std::vector<Vec2> arrival_centreline(const Raster& arrival_time, const Raster& max_depth, const Vec2& start, double dt,
                                     double min_spacing) {
  if (!(dt > 0.0) || arrival_time.nx != max_depth.nx || arrival_time.ny != max_depth.ny) return {start};
  double t_end = 0.0;
  for (double t : arrival_time.data)
    if (std::isfinite(t) && !arrival_time.is_nodata(t) && t >= 0.0) t_end = std::max(t_end, t);
  const std::size_t bins = static_cast<std::size_t>(std::floor(t_end / dt)) + 1;
  if (bins > 10'000'000) return {start};
  std::vector<double> w(bins, 0.0), wx(bins, 0.0), wy(bins, 0.0);
  for (int row = 0; row < arrival_time.ny; ++row)
    for (int col = 0; col < arrival_time.nx; ++col) {
      const double t = arrival_time.at(col, row), h = max_depth.at(col, row);
      if (!std::isfinite(t) || arrival_time.is_nodata(t) || t < 0.0) continue;
      if (!std::isfinite(h) || max_depth.is_nodata(h) || !(h > 0.0)) continue;
      const std::size_t b = std::min(bins - 1, static_cast<std::size_t>(std::floor(t / dt)));
      const Vec2 c = arrival_time.cell_centre(col, row);
      w[b] += h;
      wx[b] += h * c.x();
      wy[b] += h * c.y();
    }
  std::vector<Vec2> centroids;
  for (std::size_t b = 0; b < bins; ++b)
    if (w[b] > 0.0) centroids.emplace_back(wx[b] / w[b], wy[b] / w[b]);
  return flow_centreline(start, centroids, min_spacing);
}

ThalwegProfile thalweg_profile(const Raster& dsm, const Raster& max_depth, const Raster& max_speed,
                               const Raster& max_pressure, const std::vector<Vec2>& path, double spacing,
                               double min_depth, double half_width) {
  if (path.size() < 2 || !(spacing > 0.0) || !(half_width >= 0.0))
    throw InputError("a profile needs a path of at least two points and a positive spacing", "profile");
  for (const Raster* m : {&max_depth, &max_speed, &max_pressure})
    if (m->nx != dsm.nx || m->ny != dsm.ny)
      throw InputError("the peak maps of a profile must be on the DSM's grid", "profile");
  const Terrain terrain(dsm);
  ThalwegProfile p;
  p.half_width = half_width;
  double s0 = 0.0;
  // Offsets across the path: 0, then ±k·step out to the half-width (step ≤ half a cell).
  std::vector<double> across{0.0};
  if (half_width > 0.0) {
    const double cell = std::min(dsm.cell_size_x(), dsm.cell_size_y());
    const int n = static_cast<int>(std::ceil(half_width / (0.5 * cell) - 1e-9));
    for (int k = 1; k <= n; ++k)
      for (double sign : {1.0, -1.0}) across.push_back(sign * half_width * k / n);
  }
  Vec2 normal(0.0, 0.0);  // of the current segment
  const auto peak = [&](const Raster& m, const Vec2& q) {
    double v = 0.0;
    for (double w : across) v = std::max(v, cell_value(m, q.x() + w * normal.x(), q.y() + w * normal.y()));
    return v;
  };
  const auto add = [&](const Vec2& q, double s) {
    const double z = terrain.elevation(q.x(), q.y());
    if (!std::isfinite(z))
      throw InputError("the profile path leaves the terrain's data at (" + std::to_string(q.x()) + ", " +
                           std::to_string(q.y()) + ")",
                       "profile");
    ProfileRow r;
    r.s = s;
    r.x = q.x();
    r.y = q.y();
    r.z = z;
    r.depth = peak(max_depth, q);
    r.speed = peak(max_speed, q);
    r.pressure = peak(max_pressure, q);
    p.rows.push_back(r);
  };
  for (std::size_t k = 1; k < path.size(); ++k) {  // the first station takes the first segment's normal
    const Vec2 e = path[k] - path[k - 1];
    if (e.norm() > 0.0) {
      normal = Vec2(e.y(), -e.x()) / e.norm();
      break;
    }
  }
  add(path.front(), 0.0);
  for (std::size_t k = 1; k < path.size(); ++k) {
    const Vec2 a = path[k - 1], b = path[k];
    const double len = (b - a).norm();
    if (!(len > 0.0)) continue;
    normal = Vec2(b.y() - a.y(), a.x() - b.x()) / len;
    const int n = std::max(1, static_cast<int>(std::ceil(len / spacing - 1e-9)));
    for (int i = 1; i <= n; ++i) add(a + (b - a) * (double(i) / n), s0 + len * double(i) / n);
    s0 += len;
  }
  if (p.rows.size() < 2) throw InputError("the profile path has no length", "profile");
  // Top and run-out point of the reached part, the α line through both.
  for (const ProfileRow& r : p.rows) {
    if (!(r.depth > min_depth)) continue;
    if (!p.reached || r.z > p.z_top) {
      p.s_top = r.s;
      p.z_top = r.z;
    }
    if (!p.reached || r.s > p.s_runout) {
      p.s_runout = r.s;
      p.z_runout = r.z;
    }
    p.reached = true;
  }
  const double run = p.s_runout - p.s_top;
  const double tan_alpha = p.reached && run > 0.0 ? (p.z_top - p.z_runout) / run : 0.0;
  p.alpha_deg = std::atan(tan_alpha) * 180.0 / M_PI;
  for (ProfileRow& r : p.rows) r.alpha_z = p.z_top - tan_alpha * (r.s - p.s_top);
  return p;
}

void check_profile_path(const std::vector<Vec2>& path, const Raster& dsm, const std::string& source,
                        const std::string& key) {
  double length = 0.0;
  for (std::size_t k = 1; k < path.size(); ++k) length += (path[k] - path[k - 1]).norm();
  if (path.size() < 2 || !(length > 0.0))
    throw InputError("a profile path needs two or more distinct vertices [x1, y1, x2, y2, ...] (m)", source, key);
  const Terrain terrain(dsm);
  const double step = std::min(dsm.cell_size_x(), dsm.cell_size_y());
  const auto ext = dsm.extent();
  const auto check = [&](const Vec2& q) {
    if (std::isfinite(terrain.elevation(q.x(), q.y()))) return;
    std::ostringstream m, at;
    at << std::fixed << std::setprecision(1) << "(" << q.x() << ", " << q.y() << ")";
    m << std::fixed << std::setprecision(1) << "the profile path leaves the terrain's data at " << at.str()
      << "; allowed: on the DSM's data, inside x in [" << ext[0].x() << ", " << ext[1].x() << "] m, y in ["
      << ext[0].y() << ", " << ext[1].y() << "] m (the DSM's CRS)";
    throw InputError(m.str(), source, key, at.str());
  };
  check(path.front());
  for (std::size_t k = 1; k < path.size(); ++k) {
    const double len = (path[k] - path[k - 1]).norm();
    const int n = std::max(1, static_cast<int>(std::ceil(len / step)));
    for (int i = 1; i <= n; ++i) check(path[k - 1] + (path[k] - path[k - 1]) * (double(i) / n));
  }
}

void write_profile_csv(const std::filesystem::path& path, const ThalwegProfile& p) {
  AtomicTextFile csv(path);
  csv << "s_along_path_m,x_m,y_m,terrain_elevation_m,max_depth_m,max_speed_m_per_s,max_pressure_Pa,"
         "alpha_line_elevation_m\n";
  csv.stream() << std::setprecision(10);
  for (const ProfileRow& r : p.rows)
    csv << r.s << ',' << r.x << ',' << r.y << ',' << r.z << ',' << r.depth << ',' << r.speed << ',' << r.pressure << ','
        << r.alpha_z << '\n';
  csv.commit();
}

ProfileReach profile_reach(const ThalwegProfile& p) noexcept {
  ProfileReach r;
  if (!p.reached) return r;
  r.drop_height = p.z_top - p.z_runout;
  r.length = p.s_runout - p.s_top;
  r.ratio = r.length > 0.0 ? r.drop_height / r.length : 0.0;
  return r;
}

namespace {

/// A straight line from (s0, z0) to (s1, z1) drawn in dashes of about 24 px.
void dashed(Image& img, const PlotPanel& f, double s0, double z0, double s1, double z1, std::array<std::uint8_t, 3> c,
            int width) {
  const double px = std::hypot(f.px(s1) - f.px(s0), f.py(z1) - f.py(z0));
  const int n = std::max(1, static_cast<int>(px / 24.0));
  for (int k = 0; k < n; k += 2) {
    const double a = double(k) / n, b = double(k + 1) / n;
    draw_polyline(img, f, {s0 + a * (s1 - s0), s0 + b * (s1 - s0)}, {z0 + a * (z1 - z0), z0 + b * (z1 - z0)}, c, width);
  }
}

}  // namespace

void write_profile_png(const std::filesystem::path& path, const ThalwegProfile& p, const ProfileFigure& f) {
  const int W = 1800, H = 1250, s = 3;
  Image img(W, H);
  std::vector<double> sv, z, top, speed;
  double zlo = 1e300, zhi = -1e300, vmax = 0.0, dmax = 0.0;
  for (const ProfileRow& r : p.rows) {
    zlo = std::min(zlo, r.z);
    zhi = std::max(zhi, r.z);
    vmax = std::max(vmax, r.speed);
    dmax = std::max(dmax, r.depth);
  }
  // The depth drawn above the terrain, exaggerated so that the deepest point shows as 4 % of the
  // elevation range (a factor of 1, 2 or 5 × 10^k).
  double ex = 1.0;
  if (dmax > 0.0) {
    const double want = 0.04 * std::max(1.0, zhi - zlo) / dmax;
    const double p10 = std::pow(10.0, std::floor(std::log10(want)));
    ex = want >= 5 * p10 ? 5 * p10 : want >= 2 * p10 ? 2 * p10 : p10;
    ex = std::max(1.0, ex);
  }
  for (const ProfileRow& r : p.rows) {
    sv.push_back(r.s);
    z.push_back(r.z);
    top.push_back(r.z + ex * r.depth);
    speed.push_back(r.speed);
  }
  const double pad = 0.05 * std::max(1.0, zhi - zlo);
  const PlotPanel upper{sv.front(), sv.back(), zlo - pad, zhi + pad, 170, 90, W - 230, 700};
  const PlotPanel lower{sv.front(), sv.back(), 0.0, vmax > 0.0 ? 1.1 * vmax : 1.0, 170, 960, W - 230, 200};
  const std::array<std::uint8_t, 3> red{200, 40, 40}, orange{230, 140, 20};
  if (!f.title.empty()) draw_text(img, upper.left, 12, f.title, s);
  // The flow (depth above the terrain) filled, then the terrain, the α line, the run-out point.
  for (std::size_t k = 0; k < sv.size(); ++k)
    if (top[k] > z[k]) img.line(upper.px(sv[k]), upper.py(z[k]), upper.px(sv[k]), upper.py(top[k]), {70, 130, 200});
  draw_axes(img, upper, "horizontal distance along the path (m)", "elevation (m)", s);
  draw_polyline(img, upper, sv, top, {40, 90, 170}, 2);
  draw_polyline(img, upper, sv, z, {30, 30, 30}, 3);
  // Legend lines right-aligned at the top of the panel, where the terrain has fallen away.
  int ly = upper.top + 20;
  const auto legend = [&](const std::string& text, std::array<std::uint8_t, 3> c) {
    draw_text(img, upper.left + upper.width - 20 - text_width(text, 2), ly, text, 2, c);
    ly += 30;
  };
  legend(
      "terrain (black), peak depth x " + format_tick(ex) + " above it (blue)" +
          (p.half_width > 0.0 ? "; peaks: the largest within " + format_tick(p.half_width) + " m across the path" : ""),
      {0, 0, 0});
  char buf[240];
  if (p.reached) {
    const ProfileReach reach = profile_reach(p);
    // The toe path's H/L (summary.json), dashed from the same top down to the panel's floor.
    if (std::isfinite(f.toe_path_angle_deg) && f.toe_path_angle_deg > 0.0) {
      const double t = std::tan(f.toe_path_angle_deg * M_PI / 180.0);
      const double s_end = std::min(sv.back(), p.s_top + (p.z_top - upper.y0) / t);
      dashed(img, upper, p.s_top, p.z_top, s_end, p.z_top - t * (s_end - p.s_top), orange, 3);
    }
    draw_polyline(img, upper, {p.s_top, p.s_runout}, {p.z_top, p.z_runout}, red, 2);
    img.fill_circle(upper.px(p.s_runout), upper.py(p.z_runout), 9, red);
    img.fill_circle(upper.px(p.s_top), upper.py(p.z_top), 7, red);
    std::snprintf(buf, sizeof buf,
                  "α along the profile (red): %.1f°, H/L = %.3f (H = %.0f m, L = %.0f m); run-out point "
                  "at s = %.0f m",
                  p.alpha_deg, reach.ratio, reach.drop_height, reach.length, p.s_runout);
    legend(buf, red);
    if (std::isfinite(f.toe_path_angle_deg)) {
      std::snprintf(buf, sizeof buf,
                    "H/L of the toe path (orange, dashed; summary.json fahrboeschung): %.1f°, H/L = %.3f",
                    f.toe_path_angle_deg, std::tan(f.toe_path_angle_deg * M_PI / 180.0));
      legend(buf, orange);
    }
  } else {
    legend("the flow did not reach the path", red);
  }
  for (const ProfileMark& m : f.marks) {
    if (!std::isfinite(m.s)) continue;
    const double x = std::round(upper.px(std::clamp(m.s, upper.x0, upper.x1)));
    for (int y = upper.top; y < upper.top + upper.height; y += m.dashed ? 40 : upper.height) {
      const int y1 = std::min(upper.top + upper.height, y + (m.dashed ? 20 : upper.height));
      for (int o = -1; o <= 1; ++o) img.line(x + o, y, x + o, y1, m.colour);
    }
    legend(m.label, m.colour);
  }
  draw_axes(img, lower, "horizontal distance along the path (m)", "peak speed (m/s)", s);
  draw_polyline(img, lower, sv, speed, {150, 60, 150}, 2);
  write_png(path, img);
}

}  // namespace geohaz::runout
