// geohaz-report's pieces (libs/report/include/geohaz/report/report.hpp, docs/report.md): names and units read
// from keys and columns, numbers formatted with units, SVG plots whose points sit where the axes
// say, the grouping of summary.json (unknown keys kept), the input parameters in the user's terms,
// the back-analysis part of a geohaz-calibrate folder.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <span>
#include <string>
#include <utility>
#include <vector>

#include "calibration_results.hpp"
#include "geohaz/core/errors.hpp"
#include "geohaz/core/summary_keys.hpp"
#include "geohaz/dem/summary_keys.hpp"
#include "geohaz/report/report.hpp"
#include "geohaz/runout/summary_keys.hpp"
#include "geohaz/sph/summary_keys.hpp"
#include "summary_keys_check.hpp"

namespace fs = std::filesystem;
using namespace geohaz::report;

namespace {

fs::path temp_dir(const std::string& name) {
  const fs::path d = fs::temp_directory_path() / ("geohaz_report_" + name + "_" +
                                                  std::to_string(::testing::UnitTest::GetInstance()->random_seed()));
  fs::remove_all(d);
  fs::create_directories(d);
  return d;
}

void write_file(const fs::path& p, const std::string& text) {
  std::ofstream out(p);
  out << text;
}

const Group* find_group(const Summary& s, const std::string& title) {
  for (const auto& g : s.groups)
    if (g.title == title) return &g;
  return nullptr;
}

const Row* find_row(const std::vector<Row>& rows, const std::string& key) {
  for (const auto& r : rows)
    if (r.key == key) return &r;
  return nullptr;
}

}  // namespace

TEST(ReportNames, UnitsAreReadFromTheEndOfColumnAndKeyNames) {
  EXPECT_EQ(quantity_from_name("mean_speed_m_s").label, "mean speed");
  EXPECT_EQ(quantity_from_name("mean_speed_m_s").unit, "m/s");
  EXPECT_EQ(quantity_from_name("max_speed_m_per_s").unit, "m/s");
  EXPECT_EQ(quantity_from_name("time_s").label, "time");
  EXPECT_EQ(quantity_from_name("time_s").unit, "s");
  EXPECT_EQ(quantity_from_name("force_N").unit, "N");
  EXPECT_EQ(quantity_from_name("kinetic_energy_J_per_m").label, "kinetic energy");
  EXPECT_EQ(quantity_from_name("kinetic_energy_J_per_m").unit, "J/m");
  EXPECT_EQ(quantity_from_name("earthquake_acceleration_m_per_s2").unit, "m/s²");
  EXPECT_EQ(quantity_from_name("deposited_volume_m3").unit, "m³");
  EXPECT_EQ(quantity_from_name("max_pressure_pa").unit, "Pa");
  EXPECT_EQ(quantity_from_name("angle_deg").unit, "°");
  // No unit: the whole name is the label; a lone unit-like word stays a word.
  EXPECT_EQ(quantity_from_name("ratio_H_over_L").label, "ratio H over L");
  EXPECT_EQ(quantity_from_name("ratio_H_over_L").unit, "");
  EXPECT_EQ(quantity_from_name("s").label, "s");
  EXPECT_EQ(quantity_from_name("s").unit, "");
}

TEST(ReportNames, NumbersCarryFourDigitsAndEngineeringUnits) {
  EXPECT_EQ(format_quantity(2.208e6, "Pa"), "2.208 MPa");
  EXPECT_EQ(format_quantity(31700751174.6, "Pa"), "31.7 GPa");
  EXPECT_EQ(format_quantity(17678.389, "m³"), "17\u202F678 m³");
  EXPECT_EQ(format_quantity(0.5131776, ""), "0.5132");
  EXPECT_EQ(format_quantity(27.1658, "°"), "27.17°");
  EXPECT_EQ(format_quantity(3.0, ""), "3");
  EXPECT_EQ(format_quantity(4.5e9, "J"), "4.5 GJ");
  EXPECT_EQ(format_quantity(2.05e-16, ""), "2.050e-16");
}

