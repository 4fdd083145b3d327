// One ensemble or calibration member of debris-runout (ensemble.hpp, MemberRunner): its case
// from the plan, its run, its record and peaks on disk.
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <ctime>
#include <fstream>
#include <iomanip>
#include <iostream>
#include <map>
#include <memory>
#include <nlohmann/json.hpp>
#include <set>
#include <sstream>

#include "case_support.hpp"
#include "geohaz/core/config.hpp"
#include "geohaz/core/errors.hpp"
#include "geohaz/core/output.hpp"
#include "geohaz/runout/ensemble.hpp"
#include "geohaz/runout/run.hpp"

namespace fs = std::filesystem;

namespace geohaz::runout {

using detail::fmt;
using detail::numeric_case_keys;
using detail::origin;
using detail::resolve_path;

// ---- running a member -----------------------------------------------------------------------

struct MemberRunner::Cache {
  std::string key;
  std::unique_ptr<RunoutInputs> inputs;
};

MemberRunner::MemberRunner(const EnsembleSetup& s) : s_(s), cache_(std::make_unique<Cache>()) {}
MemberRunner::~MemberRunner() = default;

namespace {

/// Makes a member fail on purpose at its first step (ensemble.inject_failure).
class FailingObserver : public RunObserver {
 public:
  explicit FailingObserver(RunObserver* next) : next_(next) {}
  void started(const RunoutSimulation& s) override {
    if (next_) next_->started(s);
  }
  void stepped(const RunoutSimulation&) override {
    throw SimulationError("failure injected on purpose (ensemble.inject_failure) at the first step");
  }

