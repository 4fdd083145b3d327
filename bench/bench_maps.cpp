// bench_maps: the time to draw the maps of a demo-size debris-runout run and to write the report
// page (issue #33, "Speed": every map and the report of the demo under 10 s on 2 cores).
//
//   bench_maps [RESULTS_DIR] [--threads N] [--duration S] [--repeat K]
//
// 1. Runs the demo's step 3 (data/runout/alr_processes.toml with --h0 0.5: the Alplehner DTM, 5 m
//    cells, the same map extent class as step 2) in-process; not timed.
// 2. Writes its outputs K times (default 3) with output.png = false and K times with true into a
//    temporary folder; the smallest difference is the drawing of its maps (peak depth, deposit,
//    speed, pressure, arrival time, intensity, erosion) and of profile.png, everything else being
//    the same work. The demo holds two such runs (steps 2 and 3), so the demo's run-out maps take
//    about twice that.
// 3. Writes the report page (geohaz::report::write_report, as geohaz-report does) K times on
//    RESULTS_DIR (default: results/demo when it exists, else the folder of step 2) and prints the
//    smallest time.
// Prints the figures; asserts nothing (docs/performance.md "Maps and the report").
#include <omp.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <functional>
#include <iostream>
#include <limits>
#include <string>

#include "geohaz/core/config.hpp"
#include "geohaz/core/output.hpp"
#include "geohaz/report/report.hpp"
#include "geohaz/runout/run.hpp"

namespace fs = std::filesystem;
using namespace geohaz;

namespace {

double seconds(const std::function<void()>& f) {
  const auto t0 = std::chrono::steady_clock::now();
  f();
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

double smallest(int repeat, const std::function<double()>& f) {
  double best = std::numeric_limits<double>::infinity();
  for (int k = 0; k < repeat; ++k) best = std::min(best, f());
  return best;
}

}  // namespace

int main(int argc, char** argv) {
  fs::path results;
  int threads = 2, repeat = 3;
  double duration = 0.0;  // 0: the config's (600 s)
  for (int k = 1; k < argc; ++k) {
    const std::string a = argv[k];
    if (a == "--threads" && k + 1 < argc)
      threads = std::atoi(argv[++k]);
    else if (a == "--duration" && k + 1 < argc)
      duration = std::atof(argv[++k]);
    else if (a == "--repeat" && k + 1 < argc)
      repeat = std::max(1, std::atoi(argv[++k]));
    else if (!a.empty() && a[0] != '-')
      results = a;
    else {
      std::cerr << "usage: bench_maps [RESULTS_DIR] [--threads N] [--duration S] [--repeat K]\n";
      return 2;
    }
  }
  omp_set_num_threads(threads);
  const fs::path src = GEOHAZ_SOURCE_DIR;
  if (results.empty() && fs::exists(src / "results/demo/report.html")) results = src / "results/demo";

  // 1. The run (not timed).
  ConfigReader cfg = ConfigReader::from_file(src / "data/runout/alr_processes.toml");
  cfg.apply_override("model.h0=0.5");
  if (duration > 0.0) cfg.apply_override("run.duration=" + std::to_string(duration));
  runout::RunConfig c = runout::read_config(cfg);
  cfg.finish();
  c.resolved_config = cfg.resolved();
  c.output.snapshots = false;
  const runout::RunoutInputs in = runout::load_inputs(c);
  runout::RunoutSimulation sim(in, c.params, c.output);
  const double run_s = seconds([&] { sim.run(nullptr); });

  // 2. Its outputs without and with the maps.
  const fs::path tmp = fs::temp_directory_path() / ("geohaz_bench_maps_" + std::to_string(::getpid()));
  const fs::path run_dir = tmp / "runs" / "3-runout-processes";
  fs::create_directories(run_dir);
  const auto outputs = [&](bool pngs) {
    runout::RunConfig d = c;
    d.output.pngs = pngs;
    for (const auto& e : fs::directory_iterator(run_dir)) fs::remove_all(e.path());
    fs::create_directories(run_dir);
    write_text_file(run_dir / "config.resolved.toml", c.resolved_config);
    return seconds([&] { runout::write_outputs(d, sim, run_dir, threads); });
  };
  const double without = smallest(repeat, [&] { return outputs(false); });
  const double with = smallest(repeat, [&] { return outputs(true); });
  int maps = 0;
  for (const auto& e : fs::directory_iterator(run_dir)) maps += e.path().extension() == ".png";

  // 3. The report page.
  if (results.empty()) results = tmp / "runs";
  const double report_s =
      smallest(repeat, [&] { return seconds([&] { (void)report::write_report(results, "bench_maps"); }); });

  std::printf("bench_maps: %d threads, the Alplehner run (demo step 3, %.0f s simulated) ran in %.1f s\n", threads,
              sim.result().simulated_time, run_s);
  std::printf("  outputs without maps %.2f s, with maps %.2f s: %d pictures of one run drawn in %.2f s\n", without,
              with, maps, with - without);
  std::printf("  report page of %s: %.2f s\n", results.string().c_str(), report_s);
  std::printf("  the demo's maps (two run-out runs) and report: about %.1f s (target: under 10 s)\n",
              2.0 * (with - without) + report_s);
  std::error_code ec;
  fs::remove_all(tmp, ec);
  return 0;
}
