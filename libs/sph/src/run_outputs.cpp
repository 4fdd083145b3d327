// What an sph-slope run draws and tabulates: the quick-look pictures of the particles, the CSV
// tables (Table::csv) and the head of summary.json.
#include <algorithm>
#include <iomanip>
#include <sstream>

#include "geohaz/core/output.hpp"
#include "run_support.hpp"

namespace geohaz::sph {

std::string csv_number(double v) {
  std::ostringstream os;
  os << std::setprecision(9) << v;
  return os.str();
}

template <int Dim>
void draw_particles(const std::filesystem::path& path, const SphStore<Dim>& s, const std::vector<double>& value,
                    double vmax, double dx, const std::string& title,
                    const std::vector<std::array<double, 2>>& overlay) {
  const auto& x = s.template get<Position<Dim>>();
  const auto& kind = s.template get<ParticleKind>();
  double x0 = 1e300, x1 = -1e300, z0 = 1e300, z1 = -1e300;
  for (const auto& p : x) {
    x0 = std::min(x0, p[0]);
    x1 = std::max(x1, p[0]);
    z0 = std::min(z0, p[Dim - 1]);
    z1 = std::max(z1, p[Dim - 1]);
  }
  const int W = 1200, margin = 20;
  // Fit the x–z extent into at most 1200 × 1200 pixels of drawing area.
  const double scale =
      std::min((W - 2 * margin) / std::max(x1 - x0 + dx, 1e-12), (1200.0 - 2 * margin) / std::max(z1 - z0 + dx, 1e-12));
  // Below the particles: 10 px gap, then draw_colour_bar at text scale 2 (bar 20, ticks 6 + 4,
  // numbers 14, gap 8, title 14 = 66 px), and 8 px to spare.
  constexpr int kLegend = 84;
  const int H = std::max(static_cast<int>((z1 - z0 + dx) * scale) + 2 * margin + kLegend, 100);
  Image img(W, H);
  const double r = std::max(1.0, 0.5 * dx * scale);
  for (std::size_t i = 0; i < s.size(); ++i) {
    const double px = margin + (x[i][0] - x0) * scale + 0.5 * (W - 2 * margin - (x1 - x0) * scale);
    const double pz = H - kLegend - margin - (x[i][Dim - 1] - z0) * scale;
    std::array<std::uint8_t, 3> col{160, 160, 160};
    if (kind[i] == kSoil)
      col = ramp_colour(ColourRamp::Viridis, vmax > 0 ? std::clamp(value[i] / vmax, 0.0, 1.0) : 0.0);
    img.fill_circle(px, pz, r, col);
  }
  for (std::size_t k = 1; k < overlay.size(); ++k) {
    auto px = [&](double xx) { return margin + (xx - x0) * scale + 0.5 * (W - 2 * margin - (x1 - x0) * scale); };
    auto pz = [&](double zz) { return H - kLegend - margin - (zz - z0) * scale; };
    for (int d = -1; d <= 1; ++d)
      img.line(px(overlay[k - 1][0]), pz(overlay[k - 1][1]) + d, px(overlay[k][0]), pz(overlay[k][1]) + d,
               {220, 30, 30});
  }
  draw_colour_bar(img, margin, H - kLegend + 10, W - 2 * margin, ColourRamp::Viridis, 0.0, vmax > 0 ? vmax : 1.0, title,
                  2);
  write_png(path, img);
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
                                double, const std::string&, const std::vector<std::array<double, 2>>&);
template void draw_particles<3>(const std::filesystem::path&, const SphStore<3>&, const std::vector<double>&, double,
                                double, const std::string&, const std::vector<std::array<double, 2>>&);
template nlohmann::json summary_header<2>(const RunConfig&, const SphSolver<2>&, std::size_t);
template nlohmann::json summary_header<3>(const RunConfig&, const SphSolver<3>&, std::size_t);

}  // namespace geohaz::sph
