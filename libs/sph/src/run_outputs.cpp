// What an sph-slope run draws and tabulates: the quick-look pictures of the particles (in a frame
// of core's plotter, plot.hpp: x and z axes in metres at equal scale), the CSV
// tables (Table::csv) and the head of summary.json.
#include <algorithm>
#include <iomanip>
#include <sstream>

#include "geohaz/core/output.hpp"
#include "geohaz/core/plot.hpp"
#include "run_support.hpp"

namespace geohaz::sph {

std::string csv_number(double v) {
  std::ostringstream os;
  os << std::setprecision(9) << v;
  return os.str();
}

ParticlePicture particle_picture(const RunConfig& c, std::string title, std::string bar,
                                 std::vector<std::array<double, 2>> overlay) {
  ParticlePicture p{std::move(title), std::move(bar), std::move(overlay)};
  if (c.scenario == ScenarioType::Section) {
    p.x_title = "distance along the section polyline (m)";
    p.z_title = "elevation (m)";
  }
  return p;
}

template <int Dim>
void draw_particles(const std::filesystem::path& path, const SphStore<Dim>& s, const std::vector<double>& value,
                    double vmax, double dx, const ParticlePicture& pic) {
  const auto& x = s.template get<Position<Dim>>();
  const auto& kind = s.template get<ParticleKind>();
  double x0 = 1e300, x1 = -1e300, z0 = 1e300, z1 = -1e300;
  auto extend = [&](double px, double pz) {
    x0 = std::min(x0, px);
    x1 = std::max(x1, px);
    z0 = std::min(z0, pz);
    z1 = std::max(z1, pz);
  };
  for (const auto& p : x) extend(p[0], p[Dim - 1]);
  for (const auto& p : pic.overlay) extend(p[0], p[1]);
  if (x0 > x1) {  // nothing to draw: a unit square
    x0 = z0 = 0.0;
    x1 = z1 = 1.0;
  }
  // The discs (radius Δx/2) inside the frame, half a spacing to spare; 1 m in x drawn as 1 m in z,
  // both axes numbered at the same step where the z axis has room for two ticks at it.
  constexpr int ts = 2, ml = 110, mr = 40, mt = 60, kMaxW = 1050, kMaxH = 1000;
  // Below the panel: tick numbers and x title (20 + 2 · 7 · ts = 48 px), 16 px, the colour bar
  // (draw_colour_bar at ts: 36 · ts = 72 px), 8 px.
  constexpr int kBar = 64, kBelow = kBar + 36 * ts + 8;
  const PlotPanel f = equal_scale_panel(x0 - dx, x1 + dx, z0 - dx, z1 + dx, ml, mt, kMaxW, kMaxH);
  const std::string title =
      pic.title + (Dim == 3 ? " (3D: all particles projected along y, soil over walls, low y in front)" : "");
  const int bar_w = std::max(f.width, 400);
  const int W = std::max({ml + bar_w + mr, text_width(title, ts) + 20, 600});
  Image img(W, mt + f.height + kBelow);
  // Boundary particles first, the soil over them; in 3D the particles nearest the viewer (low y)
  // last, so that the projection shows the side at the lowest y.
  std::vector<std::size_t> order(s.size());
  for (std::size_t i = 0; i < order.size(); ++i) order[i] = i;
  std::stable_sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) {
    if ((kind[a] == kSoil) != (kind[b] == kSoil)) return kind[b] == kSoil;
    return Dim == 3 && x[a][1] > x[b][1];
  });
  std::vector<double> px, pz;
  std::vector<std::array<std::uint8_t, 3>> col;
  px.reserve(order.size()), pz.reserve(order.size()), col.reserve(order.size());
  for (std::size_t i : order) {
    px.push_back(x[i][0]);
    pz.push_back(x[i][Dim - 1]);
    col.push_back(kind[i] == kSoil
                      ? ramp_colour(ColourRamp::Viridis, vmax > 0 ? std::clamp(value[i] / vmax, 0.0, 1.0) : 0.0)
                      : std::array<std::uint8_t, 3>{160, 160, 160});
  }
  draw_discs(img, f, px, pz, col, 0.5 * dx);
  std::vector<double> ox, oz;
  for (const auto& p : pic.overlay) {
    ox.push_back(p[0]);
    oz.push_back(p[1]);
  }
  draw_polyline(img, f, ox, oz, {220, 30, 30}, 3);
  draw_axes(img, f, pic.x_title, Dim == 3 ? pic.z_title + ", projected along y" : pic.z_title, ts,
            {std::max(2, f.width / 100), std::max(2, f.height / 70), false, true});
  draw_text(img, std::max(10, (W - text_width(title, ts)) / 2), 10, title, ts);
  draw_colour_bar(img, f.left, f.top + f.height + kBar, bar_w, ColourRamp::Viridis, 0.0, vmax > 0 ? vmax : 1.0, pic.bar,
                  ts);
  write_plot_png(path, img, {f}, ts);
}

Table xz_table(const std::vector<std::array<double, 2>>& points) {
  Table t{{"x_m", "z_m"}, {}, {}};
  for (const auto& p : points) t.rows.push_back({p[0], p[1]});
  return t;
}

template <int Dim>
nlohmann::json summary_header(const RunConfig& c, const SphSolver<Dim>& solver, std::size_t soil_count) {
  nlohmann::json s;
  s["scenario"] = scenario_name(c.scenario);
  s["dimension"] = Dim;
  s["model"] = solver.model_name();
  s["config"] = c.config_source;
  s["soil_particles"] = soil_count;
  s["spacing_m"] = c.numerics.spacing;
  return s;
}

std::string Table::csv() const {
  std::ostringstream os;
  for (std::size_t k = 0; k < columns.size(); ++k) os << (k ? "," : "") << columns[k];
  os << '\n';
  for (const auto& row : rows) {
    for (std::size_t k = 0; k < row.size(); ++k) {
      if (k) os << ',';
      if (k < integer.size() && integer[k])
        os << static_cast<long long>(row[k]);
      else
        os << csv_number(row[k]);
    }
    os << '\n';
  }
  return os.str();
}

template void draw_particles<2>(const std::filesystem::path&, const SphStore<2>&, const std::vector<double>&, double,
                                double, const ParticlePicture&);
template void draw_particles<3>(const std::filesystem::path&, const SphStore<3>&, const std::vector<double>&, double,
                                double, const ParticlePicture&);
template nlohmann::json summary_header<2>(const RunConfig&, const SphSolver<2>&, std::size_t);
template nlohmann::json summary_header<3>(const RunConfig&, const SphSolver<3>&, std::size_t);

}  // namespace geohaz::sph
