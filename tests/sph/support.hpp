#pragma once
/// Pieces shared by the SPH test programs.
#include <gtest/gtest.h>
#include <omp.h>

#include <cstddef>
#include <utility>

#include "geohaz/sph/fields.hpp"

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

}  // namespace geohaz::sph::test_support
