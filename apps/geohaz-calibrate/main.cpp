// geohaz-calibrate: back-analysis of debris-runout against an observed event, on one rank or under
// mpirun (issue #31, docs/calibration.md).
//
//   geohaz-calibrate calibrate.toml [--set key=value ...] [--out DIR] [--threads N] [--quiet]
//   mpirun -np R geohaz-calibrate calibrate.toml ...
//
// This file is the command line and the MPI distribution only; the search, the members and the
// outputs are libs/runout calibrate.hpp (MPI-free). Rank 0 drives the search; each batch it asks for
// (the design and Morris members, then one member per live local search and iteration) is spread
// over the ranks as geohaz-ensemble spreads its members: rank 0 keeps the queue and answers the
// other ranks' requests, one member (index and values) per request, between its own members' time
// steps; every member is published on disk by the rank that ran it, and rank 0 reads the scores from
// there in index order, so the search, and the best set, do not depend on the number of ranks.
// Started without mpirun the app never calls MPI_Init and runs every member itself.
#include <omp.h>

#include <boost/program_options.hpp>
#include <chrono>
#include <cstdlib>
#include <deque>
#include <filesystem>
#include <iostream>
#include <memory>
#include <string>
#include <thread>
#include <vector>

#include "geohaz/core/app.hpp"
#include "geohaz/core/config.hpp"
#include "geohaz/core/errors.hpp"
#include "geohaz/runout/calibrate.hpp"
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

const char* const kApp = "geohaz-calibrate";

#ifdef GEOHAZ_HAVE_MPI
/// Whether an MPI launcher (mpirun/mpiexec of Open MPI or MPICH, srun with PMI/PMIx) started us.
bool launched_by_mpi() {
  for (const char* v : {"OMPI_COMM_WORLD_SIZE", "PMIX_RANK", "PMI_RANK", "PMI_SIZE"})
    if (std::getenv(v)) return true;
  return false;
}
#endif

int local_ranks() {
  for (const char* v : {"OMPI_COMM_WORLD_LOCAL_SIZE", "MPI_LOCALNRANKS", "SLURM_NTASKS_PER_NODE"})
    if (const char* s = std::getenv(v)) {
      const int n = std::atoi(s);
      if (n > 0) return n;
    }
  return 1;
}

struct World {
  bool mpi = false;
  int rank = 0, size = 1;
};

constexpr int kTagRequest = 1, kTagAssign = 2;

#ifdef GEOHAZ_HAVE_MPI
/// Wait without spinning (Open MPI's blocking calls poll at full speed and would take a core from
/// the members of the other ranks on the node).
void wait_quietly(MPI_Request* request) {
  int done = 0;
  for (;;) {
    MPI_Test(request, &done, MPI_STATUS_IGNORE);
    if (done) return;
    std::this_thread::sleep_for(std::chrono::microseconds(500));
  }
}
#endif

/// Rank 0's queue of the current batch and its answers to the other ranks. A rank that asks while
/// the queue is empty waits (unanswered) for the next batch or the end.
class Coordinator : public RunObserver {
 public:
  Coordinator(const World& w, const CalibrationSetup& s, const fs::path& out) : w_(w), s_(s), out_(out) {}

  /// Run the batch over all ranks; returns when every member of it is on disk.
  void run_batch(const std::vector<int>& batch, MemberRunner& runner, int threads) {
    for (int i : batch)
      if (!member_done(out_, i)) queue_.push_back(i);
    assign();
    while (!queue_.empty()) {
      const int i = queue_.front();
      queue_.pop_front();
      runner.run(i, out_, 0, threads, this);
      service();
    }
    while (outstanding_ > 0) {
      service();
      if (outstanding_ > 0) std::this_thread::sleep_for(std::chrono::milliseconds(2));
    }
  }
  /// Tell every other rank to stop (once each has asked for more).
  void stop() {
#ifdef GEOHAZ_HAVE_MPI
    if (!w_.mpi) return;
    while (static_cast<int>(idle_.size()) < w_.size - 1) {
      service();
      std::this_thread::sleep_for(std::chrono::milliseconds(2));
    }
    std::vector<double> msg(1 + s_.parameters.size(), -1.0);
    for (int r : idle_) MPI_Send(msg.data(), static_cast<int>(msg.size()), MPI_DOUBLE, r, kTagAssign, MPI_COMM_WORLD);
    idle_.clear();
#endif
  }
  void started(const RunoutSimulation&) override {
    service();
  }
  void stepped(const RunoutSimulation&) override {
    service();
  }

