// Tests of the in-process run (libs/sph/run.hpp, label: regression): the observer sees the phases
// and every main-phase step in order, a run without an output folder writes nothing, the summary
// and the tables of the object are those write_outputs writes, and Table writes CSV as the app
// always has. A tiny column collapse (2 cm spacing) keeps each run well under a second.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>
#include <vector>

#include "geohaz/core/config.hpp"
#include "geohaz/core/errors.hpp"
#include "geohaz/sph/config.hpp"
#include "geohaz/sph/run.hpp"

namespace {

namespace fs = std::filesystem;
using namespace geohaz;
using namespace geohaz::sph;

/// The column-collapse example, shrunk: 0.01 s of a 2 cm-spacing column, rows every 2 ms.
RunConfig tiny_column(const std::vector<std::string>& more = {}) {
  ConfigReader r = ConfigReader::from_file(fs::path(GEOHAZ_SOURCE_DIR) / "data/sph/column_collapse.toml");
  for (const char* o : {"run.end_time=0.01", "numerics.spacing=0.02", "run.output_interval=0.002"}) r.apply_override(o);
  for (const auto& o : more) r.apply_override(o);
  RunConfig c = read_config(r, false);
  r.finish();
  c.resolved_config = r.resolved();
  validate(c);
  return c;
}

/// Records what it is told, in order.
struct Recorder : RunObserver {
  std::vector<std::string> events;
  std::vector<double> times;
  std::int64_t steps = 0, before = 0;
  void progress(const SphSimulation&, const RunProgress& p) override {
    events.push_back(std::string(p.phase) + (p.done ? " done" : ""));
  }
  void started(const SphSimulation& s) override {
    events.emplace_back("started");
    times.push_back(s.time());
  }
  void before_step(const SphSimulation&) override { ++before; }
  void stepped(const SphSimulation& s) override {
    ++steps;
    times.push_back(s.time());
  }
  void finished(const SphSimulation&) override { events.emplace_back("finished"); }
};

std::string without_wall_time(const std::string& json) {
  auto j = nlohmann::json::parse(json);
  j.erase("wall_time_s");
  return j.dump();
}

TEST(SphRun, ObserverSeesThePhasesAndEveryMainPhaseStepInOrder) {
  const RunConfig c = tiny_column({"geostatic.enabled=true", "geostatic.duration=0.005"});
  SphSimulation sim(c);
  Recorder rec;
  sim.run(&rec);
  ASSERT_GE(rec.events.size(), 4u);
  EXPECT_EQ(rec.events.front(), "geostatic");
  EXPECT_EQ(rec.events[rec.events.size() - 3], "geostatic done");
  EXPECT_EQ(rec.events[rec.events.size() - 2], "started");
  EXPECT_EQ(rec.events.back(), "finished");
  const auto summary = nlohmann::json::parse(sim.summary_json());
  const std::int64_t geostatic_steps = summary["geostatic"]["steps"];
  EXPECT_EQ(rec.steps, sim.step_count() - geostatic_steps);  // the solver counts the geostatic steps too
  EXPECT_EQ(rec.before, rec.steps);
  for (std::size_t k = 1; k < rec.times.size(); ++k) EXPECT_GT(rec.times[k], rec.times[k - 1]);
  EXPECT_GE(sim.time(), c.end_time - 1e-12);
  // Rows every 2 ms from 0 and a final one: 0, 2, 4, 6, 8 ms (the 10 ms row is the final one).
  const auto tables = sim.tables();
  ASSERT_EQ(tables.front().name, "series");
  EXPECT_EQ(tables.front().table.rows.size(), 6u);
}

TEST(SphRun, WithoutAnOutputFolderNothingIsWrittenAndTheOutputsMatchTheObject) {
  const RunConfig c = tiny_column();
  const fs::path here = fs::current_path();
  const fs::path dir = fs::path(GEOHAZ_BINARY_DIR) / "tests/sph/run_test";
  fs::remove_all(dir);
  fs::create_directories(dir / "cwd");
  fs::current_path(dir / "cwd");
  SphSimulation sim(c);
  run_with_outputs(sim, "", true);
  EXPECT_TRUE(fs::is_empty(dir / "cwd"));
  fs::current_path(here);
  // The files write_outputs makes hold the object's summary and tables.
  fs::create_directories(dir / "out");
  write_outputs(sim, dir / "out");
  std::ifstream in(dir / "out/summary.json");
  std::stringstream text;
  text << in.rdbuf();
  EXPECT_EQ(without_wall_time(text.str()), without_wall_time(sim.summary_json()));
  for (const auto& [name, table] : sim.tables()) {
    std::ifstream f(dir / "out" / (name + ".csv"));
    std::stringstream csv;
    csv << f.rdbuf();
    EXPECT_EQ(csv.str(), table.csv()) << name;
  }
  const ParticleFields p = sim.particles();
  EXPECT_EQ(p.count, sim.particle_count());
  EXPECT_EQ(p.position.size(), 2 * p.count);
  EXPECT_EQ(p.stress.size(), 9 * p.count);
  fs::remove_all(dir);
}

TEST(SphRun, TableWritesIntegerColumnsAsIntegersAndTheRestWithNineDigits) {
  const Table t{{"trial", "factor", "failed"}, {{0, 1.0 / 3.0, 1}, {12, 2.5e-7, 0}}, {true, false, true}};
  EXPECT_EQ(t.csv(), "trial,factor,failed\n0,0.333333333,1\n12,2.5e-07,0\n");
  EXPECT_EQ((Table{{"x_m"}, {}, {}}).csv(), "x_m\n");
}

TEST(SphRun, AnObserverThatThrowsStopsTheRun) {
  struct Stop : RunObserver {
    void stepped(const SphSimulation&) override { throw std::runtime_error("stop"); }
  } stop;
  const RunConfig c = tiny_column();
  SphSimulation sim(c);
  EXPECT_THROW(sim.run(&stop), std::runtime_error);
  EXPECT_TRUE(sim.main_phase_started());
  EXPECT_EQ(sim.tables().front().table.rows.size(), 1u);  // the row at t = 0, before the first step
}

}  // namespace
