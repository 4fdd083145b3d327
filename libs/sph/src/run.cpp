#include "geohaz/sph/run.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <iomanip>
#include <limits>
#include <nlohmann/json.hpp>
#include <numbers>
#include <optional>
#include <sstream>
#include <string_view>

#include "geohaz/core/errors.hpp"
#include "geohaz/core/handoff.hpp"
#include "geohaz/core/output.hpp"
#include "geohaz/core/progress.hpp"
#include "geohaz/core/resources.hpp"
#include "geohaz/core/snapshot.hpp"
#include "geohaz/sph/diagnostics.hpp"
#include "geohaz/sph/limit_equilibrium.hpp"
#include "simulation_model.hpp"

namespace geohaz::sph {

namespace {

constexpr std::uint8_t kSoil = static_cast<std::uint8_t>(Kind::Soil);

const char* scenario_name(ScenarioType t) {
  switch (t) {
    case ScenarioType::Slope:
      return "slope";
    case ScenarioType::Column:
      return "column";
    case ScenarioType::Biaxial:
      return "biaxial";
    case ScenarioType::Section:
      return "section";
    case ScenarioType::Block:
      return "block";
  }
  return "?";
}

/// What a material means under the model of the run, for summary.json and the log. One case per
/// model and no generic fallback: a model added to ConstitutiveModel without its case here fails to
/// compile.
nlohmann::json model_parameters(const ConstitutiveModel& model, const MaterialParams& m) {
  using nlohmann::json;
  return std::visit(Overloaded{[&](const LinearElastic&) {
                                 return json{{"K_Pa", m.bulk}, {"G_Pa", m.shear}};
                               },
                               [&](const VonMises&) {
                                 return json{{"K_Pa", m.bulk}, {"G_Pa", m.shear}, {"yield_stress_Pa", m.yield_stress}};
                               },
                               [&](const DruckerPrager&) {
                                 return json{{"K_Pa", m.bulk},
                                             {"G_Pa", m.shear},
                                             {"alpha_phi", m.dp.alpha_phi},
                                             {"k_c_Pa", m.dp.kc},
                                             {"alpha_psi", m.dp.alpha_psi},
                                             {"min_density_kg_per_m3", DruckerPrager::min_density(m)}};
                               },
                               [&](const DruckerPragerSoftening&) {
                                 const auto r = drucker_prager_constants(m.residual_cohesion, m.residual_friction,
                                                                         m.dilatancy, m.fit);
                                 return json{{"K_Pa", m.bulk},
                                             {"G_Pa", m.shear},
                                             {"alpha_phi", m.dp.alpha_phi},
                                             {"k_c_Pa", m.dp.kc},
                                             {"alpha_psi", m.dp.alpha_psi},
                                             {"residual_alpha_phi", r.alpha_phi},
                                             {"residual_k_c_Pa", r.kc},
                                             {"softening_strain", m.softening_strain},
                                             {"min_density_kg_per_m3", DruckerPragerSoftening::min_density(m)}};
                               },
                               [&](const NewtonianFluid&) {
                                 return json{{"K_Pa", m.bulk}, {"viscosity_Pa_s", m.viscosity}};
                               }},
                    model);
}

template <int Dim>
struct Built {
  Scenario<Dim> sc;
  DiagnosticFrame frame;
};

/// Width of a 3D DSM strip as built: a whole number of spacings (the builder's ny·Δx), centred on
/// the polyline. The builder and the release export must agree on it.
double strip_width(const RunConfig& c) {
  return static_cast<double>(std::lround(c.width / c.numerics.spacing)) * c.numerics.spacing;
}

std::string csv_number(double v) {
  std::ostringstream os;
  os << std::setprecision(9) << v;
  return os.str();
}

/// Mark the soil particles inside the clamped regions (clamp.boxes); a box without soil is bad input.
template <int Dim>
void clamp_regions(const RunConfig& c, SphStore<Dim>& S) {
  const std::size_t per = 2 * Dim;
  if (c.clamp_boxes.size() % per != 0)
    throw InputError("needs " + std::to_string(per) + " numbers per box (lower corner, then upper corner, m)",
                     c.config_source, "clamp.boxes", std::to_string(c.clamp_boxes.size()) + " numbers");
  const auto& x = S.template get<Position<Dim>>();
  const auto& kind = S.template get<ParticleKind>();
  auto& cl = S.template get<Clamped>();
  for (std::size_t b = 0; b < c.clamp_boxes.size(); b += per) {
    Vec<Dim> lo, hi;
    for (int d = 0; d < Dim; ++d) {
      lo[d] = c.clamp_boxes[b + d];
      hi[d] = c.clamp_boxes[b + Dim + d];
    }
    std::ostringstream box;
    for (std::size_t k = 0; k < per; ++k) box << (k ? ", " : "[") << csv_number(c.clamp_boxes[b + k]);
    box << "]";
    if (!(lo.array() < hi.array()).all())
      throw InputError("box " + std::to_string(b / per) + ": every lower corner coordinate must be below the upper one",
                       c.config_source, "clamp.boxes", box.str());
    std::size_t held = 0;
    for (std::size_t i = 0; i < S.size(); ++i)
      if (kind[i] == kSoil && (x[i].array() >= lo.array()).all() && (x[i].array() <= hi.array()).all()) {
        cl[i] = 1;
        ++held;
      }
    if (held == 0)
      throw InputError(
          "box " + std::to_string(b / per) + " holds no soil particle: a clamped region must overlap the body",
          c.config_source, "clamp.boxes", box.str());
  }
}

/// The particles of the configured scenario.
/// The profile domain of a DSM cross-section (surface, extent, layers, bedrock; walls left default).
ProfileDomain section_profile(const RunConfig& c) {
  const auto& P = c.section.profile;
  if (P.size() < 2)
    throw InputError("the cross-section profile has fewer than 2 points", c.config_source, "section.polyline");
  ProfileDomain d;
  double zmin = 1e300;
  for (const auto& p : P) {
    d.surface.push_back({p.s, p.z});
    zmin = std::min(zmin, p.z);
  }
  d.x_left = P.front().s;
  d.x_right = P.back().s;
  d.z_bottom = zmin - c.section.soil_thickness - c.section.base_thickness;
  d.layer_tops.clear();
  d.layer_materials = {c.section.base_material};
  d.surface_layer_depth = c.section.soil_thickness;
  d.surface_material = c.section.soil_material;
  if (c.section.bedrock) d.bedrock_depth = c.section.soil_thickness + c.section.base_thickness;
  return d;
}

template <int Dim>
Built<Dim> build(const RunConfig& c) {
  std::vector<double> rho;
  for (const auto& m : c.materials) rho.push_back(m.density);
  const double dx = c.numerics.spacing, hf = c.numerics.h_factor;
  Built<Dim> b;
  switch (c.scenario) {
    case ScenarioType::Slope: {
      ProfileDomain d = c.slope.profile();
      d.left = c.left_wall;
      d.right = c.right_wall;
      d.bottom = c.bottom_wall;
      d.width = c.width;
      d.periodic_width = c.periodic_width;
      if (!c.layer_materials.empty()) {
        d.layer_tops = c.layer_tops;
        d.layer_materials = c.layer_materials;
      } else {
        d.layer_tops.clear();
        d.layer_materials.clear();
      }
      if (c.piles.enabled) {
        if (Dim != 3)
          throw InputError("pile rows need dimension = 3 (a pile row in plane strain is a wall)", c.config_source,
                           "piles.enabled", "true");
        const double xp = c.slope.toe_x() - c.piles.position * c.slope.gradient * c.slope.height;
        for (double y = 0.5 * c.piles.spacing; y < c.width; y += c.piles.spacing)
          d.piles.push_back({xp, y, c.piles.diameter});
        d.pile_top_margin = 2.0 * dx;
      }
      b.sc = build_profile<Dim>(d, dx, rho, hf);
      b.frame.toe_x = c.slope.toe_x();
      b.frame.base_length = c.slope.base_length();
      b.frame.base_top = c.slope.base_thickness;
      break;
    }
    case ScenarioType::Column: {
      ProfileDomain d;
      const double a = c.column_width, H = c.column_height;
      d.surface = {{0.0, H}, {a, H}, {a, 0.0}, {a + c.floor_length, 0.0}};
      d.x_left = 0.0;
      d.x_right = a + c.floor_length;
      d.left = c.left_wall;
      d.right = c.right_wall;
      d.bottom = c.bottom_wall;
      d.width = c.width;
      d.periodic_width = c.periodic_width;
      b.sc = build_profile<Dim>(d, dx, rho, hf);
      b.frame.toe_x = a;
      b.frame.base_length = a;
      b.frame.base_top = 0.0;
      break;
    }
    case ScenarioType::Block: {
      ProfileDomain d;
      d.surface = {{0.0, c.block_height}, {c.block_length, c.block_height}};
      d.x_left = 0.0;
      d.x_right = c.block_length;
      d.left = c.left_wall;
      d.right = c.right_wall;
      d.bottom = c.bottom_wall;
      d.width = c.width;
      d.periodic_width = c.periodic_width;
      b.sc = build_profile<Dim>(d, dx, rho, hf);
      b.frame.toe_x = c.block_length;
      b.frame.base_length = c.block_length;
      b.frame.base_top = -1e300;
      break;
    }
    case ScenarioType::Biaxial: {
      b.sc = build_biaxial<Dim>(c.biaxial, dx, rho.front(), hf);
      b.frame.toe_x = c.biaxial.width;
      b.frame.base_length = c.biaxial.width;
      b.frame.base_top = -1e300;
      break;
    }
    case ScenarioType::Section: {
      const auto& P = c.section.profile;
      ProfileDomain d = section_profile(c);
      d.left = c.left_wall;
      d.right = c.right_wall;
      d.bottom = c.bottom_wall;
      if constexpr (Dim == 3) {
        if (!c.section.bedrock)
          throw InputError("a 3D DSM section needs section.base = \"bedrock\"", c.config_source, "section.base",
                           "fill");
        if (c.periodic_width)
          throw InputError("a 3D DSM section cannot be periodic across: the terrain differs on both sides",
                           c.config_source, "geometry.periodic", "true");
        if (!c.section.terrain) throw InputError("the 3D section has no terrain", c.config_source, "section.dsm");
        d.width = c.width;
        d.periodic_width = false;
        const Terrain* terrain = c.section.terrain.get();
        const double half = 0.5 * strip_width(c);
        d.surface_xy = [terrain, &P, half, &c](double s, double y) {
          const Vec2 q = section_map_point(P, s, y - half);
          const double z = terrain->elevation(q.x(), q.y());
          if (!std::isfinite(z))
            throw InputError("the 3D section strip leaves the DSM's data at (" + std::to_string(q.x()) + ", " +
                                 std::to_string(q.y()) + "): narrow geometry.width or move the polyline",
                             c.config_source, "geometry.width", std::to_string(c.width));
          return z;
        };
      }
      b.sc = build_profile<Dim>(d, dx, rho, hf);
      b.frame.toe_x = d.x_left;  // run-out on a section: reported as the largest horizontal displacement
      b.frame.base_length = d.x_right - d.x_left;
      b.frame.base_top = 1e300;  // no particle counts for the front
      break;
    }
  }
  b.frame.spacing = dx;
  b.frame.front_thickness = c.front_thickness;
  clamp_regions<Dim>(c, b.sc.store);
  saturate_below_water_table<Dim>(c, b.sc.store);
  return b;
}

template <int Dim>
SolverSettings<Dim> settings_for(const RunConfig& c, const Scenario<Dim>& sc) {
  SolverSettings<Dim> s;
  static_cast<NumericalSettings&>(s) = c.numerics;
  if (c.scenario == ScenarioType::Biaxial) s.gravity = 0.0;
  s.periodic = sc.periodic;
  s.domain_lo = sc.domain_lo;
  s.domain_hi = sc.domain_hi;
  s.pore_water = pore_water_settings(c);
  return s;
}

template <class Tag, class Store>
void add_view(std::vector<FieldView>& v, const Store& s) {
  using Tr = FieldTraits<typename Tag::type>;
  const auto& a = s.template get<Tag>();
  v.push_back({Tag::label, Tag::unit, scalar_type_of<typename Tr::scalar>(), a.data(), a.size(), Tr::rows, Tr::cols});
}

/// The internal variables of every constitutive model (constitutive.hpp), each once.
template <int Dim, class... Tags>
void add_fields_once(std::vector<FieldView>& v, const SphStore<Dim>& s, FieldList<Tags...>) {
  [[maybe_unused]] auto once = [&](auto tag) {
    using Tag = decltype(tag);
    for (const auto& f : v)
      if (f.label == Tag::label) return;
    add_view<Tag>(v, s);
  };
  (once(Tags{}), ...);
}
template <int Dim, class... Models>
void add_internal_variables(std::vector<FieldView>& v, const SphStore<Dim>& s,
                            std::type_identity<std::variant<Models...>>) {
  (add_fields_once(v, s, typename Models::InternalVariables{}), ...);
}

/// The fields written to snapshots: the state a restart needs plus what the issue asks to see.
/// position_at_build (the positions of the last neighbour-list build) is restart state: the list,
/// hence the Verlet-skin decisions and the order of the pair sums, is rebuilt from it.
template <int Dim>
void write_fields(SnapshotWriter& w, const SphStore<Dim>& s, double t, std::int64_t step) {
  std::vector<FieldView> v;
  add_view<Position<Dim>>(v, s);
  add_view<Velocity<Dim>>(v, s);
  add_view<Displacement<Dim>>(v, s);
  add_view<Stress>(v, s);
  add_view<PlasticStrain>(v, s);
  add_view<Density>(v, s);
  add_view<MaterialId>(v, s);
  add_view<StressFree>(v, s);
  add_view<ParticleKind>(v, s);
  add_view<Mass>(v, s);
  add_view<WallNormal<Dim>>(v, s);
  add_view<LayerNormal<Dim>>(v, s);
  add_view<StructureId>(v, s);
  add_view<ParticleId>(v, s);
  add_view<Clamped>(v, s);
  add_internal_variables(v, s, std::type_identity<ConstitutiveModel>{});
  add_view<PositionAtBuild<Dim>>(v, s);
  w.write(t, step, v);
}

/// The solver state of the last snapshot (SolverState), as a root attribute: a snapshot group has
/// room for its time and step only (core snapshot.hpp). It names the snapshot it belongs to, so a
/// run killed between the snapshot and the attribute is not restarted with the wrong state; Δt in
/// hexadecimal, exact.
constexpr const char* kSolverStateAttribute = "sph_solver_state";

template <int Dim>
void write_snapshot(SnapshotWriter& w, const SphSolver<Dim>& solver, std::int64_t step) {
  write_fields<Dim>(w, solver.store(), solver.time(), step);
  const SolverState st = solver.state();
  char buf[160];
  std::snprintf(buf, sizeof buf, "snapshot %zu step %lld dt %a builds %lld", w.snapshot_count() - 1,
                static_cast<long long>(st.step), st.dt, static_cast<long long>(st.neighbour_builds));
  w.set_attribute(kSolverStateAttribute, buf);
}

/// What a restart file gives besides the particles.
struct Restart {
  double time = 0.0;
  std::int64_t step = 0;             ///< the snapshot's step
  std::optional<SolverState> state;  ///< absent in files written before it existed
};

/// Replace the store by the last snapshot of a file written by sph-slope.
template <int Dim>
Restart load_restart(const std::filesystem::path& path, SphStore<Dim>& s) {
  SnapshotReader r(path);
  if (r.model() != "sph-slope")
    throw InputError("not an sph-slope snapshot file (model '" + r.model() + "')", path.string());
  if (r.dimension() != Dim)
    throw InputError(
        "snapshot dimension " + std::to_string(r.dimension()) + " differs from run.dimension " + std::to_string(Dim),
        path.string());
  if (r.snapshot_count() == 0) throw InputError("the snapshot file holds no snapshot", path.string());
  const std::size_t k = r.snapshot_count() - 1;
  for (const char* need : {"position", "velocity", "stress", "density", "mass", "material_id", "kind"})
    if (!r.has_field(k, need))
      throw InputError(std::string("restart snapshot lacks field '") + need + "'", path.string());
  const auto pos = r.read(k, "position");
  s.resize(pos.count);
  try {
    s.for_each_field([&](auto tag, auto&) {
      using Tag = decltype(tag);
      if (r.has_field(k, Tag::label)) load_field<Tag>(r.read(k, Tag::label), s);
    });
  } catch (const std::invalid_argument& e) {
    throw InputError(e.what(), path.string());
  }
  if (!r.has_field(k, LayerNormal<Dim>::label)) {
    s.template get<LayerNormal<Dim>>().assign(s.size(), Vec<Dim>::Zero());
    fill_missing_layer_normals(s);
  }
  // Files written before structures had ids: no particle belongs to a structure (loads stay zero).
  if (!r.has_field(k, StructureId::label)) s.template get<StructureId>().assign(s.size(), -1);
  Restart out;
  out.time = r.time(k);
  out.step = r.step(k);
  // The solver state, if it belongs to this snapshot and the neighbour-list positions are there.
  std::istringstream is(r.attribute(kSolverStateAttribute));
  // Files written before Dec 2026 end in "last_reorder m" (the step of the last reordering, when
  // the schedule counted steps): the run goes on with the rebuild count from 0, so its reorderings,
  // and the round-off of its pair sums, differ from an uninterrupted run's.
  std::string w1, w2, w3, w4, dt;
  std::size_t snap = 0;
  long long step = 0, builds = 0;
  if (is >> w1 >> snap >> w2 >> step >> w3 >> dt >> w4 >> builds && snap == k &&
      r.has_field(k, PositionAtBuild<Dim>::label))
    out.state = SolverState{out.time, step, std::strtod(dt.c_str(), nullptr), w4 == "builds" ? builds : 0};
  return out;
}

/// Quick-look picture: particles in the x–z plane coloured by `value` (soil) on a ramp, boundary grey,
/// with a colour bar numbered from 0 to vmax and titled `title` ("displacement (m)").
/// `overlay` (optional): a polyline in (x, z) drawn in red over the particles (a slip circle).
template <int Dim>
void draw_particles(const std::filesystem::path& path, const SphStore<Dim>& s, const std::vector<double>& value,
                    double vmax, double dx, const std::string& title,
                    const std::vector<std::array<double, 2>>& overlay = {}) {
  const auto& x = s.template get<Position<Dim>>();
  const auto& kind = s.template get<ParticleKind>();
  double x0 = 1e300, x1 = -1e300, z0 = 1e300, z1 = -1e300;
  for (const auto& p : x) {
    x0 = std::min(x0, p[0]);
    x1 = std::max(x1, p[0]);
    z0 = std::min(z0, p[Dim - 1]);
    z1 = std::max(z1, p[Dim - 1]);
  }
  const int W = 1200, margin = 20;
  // Fit the x–z extent into at most 1200 × 1200 pixels of drawing area.
  const double scale =
      std::min((W - 2 * margin) / std::max(x1 - x0 + dx, 1e-12), (1200.0 - 2 * margin) / std::max(z1 - z0 + dx, 1e-12));
  // Below the particles: 10 px gap, then draw_colour_bar at text scale 2 (bar 20, ticks 6 + 4,
  // numbers 14, gap 8, title 14 = 66 px), and 8 px to spare.
  constexpr int kLegend = 84;
  const int H = std::max(static_cast<int>((z1 - z0 + dx) * scale) + 2 * margin + kLegend, 100);
  Image img(W, H);
  const double r = std::max(1.0, 0.5 * dx * scale);
  for (std::size_t i = 0; i < s.size(); ++i) {
    const double px = margin + (x[i][0] - x0) * scale + 0.5 * (W - 2 * margin - (x1 - x0) * scale);
    const double pz = H - kLegend - margin - (x[i][Dim - 1] - z0) * scale;
    std::array<std::uint8_t, 3> col{160, 160, 160};
    if (kind[i] == kSoil)
      col = ramp_colour(ColourRamp::Viridis, vmax > 0 ? std::clamp(value[i] / vmax, 0.0, 1.0) : 0.0);
    img.fill_circle(px, pz, r, col);
  }
  for (std::size_t k = 1; k < overlay.size(); ++k) {
    auto px = [&](double xx) { return margin + (xx - x0) * scale + 0.5 * (W - 2 * margin - (x1 - x0) * scale); };
    auto pz = [&](double zz) { return H - kLegend - margin - (zz - z0) * scale; };
    for (int d = -1; d <= 1; ++d)
      img.line(px(overlay[k - 1][0]), pz(overlay[k - 1][1]) + d, px(overlay[k][0]), pz(overlay[k][1]) + d,
               {220, 30, 30});
  }
  draw_colour_bar(img, margin, H - kLegend + 10, W - 2 * margin, ColourRamp::Viridis, 0.0, vmax > 0 ? vmax : 1.0, title,
                  2);
  write_png(path, img);
}

/// The initial velocity of the main phase (initial_velocity.*); clamped particles stay at rest.
template <int Dim>
void set_initial_velocity(const RunConfig& c, SphStore<Dim>& S) {
  const auto& iv = c.initial_velocity;
  if (iv.type == InitialVelocity::Type::None) return;
  const auto& x = S.template get<Position<Dim>>();
  auto& v = S.template get<Velocity<Dim>>();
  for (std::size_t i = 0; i < S.size(); ++i) {
    if (S.template get<ParticleKind>()[i] != kSoil || S.template get<Clamped>()[i]) continue;
    if (iv.type == InitialVelocity::Type::Uniform) {
      for (int d = 0; d < Dim; ++d) v[i][d] = iv.value[static_cast<std::size_t>(d)];
    } else {
      v[i].setZero();
      v[i][Dim - 1] = iv.amplitude * cantilever_mode_shape((x[i][0] - iv.root) / iv.length);
    }
  }
}

/// The structures a run reports (`output.structures`, all when empty), as indices into the
/// scenario's table. InputError naming the key, the unknown name and the names that exist.
template <int Dim>
std::vector<std::size_t> reported_structures(const RunConfig& c, const std::vector<Structure<Dim>>& table) {
  std::vector<std::size_t> shown;
  if (!c.structure_forces) return shown;
  if (c.structures.empty()) {
    for (std::size_t k = 0; k < table.size(); ++k) shown.push_back(k);
    return shown;
  }
  for (const auto& name : c.structures) {
    std::size_t k = 0;
    while (k < table.size() && table[k].name != name) ++k;
    if (k == table.size()) {
      std::string names;
      for (const auto& s : table) names += (names.empty() ? "" : ", ") + s.name;
      throw InputError("no structure of this name in the scenario; it has: " + (names.empty() ? "none" : names),
                       c.config_source, "output.structures", name);
    }
    if (std::find(shown.begin(), shown.end(), k) != shown.end())
      throw InputError("structure named twice", c.config_source, "output.structures", name);
    shown.push_back(k);
  }
  return shown;
}

/// The loads on the reported structures through a run: the rows of structure_forces.csv, the peaks
/// of every step for summary.json, and the normal-force histories for the quick-look plot.
template <int Dim>
class StructureReport {
 public:
  StructureReport(std::vector<Structure<Dim>> table, std::vector<std::size_t> shown)
      : table_(std::move(table)), shown_(std::move(shown)), peaks_(shown_.size()), normal_(shown_.size()) {
    // Units per unit thickness in plane strain (the 2D model is per metre out of the plane).
    const char* f = Dim == 2 ? "_N_per_m" : "_N";
    const char* m = Dim == 2 ? "_Nm_per_m" : "_Nm";
    auto& col = rows_.columns;
    col.emplace_back("time_s");
    for (const std::size_t k : shown_) {
      const std::string& n = table_[k].name;
      if constexpr (Dim == 2) {
        for (const char* a : {"_Fx", "_Fz"}) col.push_back(n + a + f);
        col.push_back(n + "_My" + m);
      } else {
        for (const char* a : {"_Fx", "_Fy", "_Fz"}) col.push_back(n + a + f);
        for (const char* a : {"_Mx", "_My", "_Mz"}) col.push_back(n + a + m);
      }
    }
  }
  bool empty() const noexcept { return shown_.empty(); }
  /// Every step: the peaks (resultant |F|, normal force F·n, moment |M|) and their times.
  void observe(double t, const std::vector<StructureLoad<Dim>>& loads) {
    for (std::size_t q = 0; q < shown_.size(); ++q) {
      const auto& l = loads[shown_[q]];
      Peak& p = peaks_[q];
      const double fr = l.force.norm(), fn = l.force.dot(table_[shown_[q]].normal), mm = l.moment.norm();
      if (!p.seen || fr > p.resultant) p.resultant = fr, p.t_resultant = t;
      if (!p.seen || fn > p.normal) p.normal = fn, p.t_normal = t;
      if (!p.seen || mm > p.moment) p.moment = mm, p.t_moment = t;
      p.seen = true;
    }
  }
  /// A row of the CSV (and of the plot); its loads count for the peaks too (the first row is the
  /// state at rest after the geostatic phase, before any main-phase step).
  void record(double t, const std::vector<StructureLoad<Dim>>& loads) {
    observe(t, loads);
    std::vector<double> row{t};
    for (std::size_t q = 0; q < shown_.size(); ++q) {
      const auto& l = loads[shown_[q]];
      for (int d = 0; d < Dim; ++d) row.push_back(l.force[d]);
      if constexpr (Dim == 2)
        row.push_back(l.moment[1]);
      else
        row.insert(row.end(), {l.moment[0], l.moment[1], l.moment[2]});
      normal_[q].push_back(l.force.dot(table_[shown_[q]].normal));
    }
    rows_.rows.push_back(std::move(row));
    times_.push_back(t);
  }
  /// The rows of structure_forces.csv.
  const Table& table() const noexcept { return rows_; }
  /// The `structures` block of summary.json.
  nlohmann::json summary() const {
    const std::string f = Dim == 2 ? "_N_per_m" : "_N", m = Dim == 2 ? "_Nm_per_m" : "_Nm";
    nlohmann::json a = nlohmann::json::array();
    for (std::size_t q = 0; q < shown_.size(); ++q) {
      const auto& s = table_[shown_[q]];
      const Peak& p = peaks_[q];
      a.push_back({{"name", s.name},
                   {"id", shown_[q]},
                   {"base_m", std::vector<double>(s.base.data(), s.base.data() + Dim)},
                   {"normal", std::vector<double>(s.normal.data(), s.normal.data() + Dim)},
                   {"peak_resultant" + f, p.resultant},
                   {"time_of_peak_resultant_s", p.t_resultant},
                   {"peak_normal" + f, p.normal},
                   {"time_of_peak_normal_s", p.t_normal},
                   {"peak_moment" + m, p.moment},
                   {"time_of_peak_moment_s", p.t_moment}});
    }
    return a;
  }
  /// Quick-look plot of the normal force F·n of each reported structure against time (one colour
  /// per structure in the order of the CSV columns; grey: zero).
  void plot(const std::filesystem::path& path) const {
    if (times_.size() < 2) return;
    const int W = 900, H = 500, m = 40;
    Image img(W, H);
    double lo = 0.0, hi = 0.0;
    for (const auto& s : normal_)
      for (const double v : s) lo = std::min(lo, v), hi = std::max(hi, v);
    if (hi - lo <= 0.0) hi = lo + 1.0;
    const double t0 = times_.front(), t1 = std::max(times_.back(), t0 + 1e-12);
    auto px = [&](double t) { return m + (t - t0) / (t1 - t0) * (W - 2 * m); };
    auto py = [&](double v) { return H - m - (v - lo) / (hi - lo) * (H - 2 * m); };
    img.line(m, H - m, W - m, H - m, {0, 0, 0});
    img.line(m, m, m, H - m, {0, 0, 0});
    img.line(m, py(0.0), W - m, py(0.0), {170, 170, 170});
    static constexpr std::array<std::array<std::uint8_t, 3>, 6> colours{
        {{31, 119, 180}, {214, 39, 40}, {44, 160, 44}, {255, 127, 14}, {148, 103, 189}, {140, 86, 75}}};
    for (std::size_t q = 0; q < normal_.size(); ++q)
      for (std::size_t k = 1; k < times_.size(); ++k)
        for (int d = 0; d <= 1; ++d)
          img.line(px(times_[k - 1]), py(normal_[q][k - 1]) + d, px(times_[k]), py(normal_[q][k]) + d,
                   colours[q % colours.size()]);
    write_png(path, img);
  }

