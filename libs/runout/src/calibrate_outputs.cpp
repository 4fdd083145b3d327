// What a calibration writes (calibrate.hpp, docs/calibration.md): the best set as a ready-to-run
// debris-runout config, the member and acceptable tables and plot, the Morris ranking, the
// comparison map and the thalweg profile, the summary.
#include <toml++/toml.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <iomanip>
#include <iostream>
#include <map>
#include <nlohmann/json.hpp>
#include <sstream>

#include "case_support.hpp"
#include "geohaz/core/config.hpp"
#include "geohaz/core/errors.hpp"
#include "geohaz/core/output.hpp"
#include "geohaz/core/raster.hpp"
#include "geohaz/core/svg.hpp"
#include "geohaz/runout/calibrate.hpp"
#include "geohaz/runout/profile.hpp"
#include "geohaz/runout/run.hpp"

namespace fs = std::filesystem;

namespace geohaz::runout {

using detail::fmt;
using detail::numeric_case_keys;
using detail::origin;
using detail::resolve_path;

namespace {

std::string csv_text(std::string s) {
  std::replace(s.begin(), s.end(), '"', '\'');
  std::replace(s.begin(), s.end(), '\n', ' ');
  return "\"" + s + "\"";
}

void member_table(const fs::path& path, const CalibrationSetup& s, const std::vector<const Evaluation*>& rows) {
  AtomicTextFile csv(path);
  csv << "member,stage,batch,status";
  for (const auto& p : s.parameters) csv << ',' << p.key;
  csv << ",score,tversky,tp_m2,fp_m2,fn_m2,runout_s_m,runout_diff_m,depth_rmse_m,volume_m3,term_footprint,term_"
         "runout,term_depth,term_volume,diagnosis\n";
  csv.stream() << std::setprecision(17);
  for (const Evaluation* e : rows) {
    const Misfit& m = e->misfit;
    csv << e->index << ',' << e->stage << ',' << e->batch << ',' << (e->ok ? "ok" : "failed");
    for (double v : e->values) csv << ',' << v;
    csv << ',' << m.score << ',' << m.tversky << ',' << m.tp << ',' << m.fp << ',' << m.fn << ',' << m.runout_s << ','
        << m.runout_diff << ',' << m.depth_rmse << ',' << m.volume << ',' << m.term_footprint << ',' << m.term_runout
        << ',' << m.term_depth << ',' << m.term_volume << ',' << csv_text(e->diagnosis) << '\n';
  }
  csv.commit();
}

/// Score against each parameter (top row) and every pair of parameters (below): all members in grey,
/// the acceptable ones coloured by score (dark = best), the best as a red ring.
void write_acceptable_svg(const fs::path& path, const CalibrationSetup& s, const CalibrationResult& r, double j_best,
                          double tol) {
  const std::size_t P = s.parameters.size();
  std::vector<std::pair<int, int>> panels;  // (x, y); y = −1: the score
  for (std::size_t a = 0; a < P; ++a) panels.emplace_back(static_cast<int>(a), -1);
  for (std::size_t a = 0; a < P; ++a)
    for (std::size_t b = a + 1; b < P && panels.size() < 12; ++b)
      panels.emplace_back(static_cast<int>(a), static_cast<int>(b));
  const int cols = static_cast<int>(std::min<std::size_t>(3, panels.size()));
  const int rows = static_cast<int>((panels.size() + cols - 1) / cols);
  const double pw = 300, ph = 240, ml = 70, mt = 40, gap = 90;
  const double W = cols * (pw + gap) + ml, H = rows * (ph + gap) + mt + 40;
  double smax = 0.0;
  for (const auto& e : r.evaluations)
    if (e.ok) smax = std::max(smax, e.misfit.score);
  SvgDocument o(W, H, {{"font-family", "sans-serif"}, {"font-size", 12}});
  o.background("white");
  o.text(W / 2, 22,
         "Members (grey) and the acceptable set (score within " + fmt(tol) + " of the best " + fmt(j_best, 4) +
             ", coloured; red ring: best)",
         {{"text-anchor", "middle"}, {"font-size", 14}})
      .newline();
  for (std::size_t k = 0; k < panels.size(); ++k) {
    const auto [a, b] = panels[k];
    const double x0 = ml + static_cast<double>(k % cols) * (pw + gap),
                 y0 = mt + static_cast<double>(k / cols) * (ph + gap);
    const auto& pa = s.parameters[static_cast<std::size_t>(a)];
    const auto X = [&](double v) { return x0 + std::clamp(pa.unit(v), 0.0, 1.0) * pw; };
    const auto Y = [&](const Evaluation& e) {
      if (b < 0) return y0 + ph * (1.0 - std::clamp(e.misfit.score / (smax > 0 ? smax : 1.0), 0.0, 1.0));
      return y0 + ph * (1.0 - std::clamp(
                                  s.parameters[static_cast<std::size_t>(b)].unit(e.values[static_cast<std::size_t>(b)]),
                                  0.0, 1.0));
    };
    o.rect(x0, y0, pw, ph, {{"fill", "none"}, {"stroke", "black"}}).newline();
    for (const auto& e : r.evaluations) {
      if (!e.ok) {
        o.text(X(e.values[static_cast<std::size_t>(a)]), y0 + ph - 2, "x",
               {{"fill", "#d62728"}, {"text-anchor", "middle"}})
            .newline();
        continue;
      }
      const bool acc = e.misfit.score <= j_best + tol;
      std::string fill = "#bbbbbb";
      if (acc) {
        const double t = tol > 0 ? (e.misfit.score - j_best) / tol : 0.0;
        const auto c = ramp_colour(ColourRamp::Viridis, std::clamp(t, 0.0, 1.0));
        std::ostringstream h;
        h << "rgb(" << int(c[0]) << ',' << int(c[1]) << ',' << int(c[2]) << ')';
        fill = h.str();
      }
      o.element("circle",
                {{"cx", X(e.values[static_cast<std::size_t>(a)])}, {"cy", Y(e)}, {"r", acc ? 4 : 3}, {"fill", fill}})
          .newline();
    }
    if (r.best >= 0) {
      const Evaluation& e = r.evaluations[static_cast<std::size_t>(r.best)];
      o.element("circle", {{"cx", X(e.values[static_cast<std::size_t>(a)])},
                           {"cy", Y(e)},
                           {"r", 7},
                           {"fill", "none"},
                           {"stroke", "#d62728"},
                           {"stroke-width", 2}})
          .newline();
    }
    for (int t = 0; t <= 4; ++t) {
      const double v = pa.value(t / 4.0);
      o.text(x0 + t * pw / 4, y0 + ph + 16, fmt(v, 3), {{"text-anchor", "middle"}}).newline();
      const double yv = b < 0 ? smax * t / 4.0 : s.parameters[static_cast<std::size_t>(b)].value(t / 4.0);
      o.text(x0 - 6, y0 + ph * (1 - t / 4.0) + 4, fmt(yv, 3), {{"text-anchor", "end"}}).newline();
    }
    o.text(x0 + pw / 2, y0 + ph + 34, pa.log_scale ? pa.key + " (log scale)" : pa.key, {{"text-anchor", "middle"}})
        .newline();
    const std::string ylabel = b < 0 ? "score J" : s.parameters[static_cast<std::size_t>(b)].key;
    std::ostringstream rotate;
    rotate << "rotate(-90 " << x0 - 50 << ' ' << y0 + ph / 2 << ')';
    o.text(x0 - 50, y0 + ph / 2, ylabel, {{"transform", rotate.str()}, {"text-anchor", "middle"}}).newline();
  }
  write_text_file(path, o.finish());
}

/// Morris elementary effects from the trajectories' members (a step touching a failed member is
/// skipped: its penalty is not an effect of the parameter).
std::vector<MorrisEffect> morris_effects(const CalibrationSetup& s, const CalibrationResult& r) {
  const int P = static_cast<int>(s.parameters.size());
  std::map<std::vector<double>, const Evaluation*> by_values;
  for (const auto& e : r.evaluations) by_values.emplace(e.values, &e);
  std::vector<std::vector<double>> ee(static_cast<std::size_t>(P));
  for (int t = 0; t < s.search.morris_trajectories; ++t) {
    const auto pts = morris_trajectory(s.search.seed, t, P, s.search.morris_levels);
    for (std::size_t k = 1; k < pts.size(); ++k) {
      int j = -1;
      for (int d = 0; d < P; ++d)
        if (pts[k][static_cast<std::size_t>(d)] != pts[k - 1][static_cast<std::size_t>(d)]) j = d;
      if (j < 0) continue;
      std::vector<double> v0(static_cast<std::size_t>(P)), v1(static_cast<std::size_t>(P));
      for (int d = 0; d < P; ++d) {
        v0[static_cast<std::size_t>(d)] =
            s.parameters[static_cast<std::size_t>(d)].value(pts[k - 1][static_cast<std::size_t>(d)]);
        v1[static_cast<std::size_t>(d)] =
            s.parameters[static_cast<std::size_t>(d)].value(pts[k][static_cast<std::size_t>(d)]);
      }
      const auto a = by_values.find(v0), b = by_values.find(v1);
      if (a == by_values.end() || b == by_values.end() || !a->second->ok || !b->second->ok) continue;
      const double du = pts[k][static_cast<std::size_t>(j)] - pts[k - 1][static_cast<std::size_t>(j)];
      ee[static_cast<std::size_t>(j)].push_back((b->second->misfit.score - a->second->misfit.score) / du);
    }
  }
  std::vector<MorrisEffect> out;
  for (int d = 0; d < P; ++d) {
    MorrisEffect m;
    m.key = s.parameters[static_cast<std::size_t>(d)].key;
    const auto& v = ee[static_cast<std::size_t>(d)];
    m.effects = static_cast<int>(v.size());
    for (double x : v) m.mu += x, m.mu_star += std::abs(x);
    if (!v.empty()) m.mu /= v.size(), m.mu_star /= v.size();
    for (double x : v) m.sigma += (x - m.mu) * (x - m.mu);
    if (v.size() > 1) m.sigma = std::sqrt(m.sigma / (v.size() - 1));
    out.push_back(m);
  }
  std::stable_sort(out.begin(), out.end(),
                   [](const MorrisEffect& a, const MorrisEffect& b) { return a.mu_star > b.mu_star; });
  return out;
}

/// Set a dotted key ("model.n") in a TOML table, creating the tables on the way.
template <class V>
void set_dotted(toml::table& t, const std::string& key, V value) {
  toml::table* cur = &t;
  std::size_t start = 0;
  for (std::size_t dot; (dot = key.find('.', start)) != std::string::npos; start = dot + 1) {
    const std::string part = key.substr(start, dot - start);
    if (!cur->contains(part) || !(*cur)[part].is_table()) cur->insert_or_assign(part, toml::table{});
    cur = (*cur)[part].as_table();
  }
  cur->insert_or_assign(key.substr(start), value);
}

/// The best set as a debris-runout config that runs from anywhere: the base case's own file (the
/// keys it sets, nothing more) with the best values and every input path made absolute; a
/// searched thickness factor becomes best_release.tif. Read back through read_config before it is
/// written.
std::string best_config(const CalibrationSetup& s, const Evaluation& best, const fs::path& out) {
  toml::table t = toml::parse_file(s.members.base_config.string());
  RunConfig base;
  {
    ConfigReader probe = ConfigReader::from_file(s.members.base_config);
    base = read_config(probe);
  }
  const auto set_path = [&](const std::string& key, const std::string& p) {
    if (!p.empty()) set_dotted(t, key, fs::absolute(p).lexically_normal().generic_string());
  };
  set_path("terrain.dsm", base.dsm);
  set_path("release.file", base.release.file);
  set_path("release.from", base.release.handoff);
  set_path("entrainment.file", base.processes.erodible);
  set_path("zones.file", base.processes.zones);
  for (int k = 0; k < kFrictionParameters; ++k)
    set_path(std::string("zones.") + kFrictionParameterNames[static_cast<std::size_t>(k)],
             base.processes.zone_rasters[static_cast<std::size_t>(k)]);
  set_path("forest.file", base.processes.forest);
  set_path("inflow.hydrograph", base.processes.hydrograph);
  set_path("barriers.file", base.barriers.file);
  std::ostringstream note;
  note << std::setprecision(17);
  for (std::size_t d = 0; d < s.parameters.size(); ++d) {
    const std::string& key = s.parameters[d].key;
    const double v = best.values[d];
    if (key == kThicknessFactorKey) {
      if (!base.release.handoff.empty()) {
        note << "# release thickness factor " << v << ": scale the hand-off release's volumes by it (no key does)\n";
        continue;
      }
      const RunoutInputs in = load_inputs(base);
      Raster r = read_raster(s.members.dsm).like(0.0, -9999.0);
      for (std::size_t k = 0; k < r.data.size(); ++k) r.data[k] = in.thickness[k] * v;
      r.description = "release thickness of the calibrated case (base release x " + fmt(v, 10) + ", vertical)";
      r.unit = "m";
      write_geotiff(out / "best_release.tif", r, true);
      set_path("release.file", (out / "best_release.tif").string());
      set_dotted(t, "release.thickness_direction", std::string("vertical"));
      note << "# release.file: the base release (as a vertical thickness) x the fitted factor " << v << "\n";
      continue;
    }
    // Integer keys stay integers (TOML types are checked on reading).
    if (toml::node* n = t.at_path(key).node(); n && n->is_integer() && v == std::floor(v))
      set_dotted(t, key, static_cast<std::int64_t>(v));
    else
      set_dotted(t, key, v);
  }
  std::ostringstream body;
  body << t << "\n";
  {
    ConfigReader check = ConfigReader::from_string(body.str(), (out / "best.toml").string());
    (void)read_config(check);
    check.finish();
  }
  std::ostringstream o;
  o << "# The best parameter set of geohaz-calibrate (member " << best.index << ", score " << std::setprecision(6)
    << best.misfit.score << "): the base case " << s.members.base_config.string()
    << " with the fitted values.\n#   debris-runout --config best.toml --out best-run\n"
    << note.str() << body.str();
  return o.str();
}

/// The comparison map (comparison.tif, .qml, .png: TP/FP/FN over the hillshade) and the binned
/// thalweg profile (thalweg_profile.csv) of the best member.
void write_comparison(const CalibrationSetup& s, const Evaluation& best, const Raster& dsm, const fs::path& out) {
  const Observation& ob = s.observation;
  const GridGeometry& g = ob.grid;
  std::vector<double> depth(g.cells(), 0.0), deposit(g.cells(), 0.0);
  if (best.ok) depth = read_member_max_depth(out, best.index), deposit = read_member_deposit(out, best.index);
  Raster cls = dsm.like(0.0, 255.0);
  double bin = s.score.profile_bin > 0.0 ? s.score.profile_bin : 2.0 * std::max(g.dx, g.dy);
  double s_end = 0.0;
  for (std::size_t k = 0; k < g.cells(); ++k) {
    const bool mod = depth[k] > s.score.depth_threshold, obs = ob.footprint[k] != 0;
    cls.data[k] = mod && obs ? 1.0 : mod ? 2.0 : obs ? 3.0 : 0.0;
    if (dsm.is_nodata(dsm.data[k])) cls.data[k] = 255.0;
    if (mod || obs) s_end = std::max(s_end, ob.s[k]);
  }
  cls.description =
      "comparison of the best member with the observation: 1 true positive, 2 false positive "
      "(modelled only), 3 false negative (observed only), 0 neither";
  cls.unit = "1";
  write_geotiff(out / "comparison.tif", cls);
  const std::vector<StyleClass> classes = {{1.0, "true positive (both)", {44, 160, 44}},
                                           {2.0, "false positive (modelled only)", {214, 39, 40}},
                                           {3.0, "false negative (observed only)", {31, 119, 180}}};
  write_qgis_class_style(out / "comparison.qml", classes);
  {
    QuicklookOptions q;
    q.title = "best member against the observation";
    q.classes = classes;
    q.overlay_min = 0.5;
    q.crop_margin_m = 10.0 * std::max(g.dx, g.dy);
    q.scale_bar = true;
    q.north_arrow = true;
    q.lines = {ob.thalweg};
    Raster overlay = cls;
    for (double& v : overlay.data)
      if (v == 255.0) v = 0.0;
    overlay.nodata.reset();
    write_quicklook_png(out / "comparison.png", dsm, &overlay, q);
  }
  {
    const int nb = std::max(1, static_cast<int>(std::ceil((s_end + 1e-9) / bin)));
    std::vector<double> oa(nb, 0.0), ma(nb, 0.0), tp(nb, 0.0), fp(nb, 0.0), fn(nb, 0.0), od(nb, 0.0), md(nb, 0.0),
        mh(nb, 0.0);
    const double a = g.cell_area();
    for (std::size_t k = 0; k < g.cells(); ++k) {
      const bool mod = depth[k] > s.score.depth_threshold, obs = ob.footprint[k] != 0;
      const bool dep = !ob.deposit.empty() && ob.deposit[k] > 0.0;
      if (!mod && !obs && !dep && !(deposit[k] > 0.0)) continue;
      const int b = std::min(nb - 1, static_cast<int>(ob.s[k] / bin));
      if (obs) oa[b] += a;
      if (mod) ma[b] += a;
      if (mod && obs) tp[b] += a;
      if (mod && !obs) fp[b] += a;
      if (!mod && obs) fn[b] += a;
      if (!ob.deposit.empty()) od[b] = std::max(od[b], ob.deposit[k]);
      md[b] = std::max(md[b], deposit[k]);
      mh[b] = std::max(mh[b], depth[k]);
    }
    AtomicTextFile csv(out / "thalweg_profile.csv");
    csv << "s_m,observed_area_m2,modelled_area_m2,tp_m2,fp_m2,fn_m2,observed_width_m,modelled_width_m,"
           "observed_max_deposit_m,modelled_max_deposit_m,modelled_max_depth_m\n";
    csv.stream() << std::setprecision(8);
    for (int b = 0; b < nb; ++b)
      csv << (b + 0.5) * bin << ',' << oa[b] << ',' << ma[b] << ',' << tp[b] << ',' << fp[b] << ',' << fn[b] << ','
          << oa[b] / bin << ',' << ma[b] / bin << ',' << (ob.deposit.empty() ? std::nan("") : od[b]) << ',' << md[b]
          << ',' << mh[b] << '\n';
    csv.commit();
  }
}

/// The best member's long profile along the observation's thalweg (profile.hpp; peaks across the
/// path within the base case's output.profile_half_width, reached where the peak depth exceeds
/// score.depth_threshold), with the observed run-out marked beside the modelled one, both as the
/// score measures them along the thalweg (issue #33 item 2). False when the best member failed.
bool write_best_profile(const CalibrationSetup& s, const Evaluation& best, const Raster& dsm, const fs::path& out) {
  if (!best.ok) return false;
  const Observation& ob = s.observation;
  const auto peaks = read_member_peak_maps(out, best.index);
  std::array<Raster, 3> maps;
  for (int f = 0; f < 3; ++f) {
    maps[f] = dsm.like(0.0, -9999.0);
    for (std::size_t k = 0; k < maps[f].data.size() && k < peaks[f].size(); ++k) maps[f].data[k] = peaks[f][k];
  }
  const double cell = std::min(dsm.cell_size_x(), dsm.cell_size_y());
  const ThalwegProfile p = thalweg_profile(dsm, maps[0], maps[1], maps[2], ob.thalweg, cell, s.score.depth_threshold,
                                           s.members.aggregation.profile_half_width);
  write_profile_csv(out / "profile.csv", p);
  ProfileFigure f;
  f.title = "best member " + std::to_string(best.index) + " along the observed thalweg";
  const std::string from = ob.runout_from == "runout_point"  ? "the observed run-out point"
                           : ob.runout_from == "runout_line" ? "the observed run-out line"
                                                             : "the farthest observed footprint cell";
  f.marks = {{ob.runout_s, "observed run-out (blue): s = " + fmt(ob.runout_s, 5) + " m, from " + from, {31, 119, 180}},
             {best.misfit.runout_s,
              "modelled run-out (purple, dashed; the score's, farthest affected cell): s = " +
                  fmt(best.misfit.runout_s, 5) + " m",
              {148, 103, 189},
              true}};
  write_profile_png(out / "profile.png", p, f);
  return true;
}

/// A member's cropped map (MemberPeaks window) on the full grid, 0 outside the window.
std::vector<double> uncrop(const MemberPeaks& p, const std::vector<double>& v) {
  std::vector<double> out(static_cast<std::size_t>(p.nx) * p.ny, 0.0);
  for (int r = 0; r < p.h; ++r)
    for (int c = 0; c < p.w; ++c)
      out[static_cast<std::size_t>(p.r0 + r) * p.nx + p.c0 + c] = v[static_cast<std::size_t>(r) * p.w + c];
  return out;
}

}  // namespace

void write_calibration_outputs(const CalibrationSetup& s, const CalibrationResult& r, const fs::path& out, int ranks,
                               int threads, double wall_time_s, bool quiet) {
  if (r.best < 0) throw std::logic_error("calibration without members");
  const Evaluation& best = r.evaluations[static_cast<std::size_t>(r.best)];
  const double j_best = best.misfit.score, tol = s.score.acceptable_tolerance;

  // 1. Tables: every member, the acceptable set.
  std::vector<const Evaluation*> all, acceptable;
  for (const auto& e : r.evaluations) {
    all.push_back(&e);
    if (e.ok && e.misfit.score <= j_best + tol) acceptable.push_back(&e);
  }
  member_table(out / "members.csv", s, all);
  std::stable_sort(acceptable.begin(), acceptable.end(),
                   [](const Evaluation* a, const Evaluation* b) { return a->misfit.score < b->misfit.score; });
  member_table(out / "acceptable.csv", s, acceptable);
  write_acceptable_svg(out / "acceptable.svg", s, r, j_best, tol);

  // 2. Morris ranking.
  const std::vector<MorrisEffect> morris = morris_effects(s, r);
  {
    AtomicTextFile csv(out / "sensitivity.csv");
    csv << "rank,key,mu_star,mu,sigma,effects\n";
    csv.stream() << std::setprecision(10);
    for (std::size_t k = 0; k < morris.size(); ++k)
      csv << k + 1 << ',' << morris[k].key << ',' << morris[k].mu_star << ',' << morris[k].mu << ',' << morris[k].sigma
          << ',' << morris[k].effects << '\n';
    csv.commit();
  }

  // 3. The best set, ready to run.
  write_text_file(out / "best.toml", best_config(s, best, out));

  // 4. Comparison map, thalweg profile and long profile of the best member.
  const Raster dsm = read_raster(s.members.dsm);
  write_comparison(s, best, dsm, out);
  const bool profile = write_best_profile(s, best, dsm, out);
  const Observation& ob = s.observation;

  // 5. Summary.
  nlohmann::json j;
  j["model"] = "geohaz-calibrate";
  j["version"] = GEOHAZ_VERSION;
  j["base_case"] = s.members.base_config.string();
  j["dsm"] = s.members.dsm;
  nlohmann::json params = nlohmann::json::array();
  for (const auto& p : s.parameters)
    params.push_back({{"key", p.key}, {"min", p.lower}, {"max", p.upper}, {"scale", p.log_scale ? "log" : "linear"}});
  j["parameters"] = params;
  nlohmann::json bj;
  for (std::size_t d = 0; d < s.parameters.size(); ++d) bj[s.parameters[d].key] = best.values[d];
  j["best"] = {{"member", best.index}, {"stage", best.stage}, {"parameters", bj}, {"values", best.values}};
  nlohmann::json mj = {{"tp_m2", best.misfit.tp},
                       {"fp_m2", best.misfit.fp},
                       {"fn_m2", best.misfit.fn},
                       {"tversky", best.misfit.tversky},
                       {"runout_s_m", best.misfit.runout_s},
                       {"runout_diff_m", best.misfit.runout_diff},
                       {"depth_rmse_m", best.misfit.depth_rmse},
                       {"volume_m3", best.misfit.volume},
                       {"terms",
                        {{"footprint", best.misfit.term_footprint},
                         {"runout", best.misfit.term_runout},
                         {"depth", best.misfit.term_depth},
                         {"volume", best.misfit.term_volume}}},
                       {"score", best.misfit.score}};
  j["best"]["misfit"] = mj;
  j["observation"] = {{"footprint_area_m2", ob.footprint_area()},
                      {"runout_s_m", ob.runout_s},
                      {"runout_from", ob.runout_from},
                      {"deposit_raster", !ob.deposit.empty()},
                      {"volume_m3", ob.volume}};
  j["score"] = {{"definition",
                 "J = w_footprint (1 - T) + w_runout |s_mod - s_obs| / s_obs + w_depth RMSE(deposit) / mean observed "
                 "deposit + w_volume |V_mod - V_obs| / V_obs; T = TP / (TP + alpha FP + beta FN)"},
                {"depth_threshold_m", s.score.depth_threshold},
                {"tversky_alpha", s.score.alpha},
                {"tversky_beta", s.score.beta},
                {"w_footprint", s.score.w_footprint},
                {"w_runout", s.score.w_runout},
                {"w_depth", s.score.w_depth},
                {"w_volume", s.score.w_volume},
                {"failed_penalty", s.score.failed_penalty},
                {"acceptable_tolerance", tol}};
  int failed = 0;
  nlohmann::json fj = nlohmann::json::array();
  for (const auto& e : r.evaluations)
    if (!e.ok) {
      ++failed;
      fj.push_back({{"member", e.index}, {"values", e.values}, {"diagnosis", e.diagnosis}});
    }
  j["members"] = r.evaluations.size();
  j["design_members"] = r.design_members;
  j["morris_members"] = r.morris_members;
  j["local_members"] = static_cast<int>(r.evaluations.size()) - r.design_members - r.morris_members;
  j["local_search"] = {{"algorithm", s.search.local_algorithm},
                       {"starts", s.search.local_starts},
                       {"restarts", s.search.local_restarts},
                       {"searches", r.local_stops.size()},
                       {"stops", r.local_stops}};
  j["failed"] = fj;
  j["acceptable_members"] = acceptable.size();
  nlohmann::json range = nlohmann::json::object();
  for (std::size_t d = 0; d < s.parameters.size(); ++d) {
    double lo = best.values[d], hi = best.values[d];
    for (const Evaluation* e : acceptable) lo = std::min(lo, e->values[d]), hi = std::max(hi, e->values[d]);
    range[s.parameters[d].key] = {lo, hi};
  }
  j["acceptable_range"] = range;
  nlohmann::json sens = nlohmann::json::array();
  for (const auto& m : morris)
    sens.push_back({{"key", m.key}, {"mu_star", m.mu_star}, {"mu", m.mu}, {"sigma", m.sigma}, {"effects", m.effects}});
  j["sensitivity"] = sens;
  j["ranks"] = ranks;
  j["threads_per_rank"] = threads;
  j["wall_time_s"] = wall_time_s;
  j["outputs"] = {"best.toml",      "members.csv",    "acceptable.csv", "acceptable.svg",      "sensitivity.csv",
                  "comparison.tif", "comparison.png", "comparison.qml", "thalweg_profile.csv", "summary.json"};
  if (profile) j["outputs"].insert(j["outputs"].end() - 1, {"profile.csv", "profile.png"});
  (void)failed;
  write_text_file(out / "summary.json", j.dump(2) + "\n");
  if (!quiet) {
    std::ostringstream o;
    o << "geohaz-calibrate: best member " << best.index << " (" << best.stage << "):";
    for (std::size_t d = 0; d < s.parameters.size(); ++d) o << ' ' << s.parameters[d].key << '=' << fmt(best.values[d]);
    o << ", score " << fmt(j_best, 5) << " (T " << fmt(best.misfit.tversky, 4) << ", run-out difference "
      << fmt(best.misfit.runout_diff, 4) << " m); " << acceptable.size() << " acceptable; outputs in " << out.string();
    std::cerr << o.str() << "\n";
  }
}

// The members' maps on the full grid (calibrate.hpp).

std::vector<double> read_member_deposit(const fs::path& out, int i) {
  const MemberPeaks p = read_member_peaks(member_dir(out, i) / "deposit.bin");
  return uncrop(p, p.depth);
}

std::vector<double> read_member_max_depth(const fs::path& out, int i) {
  const MemberPeaks p = read_member_peaks(member_dir(out, i) / "peaks.bin");
  return uncrop(p, p.depth);
}

std::array<std::vector<double>, 3> read_member_peak_maps(const fs::path& out, int i) {
  const MemberPeaks p = read_member_peaks(member_dir(out, i) / "peaks.bin");
  return {uncrop(p, p.depth), uncrop(p, p.speed), uncrop(p, p.pressure)};
}

}  // namespace geohaz::runout
