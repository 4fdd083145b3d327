// The compiled part of the Python package `geohaz` (python/geohaz/): the exceptions and an
// in-process debris-runout run (the in-process sph-slope run is in sph.cpp). The Python side (python/geohaz/runout.py)
// turns keyword arguments into the same config overrides as the app's flags; this file reads the config with the
// model's own key declarations (runout::read_config), runs through libs/runout/run.hpp, and hands the maps, particles,
// series and summary back as NumPy arrays and dicts.
//
// The GIL is released for the whole run; it is taken back only to call a progress callback (when
// one is given) and, every few hundred steps, to let Ctrl-C interrupt the run.
#include <omp.h>
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <limits>
#include <memory>
#include <optional>
#include <sstream>
#include <string>
#include <type_traits>
#include <vector>

#include "geohaz/core/app.hpp"
#include "geohaz/core/config.hpp"
#include "geohaz/core/errors.hpp"
#include "geohaz/core/raster.hpp"
#include "geohaz/runout/calibrate.hpp"
#include "geohaz/runout/ensemble.hpp"
#include "geohaz/runout/run.hpp"

namespace py = pybind11;
namespace fs = std::filesystem;
using namespace geohaz;
using namespace geohaz::runout;

namespace geohaz::python {
/// The sph-slope functions (python/src/sph.cpp).
void add_sph(py::module_& m);
/// The report page (python/src/report.cpp).
void add_report(py::module_& m);
}  // namespace geohaz::python

namespace {

// The Python exception classes, created in PYBIND11_MODULE.
PyObject* g_input_error = nullptr;
PyObject* g_simulation_error = nullptr;
PyObject* g_io_error = nullptr;

/// Raise `type` with message `what` and attributes (name → value) on the exception object.
void raise_with(PyObject* type, const char* what, std::initializer_list<std::pair<const char*, std::string>> attrs) {
  py::object exc = py::reinterpret_steal<py::object>(PyObject_CallFunction(type, "s", what));
  if (!exc) return;  // the call set a Python error already
  for (const auto& [name, value] : attrs) exc.attr(name) = value;
  PyErr_SetObject(type, exc.ptr());
}

/// A 2D (ny, nx) float64 array of a map on the DSM grid; NaN where the DSM has no data (and where
/// the map itself holds NaN, e.g. cells the flow never reached in arrival_time).
py::array_t<double> grid_array(const Raster& dsm, const std::vector<double>& v) {
  py::array_t<double> a({static_cast<py::ssize_t>(dsm.ny), static_cast<py::ssize_t>(dsm.nx)});
  double* p = a.mutable_data();
  const double nan = std::numeric_limits<double>::quiet_NaN();
  for (std::size_t k = 0; k < v.size(); ++k) p[k] = dsm.is_nodata(dsm.data[k]) ? nan : v[k];
  return a;
}

/// Every field of a particle store as NumPy arrays: scalars (n,), vectors (n, dim).
template <class Store>
py::dict particle_arrays(const Store& store) {
  py::dict out;
  const auto n = static_cast<py::ssize_t>(store.size());
  store.for_each_field([&](auto tag, const auto& v) {
    using Tag = decltype(tag);
    using T = typename Tag::type;
    if constexpr (std::is_arithmetic_v<T>) {
      py::array_t<T> a(n);
      std::copy(v.begin(), v.end(), a.mutable_data());
      out[Tag::label] = a;
    } else {  // a fixed-size Eigen vector
      constexpr py::ssize_t dim = T::SizeAtCompileTime;
      py::array_t<typename T::Scalar> a({n, dim});
      auto* p = a.mutable_data();
      for (py::ssize_t i = 0; i < n; ++i)
        for (py::ssize_t d = 0; d < dim; ++d) p[i * dim + d] = v[static_cast<std::size_t>(i)](d);
      out[Tag::label] = a;
    }
  });
  return out;
}

/// The columns of series.csv as arrays.
py::dict series_arrays(const std::vector<SeriesRow>& rows) {
  const auto n = static_cast<py::ssize_t>(rows.size());
  auto column = [&](auto get) {
    py::array_t<double> a(n);
    double* p = a.mutable_data();
    for (py::ssize_t i = 0; i < n; ++i) p[i] = get(rows[static_cast<std::size_t>(i)]);
    return a;
  };
  py::dict d;
  d["time_s"] = column([](const SeriesRow& r) { return r.time; });
  d["step"] = column([](const SeriesRow& r) { return static_cast<double>(r.step); });
  d["particles"] = column([](const SeriesRow& r) { return static_cast<double>(r.particles); });
  d["front_x_m"] = column([](const SeriesRow& r) { return r.front.x(); });
  d["front_y_m"] = column([](const SeriesRow& r) { return r.front.y(); });
  d["front_travel_m"] = column([](const SeriesRow& r) { return r.front_travel; });
  d["front_drop_m"] = column([](const SeriesRow& r) { return r.front_drop; });
  d["mean_speed_m_per_s"] = column([](const SeriesRow& r) { return r.mean_speed; });
  d["max_speed_m_per_s"] = column([](const SeriesRow& r) { return r.max_speed; });
  d["mobile_volume_m3"] = column([](const SeriesRow& r) { return r.volumes.mobile; });
  d["deposited_volume_m3"] = column([](const SeriesRow& r) { return r.volumes.deposited; });
  d["lost_volume_m3"] = column([](const SeriesRow& r) { return r.volumes.lost; });
  d["entrained_volume_m3"] = column([](const SeriesRow& r) { return r.volumes.entrained; });
  d["injected_volume_m3"] = column([](const SeriesRow& r) { return r.volumes.injected; });
  return d;
}

/// The key figures: summary.json's text, parsed by Python's json (the same numbers as the app's).
py::object summary_dict(const RunoutSimulation& sim, const RunConfig& c, int threads) {
  return py::module_::import("json").attr("loads")(summary_json(c, sim, threads));
}

/// progress_every ≥ 1, progress callable or None (InputError naming the argument).
void check_progress(const py::object& progress, int progress_every) {
  if (progress_every < 1) throw InputError("must be ≥ 1", "python", "progress_every", std::to_string(progress_every));
  if (!progress.is_none() && !PyCallable_Check(progress.ptr()))
    throw InputError("must be callable (or None)", "python", "progress");
}

/// The observer of a run from Python: the progress callback (every `every` steps, and at start
/// and end) and Ctrl-C. The snapshots and the progress line are run_case's (run.hpp).
class PythonObserver : public RunObserver {
 public:
  PythonObserver(py::object callback, int every, double duration) : cb_(std::move(callback)), every_(every) {
    duration_ = duration;
  }
  /// The member this run is of an ensemble or calibration (-1: a lone run), members finished so
  /// far and planned: passed to the callback as "member", "members_done", "members_planned".
  int member = -1, members_done = 0, members_planned = 0;

