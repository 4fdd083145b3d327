#pragma once
/// \file communicator.hpp
/// The few collective operations a model distributed over processes needs (issue #36: the SPH
/// domain decomposition), behind an interface of ours so that the libraries stay free of MPI: the
/// Open MPI implementation is `geohaz::mpi` (apps/mpi-communicator, built with the CMake option GEOHAZ_MPI),
/// linked only by the apps that run under mpirun. Called a few times per step, never per particle
/// or pair, so the virtual call costs nothing measurable.
///
/// Every operation is collective: all ranks call it, in the same order, with the same shape of
/// arguments. The reductions that decide the run (time step, drift, statistics) are either exact
/// in any order (max, integer sums) or gathered and summed in rank order by the caller
/// (`all_gather`), so a run on a given number of ranks repeats bit for bit.

#include <cstddef>
#include <cstdint>
#include <cstring>
#include <span>
#include <type_traits>
#include <vector>

namespace geohaz {

/// Collective operations over a fixed group of processes (ranks 0..size-1).
class Communicator {
 public:
  virtual ~Communicator() = default;
  /// This process's rank.
  virtual int rank() const = 0;
  /// Number of ranks.
  virtual int size() const = 0;
  /// Element-wise maximum over the ranks, in place (exact in any order).
  virtual void max_all(std::span<double> values) const = 0;
  /// Element-wise sum over the ranks, in place (integers: exact in any order).
  virtual void sum_all(std::span<std::int64_t> values) const = 0;
  /// Every rank's `values` (the same count on every rank), concatenated in rank order: a sum over
  /// them in that order is the same on every rank and in every repetition of the run.
  virtual std::vector<double> all_gather(std::span<const double> values) const = 0;
  /// Every rank's bytes, concatenated in rank order (counts may differ), on every rank.
  virtual std::vector<std::byte> all_gather_bytes(std::span<const std::byte> bytes) const = 0;
  /// How many bytes each rank will send to this one, from how many this one sends to each
  /// (`send_bytes[q]` to rank q): an all-to-all of one count per pair of ranks.
  virtual std::vector<std::int64_t> exchange_counts(std::span<const std::int64_t> send_bytes) const = 0;
  /// Personalised exchange: the bytes send[offset_q, offset_q + send_bytes[q]) go to rank q, and
  /// rank q's bytes for this one arrive in recv[offset_q, offset_q + recv_bytes[q]) (offsets: the
  /// prefix sums of the counts, in rank order). Only pairs with a nonzero count communicate.
  virtual void exchange(std::span<const std::byte> send, std::span<const std::int64_t> send_bytes,
                        std::span<std::byte> recv, std::span<const std::int64_t> recv_bytes) const = 0;
};

/// Every rank's `values` of a plain type (counts may differ), concatenated in rank order, on every
/// rank: `all_gather_bytes` typed. Empty on every rank gives an empty vector.
template <class T>
std::vector<T> all_gather_values(const Communicator& comm, std::span<const T> values) {
  static_assert(std::is_trivially_copyable_v<T>);
  const std::vector<std::byte> all = comm.all_gather_bytes(std::as_bytes(values));
  std::vector<T> out(all.size() / sizeof(T));
  if (!out.empty()) std::memcpy(out.data(), all.data(), out.size() * sizeof(T));
  return out;
}

}  // namespace geohaz
