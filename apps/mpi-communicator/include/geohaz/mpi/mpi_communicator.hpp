#pragma once
/// \file mpi_communicator.hpp
/// Open MPI behind core's Communicator (geohaz/core/communicator.hpp), and the MPI session of an app
/// that runs alone or under mpirun. Only apps and MPI tests include this header; the model
/// libraries see the Communicator interface.

#include <memory>

#include "geohaz/core/communicator.hpp"

namespace geohaz::mpi {

/// Whether an MPI launcher (mpirun/mpiexec of Open MPI or MPICH, srun with PMI/PMIx) started this
/// process: only then is MPI initialised (a plain start runs on one rank without touching MPI).
bool launched_by_mpi();

/// MPI_Init_thread (funneled: OpenMP threads inside a rank, MPI calls from the main thread only) in
/// the constructor when launched by mpirun, MPI_Finalize in the destructor; otherwise nothing. Under
/// AddressSanitizer what Open MPI allocates in its init is not reported, and the leak check of our
/// own code runs before MPI_Finalize (as apps/member-queue does; scripts/lsan.supp). One per
/// process.
class Session {
 public:
  Session(int& argc, char**& argv);
  ~Session();
  Session(const Session&) = delete;
  Session& operator=(const Session&) = delete;
  bool active() const noexcept { return active_; }
  int rank() const noexcept { return rank_; }
  int size() const noexcept { return size_; }
  /// The world communicator (null when MPI is not active).
  std::shared_ptr<const Communicator> world() const { return world_; }
  /// End every rank with `code` (an error on one rank while the others wait for it would hang).
  void abort(int code) const;

 private:
  bool active_ = false;
  int rank_ = 0, size_ = 1;
  std::shared_ptr<const Communicator> world_;
};

}  // namespace geohaz::mpi
