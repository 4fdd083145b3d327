// geohaz-ensemble: an ensemble of debris-runout runs with uncertain parameters, spread over MPI
// ranks, aggregated into probability, mean and percentile maps (issue #17, docs/ensemble.md).
//
//   geohaz-ensemble ensemble.toml [--set key=value ...] [--out DIR] [--threads N] [--quiet]
//   mpirun -np R geohaz-ensemble ensemble.toml ...
//
// This file is the command line and the MPI distribution only; the plan, the members and the
// aggregation are libs/runout ensemble.hpp (MPI-free). Distribution: rank 0 keeps the queue of
// unfinished members (index order) and answers the other ranks' requests, one member per request
// (dynamic load balancing: members differ in cost), between its own members' time steps (the run
// observer), so rank 0 computes too. Every member is published on disk by the rank that ran it;
// rank 0 aggregates from disk in index order once all are done, so the maps do not depend on the
// number of ranks. Started without mpirun (no MPI launcher in the environment) the app never calls
// MPI_Init and runs every member itself.
#include <omp.h>

#include <boost/program_options.hpp>
#include <chrono>
#include <cstdlib>
#include <deque>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <memory>
#include <sstream>
#include <string>
#include <thread>

#include "geohaz/core/app.hpp"
#include "geohaz/core/config.hpp"
#include "geohaz/core/errors.hpp"
#include "geohaz/core/output.hpp"
#include "geohaz/runout/ensemble.hpp"
#include "geohaz/runout/run.hpp"

#ifdef GEOHAZ_HAVE_MPI
#include <mpi.h>
#endif
#if defined(__SANITIZE_ADDRESS__)
#include <sanitizer/lsan_interface.h>
#endif

namespace po = boost::program_options;
namespace fs = std::filesystem;
using namespace geohaz;
using namespace geohaz::runout;

namespace {

const char* const kApp = "geohaz-ensemble";

/// Whether an MPI launcher (mpirun/mpiexec of Open MPI or MPICH, srun with PMI/PMIx) started us.
bool launched_by_mpi() {
  for (const char* v : {"OMPI_COMM_WORLD_SIZE", "PMIX_RANK", "PMI_RANK", "PMI_SIZE"})
    if (std::getenv(v)) return true;
  return false;
}

/// Ranks on this node (to share its cores between them when --threads is not given).
int local_ranks() {
  for (const char* v : {"OMPI_COMM_WORLD_LOCAL_SIZE", "MPI_LOCALNRANKS", "SLURM_NTASKS_PER_NODE"})
    if (const char* s = std::getenv(v)) {
      const int n = std::atoi(s);
      if (n > 0) return n;
    }
  return 1;
}

/// The MPI world (or a single rank without MPI).
struct World {
  bool mpi = false;
  int rank = 0, size = 1;
  void abort(int code) const {
#ifdef GEOHAZ_HAVE_MPI
    if (mpi) MPI_Abort(MPI_COMM_WORLD, code);
#endif
    (void)code;
  }
  void barrier() const;
};

constexpr int kTagRequest = 1, kTagAssign = 2;

#ifdef GEOHAZ_HAVE_MPI
/// Wait for a request without spinning: Open MPI's blocking calls poll at full speed, which takes a
/// core away from the members of other ranks (or other jobs) on the same node while this rank waits
/// for rank 0's answer or the final barrier (up to one member's time).
void wait_quietly(MPI_Request* request) {
  int done = 0;
  for (;;) {
    MPI_Test(request, &done, MPI_STATUS_IGNORE);
    if (done) return;
    std::this_thread::sleep_for(std::chrono::microseconds(500));
  }
}
#endif

void World::barrier() const {
#ifdef GEOHAZ_HAVE_MPI
  if (!mpi) return;
  MPI_Request r;
  MPI_Ibarrier(MPI_COMM_WORLD, &r);
  wait_quietly(&r);
#endif
}

/// Rank 0's queue of members and its answers to the other ranks.
class Coordinator : public RunObserver {
 public:
  Coordinator(const World& w, std::deque<int> queue) : w_(w), queue_(std::move(queue)), workers_(w.size - 1) {}
  /// The next member for rank 0 itself (-1: none left).
  int take() {
    if (queue_.empty()) return -1;
    const int i = queue_.front();
    queue_.pop_front();
    return i;
  }
  /// Answer every pending request (non-blocking).
  void service() {
#ifdef GEOHAZ_HAVE_MPI
    if (!w_.mpi) return;
    for (;;) {
      int flag = 0;
      MPI_Status st;
      MPI_Iprobe(MPI_ANY_SOURCE, kTagRequest, MPI_COMM_WORLD, &flag, &st);
      if (!flag) return;
      int done[2];
      MPI_Recv(done, 2, MPI_INT, st.MPI_SOURCE, kTagRequest, MPI_COMM_WORLD, MPI_STATUS_IGNORE);
      if (done[0] >= 0) ++finished_elsewhere_;
      int next = take();
      if (next < 0) --workers_;
      MPI_Send(&next, 1, MPI_INT, st.MPI_SOURCE, kTagAssign, MPI_COMM_WORLD);
    }
#endif
  }
  /// After rank 0's own work: answer until every other rank has been told to stop.
  void drain() {
    while (workers_ > 0) {
      service();
      if (workers_ > 0) std::this_thread::sleep_for(std::chrono::milliseconds(2));
    }
  }
  void started(const RunoutSimulation&) override {
    service();
  }
  void stepped(const RunoutSimulation&) override {
    service();
  }