 private:
  struct Peak {
    bool seen = false;
    double resultant = 0.0, t_resultant = 0.0, normal = 0.0, t_normal = 0.0, moment = 0.0, t_moment = 0.0;
  };
  std::vector<Structure<Dim>> table_;
  std::vector<std::size_t> shown_;
  std::vector<Peak> peaks_;
  Table rows_;
  std::vector<double> times_;
  std::vector<std::vector<double>> normal_;  // F·n per reported structure, per row
};

/// Every material with c/F, atan(tan φ/F) and atan(tan ψ/F) (strength reduction).
std::vector<MaterialParams> reduced_strength(const std::vector<MaterialParams>& mats, double F) {
  auto r = mats;
  for (auto& p : r) {
    p.cohesion /= F;
    p.friction = std::atan(std::tan(p.friction) / F);
    p.dilatancy = std::atan(std::tan(p.dilatancy) / F);
    p.residual_cohesion /= F;
    p.residual_friction = std::atan(std::tan(p.residual_friction) / F);
  }
  return r;
}

template <int Dim>
double max_soil_displacement(const SphStore<Dim>& s) {
  double u = 0.0;
  const auto& d = s.template get<Displacement<Dim>>();
  const auto& k = s.template get<ParticleKind>();
  for (std::size_t i = 0; i < s.size(); ++i)
    if (k[i] == kSoil) u = std::max(u, d[i].norm());
  return u;
}

/// One strength-reduction trial: its factor and what decided it.
struct SrmTrial {
  double factor = 1.0;
  double displacement = 0.0;  ///< largest soil displacement at the end (m)
  double growth = 0.0;        ///< its growth over the last quarter of the trial (m)
  bool failed = false;
  bool blew_up = false;  ///< the trial stopped with a SimulationError (counted as failed)
  std::int64_t steps = 0;
};

/// The limit-equilibrium section of a 2D slope or DSM-section scenario, at peak strength or with the
/// residual strengths of a softening soil; a slope with the config's pore water and seismic
/// coefficients.
SlopeSection section_of(const RunConfig& c, bool residual = false) {
  ProfileDomain d;
  if (c.scenario == ScenarioType::Slope) {
    d = c.slope.profile();
    if (!c.layer_materials.empty()) {
      d.layer_tops = c.layer_tops;
      d.layer_materials = c.layer_materials;
    } else {
      d.layer_tops.clear();
      d.layer_materials.clear();
    }
  } else {
    d = section_profile(c);
  }
  std::vector<LimitEquilibriumSoil> soils;
  for (std::size_t k = 0; k < c.materials.size(); ++k) {
    const auto& m = c.materials[k];
    const double sat = k < c.saturated_densities.size() ? c.saturated_densities[k] : 0.0;
    soils.push_back({m.density * c.numerics.gravity, residual ? m.residual_cohesion : m.cohesion,
                     residual ? m.residual_friction : m.friction, sat * c.numerics.gravity});
  }
  auto s = SlopeSection::from_profile(d, soils);
  if (c.scenario == ScenarioType::Slope) {
    // The pore water (clipped to the ground as the SPH's) and the pseudo-static coefficients of the
    // strength reduction (a dynamic run has none: its earthquake is the record).
    const auto le = limit_equilibrium_section(c, true);
    s.water = le.water;
    s.seismic = le.seismic;
  }
  return s;
}

BishopResult bishop_of(const RunConfig& c, bool residual = false) {
  if (c.dimension != 2 || (c.scenario != ScenarioType::Slope && c.scenario != ScenarioType::Section)) return {};
  return bishop_critical_circle(section_of(c, residual));
}

/// The Bishop cross-check beside a dynamic run of a 2D slope or section of frictional soil: the
/// static factor of the critical circle (with the run's pore water, if any) at peak strength (and, for a softening
/// soil, at residual strength), or a note saying why there is none.
struct StaticBishop {
  BishopResult peak, residual;
  InfiniteSlopeResult cover;  // the translational slide of a DSM section's soil cover
  std::string note;