// A force growing linearly over 10 s: the axes run 0–10 s and 0–1000 N, so the first point is at
// the plot's lower left corner (80, 36 + 200) and the last at its upper right (80 + 480, 36).
TEST(ReportPlots, SvgPointsSitWhereTheAxesSay) {
  const fs::path d = temp_dir("svg");
  write_file(d / "forces.csv", "time_s,step,force_N,front_x_m\n0,0,0,5\n5,10,500,6\n10,20,1000,7\n");
  const Csv csv = read_csv(d / "forces.csv");
  ASSERT_TRUE(is_plottable(csv));
  const std::string svg = svg_plot(csv, "Barrier force");
  EXPECT_NE(svg.find("points=\"80,236 320,136 560,36 \""), std::string::npos) << svg;
  EXPECT_NE(svg.find(">force (N)<"), std::string::npos);
  EXPECT_NE(svg.find(">time (s)<"), std::string::npos);
  EXPECT_EQ(svg.find("step"), std::string::npos);     // a counter, not a quantity
  EXPECT_EQ(svg.find("front x"), std::string::npos);  // map coordinates are left out
  EXPECT_NE(svg.find("width=\"760\""), std::string::npos);
  // Event lists (a text column) and tables without a time or distance column are not plotted.
  write_file(d / "ae.csv", "time_s,x_m,mode\n0,1,tensile\n1,2,shear\n");
  EXPECT_FALSE(is_plottable(read_csv(d / "ae.csv")));
  write_file(d / "fragments.csv", "fragment,discs\n0,1\n1,3\n");
  EXPECT_FALSE(is_plottable(read_csv(d / "fragments.csv")));
  fs::remove_all(d);
}

TEST(ReportSummary, KeysAreGroupedAndLabelledFromTheWritersDeclarationsAndUnknownKeysKept) {
  const auto j = nlohmann::json::parse(R"({
    "model": "debris-runout",
    "fahrboeschung": {"ratio_H_over_L": 0.5131776, "reach_m": 2802.16},
    "max_pressure_pa": 2.208e6,
    "volumes_m3": {"deposited": 3911.4},
    "wall_time_s": 61.2,
    "barrier_peak_force_N": 12500.0,
    "runout_length_along_path_m": {"p10": 2500.0},
    "long": [1,2,3,4,5,6,7,8,9,10]
  })");
  const Summary s = summarise(j);
  // Label and unit are debris-runout's declarations (runout::summary_keys), read here from them.
  const auto keys = declared_summary_keys(j);
  const auto declared = [&](const std::string& key) { return geohaz::find_summary_key(keys, key); };
  const Group* reach = find_group(s, "Reach and H/L");
  ASSERT_NE(reach, nullptr);
  const Row* hl = find_row(reach->rows, "fahrboeschung.ratio_H_over_L");
  ASSERT_NE(hl, nullptr);
  ASSERT_NE(declared("fahrboeschung.ratio_H_over_L"), nullptr);
  EXPECT_EQ(hl->label, declared("fahrboeschung.ratio_H_over_L")->label);
  EXPECT_EQ(hl->value, "0.5132");  // declared "1": dimensionless
  EXPECT_EQ(find_row(reach->rows, "fahrboeschung.reach_m")->value, "2802 m");
  // A "*" declaration: its label with what the star stands for.
  EXPECT_EQ(find_row(reach->rows, "runout_length_along_path_m.p10")->label,
            std::string(declared("runout_length_along_path_m.*")->label) + ": p10");
  const Group* volumes = find_group(s, "Volumes and areas");
  ASSERT_NE(volumes, nullptr);
  EXPECT_EQ(find_row(volumes->rows, "volumes_m3.deposited")->value, "3911 m³");  // declared "m^3"
  const Group* peak = find_group(s, "Peak values");
  ASSERT_NE(peak, nullptr);
  EXPECT_EQ(find_row(peak->rows, "max_pressure_pa")->value, "2.208 MPa");
  const Group* other = find_group(s, "Run bookkeeping / other");
  ASSERT_NE(other, nullptr);
  EXPECT_EQ(find_row(other->rows, "wall_time_s")->value, "61.2 s");
  // A key the writer does not declare is still shown, under its own name and without a unit: the
  // report guesses nothing from a name (the apps' tests make every key they write declared).
  const Row* added = find_row(other->rows, "barrier_peak_force_N");
  ASSERT_NE(added, nullptr);
  EXPECT_EQ(added->label, "barrier_peak_force_N");
  EXPECT_EQ(added->value, "12\u202F500");
  EXPECT_EQ(find_row(other->rows, "long"), nullptr);  // long arrays are left to the files
  EXPECT_NE(find_row(s.headline, "fahrboeschung.ratio_H_over_L"), nullptr);

  // dem-avalanche's biaxial tests: a table titled and headed from its declarations.
  const auto d = nlohmann::json::parse(R"({
    "model": "dem-avalanche",
    "tests": [{"name": "sigma3_5MPa", "confining_stress_Pa": 5e6, "peak_stress_Pa": 9.76e7}]
  })");
  const Summary t = summarise(d);
  ASSERT_EQ(t.tables.size(), 1u);
  EXPECT_EQ(t.tables[0].title, "Results per confining stress");
  EXPECT_FALSE(t.tables[0].folded);
  EXPECT_EQ(t.tables[0].headers[0], "test");
  EXPECT_EQ(t.tables[0].headers[1], "confining stress σ3 (Pa)");
  EXPECT_EQ(t.tables[0].cells[0][1], "5 MPa");
  // sph-slope (its "model" is the constitutive model): the materials table is bookkeeping, folded.
  const Summary m = summarise(nlohmann::json::parse(
      R"({"model": "drucker_prager", "materials": [{"name": "soil", "K_Pa": 1e7}], "failed_area_m2_per_m": 52.5})"));
  ASSERT_EQ(m.tables.size(), 1u);
  EXPECT_TRUE(m.tables[0].folded);
  EXPECT_EQ(m.tables[0].headers[1], "bulk modulus K (Pa)");
  EXPECT_EQ(find_row(m.headline, "failed_area_m2_per_m")->value, "52.5 m²/m");
}

