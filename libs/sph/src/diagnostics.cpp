#include "geohaz/sph/diagnostics.hpp"

#include <algorithm>
#include <cmath>
#include <map>

namespace geohaz::sph {

namespace {

/// The particles a diagnostic loops over: the whole store, or this rank's owned ones.
template <int Dim>
std::size_t count_of(const SphStore<Dim>& s, const OverRanks& over) {
  return over.comm ? over.owned : s.size();
}

/// Per-bin maxima (take_max) or minima of every rank, merged (collective; exact).
void reduce_bins(const OverRanks& over, std::map<long, double>& bins, bool take_max) {
  if (!over.comm) return;
  std::vector<double> mine;
  mine.reserve(2 * bins.size());
  for (const auto& [b, v] : bins) {
    mine.push_back(static_cast<double>(b));
    mine.push_back(v);
  }
  const std::vector<double> v = all_gather_values(*over.comm, std::span<const double>(mine));
  for (std::size_t k = 0; k + 1 < v.size(); k += 2) {
    auto [it, inserted] = bins.emplace(static_cast<long>(v[k]), v[k + 1]);
    if (!inserted) it->second = take_max ? std::max(it->second, v[k + 1]) : std::min(it->second, v[k + 1]);
  }
}

/// Sums of every rank's partial sums, added in rank order (collective).
void sum_in_rank_order(const OverRanks& over, std::vector<double>& sums) {
  if (!over.comm || sums.empty()) return;
  const std::vector<double> all = over.comm->all_gather(sums);
  std::fill(sums.begin(), sums.end(), 0.0);
  for (std::size_t r = 0; r < all.size() / sums.size(); ++r)
    for (std::size_t k = 0; k < sums.size(); ++k) sums[k] += all[r * sums.size() + k];
}
}  // namespace

template <int Dim>
SeriesRow series_row(const SphStore<Dim>& s, const DiagnosticFrame& f, const OverRanks& over) {
  const auto& x = s.template get<Position<Dim>>();
  const auto& v = s.template get<Velocity<Dim>>();
  const auto& u = s.template get<Displacement<Dim>>();
  const auto& m = s.template get<Mass>();
  const auto& kind = s.template get<ParticleKind>();
  const auto& ep = s.template get<PlasticStrain>();
  const auto& sf = s.template get<StressFree>();
  SeriesRow r;
  r.front = f.toe_x;
  r.tip = f.toe_x;
  std::map<long, double> top;  // bin → highest particle top above base_top
  std::size_t count = 0, plastic = 0;
  double sum_speed = 0.0;
  for (std::size_t i = 0; i < count_of(s, over); ++i) {
    if (kind[i] != kSoil) continue;
    ++count;
    const double sp = v[i].norm();
    r.max_speed = std::max(r.max_speed, sp);
    sum_speed += sp;
    r.kinetic_energy += 0.5 * m[i] * sp * sp;
    r.max_displacement = std::max(r.max_displacement, u[i].norm());
    if (ep[i] > f.plastic_threshold) ++plastic;
    const double z0 = x[i][Dim - 1] - u[i][Dim - 1];
    if (!sf[i] && z0 > f.base_top) {
      r.tip = std::max(r.tip, x[i][0] + 0.5 * f.spacing);
      const long b = static_cast<long>(std::floor(x[i][0] / f.spacing));
      const double t = x[i][Dim - 1] + 0.5 * f.spacing - f.base_top;
      auto [it, inserted] = top.emplace(b, t);
      if (!inserted) it->second = std::max(it->second, t);
    }
  }
  if (over.comm) {
    std::vector<double> mx{r.max_speed, r.max_displacement, r.tip};
    over.comm->max_all(mx);
    r.max_speed = mx[0];
    r.max_displacement = mx[1];
    r.tip = mx[2];
    std::vector<std::int64_t> n{static_cast<std::int64_t>(count), static_cast<std::int64_t>(plastic)};
    over.comm->sum_all(n);
    count = static_cast<std::size_t>(n[0]);
    plastic = static_cast<std::size_t>(n[1]);
    std::vector<double> sums{sum_speed, r.kinetic_energy};
    sum_in_rank_order(over, sums);
    sum_speed = sums[0];
    r.kinetic_energy = sums[1];
    reduce_bins(over, top, true);
  }
  const double t_min = f.front_thickness > 0.0 ? f.front_thickness : f.front_min_layers * f.spacing;
  for (const auto& [b, t] : top)
    if (t >= t_min * (1.0 - 1e-9)) r.front = std::max(r.front, (static_cast<double>(b) + 1.0) * f.spacing);
  // The front is measured at the particle's outer edge; the initial toe particle sits Δx/2 inside.
  r.front = std::max(r.front, f.toe_x);
  r.tip = std::max(r.tip, r.front);
  r.runout = r.front - f.toe_x;
  r.normalised_runout = r.runout / f.base_length;
  if (count) {
    r.mean_speed = sum_speed / static_cast<double>(count);
    r.plastic_fraction = static_cast<double>(plastic) / static_cast<double>(count);
  }
  return r;
}

template <int Dim>
std::vector<std::array<double, 2>> free_surface(const SphStore<Dim>& s, double dx, const OverRanks& over) {
  const auto& x = s.template get<Position<Dim>>();
  const auto& kind = s.template get<ParticleKind>();
  const auto& sf = s.template get<StressFree>();
  std::map<long, double> top;
  for (std::size_t i = 0; i < count_of(s, over); ++i) {
    if (kind[i] != kSoil || sf[i]) continue;
    const long b = static_cast<long>(std::floor(x[i][0] / dx));
    const double z = x[i][Dim - 1] + 0.5 * dx;
    auto [it, inserted] = top.emplace(b, z);
    if (!inserted) it->second = std::max(it->second, z);
  }
  reduce_bins(over, top, true);
  std::vector<std::array<double, 2>> out;
  out.reserve(top.size());
  for (auto& [b, z] : top) out.push_back({(static_cast<double>(b) + 0.5) * dx, z});
  return out;
}

template <int Dim>
std::vector<std::array<double, 2>> slip_surface(const SphStore<Dim>& s, double dx, double threshold,
                                                const OverRanks& over) {
  const auto& x = s.template get<Position<Dim>>();
  const auto& u = s.template get<Displacement<Dim>>();
  const auto& kind = s.template get<ParticleKind>();
  std::map<long, double> low;
  for (std::size_t i = 0; i < count_of(s, over); ++i) {
    if (kind[i] != kSoil || u[i].norm() <= threshold) continue;
    const Vec<Dim> x0 = x[i] - u[i];
    const long b = static_cast<long>(std::floor(x0[0] / dx));
    const double z = x0[Dim - 1] - 0.5 * dx;
    auto [it, inserted] = low.emplace(b, z);
    if (!inserted) it->second = std::min(it->second, z);
  }
  reduce_bins(over, low, false);
  std::vector<std::array<double, 2>> out;
  for (auto& [b, z] : low) out.push_back({(static_cast<double>(b) + 0.5) * dx, z});
  return out;
}

template <int Dim>
FailedMass failed_mass(const SphStore<Dim>& s, const std::vector<double>& rho0, double threshold,
                       const OverRanks& over) {
  const auto& u = s.template get<Displacement<Dim>>();
  const auto& m = s.template get<Mass>();
  const auto& kind = s.template get<ParticleKind>();
  const auto& mat = s.template get<MaterialId>();
  FailedMass f;
  for (std::size_t i = 0; i < count_of(s, over); ++i) {
    if (kind[i] != kSoil || u[i].norm() <= threshold) continue;
    ++f.count;
    f.volume += m[i] / rho0[static_cast<std::size_t>(mat[i])];
  }
  if (over.comm) {
    std::vector<std::int64_t> n{static_cast<std::int64_t>(f.count)};
    over.comm->sum_all(n);
    f.count = static_cast<std::size_t>(n[0]);
    std::vector<double> v{f.volume};
    sum_in_rank_order(over, v);
    f.volume = v[0];
  }
  return f;
}

template SeriesRow series_row<2>(const SphStore<2>&, const DiagnosticFrame&, const OverRanks&);
template SeriesRow series_row<3>(const SphStore<3>&, const DiagnosticFrame&, const OverRanks&);
template std::vector<std::array<double, 2>> free_surface<2>(const SphStore<2>&, double, const OverRanks&);
template std::vector<std::array<double, 2>> free_surface<3>(const SphStore<3>&, double, const OverRanks&);
template std::vector<std::array<double, 2>> slip_surface<2>(const SphStore<2>&, double, double, const OverRanks&);
template std::vector<std::array<double, 2>> slip_surface<3>(const SphStore<3>&, double, double, const OverRanks&);
template FailedMass failed_mass<2>(const SphStore<2>&, const std::vector<double>&, double, const OverRanks&);
template FailedMass failed_mass<3>(const SphStore<3>&, const std::vector<double>&, double, const OverRanks&);

}  // namespace geohaz::sph