 private:
  void service() {
#ifdef GEOHAZ_HAVE_MPI
    if (!w_.mpi) return;
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
  void assign() {
#ifdef GEOHAZ_HAVE_MPI
    while (!idle_.empty() && !queue_.empty()) {
      const int i = queue_.front();
      queue_.pop_front();
      const int r = idle_.front();
      idle_.pop_front();
      std::vector<double> msg{static_cast<double>(i)};
      const auto& v = s_.members.values.at(static_cast<std::size_t>(i));
      msg.insert(msg.end(), v.begin(), v.end());
      MPI_Send(msg.data(), static_cast<int>(msg.size()), MPI_DOUBLE, r, kTagAssign, MPI_COMM_WORLD);
      ++outstanding_;
    }
#endif
  }

  const World& w_;
  const CalibrationSetup& s_;
  const fs::path& out_;
  std::deque<int> queue_;
  std::deque<int> idle_;
  int outstanding_ = 0;
};

/// A rank other than 0: ask for members (reporting the last finished) until told to stop.
void serve(CalibrationSetup& s, const fs::path& out, int rank, int threads) {
#ifdef GEOHAZ_HAVE_MPI
  const std::unique_ptr<MemberRunner> runner = make_calibration_runner(s);
  int done[2] = {-1, 1};
  std::vector<double> msg(1 + s.parameters.size());
  for (;;) {
    MPI_Send(done, 2, MPI_INT, 0, kTagRequest, MPI_COMM_WORLD);
    MPI_Request r;
    MPI_Irecv(msg.data(), static_cast<int>(msg.size()), MPI_DOUBLE, 0, kTagAssign, MPI_COMM_WORLD, &r);
    wait_quietly(&r);
    if (msg[0] < 0.0) return;
    const int i = static_cast<int>(msg[0]);
    auto& values = s.members.values;
    if (values.size() <= static_cast<std::size_t>(i)) values.resize(static_cast<std::size_t>(i) + 1);
    values[static_cast<std::size_t>(i)].assign(msg.begin() + 1, msg.end());
    const MemberRecord rec = runner->run(i, out, rank, threads);
    done[0] = i, done[1] = rec.ok ? 1 : 0;
  }
#else
  (void)s, (void)out, (void)rank, (void)threads;
#endif
}

int run(int argc, char** argv, const World& world) {
  CommonOptions common;
  po::options_description desc("Options (SI units)");
  add_common_options(desc, common, "calibrate-out");
  po::positional_options_description pos;
  pos.add("config", 1);
  if (!parse_command_line(argc, argv, kApp,
                          "back-analysis of debris-runout against an observed event: the parameters (any numeric "
                          "key, the release thickness factor) that best reproduce a mapped footprint, run-out, "
                          "deposit and volume; a space-filling design and Morris trajectories, then NLopt local "
                          "searches, on one rank or under mpirun (docs/calibration.md).\n"
                          "Usage: [mpirun -np R] geohaz-calibrate calibrate.toml [--set key=value ...] [--out DIR] "
                          "[--threads N per rank] [--quiet]",
                          desc, &pos))
    return kExitOk;
  if (common.help_config) {
    if (world.rank == 0) {
      ConfigReader d = ConfigReader::describe();
      describe_calibration(d);
      std::cout << ConfigReader::format_reference(d.reference());
    }
    return kExitOk;
  }
  if (common.config.empty()) throw InputError("no calibration config given (positional argument)", "command line");
  int threads = common.threads;
  if (threads == 0) threads = std::max(1, omp_get_num_procs() / local_ranks());
  threads = setup_threads(threads);
  const bool quiet = common.quiet || world.rank != 0;

  // Every rank reads and checks the same config (all fail alike, nothing written).
  ConfigReader cfg = load_config(common);
  CalibrationSetup setup = read_calibration(cfg);
  const fs::path out(common.out);

  int folder_ok = 1;
  std::unique_ptr<InputError> folder_error;
  if (world.rank == 0) {
    try {
      prepare_calibration_output(setup, out);
    } catch (const InputError& e) {
      folder_ok = 0;
      folder_error = std::make_unique<InputError>(e);
    }
  }
#ifdef GEOHAZ_HAVE_MPI
  if (world.mpi) MPI_Bcast(&folder_ok, 1, MPI_INT, 0, MPI_COMM_WORLD);
#endif
  if (!folder_ok) {
    if (folder_error) throw *folder_error;
    return kExitInputError;
  }

  const auto wall0 = std::chrono::steady_clock::now();
  if (world.rank != 0) {
    serve(setup, out, world.rank, threads);
    return kExitOk;
  }
  if (!quiet)
    std::cerr << kApp << ": " << setup.parameters.size() << " parameter(s), " << setup.search.global_members
              << " design members, " << setup.search.morris_trajectories << " Morris trajectories, "
              << setup.search.local_starts << " local searches (" << setup.search.local_algorithm << ") on "
              << world.size << " rank(s) x " << threads << " thread(s)\n";
  const std::unique_ptr<MemberRunner> runner = make_calibration_runner(setup);
  Coordinator coord(world, setup, out);
  const CalibrationResult r = run_calibration(
      setup, out, [&](const std::vector<int>& batch) { coord.run_batch(batch, *runner, threads); }, quiet);
  coord.stop();
  const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - wall0).count();
  write_calibration_outputs(setup, r, out, world.size, threads, wall, quiet);
  return kExitOk;
}

}  // namespace

int main(int argc, char** argv) {
  World world;
#ifdef GEOHAZ_HAVE_MPI
  if (launched_by_mpi()) {
    int provided = 0;
#if defined(__SANITIZE_ADDRESS__)
    __lsan_disable();  // what Open MPI allocates in its init is its own business (geohaz-ensemble)
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
    // An error on one rank while others wait for it would hang the job: end them all.
    if (code != kExitOk && code != kExitInputError) MPI_Abort(MPI_COMM_WORLD, code);
#if defined(__SANITIZE_ADDRESS__)
    __lsan_do_leak_check();  // before MPI_Finalize (see geohaz-ensemble's main.cpp)
#endif
    MPI_Finalize();
  }
#endif
  return code;
}
