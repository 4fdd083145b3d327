#pragma once
/// \file parallel.hpp
/// The one small-problem threshold for OpenMP loops in the libraries.
///
/// Below kParallelMin items a particle loop runs on one thread: forking and joining a team costs a
/// few microseconds per loop, more than the work of a few thousand particles (the DEM lab cases of
/// a few hundred discs ran 3× slower on 2 threads than on 1). Loops say so with an `if` clause,
///
///     #pragma omp parallel for schedule(static) if (parallel_worth(n))
///
/// never by changing the global thread count: only an application sets that (core app.cpp,
/// `--threads`). Every fixed-order sum in the libraries gives the same bits on any thread count,
/// so the threshold changes speed only, never results.

#include <cstddef>
#include <cstdint>

namespace geohaz {

/// Loops over fewer items than this run on one thread.
inline constexpr std::int64_t kParallelMin = 2048;

/// Whether a loop over n items is worth a team of threads.
constexpr bool parallel_worth(std::int64_t n) noexcept {
  return n >= kParallelMin;
}
constexpr bool parallel_worth(std::size_t n) noexcept {
  return n >= static_cast<std::size_t>(kParallelMin);
}

}  // namespace geohaz
