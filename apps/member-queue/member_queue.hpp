#pragma once
/// \file member_queue.hpp
/// The MPI side of geohaz-ensemble and geohaz-calibrate, shared by both (the libraries stay
/// MPI-free, so this lives under apps/). Built without MPI (GEOHAZ_HAVE_MPI undefined) it is the
/// one-rank version of the same calls.
///
/// - `run_mpi_app`: main() of an app that may run under mpirun: the MPI start-up of every such app
///   (geohaz/mpi/session.hpp: MPI_Init only when an MPI launcher started the process, MPI_Finalize),
///   the app's body inside run_main's exit-code mapping, MPI_Abort when one rank fails otherwise
///   than on input (the others would wait for it). Threads per rank: mpi::threads_per_rank.
/// - `MemberQueue` (rank 0) and `request_member` (the other ranks): dynamic distribution of
///   independent members, one member per request, rank 0 computing too. Rank 0 keeps the queue in
///   the order it was filled and answers the other ranks between its own members' time steps (it is
///   the run observer); a rank asking while the queue is empty waits, unanswered, for more members
///   or the end (`stop`). An assignment is the member's index and `payload_width` numbers (its
///   parameter values, for a rank that cannot know them in advance).
/// - Waiting ranks sleep between polls instead of spinning (Open MPI's blocking calls poll at full
///   speed and would take a core from the members of the other ranks on the node).
#include <deque>
#include <functional>
#include <string>
#include <vector>

#include "geohaz/mpi/session.hpp"
#include "geohaz/runout/run.hpp"

namespace geohaz::apps {

/// The MPI world, or one rank without MPI.
struct World {
  bool mpi = false;
  int rank = 0, size = 1;
  /// Rank 0's `value` on every rank (itself without MPI).
  int broadcast(int value) const;
};

/// main() of an app that runs alone or under mpirun: `body(world)` inside run_main (exit codes of
/// geohaz/core/app.hpp), the error messages of a rank other than 0 naming the rank.
int run_mpi_app(const char* app, int argc, char** argv, const std::function<int(const World&)>& body);

/// Rank 0's queue of members and its answers to the other ranks.
class MemberQueue : public runout::RunObserver {
 public:
  /// `payload(i)`: the `payload_width` numbers sent with member i (may be empty when 0).
  MemberQueue(const World& world, std::size_t payload_width, std::function<std::vector<double>(int)> payload = nullptr);
  /// Add a member at the end of the queue (and hand it to a waiting rank at once).
  void push(int member);
  /// The next member for rank 0 itself (-1: the queue is empty).
  int take();
  /// Answer every pending request (non-blocking).
  void service();
  /// Wait (answering) until every member handed to another rank is reported finished.
  void wait_for_others();
  /// After the last member: wait until every other rank has finished and asked again, then tell it
  /// to stop. Once only.
  void stop();
  /// Members handed to other ranks and not yet reported finished.
  int outstanding() const { return outstanding_; }

  void started(const runout::RunoutSimulation&) override { service(); }
  void stepped(const runout::RunoutSimulation&) override { service(); }

 private:
  void assign();

  const World& world_;
  std::size_t width_;
  std::function<std::vector<double>(int)> payload_;
  std::deque<int> queue_, idle_;
  int outstanding_ = 0;
};

/// A rank other than 0: report the member it finished (-1 at the start; `ok` its status) and wait
/// for the next one. Returns false when told to stop; otherwise `member` and `values` (the
/// `payload_width` numbers rank 0 sent) are set.
bool request_member(int finished, bool ok, std::size_t payload_width, int& member, std::vector<double>& values);

}  // namespace geohaz::apps
