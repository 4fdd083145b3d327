#pragma once
/// Pieces shared by the SPH test programs.
#include <gtest/gtest.h>
#include <omp.h>

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <utility>
#include <vector>

#include "geohaz/sph/fields.hpp"
#include "geohaz/sph/scenario.hpp"

namespace geohaz::sph::test_support {

/// The problems of these tests are a few hundred to a few thousand particles: one OpenMP thread is
/// as fast as two and immune to oversubscription of a shared CI machine (OpenMP barriers of
/// spinning threads). Including this header runs the whole test program on one thread; a test that
/// compares thread counts sets them itself.
class OneThread : public ::testing::Environment {
 public:
  void SetUp() override { omp_set_num_threads(1); }
};
inline const auto* const kOneThread = ::testing::AddGlobalTestEnvironment(new OneThread);

/// Linear momentum Σ m v of a store, and Σ m |v|, the scale a round-off bound on it refers to.
template <int Dim>
std::pair<Vec<Dim>, double> linear_momentum(const SphStore<Dim>& S) {
  Vec<Dim> p = Vec<Dim>::Zero();
  double scale = 0.0;
  for (std::size_t i = 0; i < S.size(); ++i) {
    p += S.template get<Mass>()[i] * S.template get<Velocity<Dim>>()[i];
    scale += S.template get<Mass>()[i] * S.template get<Velocity<Dim>>()[i].norm();
  }
  return {p, scale};
}

/// Runs `solver` 50 steps and checks that Σ m v stays at its start value to 1e-12 of Σ m |v| (pair
/// terms that cancel pairwise), with the stress above `min_stress` (Pa) so that the check means
/// something.
template <class Solver>
void expect_fifty_steps_conserve_momentum(Solver& solver, double min_stress) {
  const auto [p0, scale] = linear_momentum(solver.store());
  for (int k = 0; k < 50; ++k) solver.step();
  const auto p1 = linear_momentum(solver.store()).first;
  double stress = 0.0;
  for (const auto& s : solver.store().template get<Stress>()) stress = std::max(stress, s.norm());
  std::printf("momentum change %.3g of %.3g, max |stress| %.3g Pa\n", (p1 - p0).norm(), scale, stress);
  EXPECT_GT(stress, min_stress) << "the block must be stressed for the test to mean anything";
  EXPECT_LT((p1 - p0).norm(), 1e-12 * scale);
}

/// The soil particles of a free block W × W (2D; W × W × W in 3D) at spacing dx, smoothing factor
/// h/dx = hf, density 2000 kg/m³ and no boundary particles at all (the profile builder's walls,
/// including the 3D roller side walls, removed).
template <int Dim>
SphStore<Dim> free_block(double W, double dx, double hf) {
  ProfileDomain d;
  d.surface = {{0.0, W}, {W, W}};
  d.x_left = 0.0;
  d.x_right = W;
  d.width = W;
  d.periodic_width = false;
  d.bottom = d.left = d.right = WallType::None;
  auto sc = build_profile<Dim>(d, dx, {2000.0}, hf);
  std::vector<std::uint8_t> rm(sc.store.size());
  for (std::size_t i = 0; i < rm.size(); ++i) rm[i] = sc.store.template get<ParticleKind>()[i] != 0;
  sc.store.remove_if(rm);
  return std::move(sc.store);
}

}  // namespace geohaz::sph::test_support
