// The checks of an sph-slope config before anything is built or written (validate): cross-field
// checks, the memory the particles need, the periodic width, a dry-run build of the scenario.
#include <cmath>
#include <filesystem>
#include <iomanip>
#include <sstream>
#include <string>

#include "geohaz/core/errors.hpp"
#include "geohaz/core/resources.hpp"
#include "run_support.hpp"

namespace geohaz::sph {

namespace {

/// Input checks that need the numerics and the geometry together, done before the dry-run build
/// allocates anything (issue #12): the particle count the domain and spacing ask for against the
/// memory available, and a 3D periodic width the neighbour search accepts.
void check_resources(const RunConfig& c) {
  const double dx = c.numerics.spacing;
  const double layers = std::ceil(2.0 * c.numerics.h_factor) + 1.0;  // wall layers (scenario.cpp)
  double length = 0.0, height = 0.0;
  std::string what;
  switch (c.scenario) {
    case ScenarioType::Slope:
      length = c.slope.crest_length + c.slope.gradient * c.slope.height + c.slope.front_length;
      height = c.slope.base_thickness + c.slope.height;
      what = "slope (crest_length + gradient·height + front_length, base_thickness + height)";
      break;
    case ScenarioType::Column:
      length = c.column_width + c.floor_length;
      height = c.column_height;
      what = "column (column.width + column.floor_length, column.height)";
      break;
    case ScenarioType::Biaxial:
      length = c.biaxial.width;
      height = c.biaxial.height;
      what = "biaxial specimen (biaxial.width, biaxial.height)";
      break;
    case ScenarioType::Block:
      length = c.block_length;
      height = c.block_height;
      what = "block (block.length, block.height)";
      break;
    case ScenarioType::Section: {
      const auto& P = c.section.profile;
      double zmin = 1e300, zmax = -1e300;
      for (const auto& p : P) {
        zmin = std::min(zmin, p.z);
        zmax = std::max(zmax, p.z);
      }
      length = P.empty() ? 0.0 : P.back().s - P.front().s;
      height = P.empty() ? 0.0 : zmax - zmin + c.section.soil_thickness + c.section.base_thickness;
      what = "section (polyline length, relief + soil and base thickness)";
      break;
    }
  }
  double particles = (length / dx + 2.0 * layers) * (height / dx + 2.0 * layers);
  if (c.dimension == 3) particles *= c.width / dx + 2.0 * layers;
  // A lower bound per particle: the store's fields, the neighbour list (about 2·π·(2.3 h)²/dx²
  // entries in 2D) and the solver's scratch arrays; solver.bytes_per_particle() reports ~0.6 kB (2D).
  const double per_particle = c.dimension == 3 ? 1500.0 : 500.0;
  std::ostringstream est;
  est << std::setprecision(3) << particles << " particles × " << per_particle << " B for the " << what << " at " << dx
      << " m spacing";
  check_memory(particles * per_particle, est.str(), c.config_source, "numerics.spacing", csv_number(dx));

  // The neighbour list needs a periodic axis of at least twice its cut-off, 2h plus the Verlet skin
  // (solver.cpp), on the period the builder makes: a whole number of spacings.
  if (c.dimension == 3 && c.periodic_width && c.scenario != ScenarioType::Section) {
    const double h = c.numerics.h_factor * dx;
    const double period = static_cast<double>(std::lround(c.width / dx)) * dx;
    const double need = 2.0 * (2.0 * h + c.numerics.neighbour_skin * h);
    if (!(period >= need - 1e-12 * dx)) {
      std::ostringstream m;
      m << "a periodic width must be at least twice the neighbour cut-off, 2·(2h + skin·h) = " << need
        << " m with spacing " << dx << " m, h_factor " << c.numerics.h_factor << " and numerics.neighbour_skin "
        << c.numerics.neighbour_skin << " (the width is taken as " << period
        << " m, a whole number of spacings); widen it, or set geometry.periodic = false";
      throw InputError(m.str(), c.config_source, "geometry.width", csv_number(c.width));
    }
  }
}

}  // namespace

void validate(const RunConfig& c) {
  if (c.materials.empty()) throw InputError("at least one [[material]] is required", c.config_source, "material");
  auto check_index = [&](int m, const char* key) {
    if (m < 0 || static_cast<std::size_t>(m) >= c.materials.size())
      throw InputError("material index out of range: allowed [0, " + std::to_string(c.materials.size() - 1) + "]",
                       c.config_source, key, std::to_string(m));
  };
  for (int m : c.layer_materials) check_index(m, "slope.layer_materials");
  if (!c.layer_materials.empty() && c.layer_materials.size() != c.layer_tops.size() + 1)
    throw InputError("slope.layer_materials needs one entry more than slope.layer_tops (" +
                         std::to_string(c.layer_tops.size() + 1) + ")",
                     c.config_source, "slope.layer_materials");
  for (std::size_t k = 1; k < c.layer_tops.size(); ++k)
    if (!(c.layer_tops[k] > c.layer_tops[k - 1]))
      throw InputError("slope.layer_tops must increase", c.config_source, "slope.layer_tops");
  if (c.scenario == ScenarioType::Section) {
    check_index(c.section.soil_material, "section.soil_material");
    check_index(c.section.base_material, "section.base_material");
  }
  if (c.end_time <= 0.0) throw InputError("must be > 0", c.config_source, "run.end_time");
  if (c.analysis == Analysis::StrengthReduction) {
    const auto& r = c.srm;
    if (!(r.f_min > 0.0))
      throw InputError("must be > 0", c.config_source, "strength_reduction.f_min", csv_number(r.f_min));
    if (!(r.f_max > r.f_min))
      throw InputError("must be > strength_reduction.f_min (" + csv_number(r.f_min) + ")", c.config_source,
                       "strength_reduction.f_max", csv_number(r.f_max));
    if (!(r.tolerance > 0.0))
      throw InputError("must be > 0", c.config_source, "strength_reduction.tolerance", csv_number(r.tolerance));
    if (c.scenario == ScenarioType::Biaxial)
      throw InputError("strength reduction needs a slope, column or section scenario (gravity-loaded)", c.config_source,
                       "run.analysis", "strength_reduction");
    if (!has_shear_strength(c.model))
      throw InputError(
          "has no shear strength to reduce; the strength reduction needs one of " + models_with_shear_strength(),
          c.config_source, "model.constitutive", std::string(constitutive_model_name(c.model)));
  }
  validate_water_and_seismic(c);
  if (c.analysis == Analysis::LimitEquilibrium && !has_shear_strength(c.model))
    throw InputError("has no shear strength for Bishop's method; use one of " + models_with_shear_strength(),
                     c.config_source, "model.constitutive", std::string(constitutive_model_name(c.model)));
  if (c.analysis == Analysis::LimitEquilibrium) return;  // no particles to build
  if (c.initial_velocity.type == InitialVelocity::Type::Uniform &&
      c.initial_velocity.value.size() != static_cast<std::size_t>(c.dimension))
    throw InputError(
        "initial_velocity.type = uniform needs one component per axis (" + std::to_string(c.dimension) + ", m/s)",
        c.config_source, "initial_velocity.value", std::to_string(c.initial_velocity.value.size()) + " numbers");
  check_resources(c);
  // Build once (dry run, keeping no particle: a rank of a distributed run must not hold them all) so
  // that geometry errors surface before any output exists; the structure names of
  // `output.structures` are checked against the scenario's.
  const Share dry{0, 1, true};
  if (c.dimension == 2)
    (void)reported_structures(c, build<2>(c, dry).sc.structures);
  else
    (void)reported_structures(c, build<3>(c, dry).sc.structures);
  if (!c.restart.empty() && !std::filesystem::exists(c.restart))
    throw InputError("restart file does not exist", c.config_source, "run.restart", c.restart.string());
}

}  // namespace geohaz::sph