 private:
  const World& w_;
  std::deque<int> queue_;
  int workers_;
  int finished_elsewhere_ = 0;
};

/// The next member for a rank other than 0 (reporting the one it finished, -1 at the start).
int request_member(int finished, bool ok) {
#ifdef GEOHAZ_HAVE_MPI
  int done[2] = {finished, ok ? 1 : 0};
  MPI_Send(done, 2, MPI_INT, 0, kTagRequest, MPI_COMM_WORLD);
  int next = -1;
  MPI_Request r;
  MPI_Irecv(&next, 1, MPI_INT, 0, kTagAssign, MPI_COMM_WORLD, &r);
  wait_quietly(&r);
  return next;
#else
  (void)finished, (void)ok;
  return -1;
#endif
}

void report(const MemberRecord& r, int n, bool quiet) {
  if (quiet) return;
  std::ostringstream o;
  o.precision(4);
  o << kApp << ": member " << r.index << "/" << n << " (rank " << r.rank << ") ";
  if (r.ok)
    o << "run-out " << r.runout_m << " m, H/L " << r.hl << ", " << r.wall_time_s << " s";
  else
    o << "FAILED: " << r.diagnosis;
  std::cerr << o.str() << "\n";
}

int run(int argc, char** argv, const World& world) {
  CommonOptions common;
  po::options_description desc("Options (SI units)");
  add_common_options(desc, common, "ensemble-out",
                     "output directory: new, empty, or holding the same ensemble (same config), which resumes: "
                     "members already done are kept and only the missing ones run; a different ensemble or any "
                     "other file there stops the run (exit 2)");
  po::positional_options_description pos;
  pos.add("config", 1);
  if (!parse_command_line(argc, argv, kApp,
                          "an ensemble of debris-runout runs with uncertain parameters (Latin hypercube or Monte "
                          "Carlo), on one rank or under mpirun, aggregated into probability-of-exceedance, mean and "
                          "percentile maps (docs/ensemble.md).\n"
                          "Usage: [mpirun -np R] geohaz-ensemble ensemble.toml [--set key=value ...] [--out DIR] "
                          "[--threads N per rank] [--quiet]\n"
                          "Example: geohaz-ensemble data/runout/alr_ensemble.toml --set ensemble.members=8 --out "
                          "ensemble-alr",
                          desc, &pos))
    return kExitOk;
  if (common.help_config) {
    if (world.rank == 0) {
      ConfigReader d = ConfigReader::describe();
      describe_ensemble(d);
      std::cout << ConfigReader::format_reference(d.reference());
    }
    return kExitOk;
  }
  if (common.config.empty()) throw InputError("no ensemble config given (positional argument)", "command line");
  // Threads per rank: the cores of the node shared between its ranks unless given.
  int threads = common.threads;
  if (threads == 0) threads = std::max(1, omp_get_num_procs() / local_ranks());
  threads = setup_threads(threads);
  const bool quiet = common.quiet || world.rank != 0;

  // Every rank reads and checks the same config (deterministic: all fail alike, nothing written).
  ConfigReader cfg = load_config(common);
  const EnsembleSetup setup = read_ensemble(cfg);
  const fs::path out(common.out);
  const int n = setup.plan.members;

  // Rank 0 prepares the folder: a new one, or the same ensemble to resume (all ranks learn whether
  // it could, so none waits for a rank 0 that stopped).
  int resume_ok = 1;
  std::deque<int> queue;
  std::unique_ptr<InputError> folder_error;
  if (world.rank == 0) {
    try {
      const std::vector<int> pending = prepare_output(setup, out);
      queue.assign(pending.begin(), pending.end());
    } catch (const InputError& e) {
      resume_ok = 0;
      folder_error = std::make_unique<InputError>(e);
    }
  }
#ifdef GEOHAZ_HAVE_MPI
  if (world.mpi) MPI_Bcast(&resume_ok, 1, MPI_INT, 0, MPI_COMM_WORLD);
#endif
  if (!resume_ok) {
    if (folder_error) throw *folder_error;
    return kExitInputError;
  }

  const auto wall0 = std::chrono::steady_clock::now();
  MemberRunner runner(setup);
  if (world.rank == 0) {
    const std::size_t skipped = static_cast<std::size_t>(n) - queue.size();
    if (!quiet)
      std::cerr << kApp << ": " << n << " members (" << skipped << " finished before, " << queue.size()
                << " to run) on " << world.size << " rank(s) × " << threads << " thread(s)\n";
    Coordinator coord(world, std::move(queue));
    for (int i; (i = coord.take()) >= 0;) {
      coord.service();
      report(runner.run(i, out, 0, threads, &coord), n, quiet);
    }
    coord.drain();
  } else {
    int last = -1;
    bool ok = true;
    for (int i; (i = request_member(last, ok)) >= 0;) {
      const MemberRecord r = runner.run(i, out, world.rank, threads);
      if (!common.quiet) report(r, n, false);
      last = i, ok = r.ok;
    }
  }
  world.barrier();
  if (world.rank == 0) {
    const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - wall0).count();
    aggregate_ensemble(setup, out, world.size, threads, wall, quiet);
  }
  return kExitOk;
}

}  // namespace

int main(int argc, char** argv) {
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
  const int code = run_main(world.rank == 0 ? kApp : std::string(kApp) + " (rank " + std::to_string(world.rank) + ")",
                            [&] { return run(argc, argv, world); });
#ifdef GEOHAZ_HAVE_MPI
  if (world.mpi) {
    // An error on one rank while others wait for it would hang the job: end them all. (Input
    // errors happen on every rank alike before any message is exchanged.)
    if (code != kExitOk && code != kExitInputError) world.abort(code);
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
#endif
  return code;
}
