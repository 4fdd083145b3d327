/// \file mpi_communicator.cpp
/// core's Communicator on MPI_COMM_WORLD (mpi_communicator.hpp).
#include "geohaz/mpi/mpi_communicator.hpp"

#include <mpi.h>

#include <limits>
#include <memory>
#include <stdexcept>
#include <string>

namespace geohaz::mpi {

namespace {

int checked_count(std::int64_t n) {
  if (n < 0 || n > std::numeric_limits<int>::max())
    throw std::runtime_error("MPI message of " + std::to_string(n) + " bytes: more than one message can carry");
  return static_cast<int>(n);
}

class WorldCommunicator final : public Communicator {
 public:
  WorldCommunicator() {
    MPI_Comm_rank(MPI_COMM_WORLD, &rank_);
    MPI_Comm_size(MPI_COMM_WORLD, &size_);
  }
  int rank() const override { return rank_; }
  int size() const override { return size_; }
  void max_all(std::span<double> v) const override {
    MPI_Allreduce(MPI_IN_PLACE, v.data(), checked_count(static_cast<std::int64_t>(v.size())), MPI_DOUBLE, MPI_MAX,
                  MPI_COMM_WORLD);
  }
  void sum_all(std::span<std::int64_t> v) const override {
    MPI_Allreduce(MPI_IN_PLACE, v.data(), checked_count(static_cast<std::int64_t>(v.size())), MPI_INT64_T, MPI_SUM,
                  MPI_COMM_WORLD);
  }
  std::vector<double> all_gather(std::span<const double> v) const override {
    std::vector<double> out(v.size() * static_cast<std::size_t>(size_));
    const int n = checked_count(static_cast<std::int64_t>(v.size()));
    MPI_Allgather(v.data(), n, MPI_DOUBLE, out.data(), n, MPI_DOUBLE, MPI_COMM_WORLD);
    return out;
  }
  std::vector<std::byte> all_gather_bytes(std::span<const std::byte> b) const override {
    const int mine = checked_count(static_cast<std::int64_t>(b.size()));
    std::vector<int> counts(static_cast<std::size_t>(size_)), displs(static_cast<std::size_t>(size_));
    MPI_Allgather(&mine, 1, MPI_INT, counts.data(), 1, MPI_INT, MPI_COMM_WORLD);
    std::int64_t total = 0;
    for (int q = 0; q < size_; ++q) {
      displs[static_cast<std::size_t>(q)] = checked_count(total);
      total += counts[static_cast<std::size_t>(q)];
    }
    std::vector<std::byte> out(static_cast<std::size_t>(total));
    MPI_Allgatherv(b.data(), mine, MPI_BYTE, out.data(), counts.data(), displs.data(), MPI_BYTE, MPI_COMM_WORLD);
    return out;
  }
  std::vector<std::int64_t> exchange_counts(std::span<const std::int64_t> send) const override {
    std::vector<std::int64_t> recv(static_cast<std::size_t>(size_));
    MPI_Alltoall(send.data(), 1, MPI_INT64_T, recv.data(), 1, MPI_INT64_T, MPI_COMM_WORLD);
    return recv;
  }
  void exchange(std::span<const std::byte> send, std::span<const std::int64_t> send_bytes, std::span<std::byte> recv,
                std::span<const std::int64_t> recv_bytes) const override {
    constexpr int kTag = 36;  // issue #36
    requests_.clear();
    std::int64_t off = 0;
    for (int q = 0; q < size_; ++q) {
      const std::int64_t n = recv_bytes[static_cast<std::size_t>(q)];
      if (n > 0) {
        requests_.emplace_back();
        MPI_Irecv(recv.data() + off, checked_count(n), MPI_BYTE, q, kTag, MPI_COMM_WORLD, &requests_.back());
      }
      off += n;
    }
    off = 0;
    for (int q = 0; q < size_; ++q) {
      const std::int64_t n = send_bytes[static_cast<std::size_t>(q)];
      if (n > 0) {
        requests_.emplace_back();
        MPI_Isend(send.data() + off, checked_count(n), MPI_BYTE, q, kTag, MPI_COMM_WORLD, &requests_.back());
      }
      off += n;
    }
    MPI_Waitall(static_cast<int>(requests_.size()), requests_.data(), MPI_STATUSES_IGNORE);
  }

 private:
  int rank_ = 0, size_ = 1;
  mutable std::vector<MPI_Request> requests_;
};

}  // namespace

std::shared_ptr<const Communicator> world_communicator(const Session& session) {
  if (!session.active()) return nullptr;
  return std::make_shared<WorldCommunicator>();
}

}  // namespace geohaz::mpi
