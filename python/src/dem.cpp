// geohaz._geohaz's DEM part: an in-process dem-avalanche run (python/geohaz/dem.py documents the
// Python signature). The config is read with the model's own key declarations
// (dem::read_config), the run goes through libs/dem/run.hpp, and the summary and tables come from
// the same builders as the app's summary.json and CSV files; the final disc fields are handed
// back as NumPy arrays.
//
// The GIL is released for the whole run; it is taken back only to call a progress callback (when
// one is given) and, once per record otherwise, to let Ctrl-C interrupt the run.
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <algorithm>
#include <filesystem>
#include <memory>
#include <string>
#include <type_traits>
#include <vector>

#include "geohaz/core/app.hpp"
#include "geohaz/core/config.hpp"
#include "geohaz/core/errors.hpp"
#include "geohaz/core/progress.hpp"
#include "geohaz/dem/config.hpp"
#include "geohaz/dem/run.hpp"

namespace py = pybind11;
using namespace geohaz;
using namespace geohaz::dem;

namespace {

/// The observer of a run from Python: the callback every `every` records (and at the start and end
/// of each test), the progress line when not quiet and not writing files (run_case prints it
/// then), and Ctrl-C.
class PythonDemObserver : public RunObserver {
 public:
  PythonDemObserver(py::object callback, int every, bool progress_line)
      : cb_(std::move(callback)), every_(every), progress_line_(progress_line) {}

  void started(const DemSimulation&, const std::string& test, double expected_time) override {
    test_ = test;
    expected_ = expected_time;
    records_ = 0;
    if (progress_line_) progress_ = std::make_unique<ProgressReporter>("dem-avalanche " + test, expected_time, false);
    call("started", nullptr);
  }
  void recorded(const DemSimulation&, const DemSolver& s, const std::string& phase) override {
    if (progress_) progress_->update(s.time(), s.step_count(), s.discs.size());
    if (!cb_.is_none() && records_ % every_ == 0) {
      call(phase.c_str(), &s);
    } else {
      py::gil_scoped_acquire gil;
      if (PyErr_CheckSignals() != 0) throw py::error_already_set();
    }
    ++records_;
  }
  void finished(const DemSimulation&, const std::string&, const DemSolver& s) override {
    if (progress_) progress_->finish(s.time(), s.step_count(), s.discs.size());
    progress_.reset();
    call("finished", &s);
  }

 private:
  void call(const char* phase, const DemSolver* s) {
    py::gil_scoped_acquire gil;
    if (PyErr_CheckSignals() != 0) throw py::error_already_set();
    if (cb_.is_none()) return;
    py::dict d;
    d["phase"] = phase;
    d["test"] = test_;
    d["expected_time"] = expected_;
    d["time"] = s ? s->time() : 0.0;
    d["step"] = s ? s->step_count() : 0;
    d["discs"] = s ? s->discs.size() : 0;
    cb_(d);
  }
  py::object cb_;
  int every_;
  bool progress_line_;
  std::unique_ptr<ProgressReporter> progress_;
  std::string test_;
  double expected_ = 0.0;
  long long records_ = 0;
};

/// One disc field as an array: scalars (n,), vectors (n, dim).
template <class Tag>
py::array field_array(const DiscStore& discs) {
  using T = typename Tag::type;
  const auto& v = discs.get<Tag>();
  const auto n = static_cast<py::ssize_t>(v.size());
  if constexpr (std::is_arithmetic_v<T>) {
    py::array_t<T> a(n);
    std::copy(v.begin(), v.end(), a.mutable_data());
    return a;
  } else {
    constexpr py::ssize_t dim = T::SizeAtCompileTime;
    py::array_t<typename T::Scalar> a({n, dim});
    auto* p = a.mutable_data();
    for (py::ssize_t i = 0; i < n; ++i)
      for (py::ssize_t d = 0; d < dim; ++d) p[i * dim + d] = v[static_cast<std::size_t>(i)](d);
    return a;
  }
}

/// The final state of the discs: position (n, 2), velocity (n, 2), rotation, angular velocity,
/// radius, mass, id, fragment and bond counts (n,), keyed by the snapshot field names.
py::dict disc_arrays(const DemSolver& s) {
  py::dict d;
  auto add = [&](auto tag) {
    using Tag = decltype(tag);
    d[Tag::label] = field_array<Tag>(s.discs);
  };
  add(Position<2>{});
  add(Velocity<2>{});
  add(Rotation{});
  add(AngularVelocity{});
  add(Radius{});
  add(Mass{});
  add(ParticleId{});
  add(Fragment{});
  add(IntactBonds{});
  add(BrokenBonds{});
  return d;
}

/// geohaz._geohaz.dem_run: see python/geohaz/dem.py for the documented signature.
py::dict dem_run(const std::string& config, const std::vector<std::string>& overrides, const std::string& out,
                 py::object progress, int progress_every, bool quiet, int threads) {
  if (progress_every < 1) throw InputError("must be ≥ 1", "python", "progress_every", std::to_string(progress_every));
  if (!progress.is_none() && !PyCallable_Check(progress.ptr()))
    throw InputError("must be callable (or None)", "python", "progress");
  const int nthreads = setup_threads(threads);
  // The config as the app reads it: the file, then the --set overrides; every check before anything
  // is written.
  ConfigReader cfg = ConfigReader::from_file(config);
  for (const auto& o : overrides) cfg.apply_override(o);
  RunConfig c = read_config(cfg, false);
  cfg.finish();
  c.resolved = cfg.resolved();
  PythonDemObserver obs(progress, progress_every, !quiet && out.empty());
  CaseRun run;
  {
    py::gil_scoped_release nogil;
    // The app's run (run.hpp); with an output folder under the apps' --out policy (app.hpp).
    const auto body = [&] {
      run = run_case(std::move(c), {out, quiet}, &obs);
      return kExitOk;
    };
    if (out.empty())
      body();
    else
      run_in_output_dir(out, "dem-avalanche", {}, body);
  }
  const DemSimulation& sim = *run.simulation;

  py::dict discs;
  if (sim.is_lab())
    for (const LabRun& run : sim.lab_runs()) discs[py::str(run.name)] = disc_arrays(*run.solver);
  else
    discs["avalanche"] = disc_arrays(sim.avalanche_solver());
  py::list tables;
  for (const auto& [stem, text] : csv_tables(sim)) tables.append(py::make_tuple(stem, text));
  py::dict r;
  r["summary"] = py::module_::import("json").attr("loads")(summary_json(sim));
  r["tables_csv"] = tables;
  r["discs"] = discs;
  r["resolved_config"] = sim.config().resolved;
  r["out"] = out.empty() ? py::none() : py::object(py::str(out));
  r["threads"] = nthreads;
  return r;
}

/// The config keys of dem-avalanche with unit, default, range and help (as --help-config).
std::string dem_help_config() {
  ConfigReader d = ConfigReader::describe();
  (void)read_config(d, true);
  return ConfigReader::format_reference(d.reference());
}

}  // namespace

/// Called from PYBIND11_MODULE in module.cpp.
void register_dem(py::module_& m) {
  m.def("dem_run", &dem_run, py::arg("config"), py::arg("overrides"), py::arg("out"), py::arg("progress"),
        py::arg("progress_every"), py::arg("quiet"), py::arg("threads"));
  m.def("dem_help_config", &dem_help_config);
}
