// The state an sph-slope analysis starts from and keeps: the geostatic phase, the snapshots
// (snapshots.h5) and the restart from their last one, the particle fields as flat arrays.
#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <sstream>
#include <string>

#include "geohaz/core/errors.hpp"
#include "run_support.hpp"

namespace geohaz::sph {

namespace {

/// The first `n` particles' values of a field.
template <class Tag, class Store>
void add_view(std::vector<FieldView>& v, const Store& s, std::size_t n) {
  using Tr = FieldTraits<typename Tag::type>;
  const auto& a = s.template get<Tag>();
  v.push_back({Tag::label, Tag::unit, scalar_type_of<typename Tr::scalar>(), a.data(), n, Tr::rows, Tr::cols});
}

/// The internal variables of every constitutive model (constitutive.hpp), each once.
template <int Dim, class... Tags>
void add_fields_once(std::vector<FieldView>& v, const SphStore<Dim>& s, std::size_t n, FieldList<Tags...>) {
  [[maybe_unused]] auto once = [&](auto tag) {
    using Tag = decltype(tag);
    for (const auto& f : v)
      if (f.label == Tag::label) return;
    add_view<Tag>(v, s, n);
  };
  (once(Tags{}), ...);
}
template <int Dim, class... Models>
void add_internal_variables(std::vector<FieldView>& v, const SphStore<Dim>& s, std::size_t n,
                            std::type_identity<std::variant<Models...>>) {
  (add_fields_once(v, s, n, typename Models::InternalVariables{}), ...);
}

/// The solver state of the last snapshot (SolverState), as a root attribute: a snapshot group has
/// room for its time and step only (core snapshot.hpp). It names the snapshot it belongs to, so a
/// run killed between the snapshot and the attribute is not restarted with the wrong state; Δt in
/// hexadecimal, exact.
constexpr const char* kSolverStateAttribute = "sph_solver_state";

}  // namespace

template <int Dim>
void write_fields(SnapshotWriter& w, const SphStore<Dim>& s, double t, std::int64_t step, bool pore_pressure,
                  std::size_t count) {
  const std::size_t n = std::min(count, s.size());
  std::vector<FieldView> v;
  add_view<Position<Dim>>(v, s, n);
  add_view<Velocity<Dim>>(v, s, n);
  add_view<Displacement<Dim>>(v, s, n);
  add_view<Stress>(v, s, n);
  add_view<PlasticStrain>(v, s, n);
  add_view<Density>(v, s, n);
  add_view<MaterialId>(v, s, n);
  add_view<StressFree>(v, s, n);
  add_view<ParticleKind>(v, s, n);
  add_view<Mass>(v, s, n);
  add_view<WallNormal<Dim>>(v, s, n);
  add_view<LayerNormal<Dim>>(v, s, n);
  add_view<StructureId>(v, s, n);
  add_view<ParticleId>(v, s, n);
  add_view<Clamped>(v, s, n);
  add_internal_variables(v, s, n, std::type_identity<ConstitutiveModel>{});
  add_view<PositionAtBuild<Dim>>(v, s, n);
  if (pore_pressure) add_view<PorePressure>(v, s, n);
  w.write(t, step, v);
}

template <int Dim>
void write_snapshot(SnapshotWriter& w, const SphSolver<Dim>& solver, std::int64_t step) {
  // Over several ranks each writes its owned particles (the writer joins them) and the same state.
  write_fields<Dim>(w, solver.store(), solver.time(), step, solver.settings().pore_water.active(),
                    solver.owned_count());
  const SolverState st = solver.state();
  char buf[160];
  std::snprintf(buf, sizeof buf, "snapshot %zu step %lld dt %a builds %lld", w.snapshot_count() - 1,
                static_cast<long long>(st.step), st.dt, static_cast<long long>(st.neighbour_builds));
  w.set_attribute(kSolverStateAttribute, buf);
}

template <int Dim>
Restart load_restart(const std::filesystem::path& path, SphStore<Dim>& s, const Share& share) {
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
  // Over several ranks only this rank's block of rows, the block DomainDecomposition::scatter keeps
  // of the whole file (hyperslabs: the other rows are never read).
  const std::size_t n = r.rows(k, "position");
  const std::size_t first = n * static_cast<std::size_t>(share.part) / static_cast<std::size_t>(share.parts);
  const std::size_t last = n * static_cast<std::size_t>(share.part + 1) / static_cast<std::size_t>(share.parts);
  s.resize(last - first);
  try {
    s.for_each_field([&](auto tag, auto&) {
      using Tag = decltype(tag);
      if (r.has_field(k, Tag::label)) load_field<Tag>(r.read(k, Tag::label, first, last - first), s);
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
  f.pore_pressure = s.template get<PorePressure>();
  f.density = s.template get<Density>();
  f.mass = s.template get<Mass>();
  f.material_id = s.template get<MaterialId>();
  f.kind = s.template get<ParticleKind>();
  f.id = s.template get<ParticleId>();
  return f;
}

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

template void write_fields<2>(SnapshotWriter&, const SphStore<2>&, double, std::int64_t, bool, std::size_t);
template void write_fields<3>(SnapshotWriter&, const SphStore<3>&, double, std::int64_t, bool, std::size_t);
template void write_snapshot<2>(SnapshotWriter&, const SphSolver<2>&, std::int64_t);
template void write_snapshot<3>(SnapshotWriter&, const SphSolver<3>&, std::int64_t);
template Restart load_restart<2>(const std::filesystem::path&, SphStore<2>&, const Share&);
template Restart load_restart<3>(const std::filesystem::path&, SphStore<3>&, const Share&);
template ParticleFields fields_of<2>(const SphStore<2>&);
template ParticleFields fields_of<3>(const SphStore<3>&);
template GeostaticReport geostatic_with_progress<2>(SphSolver<2>&, double, const RunConfig&, const SphSimulation&,
                                                    RunObserver*);
template GeostaticReport geostatic_with_progress<3>(SphSolver<3>&, double, const RunConfig&, const SphSimulation&,
                                                    RunObserver*);

}  // namespace geohaz::sph
