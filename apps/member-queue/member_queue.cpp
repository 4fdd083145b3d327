/// \file member_queue.cpp
/// The MPI distribution of geohaz-ensemble and geohaz-calibrate (member_queue.hpp). The protocol:
/// a rank other than 0 sends {finished member or -1, ok} (tag kTagRequest) and receives
/// {member, payload...} as doubles (tag kTagAssign); a negative member means stop.
#include "member_queue.hpp"

#include <omp.h>

#include <algorithm>
#include <chrono>
#include <cstdlib>
#include <thread>

#include "geohaz/core/app.hpp"
#include "geohaz/core/errors.hpp"

#ifdef GEOHAZ_HAVE_MPI
#include <mpi.h>
#endif
#if defined(__SANITIZE_ADDRESS__)
#include <sanitizer/lsan_interface.h>
#endif

namespace geohaz::apps {

namespace {

[[maybe_unused]] constexpr int kTagRequest = 1, kTagAssign = 2;

#ifdef GEOHAZ_HAVE_MPI
/// Whether an MPI launcher (mpirun/mpiexec of Open MPI or MPICH, srun with PMI/PMIx) started us.
bool launched_by_mpi() {
  for (const char* v : {"OMPI_COMM_WORLD_SIZE", "PMIX_RANK", "PMI_RANK", "PMI_SIZE"})
    if (std::getenv(v)) return true;
  return false;
}

/// Wait for a request without spinning (see member_queue.hpp): up to one member's time.
void wait_quietly(MPI_Request* request) {
  int done = 0;
  for (;;) {
    MPI_Test(request, &done, MPI_STATUS_IGNORE);
    if (done) return;
    std::this_thread::sleep_for(std::chrono::microseconds(500));
  }
}
#endif

}  // namespace

int World::broadcast(int value) const {
#ifdef GEOHAZ_HAVE_MPI
  if (mpi) MPI_Bcast(&value, 1, MPI_INT, 0, MPI_COMM_WORLD);
#endif
  return value;
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

int run_mpi_app(const char* app, int argc, char** argv, const std::function<int(const World&)>& body) {
  World world;
#ifdef GEOHAZ_HAVE_MPI
  if (launched_by_mpi()) {
    int provided = 0;
#if defined(__SANITIZE_ADDRESS__)
    __lsan_disable();  // what Open MPI allocates in its init is its own business (see below)
#endif
    MPI_Init_thread(&argc, &argv, MPI_THREAD_FUNNELED, &provided);
#if defined(__SANITIZE_ADDRESS__)
    __lsan_enable();
#endif
    world.mpi = true;
    MPI_Comm_rank(MPI_COMM_WORLD, &world.rank);
    MPI_Comm_size(MPI_COMM_WORLD, &world.size);
  }
#endif
  const std::string name = world.rank == 0 ? app : std::string(app) + " (rank " + std::to_string(world.rank) + ")";
  const int code = run_main(name, [&] { return body(world); });
#ifdef GEOHAZ_HAVE_MPI
  if (world.mpi) {
    // An error on one rank while others wait for it would hang the job: end them all. (Input
    // errors happen on every rank alike before any message is exchanged.)
    if (code != kExitOk && code != kExitInputError) MPI_Abort(MPI_COMM_WORLD, code);
#if defined(__SANITIZE_ADDRESS__)
    // Under the sanitizers (scripts/test --sanitize): the leak check of our own code runs here, while
    // Open MPI still holds its memory; it then skips the end-of-process check, which would report
    // what MPI_Finalize leaves behind (Open MPI 4.1 frees its components' tables only partly, in
    // libraries built without frame pointers, so no lsan.supp pattern can match those 2-frame stacks
    // short of the slow unwinder). Allocations of Open MPI's own threads are in scripts/lsan.supp.
    __lsan_do_leak_check();
#endif
    MPI_Finalize();
  }
#else
  (void)argc, (void)argv;
#endif
  return code;
}

MemberQueue::MemberQueue(const World& world, std::size_t payload_width, std::function<std::vector<double>(int)> payload)
    : world_(world), width_(payload_width), payload_(std::move(payload)) {}

void MemberQueue::push(int member) {
  queue_.push_back(member);
  assign();
}

int MemberQueue::take() {
  if (queue_.empty()) return -1;
  const int i = queue_.front();
  queue_.pop_front();
  return i;
}

void MemberQueue::service() {
#ifdef GEOHAZ_HAVE_MPI
  if (!world_.mpi) return;
  for (;;) {
    int flag = 0;
    MPI_Status st;
    MPI_Iprobe(MPI_ANY_SOURCE, kTagRequest, MPI_COMM_WORLD, &flag, &st);
    if (!flag) break;
    int done[2];
    MPI_Recv(done, 2, MPI_INT, st.MPI_SOURCE, kTagRequest, MPI_COMM_WORLD, MPI_STATUS_IGNORE);
    if (done[0] >= 0) --outstanding_;
    idle_.push_back(st.MPI_SOURCE);
  }
  assign();
#endif
}

void MemberQueue::assign() {
#ifdef GEOHAZ_HAVE_MPI
  while (!idle_.empty() && !queue_.empty()) {
    const int i = take();
    const int r = idle_.front();
    idle_.pop_front();
    std::vector<double> msg{static_cast<double>(i)};
    if (width_ > 0) {
      const std::vector<double> v = payload_(i);
      if (v.size() != width_) throw std::logic_error("member payload of the wrong width");
      msg.insert(msg.end(), v.begin(), v.end());
    }
    MPI_Send(msg.data(), static_cast<int>(msg.size()), MPI_DOUBLE, r, kTagAssign, MPI_COMM_WORLD);
    ++outstanding_;
  }
#endif
}

void MemberQueue::wait_for_others() {
  while (outstanding_ > 0) {
    service();
    if (outstanding_ > 0) std::this_thread::sleep_for(std::chrono::milliseconds(2));
  }
}

void MemberQueue::stop() {
#ifdef GEOHAZ_HAVE_MPI
  if (!world_.mpi) return;
  while (static_cast<int>(idle_.size()) < world_.size - 1) {
    service();
    if (static_cast<int>(idle_.size()) < world_.size - 1) std::this_thread::sleep_for(std::chrono::milliseconds(2));
  }
  std::vector<double> msg(1 + width_, -1.0);
  for (int r : idle_) MPI_Send(msg.data(), static_cast<int>(msg.size()), MPI_DOUBLE, r, kTagAssign, MPI_COMM_WORLD);
  idle_.clear();
#endif
}

bool request_member(int finished, bool ok, std::size_t payload_width, int& member, std::vector<double>& values) {
#ifdef GEOHAZ_HAVE_MPI
  int done[2] = {finished, ok ? 1 : 0};
  MPI_Send(done, 2, MPI_INT, 0, kTagRequest, MPI_COMM_WORLD);
  std::vector<double> msg(1 + payload_width);
  MPI_Request r;
  MPI_Irecv(msg.data(), static_cast<int>(msg.size()), MPI_DOUBLE, 0, kTagAssign, MPI_COMM_WORLD, &r);
  wait_quietly(&r);
  if (msg[0] < 0.0) return false;
  member = static_cast<int>(msg[0]);
  values.assign(msg.begin() + 1, msg.end());
  return true;
#else
  (void)finished, (void)ok, (void)payload_width, (void)member, (void)values;
  return false;
#endif
}

}  // namespace geohaz::apps
