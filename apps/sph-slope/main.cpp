// sph-slope: SPH simulation of slope failure, large deformation and post-failure flow of
// elasto-plastic soil under gravity and earthquake shaking (libs/sph, docs/sph.md).
// This file parses the command line, reads the config (libs/sph/src/config.cpp), then runs.
// Built as sph-slope-mpi (GEOHAZ_SPH_MPI, CMake option GEOHAZ_MPI) it runs alone or under mpirun,
// the particles spread over the ranks (docs/sph.md, "Domain decomposition"): every rank reads the
// config and runs the same simulation, rank 0 writes the output folder.
#ifdef GEOHAZ_SPH_MPI
#include <omp.h>

#include <array>

#include "geohaz/core/errors.hpp"
#include "geohaz/mpi/mpi_communicator.hpp"
#endif
#include "geohaz/core/app.hpp"
#include "geohaz/core/config.hpp"
#include "geohaz/sph/config.hpp"
#include "geohaz/sph/run.hpp"

using namespace geohaz;
using namespace geohaz::sph;

int main(int argc, char** argv) {
#ifdef GEOHAZ_SPH_MPI
  const geohaz::mpi::Session session(argc, argv);  // MPI_Init when launched by mpirun (apps/mpi-communicator)
  const std::shared_ptr<const Communicator> comm = geohaz::mpi::world_communicator(session);
#endif
  ConfigApp app;
  // The MPI build names itself (--version, messages, the default output folder), as its package does.
#ifdef GEOHAZ_SPH_MPI
  app.name = "sph-slope-mpi";
#else
  app.name = "sph-slope";
#endif
  app.summary =
      "SPH simulation of slope failure and post-failure flow of elasto-plastic soil "
      "(2D plane strain / 3D) under gravity and earthquake shaking.\n"
      "Usage: sph-slope --config slope.toml [--set key=value ...] [--out DIR] [--threads N] [--quiet]\n"
      "Example (a cohesionless 1.5:1 slope, 33.7 deg, with friction 20 deg: it slides, about 1 min):\n"
      "Example: sph-slope --config data/sph/slope_2d_granular.toml --set material[0].friction=20 --out slope-out";
  app.options_caption = "Options (all physical quantities in SI units: m, s, kg, Pa; angles in the config in degrees)";
  app.describe = [](ConfigReader& r) { (void)read_config(r, true); };
  app.run = [&](ConfigReader& reader, const CommonOptions& opts) {
    RunConfig cfg = read_config(reader, false);
    reader.finish();
    cfg.resolved_config = reader.resolved();
#ifdef GEOHAZ_SPH_MPI
    if (comm) check_distributable(cfg);  // what several ranks cannot do yet, before anything else
#endif
    validate(cfg);  // everything checked before the output directory is created
#ifdef GEOHAZ_SPH_MPI
    if (comm) {
      if (opts.threads == 0) omp_set_num_threads(geohaz::mpi::threads_per_rank(0));
      // Rank 0 writes the outputs, every rank its part of the snapshots into the same folder; the
      // others start when rank 0 has checked (and cleaned) the folder (the folder policy may refuse
      // it: exit 2 on every rank, not a hang).
      std::array<double, 1> refused{0.0};
      if (comm->rank() != 0) {
        comm->max_all(refused);
        if (refused[0] > 0.0) return kExitInputError;
        run_case(cfg, {opts.out, true, comm});
        return kExitOk;
      }
      bool started = false;
      try {
        return run_in_output_dir(opts.out, "sph-slope", {cfg.restart}, [&] {
          started = true;
          comm->max_all(refused);
          run_case(cfg, {opts.out, opts.quiet, comm});
          return kExitOk;
        });
      } catch (const InputError&) {
        if (!started) {
          refused[0] = 1.0;
          comm->max_all(refused);
        }
        throw;
      }
    }
#endif
    return run_in_output_dir(opts.out, "sph-slope", {cfg.restart}, [&] {
      run_case(cfg, {opts.out, opts.quiet, nullptr});
      return kExitOk;
    });
  };
#ifdef GEOHAZ_SPH_MPI
  const int code = run_config_app(argc, argv, app);
  // An error on one rank while the others wait for it would hang the job: end them all. (Input
  // errors happen on every rank alike, before any message is exchanged.)
  if (code != kExitOk && code != kExitInputError) session.abort(code);
  return code;
#else
  return run_config_app(argc, argv, app);
#endif
}