  static StaticBishop of(const RunConfig& c) {
    StaticBishop b;
    const bool frictional =
        std::holds_alternative<DruckerPrager>(c.model) || std::holds_alternative<DruckerPragerSoftening>(c.model);
    if (c.dimension != 2 || !frictional || (c.scenario != ScenarioType::Slope && c.scenario != ScenarioType::Section))
      return b;
    try {
      b.peak = bishop_of(c);
      if (std::holds_alternative<DruckerPragerSoftening>(c.model)) b.residual = bishop_of(c, true);
      if (c.scenario == ScenarioType::Section) b.cover = infinite_slope_minimum(section_of(c));
    } catch (const InputError& e) {
      b.note = e.reason();
    }
    return b;
  }
  static nlohmann::json circle_json(const BishopResult& r) {
    const auto& C = r.circle;
    return {{"factor", r.factor},   {"centre_x_m", C.xc},     {"centre_z_m", C.zc},
            {"radius_m", C.radius}, {"entry_x_m", r.x_entry}, {"exit_x_m", r.x_exit}};
  }
  void add_to(nlohmann::json& s) const {
    if (!note.empty()) s["bishop_note"] = note;
    if (peak.admissible()) s["bishop"] = circle_json(peak);
    if (residual.admissible()) s["bishop_residual"] = circle_json(residual);
    if (std::isfinite(cover.factor))
      s["infinite_slope"] = {{"factor", cover.factor},
                             {"x_m", cover.x},
                             {"angle_deg", cover.angle * 180.0 / std::numbers::pi},
                             {"window_m", cover.window}};
  }
};

/// The table of a list of (x, z) points ("x_m,z_m": a surface or a circle).
Table xz_table(const std::vector<std::array<double, 2>>& points) {
  Table t{{"x_m", "z_m"}, {}, {}};
  for (const auto& p : points) t.rows.push_back({p[0], p[1]});
  return t;
}

/// The fields of a store as flat arrays (ParticleFields).
template <int Dim>
ParticleFields fields_of(const SphStore<Dim>& s) {
  ParticleFields f;
  f.dimension = Dim;
  f.count = s.size();
  for (std::size_t i = 0; i < s.size(); ++i) {
    for (int d = 0; d < Dim; ++d) {
      f.position.push_back(s.template get<Position<Dim>>()[i][d]);
      f.velocity.push_back(s.template get<Velocity<Dim>>()[i][d]);
      f.displacement.push_back(s.template get<Displacement<Dim>>()[i][d]);
    }
    for (int a = 0; a < 3; ++a)
      for (int b = 0; b < 3; ++b) f.stress.push_back(s.template get<Stress>()[i](a, b));
  }
  f.plastic_strain = s.template get<PlasticStrain>();
  f.density = s.template get<Density>();
  f.mass = s.template get<Mass>();
  f.material_id = s.template get<MaterialId>();
  f.kind = s.template get<ParticleKind>();
  f.id = s.template get<ParticleId>();
  return f;
}

/// The summary's description of the run's particles and materials (both analyses).
template <int Dim>
nlohmann::json summary_header(const RunConfig& c, const SphSolver<Dim>& solver, std::size_t soil_count) {
  nlohmann::json s;
  s["scenario"] = scenario_name(c.scenario);
  s["dimension"] = Dim;
  s["model"] = solver.model_name();
  s["config"] = c.config_source;
  s["soil_particles"] = soil_count;
  s["spacing_m"] = c.numerics.spacing;
  return s;
}

}  // namespace

struct SphSimulation::Impl {
  std::unique_ptr<SimulationModel> model;
};

namespace {

/// The failed mass handed to debris-runout (docs/handoff.md) and, on the DSM grid, its thickness.
struct ReleaseOutput {
  Handoff handoff;
  double total = 0.0, width = 0.0;  ///< m³, m
  std::optional<Raster> thickness;  ///< release_thickness.tif (when the DSM is known)
  double binned = 0.0, max_thickness = 0.0;
};

/// The geostatic phase's duration (s): geostatic.duration, or 20 H/c_p when it is 0 (20 transits of
/// a P wave through the slope height let the loading waves die out under Cundall damping).
/// InputError (key geostatic.duration) above 100 times that default: 2000 wave transits is a
/// loading that has settled long before or never will (the phase's rest check says which), and
/// nothing a user means; a value of 1e9 s ran for hours (issue #29).
double geostatic_duration(const RunConfig& c, double href, double cmax) {
  const double natural = 20.0 * href / cmax;
  if (c.geostatic_duration > 100.0 * natural) {
    std::ostringstream m;
    m << "'geostatic.duration' = " << c.geostatic_duration
      << " s is more than 100 times the natural loading time 20 H/c_p = " << natural << " s of this slope (H = " << href
      << " m, c_p = " << cmax << " m/s): allowed [0, " << 100.0 * natural << "] s (0: 20 H/c_p)";
    throw InputError(m.str(), c.config_source, "geostatic.duration", std::to_string(c.geostatic_duration));
  }
  return c.geostatic_duration > 0.0 ? c.geostatic_duration : natural;
}

/// A run in time: the geostatic phase (or a restart), then the main phase with its series,
/// structure loads, quick-looks and the summary's figures (docs/sph.md).
/// The geostatic phase of `solver` over `dur` seconds, the observer told at the start, every 50
/// steps and at the end (phase "geostatic").
template <int Dim>
GeostaticReport geostatic_with_progress(SphSolver<Dim>& solver, double dur, const RunConfig& c,
                                        const SphSimulation& self, RunObserver* obs) {
  RunProgress p{"geostatic", 0.0, dur, 0, solver.store().size(), 0.0, false};
  if (obs) obs->progress(self, p);
  std::int64_t k = 0;
  const auto rep = solver.apply_gravity_gradually(dur, c.geostatic_damping, c.geostatic_elastic, [&] {
    if (++k % 50 == 0 && obs) {
      p.time = solver.time();
      p.steps = k;
      obs->progress(self, p);
    }
  });
  p.time = dur;
  p.steps = rep.steps;
  p.done = true;
  if (obs) obs->progress(self, p);
  return rep;
}

template <int Dim>
class DynamicRun final : public SimulationModel {
 public:
  DynamicRun(const RunConfig& c, bool quiet);
  void run(const SphSimulation& self, RunObserver* obs) override;
  double time() const override { return solver_.time(); }
  std::int64_t step_count() const override { return solver_.step_count(); }
  std::size_t particle_count() const override { return solver_.store().size(); }
  bool main_phase_started() const override { return main_started_; }
  nlohmann::json summary() const override { return summary_with(release()); }
  std::vector<NamedTable> tables() const override;
  ParticleFields particles() const override { return fields_of(solver_.store()); }
  void write_snapshot(SnapshotWriter& w) const override {
    sph::write_snapshot<Dim>(w, solver_, step_offset_ + solver_.step_count());
  }
  void draw_due_pngs(const std::filesystem::path& out) override;
  void write_outputs(const std::filesystem::path& out) const override;
  void write_partial(const std::filesystem::path& out) const override;