// The declarations the apps' tests hold every real summary.json to (EXPECT_SUMMARY_KEYS_DECLARED):
// a number without a declared label and unit is named, nested or in an array of objects, so a key
// added to a summary without its line fails; "*" patterns and array titles work as documented.
TEST(SummaryKeys, ANumberWithoutADeclarationIsNamedAndPatternsMatch) {
  const auto j = nlohmann::json::parse(R"({
    "model": "debris-runout",
    "volumes_m3": {"deposited": 1.0, "new_volume_m3": 2.0},
    "barriers": [{"name": "dam", "peak_force_n": 3.0, "new_force_n": 4.0}],
    "profile": {"runout_xy_m": [1.0, 2.0], "reached": true},
    "runout_length_along_path_m": {"p10": 5.0},
    "best": {"parameters": {"model.mu": 0.2}},
    "ended_by": "duration",
    "missing_time_s": null
  })");
  const auto missing = geohaz::testing::undeclared_summary_keys(j, geohaz::runout::summary_keys());
  EXPECT_EQ(missing,
            (std::vector<std::string>{"barriers[].new_force_n", "missing_time_s", "volumes_m3.new_volume_m3"}));
  const auto keys = geohaz::runout::summary_keys();
  ASSERT_NE(geohaz::find_summary_key(keys, "best.parameters.model.mu"), nullptr);  // a last "*": the rest
  EXPECT_EQ(geohaz::find_summary_key(keys, "best.parameters.model.mu")->key, "best.parameters.*");
  EXPECT_EQ(geohaz::find_summary_key(keys, "best.parameters"), nullptr);
  EXPECT_EQ(geohaz::find_summary_key(keys, "runout_length_along_path_m.p10")->key, "runout_length_along_path_m.*");
  // Every declaration of the three libraries has a label; every unit is one the report can show.
  for (const auto list : {geohaz::runout::summary_keys(), geohaz::sph::summary_keys(), geohaz::dem::summary_keys()})
    for (const geohaz::SummaryKey& k : list) {
      EXPECT_FALSE(k.label.empty()) << k.key;
      EXPECT_EQ(display_unit(std::string(k.unit)).find('_'), std::string::npos) << k.key;
    }
}

