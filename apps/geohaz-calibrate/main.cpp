// geohaz-calibrate: back-analysis of debris-runout against an observed event, on one rank or under
// mpirun (issue #31, docs/calibration.md).
//
//   geohaz-calibrate calibrate.toml [--set key=value ...] [--out DIR] [--threads N] [--quiet]
//   mpirun -np R geohaz-calibrate calibrate.toml ...
//
// This file is the command line; the search, the members and the outputs are libs/runout
// calibrate.hpp (MPI-free), the distribution over MPI ranks is apps/member-queue (shared with
// geohaz-ensemble). Rank 0 drives the search; each batch it asks for (the design and Morris
// members, then one member per live local search and iteration) is spread over the ranks as the
// ensemble spreads its members: rank 0 keeps the queue and answers the other ranks' requests, one
// member (index and values) per request, between its own members' time steps; every member is
// published on disk by the rank that ran it, and rank 0 reads the scores from there in index order,
// so the search, and the best set, do not depend on the number of ranks. Started without mpirun
// the app never calls MPI_Init and runs every member itself.
#include <boost/program_options.hpp>
#include <chrono>
#include <filesystem>
#include <iostream>
#include <memory>
#include <string>
#include <vector>

#include "geohaz/core/app.hpp"
#include "geohaz/core/config.hpp"
#include "geohaz/core/errors.hpp"
#include "geohaz/runout/calibrate.hpp"
#include "geohaz/runout/run.hpp"
#include "member_queue.hpp"

namespace po = boost::program_options;
namespace fs = std::filesystem;
using namespace geohaz;
using namespace geohaz::runout;
using geohaz::apps::World;

namespace {

const char* const kApp = "geohaz-calibrate";

/// Run a batch over all ranks (rank 0 too); returns when every member of it is on disk.
void run_batch(apps::MemberQueue& members, const std::vector<int>& batch, const fs::path& out, MemberRunner& runner,
               int threads) {
  for (int i : batch)
    if (!member_done(out, i)) members.push(i);
  for (int i; (i = members.take()) >= 0;) {
    runner.run(i, out, 0, threads, &members);
    members.service();
  }
  members.wait_for_others();
}

/// A rank other than 0: run the members rank 0 sends (index and values) until told to stop.
void serve(CalibrationSetup& s, const fs::path& out, int rank, int threads) {
  const std::unique_ptr<MemberRunner> runner = make_calibration_runner(s);
  int last = -1;
  bool ok = true;
  std::vector<double> values;
  for (int i; apps::request_member(last, ok, s.parameters.size(), i, values);) {
    auto& all = s.members.values;
    if (all.size() <= static_cast<std::size_t>(i)) all.resize(static_cast<std::size_t>(i) + 1);
    all[static_cast<std::size_t>(i)] = values;
    ok = runner->run(i, out, rank, threads).ok;
    last = i;
  }
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
  const int threads = setup_threads(mpi::threads_per_rank(common.threads));
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
  if (!world.broadcast(folder_ok)) {
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
  apps::MemberQueue members(world, setup.parameters.size(),
                            [&](int i) { return setup.members.values.at(static_cast<std::size_t>(i)); });
  const CalibrationResult r = run_calibration(
      setup, out, [&](const std::vector<int>& batch) { run_batch(members, batch, out, *runner, threads); }, quiet);
  members.stop();
  const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - wall0).count();
  write_calibration_outputs(setup, r, out, world.size, threads, wall, quiet);
  return kExitOk;
}

}  // namespace

int main(int argc, char** argv) {
  return geohaz::apps::run_mpi_app(kApp, argc, argv, [&](const World& world) { return run(argc, argv, world); });
}