 private:
  void print_header() const;
  void load_restart_state();
  void geostatic_phase(const SphSimulation& self, RunObserver* obs);
  void move_platens();
  void mark_free_end();
  double tip_displacement() const;
  void start_main_phase();
  void main_phase(const SphSimulation& self, RunObserver* obs);
  SeriesRow record();
  void record_biaxial();
  void write_pictures(const std::filesystem::path& out) const;
  ReleaseOutput release() const;
  void write_release(const std::filesystem::path& out, const ReleaseOutput& r) const;
  nlohmann::json summary_with(const ReleaseOutput& r) const;

  const RunConfig& c_;
  bool quiet_;
  std::chrono::steady_clock::time_point wall0_;
  Built<Dim> b_;
  SolverSettings<Dim> settings_;
  std::size_t soil_count_, boundary_count_;
  double href_;
  SphSolver<Dim> solver_;
  StructureReport<Dim> structures_;
  std::vector<double> rho0_;
  bool have_loads_ = false;  // the loads of a step exist (not before the first step of a restart)
  std::int64_t step_offset_ = 0;
  nlohmann::json phase_summary_ = nlohmann::json::object();  // "restart" or "geostatic"
  // With clamped regions: the free end's particles by id (tip_displacement_m).
  std::vector<std::uint8_t> free_end_;
  bool main_started_ = false, finished_ = false, stopped_at_rest_ = false;
  Table series_, biaxial_;
  std::vector<double> png_times_;
  std::size_t next_png_ = 0;
  double next_out_ = 0.0, max_speed_run_ = 0.0, max_runout_ = 0.0, last_moving_ = 0.0, t_start_ = 0.0;
  SeriesRow last_;
  StaticBishop bishop_;
};

template <int Dim>
DynamicRun<Dim>::DynamicRun(const RunConfig& c, bool quiet)
    : c_(c),
      quiet_(quiet),
      wall0_(std::chrono::steady_clock::now()),
      b_(build<Dim>(c)),
      settings_(settings_for<Dim>(c, b_.sc)),
      soil_count_(b_.sc.soil_count),
      boundary_count_(b_.sc.boundary_count),
      href_(b_.sc.reference_height),
      solver_(std::move(b_.sc.store), c.materials, c.model, settings_),
      // Loads on the structures, tracked from the geostatic phase on: the first row is the state at rest.
      structures_(b_.sc.structures, reported_structures(c, b_.sc.structures)) {
  if (!structures_.empty()) {
    std::vector<Vec<Dim>> bases;
    for (const auto& s : b_.sc.structures) bases.push_back(s.base);
    solver_.track_structures(std::move(bases));
  }
  for (const auto& m : solver_.materials()) rho0_.push_back(m.density);
  if (c_.geostatic && c_.restart.empty() && c_.scenario != ScenarioType::Biaxial)
    geostatic_duration(c_, href_, solver_.max_wave_speed());  // checked now
  bishop_ = StaticBishop::of(c);
  if (!quiet_) print_header();
}

template <int Dim>
void DynamicRun<Dim>::print_header() const {
  const auto& mats = solver_.materials();
  std::fprintf(stderr, "sph-slope: %dD %s, %zu soil + %zu boundary particles, h = %.4g m, model %s\n", Dim,
               scenario_name(c_.scenario), soil_count_, boundary_count_, solver_.smoothing_length(),
               solver_.model_name().c_str());
  for (std::size_t k = 0; k < mats.size(); ++k)
    std::fprintf(stderr, "  material %zu (%s): c_p = %.4g m/s, DP fit %s, %s %s\n", k,
                 k < c_.material_names.size() ? c_.material_names[k].c_str() : "", mats[k].p_wave_speed,
                 drucker_prager_fit_name(mats[k].fit), solver_.model_name().c_str(),
                 model_parameters(c_.model, mats[k]).dump().c_str());
  if (bishop_.peak.admissible()) {
    std::fprintf(stderr, "  Bishop's factor of safety (static, critical circle, x = %.4g to %.4g m): %.3f",
                 bishop_.peak.x_entry, bishop_.peak.x_exit, bishop_.peak.factor);
    if (bishop_.residual.admissible()) std::fprintf(stderr, "; at residual strength %.3f", bishop_.residual.factor);
    std::fprintf(stderr, "\n");
    if (std::isfinite(bishop_.cover.factor))
      std::fprintf(stderr,
                   "  infinite-slope factor of the soil cover (translational slide along its base): %.3f at x = %.4g m "
                   "(%.1f deg over %.3g m)\n",
                   bishop_.cover.factor, bishop_.cover.x, bishop_.cover.angle * 180.0 / std::numbers::pi,
                   bishop_.cover.window);
  } else if (!bishop_.note.empty()) {
    std::fprintf(stderr, "  Bishop's factor of safety: none (%s)\n", bishop_.note.c_str());
  }
}

template <int Dim>
void DynamicRun<Dim>::run(const SphSimulation& self, RunObserver* obs) {
  if (!c_.restart.empty())
    load_restart_state();
  else if (c_.geostatic && c_.scenario != ScenarioType::Biaxial)
    geostatic_phase(self, obs);
  if (c_.scenario == ScenarioType::Biaxial) move_platens();
  if (c_.restart.empty()) set_initial_velocity<Dim>(c_, solver_.store());
  mark_free_end();
  start_main_phase();
  if (obs) obs->started(self);
  main_phase(self, obs);
}

template <int Dim>
void DynamicRun<Dim>::load_restart_state() {
  const Restart rs = load_restart<Dim>(c_.restart, solver_.store());
  // With the solver state the run continues exactly as the one that wrote the file; without it
  // (files of older versions) from the snapshot's particles, with Δt from the wave speed and a
  // fresh neighbour list: the same physics, another round-off.
  if (rs.state)
    solver_.resume(*rs.state);
  else
    solver_.set_time(rs.time);
  step_offset_ = rs.state ? 0 : rs.step;
  phase_summary_["restart"] = {
      {"file", c_.restart.string()}, {"time_s", rs.time}, {"step", rs.step}, {"exact", rs.state.has_value()}};
}

template <int Dim>
void DynamicRun<Dim>::geostatic_phase(const SphSimulation& self, RunObserver* obs) {
  const double dur = geostatic_duration(c_, href_, solver_.max_wave_speed());
  const auto rep = geostatic_with_progress(solver_, dur, c_, self, obs);
  have_loads_ = rep.steps > 0;
  const double tol = c_.rest_tolerance * std::sqrt(c_.numerics.gravity * href_);
  const bool at_rest = rep.max_speed < tol;
  phase_summary_["geostatic"] = {{"duration_s", dur},
                                 {"steps", rep.steps},
                                 {"max_speed_m_per_s", rep.max_speed},
                                 {"rest_tolerance_m_per_s", tol},
                                 {"at_rest", at_rest}};
  if (!quiet_)
    std::fprintf(stderr, "sph-slope: geostatic phase %.4g s (%lld steps): max speed %.3g m/s -> %s\n", dur,
                 static_cast<long long>(rep.steps), rep.max_speed,
                 at_rest ? "at rest" : "NOT at rest (see summary.json)");
}

/// Biaxial test: the platens move towards each other (compression) or apart (tension) at ε̇ H / 2 each.
template <int Dim>
void DynamicRun<Dim>::move_platens() {
  auto& S = solver_.store();
  const double vp = 0.5 * c_.biaxial_strain_rate * c_.biaxial.height;
  for (std::size_t i = 0; i < S.size(); ++i) {
    if (S.template get<ParticleKind>()[i] == kSoil) continue;
    const bool top = S.template get<Position<Dim>>()[i][Dim - 1] > 0.5 * c_.biaxial.height;
    S.template get<Velocity<Dim>>()[i].setZero();
    S.template get<Velocity<Dim>>()[i][Dim - 1] = top ? -vp : vp;
  }
}

/// With clamped regions: the free end's particles (initial x within Δx/2 of the largest soil x,
/// not clamped), whose mean vertical displacement is the series' tip_displacement_m.
template <int Dim>
void DynamicRun<Dim>::mark_free_end() {
  if (c_.clamp_boxes.empty()) return;
  const auto& S = solver_.store();
  const auto& x = S.template get<Position<Dim>>();
  const auto& u = S.template get<Displacement<Dim>>();
  const auto& id = S.template get<ParticleId>();
  double xmax = -1e300;
  std::int64_t idmax = 0;
  for (std::size_t i = 0; i < S.size(); ++i) {
    idmax = std::max(idmax, id[i]);
    if (S.template get<ParticleKind>()[i] == kSoil) xmax = std::max(xmax, x[i][0] - u[i][0]);
  }
  free_end_.assign(static_cast<std::size_t>(idmax) + 1, 0);
  for (std::size_t i = 0; i < S.size(); ++i)
    if (S.template get<ParticleKind>()[i] == kSoil && !S.template get<Clamped>()[i] &&
        x[i][0] - u[i][0] >= xmax - 0.5 * c_.numerics.spacing)
      free_end_[static_cast<std::size_t>(id[i])] = 1;
}

template <int Dim>
double DynamicRun<Dim>::tip_displacement() const {
  const auto& S = solver_.store();
  const auto& id = S.template get<ParticleId>();
  double sum = 0.0;
  int count = 0;
  for (std::size_t i = 0; i < S.size(); ++i)
    if (free_end_[static_cast<std::size_t>(id[i])]) {
      sum += S.template get<Displacement<Dim>>()[i][Dim - 1];
      ++count;
    }
  return sum / std::max(count, 1);
}

template <int Dim>
void DynamicRun<Dim>::start_main_phase() {
  series_.columns = {"time_s",
                     "front_m",
                     "tip_m",
                     "runout_m",
                     "normalised_runout",
                     "max_speed_m_per_s",
                     "mean_speed_m_per_s",
                     "kinetic_energy_J",
                     "plastic_fraction",
                     "max_displacement_m",
                     "earthquake_acceleration_m_per_s2"};
  if (!free_end_.empty()) series_.columns.emplace_back("tip_displacement_m");
  biaxial_.columns = {"time_s", "axial_strain", "sigma_axial_Pa", "sigma_lateral_Pa", "deviator_Pa"};
  png_times_ = c_.velocity_png_times;
  std::sort(png_times_.begin(), png_times_.end());
  next_out_ = solver_.time();
  last_moving_ = t_start_ = solver_.time();
  main_started_ = true;
}

template <int Dim>
void DynamicRun<Dim>::main_phase(const SphSimulation& self, RunObserver* obs) {
  while (solver_.time() < c_.end_time - 1e-12) {
    if (solver_.time() >= next_out_ - 1e-12) {
      record();
      next_out_ += c_.output_interval;
    }
    if (obs) obs->before_step(self);
    solver_.step();
    have_loads_ = true;
    if (!structures_.empty()) structures_.observe(solver_.time(), solver_.structure_loads());
    const double vmax = solver_.last_stats().max_speed;
    max_speed_run_ = std::max(max_speed_run_, vmax);
    if (vmax > c_.rest_speed) last_moving_ = solver_.time();
    if (obs) obs->stepped(self);
    if (c_.stop_at_rest && solver_.time() - t_start_ > std::max(0.05, 0.1 * c_.end_time) && vmax < c_.rest_speed &&
        solver_.time() > settings_.earthquake.end_time()) {
      stopped_at_rest_ = true;
      break;
    }
  }
  last_ = record();
  finished_ = true;
  if (obs) obs->finished(self);
}

/// A row of the series (and of the structure loads, and of the biaxial curve).
template <int Dim>
SeriesRow DynamicRun<Dim>::record() {
  const auto r = series_row(solver_.store(), b_.frame);
  double runout = r.runout, nrun = r.normalised_runout;
  if (c_.scenario == ScenarioType::Section) {
    runout = 0.0;
    for (const auto& u : solver_.store().template get<Displacement<Dim>>()) runout = std::max(runout, std::abs(u[0]));
    nrun = runout / b_.frame.base_length;
  }
  max_runout_ = std::max(max_runout_, runout);
  if (have_loads_ && !structures_.empty()) structures_.record(solver_.time(), solver_.structure_loads());
  std::vector<double> row{solver_.time(),
                          r.front,
                          r.tip,
                          runout,
                          nrun,
                          r.max_speed,
                          r.mean_speed,
                          r.kinetic_energy,
                          r.plastic_fraction,
                          r.max_displacement,
                          settings_.earthquake.horizontal(solver_.time())};
  if (!free_end_.empty()) row.push_back(tip_displacement());
  series_.rows.push_back(std::move(row));
  if (c_.scenario == ScenarioType::Biaxial) record_biaxial();
  return r;
}

/// The mean axial and lateral stress of the specimen.
template <int Dim>
void DynamicRun<Dim>::record_biaxial() {
  const auto& S = solver_.store();
  double sa = 0, sl = 0;
  int n = 0;
  for (std::size_t i = 0; i < S.size(); ++i)
    if (S.template get<ParticleKind>()[i] == kSoil) {
      sa += S.template get<Stress>()[i](Dim - 1, Dim - 1);
      sl += S.template get<Stress>()[i](0, 0);
      ++n;
    }
  sa /= std::max(n, 1);
  sl /= std::max(n, 1);
  biaxial_.rows.push_back({solver_.time(), c_.biaxial_strain_rate * solver_.time(), sa, sl, sa - sl});
}

template <int Dim>
void DynamicRun<Dim>::draw_due_pngs(const std::filesystem::path& out) {
  while (next_png_ < png_times_.size() && solver_.time() >= png_times_[next_png_] - 1e-12) {
    std::vector<double> v(solver_.store().size());
    for (std::size_t i = 0; i < v.size(); ++i) v[i] = solver_.store().template get<Velocity<Dim>>()[i].norm();
    const double vm = *std::max_element(v.begin(), v.end());
    std::ostringstream name;
    name << "velocity_t" << std::fixed << std::setprecision(3) << png_times_[next_png_] << ".png";
    draw_particles<Dim>(out / name.str(), solver_.store(), v, vm, c_.numerics.spacing, "speed (m/s)");
    ++next_png_;
  }
}

template <int Dim>
std::vector<NamedTable> DynamicRun<Dim>::tables() const {
  std::vector<NamedTable> t{{"series", series_}};
  if (!structures_.empty()) t.push_back({"structure_forces", structures_.table()});
  if (c_.scenario == ScenarioType::Biaxial) t.push_back({"stress_strain", biaxial_});
  t.push_back({"surface_final", xz_table(free_surface(solver_.store(), c_.numerics.spacing))});
  t.push_back({"slip_surface", xz_table(slip_surface(solver_.store(), c_.numerics.spacing, c_.failed_threshold))});
  return t;
}

template <int Dim>
void DynamicRun<Dim>::write_partial(const std::filesystem::path& out) const {
  write_text_file(out / "series.csv", series_.csv());
  if (!structures_.empty()) write_text_file(out / "structure_forces.csv", structures_.table().csv());
}

template <int Dim>
void DynamicRun<Dim>::write_outputs(const std::filesystem::path& out) const {
  for (const auto& [name, table] : tables()) write_text_file(out / (name + ".csv"), table.csv());
  if (!structures_.empty()) structures_.plot(out / "structure_forces.png");
  write_pictures(out);
  const ReleaseOutput rel = release();
  write_release(out, rel);
  const nlohmann::json summary = summary_with(rel);
  write_text_file(out / "summary.json", summary.dump(2) + "\n");
  if (!quiet_) {
    const auto fm = failed_mass(solver_.store(), rho0_, c_.failed_threshold);
    std::fprintf(stderr, "sph-slope: t = %.4g s, run-out %.4g m (normalised %.4g), failed %s %.4g, outputs in %s\n",
                 solver_.time(), summary["runout_m"].get<double>(), summary["normalised_runout"].get<double>(),
                 Dim == 2 ? "area (m^2/m)" : "volume (m^3)", fm.volume, out.string().c_str());
  }
}

/// Quick-looks of the final state coloured by displacement and by plastic strain.
template <int Dim>
void DynamicRun<Dim>::write_pictures(const std::filesystem::path& out) const {
  const auto& S = solver_.store();
  std::vector<double> u(S.size());
  double umax = 0.0;
  for (std::size_t i = 0; i < u.size(); ++i) {
    u[i] = S.template get<Displacement<Dim>>()[i].norm();
    if (S.template get<ParticleKind>()[i] == kSoil) umax = std::max(umax, u[i]);
  }
  draw_particles<Dim>(out / "final_displacement.png", S, u, umax, c_.numerics.spacing, "displacement (m)");
  const auto& ep = S.template get<PlasticStrain>();
  const double epmax = ep.empty() ? 0.0 : *std::max_element(ep.begin(), ep.end());
  draw_particles<Dim>(out / "final_plastic_strain.png", S, ep, epmax, c_.numerics.spacing,
                      "accumulated plastic strain (1)");
}

/// Failed mass for debris-runout (docs/handoff.md): only when the section is georeferenced.
/// 2D: each plane-strain particle of area A becomes k = W/Δx map points spread across the width W,
/// each of volume A·W/k. 3D: each particle is one map point (its position on the strip) carrying
/// its own volume m/ρ0.
template <int Dim>
ReleaseOutput DynamicRun<Dim>::release() const {
  ReleaseOutput r;
  if (c_.scenario != ScenarioType::Section || !c_.write_release) return r;
  const auto& P = c_.section.profile;
  const auto& S = solver_.store();
  std::vector<Vec2> pts;
  std::vector<double> vols;
  const double W = Dim == 2 ? c_.section.release_width : strip_width(c_);
  const int k = Dim == 2 ? std::max(1, static_cast<int>(std::lround(W / c_.numerics.spacing))) : 1;
  for (std::size_t i = 0; i < S.size(); ++i) {
    if (S.template get<ParticleKind>()[i] != kSoil) continue;
    if (S.template get<Displacement<Dim>>()[i].norm() <= c_.failed_threshold) continue;
    const Vec<Dim>& x = S.template get<Position<Dim>>()[i];
    const double vol = S.template get<Mass>()[i] / rho0_[static_cast<std::size_t>(S.template get<MaterialId>()[i])] *
                       (Dim == 2 ? W / k : 1.0) * c_.bulking_factor;
    for (int q = 0; q < k; ++q) {
      const double t = Dim == 2 ? -0.5 * W + (q + 0.5) * W / k : x[1] - 0.5 * W;
      pts.push_back(section_map_point(P, x[0], t));
      vols.push_back(vol);
      r.total += vol;
    }
  }
  r.width = W;
  std::ostringstream src;
  src << c_.config_source << "; " << Dim << "D section; displacement > " << c_.failed_threshold << " m; width " << W
      << " m";
  r.handoff =
      Handoff{pts, vols, c_.section.crs_wkt, src.str(), c_.bulking_factor, solver_.time(), solver_.step_count()};
  if (c_.section.dsm) {
    // Nodata where the DSM has none (-9999, as the debris-runout maps), a band description and
    // unit, and a QGIS style beside it, like every GeoTIFF geohaz writes (issue #16).
    constexpr double kNodata = -9999.0;
    const Raster& dsm = *c_.section.dsm;
    Raster th = dsm.like(0.0, kNodata);
    th.description = "release thickness: failed volume per cell area (sph-slope section)";
    th.unit = "m";
    for (std::size_t q = 0; q < th.data.size(); ++q)
      if (dsm.is_nodata(dsm.data[q])) th.data[q] = kNodata;
    const double cell = th.cell_size_x() * th.cell_size_y();
    for (std::size_t q = 0; q < pts.size(); ++q) {
      const Vec2 px = th.to_pixel(pts[q]);
      const int col = static_cast<int>(std::lround(px.x())), row = static_cast<int>(std::lround(px.y()));
      if (col < 0 || row < 0 || col >= th.nx || row >= th.ny || th.at(col, row) == kNodata) continue;
      th.at(col, row) += vols[q] / cell;
      r.binned += vols[q];
    }
    for (double v : th.data)
      if (v != kNodata) r.max_thickness = std::max(r.max_thickness, v);
    r.thickness = std::move(th);
  }
  return r;
}

template <int Dim>
void DynamicRun<Dim>::write_release(const std::filesystem::path& out, const ReleaseOutput& r) const {
  if (c_.scenario != ScenarioType::Section || !c_.write_release) return;
  write_handoff(out / "release.h5", r.handoff, c_.resolved_config);
  if (!r.thickness) return;
  write_geotiff(out / "release_thickness.tif", *r.thickness);
  write_qgis_ramp_style(out / "release_thickness.qml", ColourRamp::Viridis, 0.0,
                        r.max_thickness > 0.0 ? r.max_thickness : 1.0, "m", 0.0);
}

template <int Dim>
nlohmann::json DynamicRun<Dim>::summary_with(const ReleaseOutput& rel) const {
  const auto& S = solver_.store();
  const auto& mats = solver_.materials();
  nlohmann::json s = summary_header<Dim>(c_, solver_, soil_count_);
  s["boundary_particles"] = boundary_count_;
  s["smoothing_length_m"] = solver_.smoothing_length();
  for (std::size_t k = 0; k < mats.size(); ++k) {
    nlohmann::json e = {{"name", k < c_.material_names.size() ? c_.material_names[k] : ""},
                        {"p_wave_speed_m_per_s", mats[k].p_wave_speed},
                        {"dp_fit", drucker_prager_fit_name(mats[k].fit)}};
    e.update(model_parameters(c_.model, mats[k]));
    s["materials"].push_back(e);
  }
  s.update(phase_summary_);
  if (!structures_.empty()) s["structures"] = structures_.summary();
  double umax = 0.0;
  for (std::size_t i = 0; i < S.size(); ++i)
    if (S.template get<ParticleKind>()[i] == kSoil)
      umax = std::max(umax, S.template get<Displacement<Dim>>()[i].norm());
  const auto& ep = S.template get<PlasticStrain>();
  s["max_plastic_strain"] = ep.empty() ? 0.0 : *std::max_element(ep.begin(), ep.end());
  const bool section = c_.scenario == ScenarioType::Section;
  s["end_time_s"] = solver_.time();
  s["steps"] = solver_.step_count();
  s["stopped_at_rest"] = stopped_at_rest_;
  s["runout_m"] = section ? max_runout_ : last_.runout;
  s["normalised_runout"] = section ? max_runout_ / b_.frame.base_length : last_.normalised_runout;
  s["front_m"] = last_.front;
  s["tip_m"] = last_.tip;
  s["max_runout_m"] = max_runout_;
  s["max_speed_m_per_s"] = max_speed_run_;
  s["final_max_speed_m_per_s"] = last_.max_speed;
  s["max_displacement_m"] = umax;
  s["failed_threshold_m"] = c_.failed_threshold;
  s["front_thickness_m"] =
      b_.frame.front_thickness > 0.0 ? b_.frame.front_thickness : b_.frame.front_min_layers * b_.frame.spacing;
  const auto fm = failed_mass(S, rho0_, c_.failed_threshold);
  s["failed_particles"] = fm.count;
  s[Dim == 2 ? "failed_area_m2_per_m" : "failed_volume_m3"] = fm.volume;
  s["time_to_rest_s"] = last_.max_speed < c_.rest_speed ? nlohmann::json(last_moving_ - t_start_) : nlohmann::json();
  s["rest_speed_m_per_s"] = c_.rest_speed;
  s["bytes_per_particle"] = solver_.bytes_per_particle();
  bishop_.add_to(s);
  if (section && c_.write_release) {
    s["release"] = {{"file", "release.h5"},
                    {"points", rel.handoff.points.size()},
                    {"total_volume_m3", rel.total},
                    {"width_m", rel.width}};
    if (rel.thickness) {
      s["release"]["thickness_style"] = "release_thickness.qml";
      s["release"]["thickness_raster"] = "release_thickness.tif";
      s["release"]["volume_on_raster_m3"] = rel.binned;
    }
  }
  if (Dim == 2 && c_.scenario == ScenarioType::Slope && c_.numerics.earthquake.active()) {
    // Beside the SPH run: Newmark's rigid block on the circle of the smallest yield coefficient.
    try {
      s["newmark"] = newmark_report(c_);
      s["newmark"]["sph_max_displacement_m"] = umax;
    } catch (const InputError& e) {
      s["newmark_note"] = e.reason();
    }
  }
  s["wall_time_s"] = std::chrono::duration<double>(std::chrono::steady_clock::now() - wall0_).count();
  return s;
}

/// The settings of the geostatic phase and the trials of a strength reduction: gravity only, the
/// trials' damping.
template <int Dim>
SolverSettings<Dim> trial_settings(const RunConfig& c, const Scenario<Dim>& sc) {
  auto s = settings_for<Dim>(c, sc);
  s.earthquake = EarthquakeLoading{};
  if (c.seismic.kh != 0.0 || c.seismic.kv != 0.0) {
    // Pseudo-static coefficients: a constant body acceleration k_h g towards +x (the slope scenario's
    // face descends towards +x, SlopeGeometry) and k_v g upward, in the trials only (the geostatic
    // phase turns the earthquake off), as Bishop's k_h W and k_v W.
    const double g = c.numerics.gravity, ah = c.seismic.kh * g, av = c.seismic.kv * g;
    s.earthquake = EarthquakeLoading::record({0.0, 1e12}, {ah, ah}, {av, av});
  }
  s.damping = c.srm.damping;
  return s;
}

/// Factor of safety by strength reduction (docs/sph.md, "Factor of safety by strength reduction"):
/// the geostatic state (or a restart), trials bisecting F, the Bishop circle beside it.
template <int Dim>
class StrengthReductionRun final : public SimulationModel {
 public:
  StrengthReductionRun(const RunConfig& c, bool quiet);
  void run(const SphSimulation& self, RunObserver* obs) override;
  double time() const override { return 0.0; }
  std::int64_t step_count() const override { return trial_steps_; }
  std::size_t particle_count() const override { return geo_.store().size(); }
  bool main_phase_started() const override { return false; }
  nlohmann::json summary() const override;
  std::vector<NamedTable> tables() const override;
  ParticleFields particles() const override { return mechanism_ ? fields_of(*mechanism_) : ParticleFields{}; }
  /// Before the trials the geostatic state (snapshot 0), after them the failed trial at the
  /// critical factor (snapshot 1).
  void write_snapshot(SnapshotWriter& w) const override {
    if (!finished_)
      write_fields<Dim>(w, *initial_, 0.0, 0);
    else if (mechanism_)
      write_fields<Dim>(w, *mechanism_, trial_duration_, 1);
  }
  void draw_due_pngs(const std::filesystem::path&) override {}
  void write_outputs(const std::filesystem::path& out) const override;
  void write_partial(const std::filesystem::path&) const override {}