// The keys of the three libraries that echo a config value (config_echo) take label and unit from
// that key's declaration: every referenced key exists, has a short label, and its unit is the one
// the summary key's name promises (issue #30 item 4).
TEST(SummaryKeys, ConfigEchoesTakeLabelAndUnitFromTheirDeclarations) {
  using geohaz::testing::config_echo_problems;
  const std::pair<std::span<const geohaz::SummaryKey>, std::span<const geohaz::KeyReference>> libs[] = {
      {geohaz::runout::summary_keys(), geohaz::runout::summary_config_declarations()},
      {geohaz::sph::summary_keys(), geohaz::sph::summary_config_declarations()},
      {geohaz::dem::summary_keys(), geohaz::dem::summary_config_declarations()}};
  for (const auto& [keys, refs] : libs) {
    const auto problems = config_echo_problems(keys, refs);
    std::string list;
    for (const auto& p : problems) list += "\n  " + p;
    EXPECT_TRUE(problems.empty()) << list;
  }
  // As the declarations say: run.stop_energy_fraction and the SPH particle spacing.
  const auto* stop = geohaz::find_summary_key(geohaz::runout::summary_keys(), "stop_energy_fraction");
  ASSERT_NE(stop, nullptr);
  EXPECT_EQ(stop->config_key, "run.stop_energy_fraction");
  EXPECT_EQ(stop->label, "kinetic energy fraction that ends the run");
  EXPECT_EQ(stop->unit, "1");
  const auto* dx = geohaz::find_summary_key(geohaz::sph::summary_keys(), "spacing_m");
  ASSERT_NE(dx, nullptr);
  EXPECT_EQ(dx->label, "particle spacing");
  EXPECT_EQ(dx->unit, "m");
  // A label of the entry's own is kept; the unit is still the declaration's.
  const auto* sigma3 = geohaz::find_summary_key(geohaz::dem::summary_keys(), "tests[].confining_stress_Pa");
  ASSERT_NE(sigma3, nullptr);
  EXPECT_EQ(sigma3->label, "confining stress σ3");
  EXPECT_EQ(sigma3->unit, "Pa");
}

// The check fails, naming the key, on each way an echo can drift from its declaration.
TEST(SummaryKeys, AnEchoThatDriftsFromItsDeclarationIsNamed) {
  using geohaz::config_echo;
  const std::vector<geohaz::KeyReference> refs = {
      {"a.depth", "number", "m", "1", "[0, inf)", "flow depth above which ...", "depth threshold"},
      {"a.count", "integer", "1", "3", "[1, 9]", "how many", ""}};
  const geohaz::SummaryKey table[] = {config_echo("depth_m", "a.depth"),             // fine
                                      config_echo("gone_m", "a.no_such_key"),        // not declared
                                      config_echo("depth_s", "a.depth"),             // the name promises seconds
                                      config_echo("depth", "a.depth"),               // no unit suffix, declared in m
                                      config_echo("count", "a.count"),               // no label anywhere
                                      config_echo("count2", "counted", "a.count")};  // its own label: fine
  const auto keys = geohaz::with_config_declarations(table, refs);
  EXPECT_EQ(keys[0].label, "depth threshold");
  EXPECT_EQ(keys[0].unit, "m");
  EXPECT_EQ(keys[1].unit, "");  // left empty for the check to name
  const auto problems = geohaz::testing::config_echo_problems(keys, refs);
  ASSERT_EQ(problems.size(), 4u);
  EXPECT_NE(problems[0].find("gone_m (echoes a.no_such_key): no such config key"), std::string::npos);
  EXPECT_NE(problems[1].find("depth_s (echoes a.depth): the key's name promises 's', declared 'm'"), std::string::npos);
  EXPECT_NE(problems[2].find("depth (echoes a.depth): the key's name has no unit suffix"), std::string::npos);
  EXPECT_NE(problems[3].find("count (echoes a.count): no label"), std::string::npos);
  // A unit written on the entry that differs from the declaration's is named too.
  geohaz::SummaryKey hand = keys[0];
  hand.unit = "km";
  EXPECT_EQ(geohaz::testing::config_echo_problems(std::span(&hand, 1), refs),
            (std::vector<std::string>{"depth_m (echoes a.depth): unit 'km', declared 'm'"}));
}