 private:
  RunObserver* next_;
};

std::string inputs_key(const RunConfig& c) {
  std::ostringstream o;
  o << std::setprecision(17) << c.dsm << '|' << c.release.file << '|' << c.release.handoff << '|' << c.release.attribute
    << '|' << c.release.depth << '|' << to_string(c.release.direction) << '|' << c.params.d0 << '|'
    << friction_name(c.params.friction) << '|' << c.processes.zones << '|' << c.processes.forest << '|'
    << c.processes.stem_density << '|' << c.processes.stem_diameter << '|' << c.processes.drag_coefficient << '|'
    << c.processes.erodible << '|' << c.processes.erodible_attribute << '|' << c.processes.erodible_depth << '|'
    << c.processes.hydrograph << '|' << c.processes.inflow_azimuth << '|' << c.processes.inflow_speed;
  for (const auto& z : c.processes.zone_rasters) o << '|' << z;
  for (double v : c.processes.inflow_points) o << '|' << v;
  return o.str();
}

}  // namespace

MemberRecord MemberRunner::run(int i, const fs::path& out, int rank, int threads, RunObserver* observer) {
  const EnsemblePlan& plan = s_.plan;
  const std::vector<double>& values = s_.values.at(static_cast<std::size_t>(i));
  MemberRecord rec;
  rec.index = i;
  rec.values = values;
  rec.rank = rank;
  rec.threads = threads;
  ConfigReader m = ConfigReader::from_file(s_.base_config);
  double factor = 1.0;
  for (std::size_t d = 0; d < plan.parameters.size(); ++d) {
    const std::string& key = plan.parameters[d].key;
    if (key == kThicknessFactorKey) {
      factor = values[d];
    } else if (key == kReleaseAlternativeKey) {
      m.apply_override("release.file=\"" + plan.release_alternatives.at(static_cast<std::size_t>(values[d])) + "\"");
    } else {
      std::ostringstream o;
      o << key << '=' << std::setprecision(17) << values[d];
      m.apply_override(o.str());
    }
  }
  RunConfig c = read_config(m);
  c.output.snapshots = false;
  c.output.pngs = false;
  const std::string key = inputs_key(c);
  if (!cache_->inputs || cache_->key != key) {
    cache_->inputs.reset();
    cache_->inputs = std::make_unique<RunoutInputs>(load_inputs(c));
    cache_->key = key;
  }
  const RunoutInputs* in = cache_->inputs.get();
  std::unique_ptr<RunoutInputs> scaled;
  if (factor != 1.0) {
    scaled = std::make_unique<RunoutInputs>(*in);
    for (double& t : scaled->thickness) t *= factor;
    scaled->volume *= factor;
    in = scaled.get();
  }

  const fs::path dir = member_dir(out, i);
  const fs::path tmp = dir.string() + ".partial." + std::to_string(::getpid());
  fs::remove_all(tmp);
  fs::create_directories(tmp);
  const auto wall0 = std::chrono::steady_clock::now();
  const std::clock_t cpu0 = std::clock();
  const bool inject = std::find(s_.inject_failure.begin(), s_.inject_failure.end(), i) != s_.inject_failure.end();
  try {
    RunoutSimulation sim(*in, c.params, c.output);
    FailingObserver failing(observer);
    sim.run(inject ? &failing : observer);
    const RunoutResult r = sim.result();
    rec.ok = true;
    rec.runout_m = r.path.runout_length;
    rec.drop_height_m = r.path.drop_height;
    rec.reach_m = r.path.reach;
    rec.hl = r.path.fahrboeschung;
    rec.hl_deg = r.path.fahrboeschung_deg;
    rec.release_m3 = in->volume;
    rec.deposited_m3 = r.volumes.deposited;
    rec.mobile_m3 = r.volumes.mobile;
    rec.lost_m3 = r.volumes.lost;
    rec.max_speed = r.max_speed;
    rec.affected_area_m2 = r.affected_area;
    rec.simulated_time_s = r.simulated_time;
    rec.steps = r.steps;
    rec.ended_by = to_string(r.ended);
    rec.unfinished = r.unfinished();
    // Peak maps cropped to the cells reached (nodata cells of the DSM count as not reached).
    const HazardMaps& maps = sim.maps();
    const GridGeometry& g = in->grid();
    const std::vector<double> pressure = maps.max_pressure();
    int c0 = g.nx, c1 = -1, r0 = g.ny, r1 = -1;
    for (int row = 0; row < g.ny; ++row)
      for (int col = 0; col < g.nx; ++col) {
        const std::size_t k = g.index(col, row);
        if (maps.max_depth()[k] > 0.0 && !in->dsm.is_nodata(in->dsm.data[k])) {
          c0 = std::min(c0, col), c1 = std::max(c1, col), r0 = std::min(r0, row), r1 = std::max(r1, row);
        }
      }
    MemberPeaks p;
    p.nx = g.nx, p.ny = g.ny, p.density = sim.parameters().density;
    if (c1 >= 0) {
      p.c0 = c0, p.r0 = r0, p.w = c1 - c0 + 1, p.h = r1 - r0 + 1;
      const std::size_t cells = static_cast<std::size_t>(p.w) * p.h;
      p.depth.resize(cells), p.speed.resize(cells), p.pressure.resize(cells);
      for (int row = 0; row < p.h; ++row)
        for (int col = 0; col < p.w; ++col) {
          const std::size_t k = g.index(c0 + col, r0 + row), m2 = static_cast<std::size_t>(row) * p.w + col;
          const bool nod = in->dsm.is_nodata(in->dsm.data[k]);
          const auto val = [&](double v) { return nod || !std::isfinite(v) ? 0.0 : v; };
          p.depth[m2] = val(maps.max_depth()[k]);
          p.speed[m2] = val(maps.max_speed()[k]);
          p.pressure[m2] = val(pressure[k]);
        }
    }
    write_member_peaks(tmp / "peaks.bin", p);
    if (hook_) hook_(sim, rec, tmp);
  } catch (const SimulationError& e) {
    rec.ok = false;
    rec.diagnosis = std::string("simulation failed: ") + e.what();
  } catch (const InputError& e) {
    rec.ok = false;
    rec.diagnosis = std::string("member input rejected: ") + e.what();
  } catch (...) {  // stopped from outside (an observer's Cancel): no folder for this member
    std::error_code ec;
    fs::remove_all(tmp, ec);
    throw;
  }
  rec.wall_time_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - wall0).count();
  rec.cpu_time_s = static_cast<double>(std::clock() - cpu0) / CLOCKS_PER_SEC;
  write_text_file(tmp / "member.json", member_json(rec, plan) + "\n");
  // Publish atomically: a folder members/<i> exists only complete.
  std::error_code ec;
  fs::rename(tmp, dir, ec);
  if (ec) {
    // Another process finished the same member first (a resumed run next to a live one): keep theirs.
    fs::remove_all(tmp);
  }
  return rec;
}

}  // namespace geohaz::runout
