// The in-process sph-slope run of the Python package (python/geohaz/sph.py): the config is read
// with the model's own key declarations (sph::read_config, libs/sph/src/config.cpp), checked by
// sph::validate, and run through libs/sph/run.hpp as the app does; the summary, the tables (the
// CSV files' columns) and the final particle fields come back as a dict and NumPy arrays.
//
// The GIL is released for the whole run; it is taken back only to call a progress callback (when
// one is given) and, every few hundred steps, to let Ctrl-C interrupt the run.
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <algorithm>
#include <filesystem>
#include <memory>
#include <string>
#include <vector>

#include "geohaz/core/app.hpp"
#include "geohaz/core/config.hpp"
#include "geohaz/core/errors.hpp"
#include "geohaz/sph/config.hpp"
#include "geohaz/sph/run.hpp"

namespace py = pybind11;
using namespace geohaz;
using namespace geohaz::sph;

namespace geohaz::python {

namespace {

/// A NumPy array of `shape` holding `v` (row-major).
template <class T>
py::array_t<T> array_of(const std::vector<T>& v, std::vector<py::ssize_t> shape) {
  py::array_t<T> a(shape);
  std::copy(v.begin(), v.end(), a.mutable_data());
  return a;
}

/// The final particle fields: vectors (n, dim), stress (n, 3, 3), scalars (n,).
py::dict particle_arrays(const ParticleFields& f) {
  const auto n = static_cast<py::ssize_t>(f.count), dim = static_cast<py::ssize_t>(f.dimension);
  py::dict d;
  d["position"] = array_of(f.position, {n, dim});
  d["velocity"] = array_of(f.velocity, {n, dim});
  d["displacement"] = array_of(f.displacement, {n, dim});
  d["stress"] = array_of(f.stress, {n, 3, 3});
  d["plastic_strain"] = array_of(f.plastic_strain, {n});
  d["pore_pressure"] = array_of(f.pore_pressure, {n});
  d["density"] = array_of(f.density, {n});
  d["mass"] = array_of(f.mass, {n});
  d["material_id"] = array_of(f.material_id, {n});
  d["kind"] = array_of(f.kind, {n});
  d["id"] = array_of(f.id, {n});
  return d;
}

/// Every table as {column: float64 array}, by CSV stem.
py::dict table_arrays(const std::vector<NamedTable>& tables) {
  py::dict d;
  for (const auto& [name, t] : tables) {
    py::dict cols;
    const auto n = static_cast<py::ssize_t>(t.rows.size());
    for (std::size_t k = 0; k < t.columns.size(); ++k) {
      py::array_t<double> a(n);
      double* p = a.mutable_data();
      for (py::ssize_t i = 0; i < n; ++i) p[i] = t.rows[static_cast<std::size_t>(i)][k];
      cols[py::str(t.columns[k])] = a;
    }
    d[py::str(name)] = cols;
  }
  return d;
}

/// The observer of a run from Python: the progress callback (phases every 50 steps, the main phase
/// every `every` steps, and at its start and end) and Ctrl-C.
class PythonObserver : public RunObserver {
 public:
  PythonObserver(py::object callback, int every) : cb_(std::move(callback)), every_(every) {}

  void progress(const SphSimulation&, const RunProgress& p) override {
    call(p.phase, p.time, p.end_time, p.steps, p.particles, p.factor);
  }
  void started(const SphSimulation& sim) override { main("started", sim); }
  void stepped(const SphSimulation& sim) override {
    const std::int64_t k = sim.step_count();
    if (!cb_.is_none() && k % every_ == 0) {
      main("running", sim);
    } else if (k % 256 == 0) {  // let Ctrl-C through without a callback
      py::gil_scoped_acquire gil;
      if (PyErr_CheckSignals() != 0) throw py::error_already_set();
    }
  }
  void finished(const SphSimulation& sim) override { main("finished", sim); }

 private:
  void main(const char* phase, const SphSimulation& sim) {
    const bool srm = sim.config().analysis == Analysis::StrengthReduction;
    call(phase, sim.time(), srm ? 0.0 : sim.config().end_time, sim.step_count(), sim.particle_count(), 0.0);
  }
  void call(const char* phase, double time, double end_time, std::int64_t step, std::size_t particles, double factor) {
    py::gil_scoped_acquire gil;
    if (PyErr_CheckSignals() != 0) throw py::error_already_set();
    if (cb_.is_none()) return;
    py::dict d;
    d["phase"] = phase;
    d["time"] = time;
    d["end_time"] = end_time;
    d["step"] = step;
    d["particles"] = particles;
    if (std::string_view(phase) == "trial") d["factor"] = factor;
    cb_(d);
  }
  py::object cb_;
  int every_;
};

/// geohaz._geohaz.sph_run: see python/geohaz/sph.py for the documented signature.
py::dict sph_run(const std::string& config, const std::vector<std::string>& overrides, const std::string& out,
                 py::object progress, int progress_every, bool quiet, int threads, bool particles) {
  if (progress_every < 1) throw InputError("must be ≥ 1", "python", "progress_every", std::to_string(progress_every));
  if (!progress.is_none() && !PyCallable_Check(progress.ptr()))
    throw InputError("must be callable (or None)", "python", "progress");
  const int nthreads = setup_threads(threads);
  // The config as the app reads it (run_config_app): the file, the --set overrides, every key.
  ConfigReader reader = ConfigReader::from_file(config);
  for (const auto& o : overrides) reader.apply_override(o);
  RunConfig cfg = read_config(reader, false);
  reader.finish();
  cfg.resolved_config = reader.resolved();

  CaseRun run;
  PythonObserver obs(progress, progress_every);
  {
    py::gil_scoped_release nogil;
    validate(cfg);  // everything checked before anything is written
    // The app's run (run.hpp); with an output folder under the apps' --out policy (app.hpp).
    const auto body = [&] {
      run = run_case(cfg, {out, quiet, nullptr}, &obs);
      return 0;
    };
    if (out.empty())
      body();
    else
      run_in_output_dir(out, "sph-slope", {cfg.restart}, body);
  }
  const SphSimulation* sim = run.simulation.get();
  py::dict r;
  r["summary"] = py::module_::import("json").attr("loads")(sim->summary_json());
  r["tables"] = table_arrays(sim->tables());
  r["particles"] = particles ? py::object(particle_arrays(sim->particles())) : py::none();
  r["resolved_config"] = cfg.resolved_config;
  r["out"] = out.empty() ? py::none() : py::object(py::str(out));
  r["threads"] = nthreads;
  return r;
}

/// The config keys of sph-slope with unit, default, range and help (as --help-config).
std::string sph_help_config() {
  ConfigReader d = ConfigReader::describe();
  (void)read_config(d, true);
  return ConfigReader::format_reference(d.reference());
}

}  // namespace

void add_sph(py::module_& m) {
  m.def("sph_run", &sph_run, py::arg("config"), py::arg("overrides"), py::arg("out"), py::arg("progress"),
        py::arg("progress_every"), py::arg("quiet"), py::arg("threads"), py::arg("particles"));
  m.def("sph_help_config", &sph_help_config);
}

}  // namespace geohaz::python
