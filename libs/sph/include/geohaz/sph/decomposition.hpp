#pragma once
/// \file decomposition.hpp
/// Domain decomposition of the SPH particles over the ranks of a Communicator (issue #36; docs/sph.md,
/// "Domain decomposition"). MPI-free: the ranks talk through core's Communicator interface, whose Open
/// MPI implementation (apps/mpi-communicator) only the apps link.
///
/// Each rank's store holds its owned particles at [0, owned()) and, after them, ghost copies of the
/// other ranks' particles within the halo of its subdomain (the kernel support plus the Verlet skin).
/// At every neighbour-list rebuild (`rebuild`, the same step on every rank: the drift that decides
/// it is a global maximum):
///   1. the ghosts are dropped;
///   2. at the first rebuild and then at the solver's reordering schedule, the subdomains are
///      recomputed by recursive coordinate bisection (RCB): the ranks are halved recursively, each
///      half of a group of ranks taking a slab of its box cut normal to the longest axis of the
///      group's particles, at the coordinate where the summed particle weights split as the ranks
///      do (a soil particle weighs 1 + its neighbour count, a boundary particle 1: the pair passes
///      loop over soil particles). The cut is found by bisection on the coordinate with integer
///      weight sums over the ranks (exact, so every rank finds the same cut);
///   3. every particle outside its rank's box moves to the owner of the box that holds it with its
///      whole state (every field of the store: the stress and the models' internal variables);
///   4. the owned particles are sorted by cell when the reordering schedule says so;
///   5. every particle closer than the halo to another rank's box (minimum image along periodic
///      axes) is copied there as a ghost, with every field; the copies arrive in rank order.
/// Between rebuilds the ghosts are the same particles in the same slots, and `update_ghosts` refreshes
/// the fields a pass reads (positions and velocities after the integration, density, volume and the
/// pair stresses after the stress update, the kernel-gradient correction after it is computed).
///
/// A pair within the cut-off at any step between two rebuilds was within cut-off + skin at the
/// rebuild (no particle drifts more than skin/2), when the owned particle lay in its box: so its
/// partner is owned or a ghost, and every owned particle sees every neighbour it would see on one
/// rank.

#include <cstddef>
#include <cstdint>
#include <cstring>
#include <memory>
#include <span>
#include <utility>
#include <vector>

#include "geohaz/core/communicator.hpp"
#include "geohaz/core/neighbours.hpp"
#include "geohaz/core/parallel.hpp"
#include "geohaz/sph/fields.hpp"

namespace geohaz::sph {

/// What the decomposition has done so far (per rank; `gather`ed numbers in docs/performance.md).
struct DecompositionStats {
  std::int64_t rebuilds = 0;            ///< rebuilds (ghost layers made)
  std::int64_t partitions = 0;          ///< RCB partitions computed
  std::int64_t migrated_out = 0;        ///< particles sent to another rank at rebuilds, in all
  std::int64_t migrated_in = 0;         ///< particles received from another rank at rebuilds, in all
  std::int64_t first_migrated_out = 0;  ///< of migrated_out, at the first rebuild (the initial share-out)
  std::size_t ghosts = 0;               ///< ghosts held now
};

template <int Dim>
class DomainDecomposition {
 public:
  /// An axis-aligned box; infinite along non-periodic axes at the outside of the domain, within
  /// [lo, hi] of the period along periodic ones.
  struct Box {
    Vec<Dim> lo, hi;
  };

  DomainDecomposition(std::shared_ptr<const Communicator> comm, const Periodicity<Dim>& periodic);

  const Communicator& comm() const noexcept { return *comm_; }
  int rank() const noexcept { return rank_; }
  int size() const noexcept { return size_; }
  /// Owned particles: slots [0, owned()) of the store; ghosts after them.
  std::size_t owned() const noexcept { return owned_; }
  const DecompositionStats& stats() const noexcept { return stats_; }
  /// The subdomain of each rank (after the first rebuild).
  const std::vector<Box>& boxes() const noexcept { return boxes_; }

  /// Keep this rank's share of a store that every rank holds in full (the scenario builder's):
  /// a block of consecutive particles. The first rebuild then partitions them.
  void scatter(SphStore<Dim>& s);
  /// Take a store that already is this rank's share (that block, made or read by block: BuildShare
  /// in scenario.hpp, the restart's rows) as it is.
  void adopt(const SphStore<Dim>& s) noexcept {
    owned_ = s.size();
    ghosts_ = 0;
  }
  /// The block of n particles that scatter keeps on `rank` of `ranks`: [first, last).
  static std::pair<std::size_t, std::size_t> block(std::size_t n, int rank, int ranks) noexcept {
    return {n * static_cast<std::size_t>(rank) / static_cast<std::size_t>(ranks),
            n * static_cast<std::size_t>(rank + 1) / static_cast<std::size_t>(ranks)};
  }

