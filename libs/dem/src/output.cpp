#include "geohaz/dem/output.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <iomanip>
#include <sstream>
#include <string>

#include "geohaz/core/output.hpp"
#include "geohaz/core/plot.hpp"
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

/// The picture `plot` drawn in `f` as a panel of core's plotter (plot.hpp), numbered in metres
/// (`x_title`, `y_title`), a title above and a legend below; written with its panel recorded.
void write_framed_png(const std::filesystem::path& path, const Image& plot, const Frame& f, const std::string& title,
                      const std::string& x_title, const std::string& y_title, const std::vector<LegendEntry>& legend) {
  constexpr int s = 2, ml = 110, mr = 30, mt = 56, mb = 70;
  const int W = plot.width + ml + mr;
  const int H = mt + plot.height + mb + (legend.empty() ? 0 : legend_height(legend, plot.width, s) + 10);
  Image img(W, H);
  draw_picture(img, plot, ml, mt);
  // The panel spans the picture's pixel centres: column 0 is f.lo.x(), column w − 1 is f.lo.x() + (w − 1)/scale.
  const PlotPanel panel{f.lo.x(),
                        f.lo.x() + (plot.width - 1) / f.scale,
                        f.lo.y(),
                        f.lo.y() + (plot.height - 1) / f.scale,
                        ml,
                        mt,
                        plot.width - 1,
                        plot.height - 1};
  draw_axes(img, panel, x_title, y_title, s, {std::max(2, plot.width / 140), std::max(2, plot.height / 90), false});
  draw_text(img, ml + (plot.width - text_width(title, s)) / 2, 8, title, s);
  draw_legend(img, ml, mt + plot.height + mb, plot.width, legend, s);
  write_plot_png(path, img, {panel}, s);
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
  write_framed_png(path, img, f, title, "x (m)", "y (m)",
                   {{{40, 90, 200}, "intact bond"},
                    {{220, 30, 30}, "tensile crack"},
                    {{250, 150, 0}, "shear crack"},
                    {{20, 160, 60}, "cut by a joint"}});
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
  write_framed_png(path, img, f, "rock avalanche at the end (discs coloured by fragment)",
                   "distance along the section (m)", "elevation (m)",
                   {{{60, 40, 20}, "terrain"}, {{150, 150, 150}, "source outline"}});
}

void write_deposit_png(const std::filesystem::path& path, const std::vector<std::pair<double, double>>& deposit) {
  constexpr int W = 900, H = 380, ml = 90, mr = 20, mt = 36, mb = 56, s = 2;
  std::vector<double> x, h;
  for (const auto& [xk, hk] : deposit) {
    x.push_back(xk);
    h.push_back(hk);
  }
  double x0 = x.empty() ? 0.0 : x.front(), x1 = x.empty() ? 1.0 : x.back();
  double y0 = 0.0, y1 = std::max(1e-3, h.empty() ? 0.0 : *std::max_element(h.begin(), h.end()));
  if (!(x1 > x0)) x1 = x0 + 1;
  nice_range(x0, x1);
  nice_range(y0, y1);
  const PlotPanel f{x0, x1, y0, y1, ml, mt, W - ml - mr, H - mt - mb};
  Image img(W, H);
  draw_axes(img, f, "distance along the profile (m)", "deposit thickness (m)", s);
  // Thickness as filled columns, one sample's spacing wide.
  const int bar = x.size() >= 2 ? std::max(1, static_cast<int>(std::lround(f.px(x[1]) - f.px(x[0]))) - 1) : 1;
  draw_bars(img, f, x, h, {190, 150, 100}, bar);
  draw_polyline(img, f, x, h, {0, 0, 0});  // deposit surface
  draw_frame(img, f);                      // over the columns' feet
  write_plot_png(path, img, {f}, s);
}

}  // namespace geohaz::dem
