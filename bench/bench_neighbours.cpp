// Throughput of the particle core: neighbour-list rebuild and one SPH-like pair loop (density
// summation + a stress-divergence-like gradient sum), on a jittered lattice with h = 1.2 Δx and
// cut-off 2h, in 2D and 3D, for 1e5 and 1e6 particles, with 1 and 2 threads.
// Prints rates; asserts nothing.  Usage: bench_neighbours [max_particles]  (default 1e6)
#include <omp.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <random>

#include "geohaz/core/kernels.hpp"
#include "geohaz/core/neighbours.hpp"
#include "geohaz/core/particles.hpp"

using namespace geohaz;

namespace {
double now() {
  return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count();
}

struct Density {
  using type = double;
  static constexpr const char* label = "density";
  static constexpr const char* unit = "kg/m^3";
};

template <int Dim>
void run(std::size_t n, int threads) {
  using Store = ParticleStore<Position<Dim>, Acceleration<Dim>, Density>;
  Store s;
  const double dx = 0.01, h = 1.2 * dx, rc = 2.0 * h;
  const int side = static_cast<int>(std::round(std::pow(double(n), 1.0 / Dim)));
  n = 1;
  for (int d = 0; d < Dim; ++d) n *= side;
  s.resize(n);
  std::mt19937 rng(1);
  std::uniform_real_distribution<double> jitter(-0.05 * dx, 0.05 * dx);
  auto& x = s.template get<Position<Dim>>();
  // Shuffled insertion order: the first reorder by cell is part of what is measured separately.
  for (std::size_t i = 0; i < n; ++i) {
    std::size_t k = i;
    for (int d = 0; d < Dim; ++d) {
      x[i][d] = (k % side) * dx + jitter(rng);
      k /= side;
    }
  }
  std::shuffle(x.begin(), x.end(), rng);
  omp_set_num_threads(threads);
  NeighbourList<Dim> nl;
  nl.build(x, rc);
  s.reorder(nl.cell_order());

  const int reps = n > 200000 ? 3 : 10;
  double t_build = 0.0, t_loop = 0.0;
  auto& rho = s.template get<Density>();
  auto& acc = s.template get<Acceleration<Dim>>();
  const double m = 1000.0 * std::pow(dx, Dim);
  for (int r = 0; r < reps; ++r) {
    const double t0 = now();
    nl.build(x, rc);
    const double t1 = now();
    // Pass 1: density. Pass 2: symmetric gradient sum (the shape of the SPH momentum equation).
    const std::int64_t nn = static_cast<std::int64_t>(n);
#pragma omp parallel for schedule(static)
    for (std::int64_t ii = 0; ii < nn; ++ii) {
      const std::size_t i = static_cast<std::size_t>(ii);
      double sum = m * CubicSpline<Dim>::value(0.0, h);
      for (std::uint32_t j : nl.neighbours(i)) sum += m * CubicSpline<Dim>::value((x[i] - x[j]).norm(), h);
      rho[i] = sum;
    }
    nl.for_each_pair(std::span<const Vec<Dim>>(x), [&](std::size_t i, std::size_t j, const Vec<Dim>& xij, double rr) {
      const double p = 1.0 / (rho[i] * rho[i]) + 1.0 / (rho[j] * rho[j]);
      if (j == nl.neighbours(i).front()) acc[i].setZero();
      acc[i] -= m * p * CubicSpline<Dim>::gradient(xij, rr, h);
    });
    const double t2 = now();
    t_build += t1 - t0;
    t_loop += t2 - t1;
  }
  t_build /= reps;
  t_loop /= reps;
  const double pairs = static_cast<double>(nl.pair_count());
  std::printf(
      "%dD n=%8zu threads=%d  neighbours/particle=%5.1f  rebuild %.4f s  pair loops %.4f s  "
      "rebuild share %4.1f%%  pairs/s %.3g  particle-steps/s %.3g\n",
      Dim, n, threads, pairs / n, t_build, t_loop, 100.0 * t_build / (t_build + t_loop), 2.0 * pairs / t_loop,
      n / (t_build + t_loop));
}
}  // namespace

int main(int argc, char** argv) {
  const std::size_t max_n = argc > 1 ? std::strtoull(argv[1], nullptr, 10) : 1000000;
  std::printf("geohaz core benchmark: neighbour rebuild + SPH-like pair loops (h = 1.2 dx, cutoff 2h)\n");
  for (std::size_t n : {std::size_t(100000), std::size_t(1000000)}) {
    if (n > max_n) continue;
    for (int t : {1, 2}) run<2>(n, t);
    for (int t : {1, 2}) run<3>(n, t);
  }
  return 0;
}
