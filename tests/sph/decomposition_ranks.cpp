// The SPH solver on several ranks against the same run on one (issue #36; docs/sph.md, "Domain
// decomposition"). Run under mpirun by test_decomposition.cpp (or alone: one rank):
//   sph_decomposition_ranks CASE [STEPS]     CASE: column2d, slope3d, block2d
// Every rank steps the distributed solver; every rank also steps the plain one-process solver on
// the whole scenario (the reference: the code path every other test checks), and the gathered state
// of the first is compared with the second particle by particle (by id). Rank 0 prints one line,
//   case C ranks P particles N steps S position R velocity R stress R density R dt R migrated M ghosts G
//   repeat B
// with the largest differences relative to the largest value of each field (R), the particles that
// changed rank after the first partition (M; the share-out of the scenario not counted), the ghosts
// on rank 0 (G), and B = 1 when a second distributed run gave the same bits (a fixed reduction
// order: the same number of ranks repeats a run exactly); the exit code is 0 unless a rank failed.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <numbers>
#include <string>

#include "geohaz/core/errors.hpp"
#include "geohaz/mpi/mpi_communicator.hpp"
#include "geohaz/sph/scenario.hpp"
#include "geohaz/sph/solver.hpp"

using namespace geohaz;
using namespace geohaz::sph;

