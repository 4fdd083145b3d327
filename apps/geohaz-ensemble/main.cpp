// geohaz-ensemble: an ensemble of debris-runout runs with uncertain parameters, spread over MPI
// ranks, aggregated into probability, mean and percentile maps (issue #17, docs/ensemble.md).
//
//   geohaz-ensemble ensemble.toml [--set key=value ...] [--out DIR] [--threads N] [--quiet]
//   mpirun -np R geohaz-ensemble ensemble.toml ...
//
// This file is the command line; the plan, the members and the aggregation are libs/runout
// ensemble.hpp (MPI-free), the distribution over MPI ranks is apps/member-queue (shared with
// geohaz-calibrate): rank 0 keeps the queue of unfinished members (index order) and answers the
// other ranks' requests, one member per request (dynamic load balancing: members differ in cost),
// between its own members' time steps, so rank 0 computes too. Every member is published on disk by
// the rank that ran it; rank 0 aggregates from disk in index order once all are done, so the maps
// do not depend on the number of ranks. Started without mpirun (no MPI launcher in the
// environment) the app never calls MPI_Init and runs every member itself.
#include <boost/program_options.hpp>
#include <chrono>
#include <filesystem>
#include <iostream>
#include <memory>
#include <sstream>
#include <string>
#include <vector>

#include "geohaz/core/app.hpp"
#include "geohaz/core/config.hpp"
#include "geohaz/core/errors.hpp"
#include "geohaz/core/output.hpp"
#include "geohaz/runout/ensemble.hpp"
#include "geohaz/runout/run.hpp"
#include "member_queue.hpp"

namespace po = boost::program_options;
namespace fs = std::filesystem;
using namespace geohaz;
using namespace geohaz::runout;
using geohaz::apps::World;

namespace {

const char* const kApp = "geohaz-ensemble";

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
  const int threads = setup_threads(mpi::threads_per_rank(common.threads));
  const bool quiet = common.quiet || world.rank != 0;

  // Every rank reads and checks the same config (deterministic: all fail alike, nothing written).
  ConfigReader cfg = load_config(common);
  const EnsembleSetup setup = read_ensemble(cfg);
  const fs::path out(common.out);
  const int n = setup.plan.members;

  // Rank 0 prepares the folder: a new one, or the same ensemble to resume (all ranks learn whether
  // it could, so none waits for a rank 0 that stopped).
  int resume_ok = 1;
  std::vector<int> queue;
  std::unique_ptr<InputError> folder_error;
  if (world.rank == 0) {
    try {
      queue = prepare_output(setup, out);
    } catch (const InputError& e) {
      resume_ok = 0;
      folder_error = std::make_unique<InputError>(e);
    }
  }
  if (!world.broadcast(resume_ok)) {
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
    apps::MemberQueue members(world, 0);
    for (int i : queue) members.push(i);
    for (int i; (i = members.take()) >= 0;) {
      members.service();
      report(runner.run(i, out, 0, threads, &members), n, quiet);
    }
    members.stop();  // returns when every other rank has finished its last member
  } else {
    int last = -1;
    bool ok = true;
    std::vector<double> none;
    for (int i; apps::request_member(last, ok, 0, i, none);) {
      const MemberRecord r = runner.run(i, out, world.rank, threads);
      if (!common.quiet) report(r, n, false);
      last = i, ok = r.ok;
    }
  }
  if (world.rank == 0) {
    const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - wall0).count();
    aggregate_ensemble(setup, out, world.size, threads, wall, quiet);
  }
  return kExitOk;
}

}  // namespace

int main(int argc, char** argv) {
  return geohaz::apps::run_mpi_app(kApp, argc, argv, [&](const World& world) { return run(argc, argv, world); });
}
