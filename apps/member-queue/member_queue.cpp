/// \file member_queue.cpp
/// The MPI distribution of geohaz-ensemble and geohaz-calibrate (member_queue.hpp). The protocol:
/// a rank other than 0 sends {finished member or -1, ok} (tag kTagRequest) and receives
/// {member, payload...} as doubles (tag kTagAssign); a negative member means stop.
#include "member_queue.hpp"

#include <algorithm>
#include <chrono>
#include <cstdlib>
#include <thread>

#include "geohaz/core/app.hpp"
#include "geohaz/core/errors.hpp"
#include "geohaz/mpi/session.hpp"

#ifdef GEOHAZ_HAVE_MPI
#include <mpi.h>
#endif

namespace geohaz::apps {

namespace {

[[maybe_unused]] constexpr int kTagRequest = 1, kTagAssign = 2;

#ifdef GEOHAZ_HAVE_MPI
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

int run_mpi_app(const char* app, int argc, char** argv, const std::function<int(const World&)>& body) {
  const mpi::Session session(argc, argv);  // MPI_Init when launched by mpirun; MPI_Finalize at the end
  World world;
  world.mpi = session.active();
  world.rank = session.rank();
  world.size = session.size();
  const std::string name = world.rank == 0 ? app : std::string(app) + " (rank " + std::to_string(world.rank) + ")";
  const int code = run_main(name, [&] { return body(world); });
  // An error on one rank while others wait for it would hang the job: end them all. (Input
  // errors happen on every rank alike before any message is exchanged.)
  if (code != kExitOk && code != kExitInputError) session.abort(code);
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
