/// \file session.cpp
/// The MPI start-up of the apps (session.hpp).
#include "geohaz/mpi/session.hpp"

#include <omp.h>

#include <algorithm>
#include <cstdlib>

#ifdef GEOHAZ_HAVE_MPI
#include <mpi.h>
#endif
#if defined(__SANITIZE_ADDRESS__)
#include <sanitizer/lsan_interface.h>
#endif

namespace geohaz::mpi {

bool launched_by_mpi() {
  for (const char* v : {"OMPI_COMM_WORLD_SIZE", "PMIX_RANK", "PMI_RANK", "PMI_SIZE"})
    if (std::getenv(v)) return true;
  return false;
}

int local_ranks() {
  for (const char* v : {"OMPI_COMM_WORLD_LOCAL_SIZE", "MPI_LOCALNRANKS", "SLURM_NTASKS_PER_NODE"})
    if (const char* s = std::getenv(v)) {
      const int n = std::atoi(s);
      if (n > 0) return n;
    }
  return 1;
}

int threads_per_rank(int requested) {
  return requested > 0 ? requested : std::max(1, omp_get_num_procs() / local_ranks());
}

Session::Session(int& argc, char**& argv) {
#ifdef GEOHAZ_HAVE_MPI
  if (!launched_by_mpi()) return;
  int provided = 0;
#if defined(__SANITIZE_ADDRESS__)
  __lsan_disable();  // what Open MPI allocates in its init is its own business
#endif
  MPI_Init_thread(&argc, &argv, MPI_THREAD_FUNNELED, &provided);
#if defined(__SANITIZE_ADDRESS__)
  __lsan_enable();
#endif
  active_ = true;
  MPI_Comm_rank(MPI_COMM_WORLD, &rank_);
  MPI_Comm_size(MPI_COMM_WORLD, &size_);
#else
  (void)argc, (void)argv;
#endif
}

Session::~Session() {
#ifdef GEOHAZ_HAVE_MPI
  if (!active_) return;
#if defined(__SANITIZE_ADDRESS__)
  // Under the sanitizers (scripts/test --sanitize): the leak check of our own code runs here, while
  // Open MPI still holds its memory; it then skips the end-of-process check, which would report
  // what MPI_Finalize leaves behind (Open MPI 4.1 frees its components' tables only partly, in
  // libraries built without frame pointers, so no lsan.supp pattern can match those 2-frame stacks
  // short of the slow unwinder). Allocations of Open MPI's own threads are in scripts/lsan.supp.
  __lsan_do_leak_check();
#endif
  MPI_Finalize();
#endif
}

void Session::abort(int code) const {
#ifdef GEOHAZ_HAVE_MPI
  if (active_) MPI_Abort(MPI_COMM_WORLD, code);
#else
  (void)code;
#endif
}

}  // namespace geohaz::mpi