  void started(const RunoutSimulation& sim) override { call("started", sim); }
  void stepped(const RunoutSimulation& sim) override {
    const std::int64_t k = sim.solver().step_count();
    if (!cb_.is_none() && k % every_ == 0) {
      call("running", sim);
    } else if (k % 256 == 0) {  // let Ctrl-C through without a callback
      py::gil_scoped_acquire gil;
      if (PyErr_CheckSignals() != 0) throw py::error_already_set();
    }
  }
  void finished(const RunoutSimulation& sim) override { call("finished", sim); }

 private:
  void call(const char* phase, const RunoutSimulation& sim) {
    py::gil_scoped_acquire gil;
    if (PyErr_CheckSignals() != 0) throw py::error_already_set();
    if (cb_.is_none()) return;
    const auto& s = sim.solver();
    py::dict d;
    d["phase"] = phase;
    d["time"] = s.time();
    d["duration"] = member >= 0 ? sim.parameters().duration : duration_;
    if (member >= 0) {
      d["member"] = member;
      d["members_done"] = members_done;
      d["members_planned"] = members_planned;
    }
    d["step"] = s.step_count();
    d["particles"] = s.particles().size();
    d["mobile_volume"] = s.budget().mobile;
    cb_(d);
  }
  py::object cb_;
  int every_;
  double duration_ = 0.0;
};

/// geohaz._geohaz.runout_run: see python/geohaz/runout.py for the documented signature.
py::dict runout_run(const std::string& config, const std::vector<std::string>& overrides, const std::string& out,
                    py::object progress, int progress_every, bool quiet, int threads, bool particles) {
  check_progress(progress, progress_every);
  const int nthreads = setup_threads(threads);
  // Config: the file, then the overrides in the order of the app (--set, direct flags, inputs).
  ConfigReader cfg =
      config.empty() ? ConfigReader::from_string("", "<no config file>") : ConfigReader::from_file(config);
  for (const auto& o : overrides) cfg.apply_override(o);
  RunConfig c = read_config(cfg);
  cfg.finish();
  c.resolved_config = cfg.resolved();

  PythonObserver obs(progress, progress_every, c.params.duration);
  CaseRun run;
  {
    py::gil_scoped_release nogil;
    // The app's run (run.hpp): every input checked before anything is written; outputs, when asked
    // for, in a folder under the apps' --out policy (app.hpp).
    const RunOptions options{out, quiet, nthreads};
    if (out.empty())
      run = run_case(c, options, &obs);
    else
      run_in_output_dir(out, "debris-runout",
                        {c.dsm, c.release.file, c.release.handoff, c.processes.hydrograph, c.processes.erodible}, [&] {
                          run = run_case(c, options, &obs);
                          return 0;
                        });
  }
  const RunoutInputs* in = run.inputs.get();
  const RunoutSimulation* sim = run.simulation.get();

  const Raster& dsm = in->dsm;
  const HazardMaps& m = sim->maps();
  py::dict maps;
  maps["max_depth"] = grid_array(dsm, m.max_depth());
  maps["max_speed"] = grid_array(dsm, m.max_speed());
  maps["max_pressure"] = grid_array(dsm, m.max_pressure());
  maps["deposit"] = grid_array(dsm, sim->deposit());
  maps["mobile_at_end"] = grid_array(dsm, sim->mobile_at_end());
  maps["arrival_time"] = grid_array(dsm, m.arrival_time());
  maps["max_momentum"] = grid_array(dsm, m.max_momentum());
  maps["intensity"] = grid_array(dsm, intensity_classes(m, c.output.intensity));
  if (!sim->solver().eroded_depth().empty()) maps["erosion_depth"] = grid_array(dsm, sim->solver().eroded_depth());
  std::vector<double> z(dsm.data);
  for (double& v : z)
    if (dsm.is_nodata(v)) v = std::numeric_limits<double>::quiet_NaN();

  py::dict r;
  r["summary"] = summary_dict(*sim, c, nthreads);
  r["maps"] = maps;
  r["dsm"] = grid_array(dsm, z);
  r["release_thickness"] = grid_array(dsm, in->thickness);
  r["geotransform"] = py::make_tuple(dsm.geotransform[0], dsm.geotransform[1], dsm.geotransform[2], dsm.geotransform[3],
                                     dsm.geotransform[4], dsm.geotransform[5]);
  r["crs_wkt"] = dsm.crs_wkt;
  r["series"] = series_arrays(sim->series());
  r["particles"] = particles ? py::object(particle_arrays(sim->solver().particles())) : py::none();
  r["resolved_config"] = c.resolved_config;
  r["out"] = out.empty() ? py::none() : py::object(py::str(out));
  r["threads"] = nthreads;
  return r;
}

/// The config keys of debris-runout with unit, default, range and help (as --help-config).
std::string runout_help_config() {
  ConfigReader d = ConfigReader::describe();
  read_config(d);
  return ConfigReader::format_reference(d.reference());
}

/// The observer of an ensemble or a calibration from Python: each member's steps go to the
/// progress callback as for a lone run (with the member's index and the count), and after each
/// member {"phase": "member_finished", "member", "members_done", "members_planned", "ok"}. The
/// callback raising (Cancel) or Ctrl-C stops the run (ensemble.hpp MemberObserver).
class PythonMemberObserver : public MemberObserver {
 public:
  PythonMemberObserver(py::object callback, int every) : steps_(callback, every, 0.0), cb_(std::move(callback)) {}
  RunObserver* member_started(int i, int done, int planned) override {
    steps_.member = i, steps_.members_done = done, steps_.members_planned = planned;
    return &steps_;
  }
  void member_finished(const MemberRecord& rec, int done, int planned) override {
    py::gil_scoped_acquire gil;
    if (PyErr_CheckSignals() != 0) throw py::error_already_set();
    if (cb_.is_none()) return;
    py::dict d;
    d["phase"] = "member_finished";
    d["member"] = rec.index;
    d["members_done"] = done;
    d["members_planned"] = planned;
    d["ok"] = rec.ok;
    cb_(d);
  }