 private:
  void geostatic_state(const SphSimulation& self, RunObserver* obs);
  bool trial(double F, const SphSimulation& self, RunObserver* obs);
  void bracket(const SphSimulation& self, RunObserver* obs);
  void bishop_check();
  Table curve() const;
  void plot_curve(const std::filesystem::path& path) const;
  void write_mechanism(const std::filesystem::path& out) const;

  const RunConfig& c_;
  bool quiet_;
  std::chrono::steady_clock::time_point wall0_;
  Built<Dim> b_;
  SolverSettings<Dim> settings_;
  double href_;
  SphSolver<Dim> geo_;
  double cmax_;                                              // largest P-wave speed (m/s)
  nlohmann::json phase_summary_ = nlohmann::json::object();  // "restart" or "geostatic"
  std::optional<SphStore<Dim>> initial_;                     // the geostatic state every trial starts from
  double trial_duration_ = 0.0;                              // T, s
  double u_ref_ = -1.0;  // largest displacement of the f_min trial (the stable reference), m
  std::vector<SrmTrial> trials_;
  std::int64_t trial_steps_ = 0;
  std::optional<SphStore<Dim>> mechanism_;  // the store of the failed trial at the upper end of the bracket
  double lo_ = 0.0, hi_ = 0.0;
  std::string outcome_ = "bracketed";
  BishopResult bishop_;
  std::string bishop_note_;
  std::vector<std::array<double, 2>> circle_;
  bool finished_ = false;
};

template <int Dim>
StrengthReductionRun<Dim>::StrengthReductionRun(const RunConfig& c, bool quiet)
    : c_(c),
      quiet_(quiet),
      wall0_(std::chrono::steady_clock::now()),
      b_(build<Dim>(c)),
      settings_(trial_settings<Dim>(c, b_.sc)),
      href_(b_.sc.reference_height),
      geo_(std::move(b_.sc.store), c.materials, c.model, settings_),
      cmax_(geo_.max_wave_speed()) {
  if (c_.restart.empty()) geostatic_duration(c_, href_, cmax_);  // checked before anything is written
}

template <int Dim>
void StrengthReductionRun<Dim>::run(const SphSimulation& self, RunObserver* obs) {
  geostatic_state(self, obs);
  trial_duration_ = c_.srm.trial_duration > 0.0 ? c_.srm.trial_duration : 30.0 * href_ / cmax_;
  if (obs) obs->started(self);
  bracket(self, obs);
  bishop_check();
  finished_ = true;
  if (obs) obs->finished(self);
}

template <int Dim>
void StrengthReductionRun<Dim>::geostatic_state(const SphSimulation& self, RunObserver* obs) {
  if (!c_.restart.empty()) {
    const Restart rs = load_restart<Dim>(c_.restart, geo_.store());
    for (auto& v : geo_.store().template get<Velocity<Dim>>()) v.setZero();
    for (auto& u : geo_.store().template get<Displacement<Dim>>()) u.setZero();
    phase_summary_["restart"] = {{"file", c_.restart.string()}, {"time_s", rs.time}};
  } else {
    const double dur = geostatic_duration(c_, href_, cmax_);
    const auto rep = geostatic_with_progress(geo_, dur, c_, self, obs);
    phase_summary_["geostatic"] = {{"duration_s", dur}, {"steps", rep.steps}, {"max_speed_m_per_s", rep.max_speed}};
  }
  initial_ = geo_.store();
}

/// One trial with every strength divided by F; true when it fails.
template <int Dim>
bool StrengthReductionRun<Dim>::trial(double F, const SphSimulation& self, RunObserver* obs) {
  const double T = trial_duration_;
  SrmTrial t;
  t.factor = F;
  SphSolver<Dim> s(*initial_, reduced_strength(c_.materials, F), c_.model, settings_);
  RunProgress p{"trial", 0.0, T, 0, s.store().size(), F, false};
  double u75 = -1.0;
  try {
    while (s.time() < T) {
      s.step();
      if (u75 < 0.0 && s.time() >= 0.75 * T) u75 = max_soil_displacement(s.store());
      if (obs && s.step_count() % 50 == 0) {
        p.time = s.time();
        p.steps = s.step_count();
        obs->progress(self, p);
      }
    }
    t.displacement = max_soil_displacement(s.store());
    t.growth = t.displacement - std::max(u75, 0.0);
    // Failure: the displacement has not converged, or (once the stable reference exists) it lies
    // beyond the knee of the F–displacement curve. SPH follows a failing mass to a new equilibrium
    // after it has slid, so a trial just above the critical F may have stopped again by T.
    t.failed = t.growth > c_.srm.growth_ratio * t.displacement ||
               (u_ref_ >= 0.0 && t.displacement > c_.srm.knee_ratio * std::max(u_ref_, 1e-3 * c_.numerics.spacing));
  } catch (const SimulationError& e) {
    t.failed = t.blew_up = true;
    t.displacement = max_soil_displacement(s.store());
    if (!quiet_) std::fprintf(stderr, "sph-slope: trial F = %.4g stopped (%s): counted as failed\n", F, e.what());
  }
  t.steps = s.step_count();
  trial_steps_ += t.steps;
  if (obs) {
    p.time = s.time();
    p.steps = t.steps;
    p.done = true;
    obs->progress(self, p);
  }
  if (!quiet_)
    std::fprintf(stderr, "sph-slope: trial F = %.4f: max displacement %.4g m, last-quarter growth %.3g m -> %s\n", F,
                 t.displacement, t.growth, t.failed ? "fails" : "stable");
  trials_.push_back(t);
  if (t.failed) mechanism_ = s.store();
  return t.failed;
}

/// f_min, f_max, then bisection until the bracket is narrower than the tolerance.
template <int Dim>
void StrengthReductionRun<Dim>::bracket(const SphSimulation& self, RunObserver* obs) {
  lo_ = c_.srm.f_min;
  hi_ = c_.srm.f_max;
  const bool low_fails = trial(lo_, self, obs);
  u_ref_ = trials_.back().displacement;
  if (low_fails) {
    outcome_ = "below_f_min";
  } else if (!trial(hi_, self, obs)) {
    outcome_ = "above_f_max";
  } else {
    auto best_failed = mechanism_;
    while (hi_ - lo_ > c_.srm.tolerance * (1.0 + 1e-9)) {
      const double mid = 0.5 * (lo_ + hi_);
      if (trial(mid, self, obs)) {
        hi_ = mid;
        best_failed = mechanism_;
      } else {
        lo_ = mid;
      }
    }
    mechanism_ = best_failed;
  }
}

template <int Dim>
void StrengthReductionRun<Dim>::bishop_check() {
  try {
    bishop_ = bishop_of(c_);
  } catch (const InputError& e) {
    bishop_note_ = e.reason();
  }
  if (!bishop_.admissible()) return;
  const auto& C = bishop_.circle;
  for (int k = 0; k <= 100; ++k) {
    const double x = bishop_.x_entry + (bishop_.x_exit - bishop_.x_entry) * k / 100.0;
    circle_.push_back({x, C.zc - std::sqrt(std::max(0.0, C.radius * C.radius - (x - C.xc) * (x - C.xc)))});
  }
}

/// The F–displacement curve: the trials sorted by F.
template <int Dim>
Table StrengthReductionRun<Dim>::curve() const {
  auto sorted = trials_;
  std::sort(sorted.begin(), sorted.end(), [](const auto& a, const auto& b) { return a.factor < b.factor; });
  Table t{{"factor", "max_displacement_m", "failed"}, {}, {false, false, true}};
  for (const auto& s : sorted) t.rows.push_back({s.factor, s.displacement, s.failed ? 1.0 : 0.0});
  return t;
}

template <int Dim>
std::vector<NamedTable> StrengthReductionRun<Dim>::tables() const {
  Table tr{{"trial", "factor", "max_displacement_m", "growth_last_quarter_m", "failed", "steps"},
           {},
           {true, false, false, false, true, true}};
  for (std::size_t k = 0; k < trials_.size(); ++k)
    tr.rows.push_back({static_cast<double>(k), trials_[k].factor, trials_[k].displacement, trials_[k].growth,
                       trials_[k].failed ? 1.0 : 0.0, static_cast<double>(trials_[k].steps)});
  std::vector<NamedTable> t{{"srm_trials", tr}, {"srm_curve", curve()}};
  if (bishop_.admissible()) t.push_back({"bishop_circle", xz_table(circle_)});
  if (mechanism_) {
    // The slip surface of the mechanism: the lower edge of the soil displaced by more than a tenth
    // of the largest displacement.
    t.push_back({"slip_surface",
                 xz_table(slip_surface(*mechanism_, c_.numerics.spacing, 0.1 * max_soil_displacement(*mechanism_)))});
  }
  return t;
}

/// Plot: F on x (f_min … f_max), displacement on y (log10, 4 decades below the largest), stable
/// trials blue, failed red, the bracket as two grey verticals.
template <int Dim>
void StrengthReductionRun<Dim>::plot_curve(const std::filesystem::path& path) const {
  const Table t = curve();
  const int W = 800, H = 500, m = 40;
  Image img(W, H);
  double umax = 0.0;
  for (const auto& r : t.rows) umax = std::max(umax, r[1]);
  const double ly1 = std::log10(std::max(umax, 1e-12)), ly0 = ly1 - 4.0;
  auto px = [&](double F) { return m + (F - c_.srm.f_min) / (c_.srm.f_max - c_.srm.f_min) * (W - 2 * m); };
  auto py = [&](double u) {
    const double l = std::clamp(std::log10(std::max(u, 1e-300)), ly0, ly1);
    return H - m - (l - ly0) / (ly1 - ly0) * (H - 2 * m);
  };
  img.line(m, H - m, W - m, H - m, {0, 0, 0});
  img.line(m, m, m, H - m, {0, 0, 0});
  for (int d = 0; d <= 4; ++d)
    img.line(m - 5, py(umax * std::pow(10.0, -d)), m, py(umax * std::pow(10.0, -d)), {0, 0, 0});
  img.line(px(lo_), m, px(lo_), H - m, {170, 170, 170});
  img.line(px(hi_), m, px(hi_), H - m, {170, 170, 170});
  for (std::size_t k = 1; k < t.rows.size(); ++k)
    img.line(px(t.rows[k - 1][0]), py(t.rows[k - 1][1]), px(t.rows[k][0]), py(t.rows[k][1]), {90, 90, 90});
  for (const auto& r : t.rows)
    img.fill_circle(px(r[0]), py(r[1]), 5.0,
                    r[2] != 0.0 ? std::array<std::uint8_t, 3>{210, 40, 40} : std::array<std::uint8_t, 3>{40, 80, 210});
  write_png(path, img);
}

/// The mechanism drawn where the particles started (with the Bishop circle) and deformed.
template <int Dim>
void StrengthReductionRun<Dim>::write_mechanism(const std::filesystem::path& out) const {
  std::vector<double> u(mechanism_->size());
  double umax = 0.0;
  SphStore<Dim> reference = *mechanism_;
  for (std::size_t i = 0; i < u.size(); ++i) {
    u[i] = mechanism_->template get<Displacement<Dim>>()[i].norm();
    reference.template get<Position<Dim>>()[i] -= mechanism_->template get<Displacement<Dim>>()[i];
    if (mechanism_->template get<ParticleKind>()[i] == kSoil) umax = std::max(umax, u[i]);
  }
  draw_particles<Dim>(out / "mechanism.png", reference, u, umax, c_.numerics.spacing, "displacement (m)", circle_);
  draw_particles<Dim>(out / "mechanism_deformed.png", *mechanism_, u, umax, c_.numerics.spacing, "displacement (m)",
                      circle_);
}

template <int Dim>
void StrengthReductionRun<Dim>::write_outputs(const std::filesystem::path& out) const {
  for (const auto& [name, table] : tables()) write_text_file(out / (name + ".csv"), table.csv());
  plot_curve(out / "srm_curve.png");
  if (mechanism_) write_mechanism(out);
  write_text_file(out / "summary.json", summary().dump(2) + "\n");
  if (!quiet_) {
    if (outcome_ == "bracketed")
      std::fprintf(stderr, "sph-slope: factor of safety (strength reduction) %.4g, failed at %.4g", lo_, hi_);
    else
      std::fprintf(stderr, "sph-slope: factor of safety %s the range [%.4g, %.4g]",
                   outcome_ == "below_f_min" ? "below" : "above", c_.srm.f_min, c_.srm.f_max);
    if (bishop_.admissible()) std::fprintf(stderr, "; Bishop %.4g", bishop_.factor);
    std::fprintf(stderr, "; outputs in %s\n", out.string().c_str());
  }
}

template <int Dim>
nlohmann::json StrengthReductionRun<Dim>::summary() const {
  nlohmann::json s = summary_header<Dim>(c_, geo_, b_.sc.soil_count);
  s["analysis"] = "strength_reduction";
  s.update(phase_summary_);
  if (!bishop_note_.empty()) s["bishop_note"] = bishop_note_;
  if (bishop_.admissible()) {
    s["bishop"] = StaticBishop::circle_json(bishop_);
    if (std::isfinite(bishop_.yield_coefficient)) s["bishop"]["yield_coefficient"] = bishop_.yield_coefficient;
  }
  s["seismic"] = {{"kh", c_.seismic.kh}, {"kv", c_.seismic.kv}};

  s["outcome"] = outcome_;
  s["factor_of_safety"] = outcome_ == "bracketed" ? nlohmann::json(lo_) : nlohmann::json();
  s["bracket"] = {lo_, hi_};
  s["tolerance"] = c_.srm.tolerance;
  s["trial_duration_s"] = trial_duration_;
  s["trial_damping"] = c_.srm.damping;
  s["growth_ratio"] = c_.srm.growth_ratio;
  s["knee_ratio"] = c_.srm.knee_ratio;
  s["reference_displacement_m"] = u_ref_;
  s["trials"] = trials_.size();
  s["wall_time_s"] = std::chrono::duration<double>(std::chrono::steady_clock::now() - wall0_).count();
  return s;
}

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

Vec2 section_map_point(const std::vector<ProfilePoint>& P, double s, double t) {
  s = std::clamp(s, P.front().s, P.back().s);
  std::size_t seg = 1;
  while (seg + 1 < P.size() && P[seg].s < s) ++seg;
  const double ds = P[seg].s - P[seg - 1].s;
  const double w = ds > 0 ? (s - P[seg - 1].s) / ds : 0.0;
  const Vec2 a(P[seg - 1].x, P[seg - 1].y), b(P[seg].x, P[seg].y);
  Vec2 tan = b - a;
  tan = tan.norm() > 0 ? Vec2(tan / tan.norm()) : Vec2(1.0, 0.0);
  return a + w * (b - a) + t * Vec2(-tan.y(), tan.x());
}

double cantilever_mode_shape(double xi) {
  constexpr double k = 1.8751040687119611;  // first root of 1 + cos k cosh k = 0
  const double s = (std::cosh(k) + std::cos(k)) / (std::sinh(k) + std::sin(k));
  auto phi = [&](double z) { return std::cosh(k * z) - std::cos(k * z) - s * (std::sinh(k * z) - std::sin(k * z)); };
  return phi(std::clamp(xi, 0.0, 1.0)) / phi(1.0);
}

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
  }
  validate_water_and_seismic(c);
  if (c.analysis == Analysis::LimitEquilibrium) return;  // no particles to build
  if (c.initial_velocity.type == InitialVelocity::Type::Uniform &&
      c.initial_velocity.value.size() != static_cast<std::size_t>(c.dimension))
    throw InputError(
        "initial_velocity.type = uniform needs one component per axis (" + std::to_string(c.dimension) + ", m/s)",
        c.config_source, "initial_velocity.value", std::to_string(c.initial_velocity.value.size()) + " numbers");
  check_resources(c);
  // Build once (dry run) so that geometry errors surface before any output exists; the structure
  // names of `output.structures` are checked against the scenario's.
  if (c.dimension == 2)
    (void)reported_structures(c, build<2>(c).sc.structures);
  else
    (void)reported_structures(c, build<3>(c).sc.structures);
  if (!c.restart.empty() && !std::filesystem::exists(c.restart))
    throw InputError("restart file does not exist", c.config_source, "run.restart", c.restart.string());
}

