#pragma once
/// \file session.hpp
/// The MPI start-up of every app that runs alone or under mpirun (sph-slope-mpi; geohaz-ensemble
/// and geohaz-calibrate through apps/member-queue), in one place: MPI stays in apps/, the libraries,
/// the Python module and the packages stay MPI-free. Built without an MPI installation
/// (GEOHAZ_HAVE_MPI undefined) it is the one-rank version: a Session is never active.

namespace geohaz::mpi {

/// Whether an MPI launcher (mpirun/mpiexec of Open MPI or MPICH, srun with PMI/PMIx) started this
/// process: only then is MPI initialised (a plain start runs on one rank without touching MPI).
bool launched_by_mpi();

/// Ranks on this node (Open MPI, MPICH or Slurm's variables; 1 when none is set): the node's cores
/// are shared between them when the user does not give --threads.
int local_ranks();

/// OpenMP threads per rank: `requested`, or (0) the node's cores shared between its ranks.
int threads_per_rank(int requested);

/// MPI_Init_thread (funneled: OpenMP threads inside a rank, MPI calls from the main thread only) in
/// the constructor when launched by mpirun, MPI_Finalize in the destructor; otherwise nothing. Under
/// AddressSanitizer what Open MPI allocates in its init is not reported, and the leak check of our
/// own code runs before MPI_Finalize (session.cpp; Open MPI's own threads: scripts/lsan.supp). One
/// per process, constructed first in main().
class Session {
 public:
  Session(int& argc, char**& argv);
  ~Session();
  Session(const Session&) = delete;
  Session& operator=(const Session&) = delete;
  bool active() const noexcept { return active_; }
  int rank() const noexcept { return rank_; }
  int size() const noexcept { return size_; }
  /// End every rank with `code` (an error on one rank while the others wait for it would hang).
  /// Nothing when not active.
  void abort(int code) const;

 private:
  bool active_ = false;
  int rank_ = 0, size_ = 1;
};

}  // namespace geohaz::mpi