 private:
  PythonObserver steps_;
  py::object cb_;
};

/// An ensemble (geohaz-ensemble's config) run in this process on one rank: members and products in
/// `out` (resumed when it holds the same ensemble); returns the text of its summary.json.
std::string ensemble_run(const std::string& config, const std::vector<std::string>& overrides, const std::string& out,
                         int threads, bool quiet, py::object progress, int progress_every) {
  check_progress(progress, progress_every);
  ConfigReader cfg = ConfigReader::from_file(config);
  for (const auto& o : overrides) cfg.apply_override(o);
  const EnsembleSetup s = read_ensemble(cfg);
  const int nthreads = threads > 0 ? setup_threads(threads) : omp_get_max_threads();
  PythonMemberObserver obs(std::move(progress), progress_every);
  {
    py::gil_scoped_release release;
    run_ensemble_serial(s, out, nthreads, quiet, &obs);
  }
  std::ifstream in(fs::path(out) / "summary.json");
  std::ostringstream text;
  text << in.rdbuf();
  return text.str();
}

/// A calibration (geohaz-calibrate's config) run in this process on one rank: members and outputs in
/// `out` (resumed when it holds the same calibration); returns the text of its summary.json.
std::string calibrate_run(const std::string& config, const std::vector<std::string>& overrides, const std::string& out,
                          int threads, bool quiet, py::object progress, int progress_every) {
  check_progress(progress, progress_every);
  ConfigReader cfg = ConfigReader::from_file(config);
  for (const auto& o : overrides) cfg.apply_override(o);
  CalibrationSetup s = read_calibration(cfg);
  const int nthreads = threads > 0 ? setup_threads(threads) : omp_get_max_threads();
  PythonMemberObserver obs(std::move(progress), progress_every);
  {
    py::gil_scoped_release release;
    run_calibration_serial(s, out, nthreads, quiet, &obs);
  }
  std::ifstream in(fs::path(out) / "summary.json");
  std::ostringstream text;
  text << in.rdbuf();
  return text.str();
}

/// The config keys of geohaz-calibrate (as its --help-config).
std::string calibrate_help_config() {
  ConfigReader d = ConfigReader::describe();
  describe_calibration(d);
  return ConfigReader::format_reference(d.reference());
}

/// The config keys of geohaz-ensemble (as its --help-config).
std::string ensemble_help_config() {
  ConfigReader d = ConfigReader::describe();
  describe_ensemble(d);
  return ConfigReader::format_reference(d.reference());
}

/// Band 1 of a GDAL raster (any CRS) through the core reader the apps use: values (ny, nx) float64
/// with NaN at nodata, the grid, CRS, nodata value, and the band's unit and description as written
/// by write_geotiff. geohaz.read_run builds on it.
py::dict read_raster_dict(const std::string& path) {
  Raster r;
  {
    py::gil_scoped_release release;
    r = read_raster(path, CrsPolicy::Any);
  }
  py::dict d;
  d["values"] = grid_array(r, r.data);
  d["geotransform"] = py::make_tuple(r.geotransform[0], r.geotransform[1], r.geotransform[2], r.geotransform[3],
                                     r.geotransform[4], r.geotransform[5]);
  d["crs_wkt"] = r.crs_wkt;
  d["nodata"] = r.nodata ? py::object(py::float_(*r.nodata)) : py::object(py::none());
  d["unit"] = r.unit;
  d["description"] = r.description;
  return d;
}

}  // namespace