TEST(ReportInputs, ParametersInTheUsersTermsForTheChosenLawOnly) {
  const fs::path d = temp_dir("inputs");
  write_file(d / "runout.toml",
             "[model]\nfriction = 'manning'\ndensity = 1900.0\nn = 0.06\nicr = 0.15\nmu = 0.15\nxi = 500.0\n");
  const auto r = input_parameters(d / "runout.toml");
  const Row* n = find_row(r, "model.n");
  ASSERT_NE(n, nullptr);
  EXPECT_EQ(n->label, "Manning roughness n");  // the declaration's help text up to its laws
  EXPECT_EQ(n->value, "0.06 s/m^(1/3)");
  EXPECT_NE(find_row(r, "model.icr"), nullptr);
  EXPECT_EQ(find_row(r, "model.mu"), nullptr);  // Voellmy's coefficients do not apply to Manning
  EXPECT_EQ(find_row(r, "model.xi"), nullptr);
  // The rheologies' coefficients are labelled from the law's key declarations (runout config).
  write_file(d / "hb.toml",
             "[model]\nfriction = 'herschel_bulkley'\ntau_y = 1907.0\nconsistency = 572.0\nflow_index = 0.3333\n"
             "n = 0.06\n");
  const auto h = input_parameters(d / "hb.toml");
  const Row* tau = find_row(h, "model.tau_y");
  ASSERT_NE(tau, nullptr);
  EXPECT_EQ(tau->label, "yield stress τ_y");
  EXPECT_EQ(tau->value, "1.907 kPa");
  const Row* k = find_row(h, "model.consistency");
  ASSERT_NE(k, nullptr);
  EXPECT_EQ(k->label, "consistency K of τ = τ_y + K γ̇^n");
  EXPECT_NE(k->value.find("Pa·s^n"), std::string::npos) << k->value;  // declared "Pa*s^n"
  EXPECT_NE(find_row(h, "model.flow_index"), nullptr);
  EXPECT_EQ(find_row(h, "model.n"), nullptr);  // Manning's n is not a Herschel–Bulkley coefficient
  write_file(d / "pf.toml", "[model]\nfriction = 'pouliquen'\ndelta1 = 20.9\nhstop_length = 0.00065\n");
  const auto pf = input_parameters(d / "pf.toml");
  const Row* d1 = find_row(pf, "model.delta1");
  ASSERT_NE(d1, nullptr);
  EXPECT_EQ(d1->label, "δ₁: slope below which no layer flows");
  EXPECT_NE(find_row(pf, "model.hstop_length"), nullptr);
  write_file(d / "slope.toml",
             "[[material]]\nname = 'colluvium'\ncohesion = 20000.0\nfriction = 35.0\ndilatancy = 0.0\n"
             "young = 2e8\npoisson = 0.3\n");
  const auto m = input_parameters(d / "slope.toml");
  ASSERT_GE(m.size(), 5u);
  bool c = false, phi = false;
  for (const auto& row : m) {
    // Labels and units from sph-slope's declarations (help "cohesion c (Drucker-Prager)", "Pa").
    c = c || (row.label == "colluvium: cohesion c" && row.value == "20 kPa");
    phi = phi || (row.label == "colluvium: friction angle φ" && row.value == "35°");
  }
  EXPECT_TRUE(c);
  EXPECT_TRUE(phi);
  EXPECT_TRUE(input_parameters(d / "absent.toml").empty());
  fs::remove_all(d);
}

namespace {

std::size_t count(const std::string& text, const std::string& what) {
  std::size_t n = 0;
  for (auto p = text.find(what); p != std::string::npos; p = text.find(what, p + 1)) ++n;
  return n;
}

/// The text of the first <table class=NAME> … </table>.
std::string table_of(const std::string& html, const std::string& cls) {
  const auto a = html.find("<table class=" + cls + ">");
  if (a == std::string::npos) return "";
  return html.substr(a, html.find("</table>", a) - a);
}

}  // namespace