  /// Steps 1–5 of the file comment. `weights`: one per owned particle (its cost); `repartition`:
  /// recompute the boxes (always done at the first rebuild); `sort_cell` > 0: sort the owned
  /// particles by cells of that edge (m). `halo`: cut-off + skin (m).
  void rebuild(SphStore<Dim>& s, double halo, bool repartition, std::span<const std::int64_t> weights,
               double sort_cell);

  /// Refresh the ghosts' values of the fields Tags from their owners.
  template <class... Tags>
  void update_ghosts(SphStore<Dim>& s) {
    constexpr std::size_t bytes = (sizeof(typename Tags::type) + ...);
    pack_sends(bytes, [&](std::size_t i, std::byte* p) {
      ((std::memcpy(p, &s.template get<Tags>()[i], sizeof(typename Tags::type)), p += sizeof(typename Tags::type)),
       ...);
    });
    unpack_ghosts(bytes, [&](std::size_t i, const std::byte* p) {
      ((std::memcpy(static_cast<void*>(&s.template get<Tags>()[i]), p, sizeof(typename Tags::type)),
        p += sizeof(typename Tags::type)),
       ...);
    });
  }
  /// Refresh the ghosts' entries of a per-particle array that is not a field (slots as the store).
  template <class T>
  void update_ghost_array(std::vector<T>& a) {
    pack_sends(sizeof(T), [&](std::size_t i, std::byte* p) { std::memcpy(p, &a[i], sizeof(T)); });
    unpack_ghosts(sizeof(T),
                  [&](std::size_t i, const std::byte* p) { std::memcpy(static_cast<void*>(&a[i]), p, sizeof(T)); });
  }

  /// Every rank's owned particles with every field, sorted by ParticleId, on every rank
  /// (collective); `root_only`: on rank 0 only, the others get an empty store (the pictures and
  /// the release a run's rank 0 makes: no other rank holds the whole state).
  SphStore<Dim> gather(const SphStore<Dim>& s, bool root_only = false) const;

  /// The block of the particles by id that scatter would keep of the gathered store, without
  /// gathering it (collective): every owned particle goes to the rank whose block
  /// (block(n, rank, size)) holds its id, with every field, sorted by id. Needs the ids to be
  /// 0 … n−1 (as a scenario numbers them); otherwise the gather and scatter themselves.
  SphStore<Dim> id_block(const SphStore<Dim>& s) const;

  /// The rank whose box holds x (x wrapped along periodic axes).
  int owner(const Vec<Dim>& x) const noexcept;

 private:
  void partition(const SphStore<Dim>& s, std::span<const std::int64_t> weights);
  void migrate(SphStore<Dim>& s);
  void make_ghosts(SphStore<Dim>& s, double halo);
  bool near_box(const Vec<Dim>& x, const Box& b, double halo2) const noexcept;

  template <class Pack>
  void pack_sends(std::size_t bytes, Pack&& pack) {
    const auto n = static_cast<std::int64_t>(send_index_.size());
    send_buf_.resize(send_index_.size() * bytes);
    std::byte* out = send_buf_.data();
#pragma omp parallel for schedule(static) if (parallel_worth(n))
    for (std::int64_t k = 0; k < n; ++k) pack(send_index_[static_cast<std::size_t>(k)], out + k * bytes);
    for (int q = 0; q < size_; ++q) {
      send_bytes_[static_cast<std::size_t>(q)] =
          send_count_[static_cast<std::size_t>(q)] * static_cast<std::int64_t>(bytes);
      recv_bytes_[static_cast<std::size_t>(q)] =
          recv_count_[static_cast<std::size_t>(q)] * static_cast<std::int64_t>(bytes);
    }
  }
  template <class Unpack>
  void unpack_ghosts(std::size_t bytes, Unpack&& unpack) {
    recv_buf_.resize(ghosts_ * bytes);
    comm_->exchange(send_buf_, send_bytes_, recv_buf_, recv_bytes_);
    const auto n = static_cast<std::int64_t>(ghosts_);
    const std::byte* in = recv_buf_.data();
#pragma omp parallel for schedule(static) if (parallel_worth(n))
    for (std::int64_t k = 0; k < n; ++k) unpack(owned_ + static_cast<std::size_t>(k), in + k * bytes);
  }

  /// A node of the RCB tree: ranks [lo, hi); an inner node sends x[axis] < cut to `left`.
  struct Node {
    int lo = 0, hi = 1;
    int axis = 0;
    double cut = 0.0;
    int left = -1, right = -1;
    Box box;
  };

  std::shared_ptr<const Communicator> comm_;
  Periodicity<Dim> periodic_;
  int rank_ = 0, size_ = 1;
  std::size_t owned_ = 0, ghosts_ = 0;
  std::vector<Node> tree_;
  std::vector<Box> boxes_;
  // The ghost pattern of the last rebuild: owned slots sent to each rank (rank order), counts.
  std::vector<std::size_t> send_index_;
  std::vector<std::int64_t> send_count_, recv_count_, send_bytes_, recv_bytes_;
  std::vector<std::byte> send_buf_, recv_buf_;
  DecompositionStats stats_;
};

extern template class DomainDecomposition<2>;
extern template class DomainDecomposition<3>;

}  // namespace geohaz::sph
