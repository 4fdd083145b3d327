// What an sph-slope run over several ranks cannot do yet (run.hpp check_distributable; docs/sph.md,
// "Domain decomposition"): the refusal names the key, before anything is built or written.
#include <string>

#include "geohaz/core/errors.hpp"
#include "geohaz/sph/run.hpp"

namespace geohaz::sph {

void check_distributable(const RunConfig& c) {
  const std::string why = " does not run on several MPI ranks yet (issue #36): run it on one process";
  if (c.numerics.total_lagrangian)
    throw InputError("the total-Lagrangian formulation" + why, c.config_source, "numerics.formulation",
                     "total_lagrangian");
}

}  // namespace geohaz::sph