std::string Table::csv() const {
  std::ostringstream os;
  for (std::size_t k = 0; k < columns.size(); ++k) os << (k ? "," : "") << columns[k];
  os << '\n';
  for (const auto& row : rows) {
    for (std::size_t k = 0; k < row.size(); ++k) {
      if (k) os << ',';
      if (k < integer.size() && integer[k])
        os << static_cast<long long>(row[k]);
      else
        os << csv_number(row[k]);
    }
    os << '\n';
  }
  return os.str();
}

SphSimulation::SphSimulation(const RunConfig& cfg, bool quiet) : cfg_(cfg), impl_(std::make_unique<Impl>()) {
  const bool srm = cfg.analysis == Analysis::StrengthReduction;
  if (cfg.analysis == Analysis::LimitEquilibrium)
    impl_->model = make_limit_equilibrium_run(cfg, quiet);
  else if (cfg.dimension == 2)
    impl_->model = srm ? std::unique_ptr<SimulationModel>(std::make_unique<StrengthReductionRun<2>>(cfg, quiet))
                       : std::make_unique<DynamicRun<2>>(cfg, quiet);
  else
    impl_->model = srm ? std::unique_ptr<SimulationModel>(std::make_unique<StrengthReductionRun<3>>(cfg, quiet))
                       : std::make_unique<DynamicRun<3>>(cfg, quiet);
}

