// What an sph-slope run over several ranks can do (run.hpp check_distributable; docs/sph.md,
// "Domain decomposition"): the refusals, each naming the key, before anything is built or written.
#include <string>

#include "geohaz/core/errors.hpp"
#include "geohaz/sph/run.hpp"

namespace geohaz::sph {

void check_distributable(const RunConfig& c) {
  const std::string why = " does not run on several MPI ranks yet (issue #36): run it on one process";
  if (c.analysis == Analysis::StrengthReduction)
    throw InputError("the strength reduction" + why, c.config_source, "run.analysis", "strength_reduction");
  if (c.analysis == Analysis::LimitEquilibrium)
    throw InputError("the limit-equilibrium analysis" + why, c.config_source, "run.analysis", "limit_equilibrium");
  if (!c.restart.empty())
    throw InputError("a restart" + why + " (a snapshot written on several ranks restarts on one)", c.config_source,
                     "run.restart", c.restart.string());
  if (!c.velocity_png_times.empty())
    throw InputError("drawing quick-look PNGs during the run" + why + " (the final pictures are written)",
                     c.config_source, "run.velocity_png_times", std::to_string(c.velocity_png_times.size()) + " times");
  if (c.numerics.total_lagrangian)
    throw InputError("the total-Lagrangian formulation" + why, c.config_source, "numerics.formulation",
                     "total_lagrangian");
}

}  // namespace geohaz::sph