namespace {

template <int Dim>
struct Case {
  SphStore<Dim> store;
  std::vector<MaterialParams> materials;
  ConstitutiveModel model = DruckerPrager{};
  SolverSettings<Dim> settings;
};

/// A 2D Drucker–Prager column collapsing onto a floor (the benchmark's geometry, smaller).
Case<2> column2d() {
  Case<2> c;
  MaterialParams m;
  m.density = 1800;
  m.young = 1e6;
  m.poisson = 0.3;
  m.friction = 30 * std::numbers::pi / 180;
  const double dx = 0.005;
  ProfileDomain d;
  d.surface = {{0.0, 0.2}, {0.1, 0.2}, {0.1, 0.0}, {0.3, 0.0}};
  d.x_left = 0.0;
  d.x_right = 0.3;
  d.right = WallType::None;
  auto sc = build_profile<2>(d, dx, {m.density}, 1.2);
  c.store = std::move(sc.store);
  c.materials = {m};
  c.settings.spacing = dx;
  c.settings.periodic = sc.periodic;
  c.settings.domain_lo = sc.domain_lo;
  c.settings.domain_hi = sc.domain_hi;
  return c;
}

/// A small 3D slope (SPH-slope paper 2020, Fig. 3 geometry), periodic across its width.
Case<3> slope3d() {
  Case<3> c;
  MaterialParams m;
  m.density = 1800;
  m.young = 1e6;
  m.poisson = 0.3;
  m.friction = 20 * std::numbers::pi / 180;
  m.fit = DruckerPragerFit::Compression3D;
  SlopeGeometry g;
  g.height = 0.1;
  g.crest_length = 0.1;
  g.front_length = 0.15;
  g.base_thickness = 0.03;
  auto d = g.profile();
  const double dx = 0.01;
  d.width = 0.06;
  auto sc = build_profile<3>(d, dx, {m.density}, 1.2);
  c.store = std::move(sc.store);
  c.materials = {m};
  c.settings.spacing = dx;
  c.settings.periodic = sc.periodic;
  c.settings.domain_lo = sc.domain_lo;
  c.settings.domain_hi = sc.domain_hi;
  return c;
}

/// A free linear-elastic block (no walls, no gravity) moving at 1 m/s along x while it stretches
/// and bends: it crosses the cut of the first partition (never recomputed: reorder_every = 0), so
/// its particles change rank with their stress.
Case<2> block2d() {
  Case<2> c;
  MaterialParams m;
  m.density = 1000;
  m.young = 1e4;
  m.poisson = 0.3;
  const double dx = 0.01, L = 0.4, H = 0.1;
  const int nx = static_cast<int>(std::lround(L / dx)), nz = static_cast<int>(std::lround(H / dx));
  auto& S = c.store;
  S.resize(static_cast<std::size_t>(nx * nz));
  for (int a = 0; a < nx; ++a)
    for (int b = 0; b < nz; ++b) {
      const auto i = static_cast<std::size_t>(a * nz + b);
      const Vec2 x((a + 0.5) * dx, (b + 0.5) * dx);
      S.get<Position<2>>()[i] = x;
      S.get<Velocity<2>>()[i] = Vec2(1.0 + 0.1 * (x[0] / L - 0.5), 0.1 * std::sin(std::numbers::pi * x[0] / L));
      S.get<Density>()[i] = m.density;
      S.get<Mass>()[i] = m.density * dx * dx;
      S.get<ParticleId>()[i] = static_cast<std::int64_t>(i);
    }
  c.materials = {m};
  c.model = LinearElastic{};
  c.settings.spacing = dx;
  c.settings.gravity = 0.0;
  c.settings.reorder_every = 0;
  return c;
}

/// max |a − b| over the particles, relative to max |b|.
template <class V>
double relative_difference(const std::vector<V>& a, const std::vector<V>& b) {
  double d = 0.0, ref = 0.0;
  for (std::size_t i = 0; i < b.size(); ++i) {
    if constexpr (std::is_arithmetic_v<V>) {
      d = std::max(d, std::abs(a[i] - b[i]));
      ref = std::max(ref, std::abs(b[i]));
    } else {
      d = std::max(d, (a[i] - b[i]).norm());
      ref = std::max(ref, b[i].norm());
    }
  }
  return ref > 0.0 ? d / ref : d;
}

template <int Dim>
int run(const char* name, Case<Dim> c, int steps, const std::shared_ptr<const Communicator>& comm) {
  SphSolver<Dim> reference(c.store, c.materials, c.model, c.settings);
  SphSolver<Dim> repeat(c.store, c.materials, c.model, c.settings);
  SphSolver<Dim> solver(std::move(c.store), c.materials, c.model, c.settings);
  if (comm) {
    solver.distribute(comm);
    repeat.distribute(comm);
  }
  for (int s = 0; s < steps; ++s) {
    reference.step();
    solver.step();
    repeat.step();
  }
  // The two distributed runs hold the same particles in the same slots if they went the same way.
  const auto& xs = solver.store().template get<Position<Dim>>();
  const auto& xr = repeat.store().template get<Position<Dim>>();
  const auto& ss = solver.store().template get<Stress>();
  const auto& sr = repeat.store().template get<Stress>();
  std::int64_t differ = xs.size() != xr.size() || solver.dt() != repeat.dt();
  for (std::size_t i = 0; !differ && i < xs.size(); ++i) differ = xs[i] != xr[i] || ss[i] != sr[i];
  if (comm) comm->sum_all(std::span<std::int64_t>(&differ, 1));
  const SphStore<Dim> a = solver.gathered_store(), b = reference.gathered_store();
  if (a.size() != b.size() || a.template get<ParticleId>() != b.template get<ParticleId>()) {
    std::fprintf(stderr, "%s: the gathered store has %zu particles, the reference %zu\n", name, a.size(), b.size());
    return 1;
  }
  const auto* dom = solver.domain();
  std::int64_t moved[2] = {dom ? dom->stats().migrated_out - dom->stats().first_migrated_out : 0, 0};
  if (comm) comm->sum_all(std::span<std::int64_t>(moved, 1));
  const int rank = comm ? comm->rank() : 0;
  if (rank == 0)
    std::printf(
        "case %s ranks %d particles %zu steps %d position %.3e velocity %.3e stress %.3e density %.3e dt %.3e "
        "migrated %lld ghosts %zu repeat %d\n",
        name, comm ? comm->size() : 1, a.size(), steps,
        relative_difference(a.template get<Position<Dim>>(), b.template get<Position<Dim>>()),
        relative_difference(a.template get<Velocity<Dim>>(), b.template get<Velocity<Dim>>()),
        relative_difference(a.template get<Stress>(), b.template get<Stress>()),
        relative_difference(a.template get<Density>(), b.template get<Density>()),
        std::abs(solver.dt() - reference.dt()) / reference.dt(), static_cast<long long>(moved[0]),
        dom ? dom->stats().ghosts : std::size_t{0}, differ == 0 ? 1 : 0);
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  geohaz::mpi::Session session(argc, argv);
  const auto world = geohaz::mpi::world_communicator(session);
  const std::string name = argc > 1 ? argv[1] : "column2d";
  const int steps = argc > 2 ? std::atoi(argv[2]) : 100;
  try {
    if (name == "column2d") return run<2>("column2d", column2d(), steps, world);
    if (name == "slope3d") return run<3>("slope3d", slope3d(), steps, world);
    if (name == "block2d") return run<2>("block2d", block2d(), steps, world);
    std::fprintf(stderr, "unknown case %s (column2d, slope3d, block2d)\n", name.c_str());
    return 2;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "rank %d: %s\n", session.rank(), e.what());
    session.abort(1);
    return 1;
  }
}