void register_dem(py::module_& m);  // python/src/dem.cpp: geohaz.dem in-process

PYBIND11_MODULE(_geohaz, m) {
  m.doc() = "geohaz: compiled core of the Python package (use the geohaz package, not this module)";
  m.attr("__version__") = GEOHAZ_VERSION;

  // Exceptions: InputError subclasses ValueError (bad input), IoError subclasses OSError,
  // SimulationError subclasses RuntimeError; all three carry the message the apps print after
  // "<app>: input error: " etc.
  static py::exception<InputError> input_error(m, "InputError", PyExc_ValueError);
  static py::exception<SimulationError> simulation_error(m, "SimulationError", PyExc_RuntimeError);
  static py::exception<IoError> io_error(m, "IoError", PyExc_OSError);
  g_input_error = input_error.ptr();
  g_simulation_error = simulation_error.ptr();
  g_io_error = io_error.ptr();
  py::register_exception_translator([](std::exception_ptr p) {
    try {
      if (p) std::rethrow_exception(p);
    } catch (const InputError& e) {
      raise_with(g_input_error, e.what(),
                 {{"file", e.file()}, {"key", e.key()}, {"value", e.value()}, {"reason", e.reason()}});
    } catch (const SimulationError& e) {
      raise_with(g_simulation_error, e.what(), {});
    } catch (const IoError& e) {
      raise_with(g_io_error, e.what(), {{"file", e.file()}});
    }
  });

  m.def("runout_run", &runout_run, py::arg("config"), py::arg("overrides"), py::arg("out"), py::arg("progress"),
        py::arg("progress_every"), py::arg("quiet"), py::arg("threads"), py::arg("particles"));
  m.def("runout_help_config", &runout_help_config);
  m.def("ensemble_run", &ensemble_run, py::arg("config"), py::arg("overrides"), py::arg("out"), py::arg("threads"),
        py::arg("quiet"), py::arg("progress") = py::none(), py::arg("progress_every") = 1);
  m.def("ensemble_help_config", &ensemble_help_config);
  m.def("calibrate_run", &calibrate_run, py::arg("config"), py::arg("overrides"), py::arg("out"), py::arg("threads"),
        py::arg("quiet"), py::arg("progress") = py::none(), py::arg("progress_every") = 1);
  m.def("calibrate_help_config", &calibrate_help_config);
  m.def("read_raster", &read_raster_dict, py::arg("path"));
  geohaz::python::add_sph(m);
  register_dem(m);
  geohaz::python::add_report(m);
}