SphSimulation::~SphSimulation() = default;

void SphSimulation::run(RunObserver* observer) {
  impl_->model->run(*this, observer);
}
double SphSimulation::time() const {
  return impl_->model->time();
}
std::int64_t SphSimulation::step_count() const {
  return impl_->model->step_count();
}
std::size_t SphSimulation::particle_count() const {
  return impl_->model->particle_count();
}
bool SphSimulation::main_phase_started() const {
  return impl_->model->main_phase_started();
}
std::string SphSimulation::summary_json() const {
  return impl_->model->summary().dump(2) + "\n";
}
std::vector<NamedTable> SphSimulation::tables() const {
  return impl_->model->tables();
}
ParticleFields SphSimulation::particles() const {
  return impl_->model->particles();
}

/// The files of a run made during it (the output folder, the resolved config, the snapshots and
/// the velocity PNGs) and the progress lines on stderr; passes every event on to `next`.
class SphRunFiles final : public RunObserver {
 public:
  SphRunFiles(const SphSimulation& sim, std::filesystem::path out, bool quiet, RunObserver* next)
      : model_(*sim.impl_->model), cfg_(sim.config()), out_(std::move(out)), quiet_(quiet), next_(next) {
    if (out_.empty()) return;
    make_output_dir(out_);
    write_text_file(out_ / "config.resolved.toml", cfg_.resolved_config);
    if (cfg_.analysis == Analysis::LimitEquilibrium) return;  // no particles
    snaps_ = std::make_unique<SnapshotWriter>(out_ / "snapshots.h5", "sph-slope", cfg_.dimension, cfg_.resolved_config);
    snaps_->set_attribute("scenario", scenario_name(cfg_.scenario));
    snaps_->set_attribute("units", "SI: m, s, kg, Pa");
    if (cfg_.analysis == Analysis::StrengthReduction)
      snaps_->set_attribute("contents",
                            "snapshot 0: geostatic state; snapshot 1: the failed trial at the critical factor");
    else if (cfg_.scenario == ScenarioType::Section && !cfg_.section.crs_wkt.empty())
      snaps_->set_attribute("crs_wkt", cfg_.section.crs_wkt);
  }
  void progress(const SphSimulation& sim, const RunProgress& p) override {
    if (std::string_view(p.phase) == "geostatic") {
      if (!geostatic_) geostatic_.emplace("sph-slope geostatic", p.end_time, quiet_);
      if (p.done)
        geostatic_->finish(p.time, p.steps, p.particles);
      else if (p.steps > 0)
        geostatic_->update(p.time, p.steps, p.particles);
    }
    if (next_) next_->progress(sim, p);
  }
  void started(const SphSimulation& sim) override {
    if (snaps_) model_.write_snapshot(*snaps_);
    next_snap_ = sim.time() + cfg_.snapshot_interval;
    if (cfg_.analysis == Analysis::Dynamic) main_.emplace("sph-slope", cfg_.end_time, quiet_);
    if (next_) next_->started(sim);
  }
  void before_step(const SphSimulation& sim) override {
    if (!out_.empty()) model_.draw_due_pngs(out_);
    if (next_) next_->before_step(sim);
  }
  void stepped(const SphSimulation& sim) override {
    if (main_) main_->update(sim.time(), sim.step_count(), sim.particle_count());
    if (snaps_ && cfg_.snapshot_interval > 0.0 && sim.time() >= next_snap_ - 1e-12) {
      model_.write_snapshot(*snaps_);
      next_snap_ += cfg_.snapshot_interval;
    }
    if (next_) next_->stepped(sim);
  }
  void finished(const SphSimulation& sim) override {
    if (main_) main_->finish(sim.time(), sim.step_count(), sim.particle_count());
    if (snaps_) model_.write_snapshot(*snaps_);
    if (next_) next_->finished(sim);
  }
  /// Close the snapshot file.
  void close() { snaps_.reset(); }
  SimulationModel& model() { return model_; }

 private:
  SimulationModel& model_;
  const RunConfig& cfg_;
  std::filesystem::path out_;
  bool quiet_;
  RunObserver* next_;
  std::unique_ptr<SnapshotWriter> snaps_;
  std::optional<ProgressReporter> geostatic_, main_;
  double next_snap_ = 0.0;
};

void write_outputs(const SphSimulation& sim, const std::filesystem::path& out) {
  sim.impl_->model->write_outputs(out);
}

void run_with_outputs(SphSimulation& sim, const std::filesystem::path& out, bool quiet, RunObserver* observer) {
  SphRunFiles files(sim, out, quiet, observer);
  try {
    sim.run(&files);
  } catch (const SimulationError&) {
    if (!out.empty() && sim.main_phase_started()) files.model().write_partial(out);
    throw;
  }
  files.close();
  if (!out.empty()) write_outputs(sim, out);
}

int run_case(const RunConfig& cfg, const std::filesystem::path& out, bool quiet) {
  SphSimulation sim(cfg, quiet);
  run_with_outputs(sim, out, quiet);
  return 0;
}

}  // namespace geohaz::sph