TEST(ReportCalibration, BestSetAcceptableSetMorrisMapAndProfileFromACalibrationFolder) {
  const fs::path d = temp_dir("calibration");
  calibration_results::make(d / "cal");
  const nlohmann::json sj = nlohmann::json::parse(std::ifstream(d / "cal" / "summary.json"));
  const CalibrationPart p = calibration_part(d / "cal", sj, "cal", "cal_");
  ASSERT_TRUE(p.present);
  // The overview: the best score and T, and each parameter's best value in the user's terms.
  ASSERT_EQ(p.headline.size(), 4u);
  EXPECT_EQ(p.headline[0].value, "0.1514");
  EXPECT_EQ(p.headline[1].value, "0.9931");
  EXPECT_EQ(p.headline[2].label, "calibration: best Manning roughness n");
  EXPECT_EQ(p.headline[2].value, "0.0517 s/m^(1/3)");
  // The best set: values, search boxes, acceptable ranges; the config ready to run.
  const std::string best = table_of(p.html, "calibration-best");
  EXPECT_NE(best.find("<td class=v>model.icr</td><td class=v>0.1707</td>"), std::string::npos) << best;
  EXPECT_NE(best.find("0.03 s/m^(1/3) – 0.12 s/m^(1/3) (log)"), std::string::npos) << best;
  EXPECT_NE(best.find("0.1689 – 0.1726"), std::string::npos) << best;
  EXPECT_NE(p.html.find("href=\"cal/best.toml\""), std::string::npos);
  EXPECT_NE(table_of(p.html, "calibration-misfit").find("deposit RMSE"), std::string::npos);
  EXPECT_EQ(table_of(p.html, "calibration-misfit").find("observed deposit volume"), std::string::npos);  // none
  // The acceptable set: the best 20 of 25 rows, best first, and where the rest are.
  const std::string acc = table_of(p.html, "calibration-acceptable");
  EXPECT_EQ(count(acc, "<tr>"), 1u + 20u);
  EXPECT_LT(acc.find("<td>37</td>"), acc.find("<td>38</td>"));
  EXPECT_EQ(acc.find("<td>57</td>"), std::string::npos);  // the 21st
  EXPECT_NE(p.html.find("25 successful member(s) with J ≤"), std::string::npos);
  EXPECT_NE(p.html.find("the best 20 shown"), std::string::npos);
  // Morris: ranked by μ*, bars proportional to μ* (120 px for the largest).
  const std::string morris = table_of(p.html, "calibration-morris");
  EXPECT_LT(morris.find("critical slope gradient i_cr"), morris.find("Manning roughness n"));
  EXPECT_NE(morris.find("width:120px"), std::string::npos);
  EXPECT_NE(morris.find("width:6px"), std::string::npos);  // 120 × 0.17 / 3.66 = 5.6
  // The comparison map in three colours, the score plot, the thalweg profiles.
  EXPECT_NE(p.html.find("src=\"cal/comparison.png\""), std::string::npos);
  EXPECT_NE(p.html.find("src=\"cal/acceptable.svg\""), std::string::npos);
  for (const char* colour : {"#2ca02c", "#d62728", "#1f77b4"}) EXPECT_NE(p.html.find(colour), std::string::npos);
  EXPECT_EQ(p.html.find("map-problem"), std::string::npos);  // legend, ticks, scale bar present
  ASSERT_EQ(p.plots.size(), 2u);
  EXPECT_EQ(p.plots[0].first, "cal_thalweg_width.svg");
  EXPECT_EQ(p.plots[1].first, "cal_thalweg_deposit.svg");
  for (const char* label : {"observed width", "modelled width"})
    EXPECT_NE(p.plots[0].second.find(label), std::string::npos);
  for (const char* label : {"observed max deposit", "modelled max deposit"})
    EXPECT_NE(p.plots[1].second.find(label), std::string::npos);
  EXPECT_NE(p.html.find("src=\"report_files/cal_thalweg_width.svg\""), std::string::npos);
  EXPECT_EQ(p.shown.size(), 5u);  // acceptable.svg, comparison.png, thalweg_profile.csv, profile.png/.csv
  // Not a calibration: no part. A calibration summary without its best set: InputError.
  EXPECT_FALSE(calibration_part(d / "cal", nlohmann::json{{"model", "debris-runout"}}, "cal", "cal_").present);
  nlohmann::json broken = sj;
  broken.erase("best");
  EXPECT_THROW(calibration_part(d / "cal", broken, "cal", "cal_"), geohaz::InputError);
  fs::remove_all(d);
}
