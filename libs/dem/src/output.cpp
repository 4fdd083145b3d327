#include "geohaz/dem/output.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <iomanip>
#include <sstream>
#include <string>

#include "geohaz/core/output.hpp"
#include "geohaz/core/raster.hpp"

namespace geohaz::dem {

void write_snapshot(SnapshotWriter& w, const DemSolver& s) {
  const auto& d = s.discs;
  auto view = [&](auto tag) {
    using Tag = decltype(tag);
    using Tr = FieldTraits<typename Tag::type>;
    const auto& v = d.template get<Tag>();
    return FieldView{Tag::label, Tag::unit, scalar_type_of<typename Tr::scalar>(), v.data(), v.size(),
                     Tr::rows,   Tr::cols};
  };
  std::vector<FieldView> fields{view(Position<2>{}), view(Velocity<2>{}), view(Rotation{}),   view(AngularVelocity{}),
                                view(Radius{}),      view(Mass{}),        view(ParticleId{}), view(BrokenBonds{}),
                                view(IntactBonds{}), view(Fragment{}),    view(Force{})};
  std::vector<std::uint32_t> lines;
  for (std::size_t b = 0; b < s.bonds.size(); ++b) {
    if (s.bonds.state[b] != BondState::Intact) continue;
    lines.push_back(s.index_of(s.bonds.id_a[b]));
    lines.push_back(s.index_of(s.bonds.id_b[b]));
  }
  w.write(s.time(), s.step_count(), fields, lines);
}

std::string curve_csv(const std::vector<CurvePoint>& curve) {
  std::ostringstream o;
  o << std::setprecision(9);
  o << "time_s,axial_strain,lateral_strain,volumetric_strain,axial_stress_Pa,lateral_stress_Pa,ae_count,ae_energy_J_"
       "per_m,"
       "broken_bonds_total\n";
  for (const auto& p : curve)
    o << p.time << ',' << p.axial_strain << ',' << p.lateral_strain << ',' << p.volumetric_strain << ','
      << p.axial_stress << ',' << p.lateral_stress << ',' << p.ae_count << ',' << p.ae_energy << ',' << p.broken_total
      << '\n';
  return o.str();
}

void write_curve_csv(const std::filesystem::path& path, const std::vector<CurvePoint>& curve) {
  write_text_file(path, curve_csv(curve));
}

std::string ae_csv(const std::vector<AcousticEvent>& events) {
  std::ostringstream o;
  o << std::setprecision(9);
  o << "time_s,x_m,y_m,mode,energy_J_per_m,bond\n";
  for (const auto& e : events)
    o << e.time << ',' << e.position.x() << ',' << e.position.y() << ','
      << (e.mode == FailureMode::Tensile ? "tensile" : "shear") << ',' << e.energy << ',' << e.bond << '\n';
  return o.str();
}

void write_ae_csv(const std::filesystem::path& path, const std::vector<AcousticEvent>& events) {
  write_text_file(path, ae_csv(events));
}

std::string avalanche_csv(const std::vector<AvalanchePoint>& series) {
  std::ostringstream o;
  o << std::setprecision(9);
  o << "time_s,front_m,front_velocity_m_per_s,kinetic_energy_J_per_m,fragments,largest_fragment_discs,ae_count,"
       "ae_energy_J_per_m,max_speed_m_per_s,moving_mass_fraction\n";
  for (const auto& p : series)
    o << p.time << ',' << p.front << ',' << p.front_velocity << ',' << p.kinetic_energy << ',' << p.fragments << ','
      << p.largest_fragment << ',' << p.ae_count << ',' << p.ae_energy << ',' << p.max_speed << ',' << p.moving_fraction
      << '\n';
  return o.str();
}

void write_avalanche_csv(const std::filesystem::path& path, const std::vector<AvalanchePoint>& series) {
  write_text_file(path, avalanche_csv(series));
}

std::string deposit_csv(const std::vector<std::pair<double, double>>& deposit) {
  std::ostringstream o;
  o << std::setprecision(9) << "x_m,thickness_m\n";
  for (const auto& [x, h] : deposit) o << x << ',' << h << '\n';
  return o.str();
}

void write_deposit_csv(const std::filesystem::path& path, const std::vector<std::pair<double, double>>& deposit) {
  write_text_file(path, deposit_csv(deposit));
}

namespace {

struct Frame {
  Vec2 lo, hi;
  int w, h;
  double scale;
  double px(double x) const { return (x - lo.x()) * scale; }
  double py(double y) const { return h - 1 - (y - lo.y()) * scale; }
};

Frame make_frame(Vec2 lo, Vec2 hi, int width_px) {
  const Vec2 pad = 0.03 * (hi - lo) + Vec2::Constant(1e-9);
  lo -= pad;
  hi += pad;
  Frame f;
  f.lo = lo;
  f.hi = hi;
  f.w = std::max(16, width_px);
  f.scale = f.w / (hi.x() - lo.x());
  f.h = std::clamp(static_cast<int>((hi.y() - lo.y()) * f.scale), 16, 4 * f.w);
  return f;
}

/// One entry of a picture's legend: a colour swatch and its text.
struct LegendEntry {
  std::array<std::uint8_t, 3> colour;
  std::string text;
};

/// The picture `plot` drawn in `f` framed with numbered axes in metres (`x_title`, `y_title`), a
/// title above and a legend below.
Image with_axes(const Image& plot, const Frame& f, const std::string& title, const std::string& x_title,
                const std::string& y_title, const std::vector<LegendEntry>& legend) {
  constexpr int s = 2, ml = 110, mr = 30, mt = 56, mb = 70;
  const int th = 7 * s;
  // Legend rows.
  const int W = plot.width + ml + mr;
  std::vector<std::pair<int, int>> pos;
  int lx = ml, ly = mt + plot.height + mb;
  for (const auto& e : legend) {
    const int w = 14 * s + text_width(e.text, s);
    if (lx > ml && lx + w > W - mr) {
      lx = ml;
      ly += th + 8;
    }
    pos.emplace_back(lx, ly);
    lx += w + 20;
  }
  const int H = (legend.empty() ? mt + plot.height + mb : ly + th + 10);
  Image img(W, H);
  for (int y = 0; y < plot.height; ++y)
    for (int x = 0; x < plot.width; ++x) {
      const std::size_t i = (static_cast<std::size_t>(y) * plot.width + x) * 3;
      img.set(ml + x, mt + y, {plot.rgb[i], plot.rgb[i + 1], plot.rgb[i + 2]});
    }
  const std::array<std::uint8_t, 3> black{0, 0, 0};
  const int x0 = ml, x1 = ml + plot.width - 1, y0 = mt, y1 = mt + plot.height - 1;
  img.line(x0, y0, x1, y0, black);
  img.line(x0, y1, x1, y1, black);
  img.line(x0, y0, x0, y1, black);
  img.line(x1, y0, x1, y1, black);
  const double xlo = f.lo.x(), xhi = f.lo.x() + (plot.width - 1) / f.scale;
  const double ylo = f.lo.y(), yhi = f.lo.y() + (plot.height - 1) / f.scale;
  for (double v : nice_ticks(xlo, xhi, std::max(2, plot.width / 140))) {
    const int px = ml + static_cast<int>(std::lround(f.px(v)));
    img.line(px, y1, px, y1 + 6, black);
    const std::string t = format_tick(v);
    draw_text(img, px - text_width(t, s) / 2, y1 + 10, t, s);
  }
  for (double v : nice_ticks(ylo, yhi, std::max(2, plot.height / 90))) {
    const int py = mt + static_cast<int>(std::lround(f.py(v)));
    img.line(x0 - 6, py, x0, py, black);
    const std::string t = format_tick(v);
    draw_text(img, x0 - 10 - text_width(t, s), py - th / 2, t, s);
  }
  draw_text(img, ml + (plot.width - text_width(x_title, s)) / 2, y1 + 16 + th, x_title, s);
  draw_text(img, 8, mt - th - 8, y_title, s);
  draw_text(img, ml + (plot.width - text_width(title, s)) / 2, 8, title, s);
  for (std::size_t k = 0; k < legend.size(); ++k) {
    const auto [x, y] = pos[k];
    for (int a = 0; a < th; ++a)
      for (int b = 0; b < th; ++b) img.set(x + b, y + a, legend[k].colour);
    draw_text(img, x + th + 8, y, legend[k].text, s);
  }
  return img;
}

}  // namespace

void write_sample_png(const std::filesystem::path& path, const DemSolver& s, const std::string& title, int width_px) {
  const auto& x = s.discs.get<Position<2>>();
  const auto& R = s.discs.get<Radius>();
  Vec2 lo = Vec2::Constant(1e300), hi = Vec2::Constant(-1e300);
  for (std::size_t i = 0; i < s.discs.size(); ++i) {
    lo = lo.cwiseMin(x[i] - Vec2::Constant(R[i]));
    hi = hi.cwiseMax(x[i] + Vec2::Constant(R[i]));
  }
  const Frame f = make_frame(lo, hi, width_px);
  Image img(f.w, f.h);
  for (std::size_t i = 0; i < s.discs.size(); ++i)
    img.fill_circle(f.px(x[i].x()), f.py(x[i].y()), R[i] * f.scale, {215, 215, 215});
  for (const auto& w : s.walls)
    if (w.active) img.line(f.px(w.a.x()), f.py(w.a.y()), f.px(w.b.x()), f.py(w.b.y()), {0, 0, 0});
  for (std::size_t b = 0; b < s.bonds.size(); ++b) {
    std::array<std::uint8_t, 3> c{};
    switch (s.bonds.state[b]) {
      case BondState::Intact:
        c = {40, 90, 200};
        break;
      case BondState::BrokenTension:
        c = {220, 30, 30};
        break;
      case BondState::BrokenShear:
        c = {250, 150, 0};
        break;
      case BondState::CutByJoint:
        c = {20, 160, 60};
        break;
    }
    const Vec2& a = x[s.index_of(s.bonds.id_a[b])];
    const Vec2& bb = x[s.index_of(s.bonds.id_b[b])];
    if (s.bonds.state[b] == BondState::Intact) {
      img.line(f.px(a.x()), f.py(a.y()), f.px(bb.x()), f.py(bb.y()), c);
    } else {  // a crack: mark the bond centre boldly
      const Vec2 m = 0.5 * (a + bb);
      img.fill_circle(f.px(m.x()), f.py(m.y()), std::max(1.5, 0.4 * s.bonds.radius[b] * f.scale), c);
    }
  }
  write_png(path, with_axes(img, f, title, "x (m)", "y (m)",
                            {{{40, 90, 200}, "intact bond"},
                             {{220, 30, 30}, "tensile crack"},
                             {{250, 150, 0}, "shear crack"},
                             {{20, 160, 60}, "cut by a joint"}}));
}

void write_avalanche_png(const std::filesystem::path& path, const DemSolver& s, const std::vector<Vec2>& terrain,
                         const std::vector<Vec2>& source, int width_px) {
  Vec2 lo = Vec2::Constant(1e300), hi = Vec2::Constant(-1e300);
  for (const auto& p : terrain) {
    lo = lo.cwiseMin(p);
    hi = hi.cwiseMax(p);
  }
  for (const auto& p : source) {
    lo = lo.cwiseMin(p);
    hi = hi.cwiseMax(p);
  }
  const Frame f = make_frame(lo, hi, width_px);
  Image img(f.w, f.h);
  for (std::size_t k = 0; k + 1 < terrain.size(); ++k)
    img.line(f.px(terrain[k].x()), f.py(terrain[k].y()), f.px(terrain[k + 1].x()), f.py(terrain[k + 1].y()),
             {60, 40, 20});
  for (std::size_t k = 0; k < source.size(); ++k) {
    const Vec2& a = source[k];
    const Vec2& b = source[(k + 1) % source.size()];
    img.line(f.px(a.x()), f.py(a.y()), f.px(b.x()), f.py(b.y()), {150, 150, 150});
  }
  const auto& x = s.discs.get<Position<2>>();
  const auto& R = s.discs.get<Radius>();
  const auto& frag = s.discs.get<Fragment>();
  int maxf = 1;
  for (auto q : frag) maxf = std::max(maxf, q);
  for (std::size_t i = 0; i < s.discs.size(); ++i) {
    const double t = frag[i] <= 0 ? 0.0 : 0.15 + 0.85 * std::fmod(0.618034 * frag[i], 1.0);
    img.fill_circle(f.px(x[i].x()), f.py(x[i].y()), std::max(0.8, R[i] * f.scale), ramp_colour(ColourRamp::Viridis, t));
  }
  write_png(path, with_axes(img, f, "rock avalanche at the end (discs coloured by fragment)",
                            "distance along the section (m)", "elevation (m)",
                            {{{60, 40, 20}, "terrain"}, {{150, 150, 150}, "source outline"}}));
}

namespace {

/// A "nice" tick step (1, 2 or 5 × 10^k) giving about n ticks over span.
double nice_step(double span, int n) {
  const double raw = span / n, p = std::pow(10.0, std::floor(std::log10(raw)));
  for (double m : {1.0, 2.0, 5.0, 10.0})
    if (m * p >= raw) return m * p;
  return 10 * p;
}

std::string tick_label(double v, double step) {
  std::ostringstream o;
  o << std::fixed << std::setprecision(step >= 1 ? 0 : static_cast<int>(std::ceil(-std::log10(step)))) << v;
  return o.str();
}

}  // namespace

void write_deposit_png(const std::filesystem::path& path, const std::vector<std::pair<double, double>>& deposit) {
  const int W = 900, H = 380, ml = 90, mr = 20, mt = 30, mb = 56;
  Image img(W, H);
  double x0 = 0, x1 = 1, hmax = 0;
  if (!deposit.empty()) {
    x0 = deposit.front().first;
    x1 = deposit.back().first;
    for (const auto& d : deposit) hmax = std::max(hmax, d.second);
  }
  if (!(x1 > x0)) x1 = x0 + 1;
  const double xs = nice_step(x1 - x0, 8), ys = nice_step(std::max(hmax, 1e-3), 5);
  x0 = std::floor(x0 / xs) * xs;
  x1 = std::ceil(x1 / xs) * xs;
  const double y1 = std::ceil(std::max(hmax, 1e-3) / ys) * ys;
  auto px = [&](double x) { return ml + (x - x0) / (x1 - x0) * (W - ml - mr); };
  auto py = [&](double y) { return H - mb - y / y1 * (H - mt - mb); };
  const std::array<std::uint8_t, 3> grid{225, 225, 225}, black{0, 0, 0}, fill{160, 120, 70};
  for (const auto& [x, h] : deposit)  // thickness as filled columns
    if (h > 0) img.line(px(x), py(0), px(x), py(h), fill);
  for (double x = x0; x <= x1 + 1e-9 * xs; x += xs) {
    img.line(px(x), py(0), px(x), py(y1), grid);
    const std::string l = tick_label(x, xs);
    draw_text(img, static_cast<int>(px(x)) - text_width(l, 2) / 2, H - mb + 8, l, 2);
  }
  for (double y = 0; y <= y1 + 1e-9 * ys; y += ys) {
    img.line(px(x0), py(y), px(x1), py(y), grid);
    const std::string l = tick_label(y, ys);
    draw_text(img, ml - 8 - text_width(l, 2), static_cast<int>(py(y)) - 7, l, 2);
  }
  for (std::size_t k = 1; k < deposit.size(); ++k)  // deposit surface
    img.line(px(deposit[k - 1].first), py(deposit[k - 1].second), px(deposit[k].first), py(deposit[k].second), black);
  img.line(px(x0), py(0), px(x1), py(0), black);
  img.line(px(x0), py(0), px(x0), py(y1), black);
  const std::string xt = "distance along the profile (m)";
  draw_text(img, ml + (W - ml - mr - text_width(xt, 2)) / 2, H - 22, xt, 2);
  draw_text(img, 8, 6, "deposit thickness (m)", 2);
  write_png(path, img);
}

}  // namespace geohaz::dem
