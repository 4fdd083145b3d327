// The ensemble part of geohaz-report (libs/report/src/report_ensemble.cpp, docs/report.md "An
// ensemble"): parameter labels and units are the runout config reader's declarations; the
// histogram counts every member once, in the bin its edges say; the part's pieces in reading
// order from a geohaz-ensemble folder made here (summary.json and members.csv as the app writes
// them; the app's own folder is checked in the browser test, test_report_browser.cpp).
#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "geohaz/core/config.hpp"
#include "geohaz/report/report.hpp"
#include "geohaz/runout/run.hpp"

namespace fs = std::filesystem;
using namespace geohaz::report;

namespace {

/// The declaration of a debris-runout key as read_config records it (the reader, not the report).
geohaz::KeyReference declaration(const std::string& key) {
  geohaz::ConfigReader d = geohaz::ConfigReader::describe();
  (void)geohaz::runout::read_config(d);
  for (const auto& r : d.reference())
    if (r.key == key) return r;
  ADD_FAILURE() << "no declaration of " << key;
  return {};
}

/// Every value of attribute `name` in `text`, as numbers.
std::vector<double> attributes(const std::string& text, const std::string& name) {
  std::vector<double> v;
  const std::string key = " " + name + "=\"";
  for (auto p = text.find(key); p != std::string::npos; p = text.find(key, p + 1))
    v.push_back(std::stod(text.substr(p + key.size())));
  return v;
}

std::size_t count(const std::string& text, const std::string& what) {
  std::size_t n = 0;
  for (auto p = text.find(what); p != std::string::npos; p = text.find(what, p + 1)) ++n;
  return n;
}

}  // namespace

TEST(ReportEnsemble, ParameterLabelsAndUnitsAreTheConfigReadersDeclarations) {
  // A declared unit as the page writes it (the conversion is not the identity).
  EXPECT_EQ(display_unit("m/s^2"), "m/s²");
  EXPECT_EQ(display_unit("kg/m^3"), "kg/m³");
  EXPECT_EQ(display_unit("Pa*s"), "Pa·s");
  EXPECT_EQ(display_unit("1"), "");
  // Each key's unit is its declaration's, its label the start of the declared help text.
  for (const char* key :
       {"model.xi", "model.n", "model.mu", "model.density", "model.d0", "model.tau_y", "run.duration"}) {
    const geohaz::KeyReference r = declaration(key);
    const auto [label, unit] = parameter_label(key);
    EXPECT_EQ(unit, display_unit(r.unit)) << key;
    EXPECT_FALSE(label.empty()) << key;
    EXPECT_EQ(r.help.rfind(label, 0), 0u) << key << ": " << label << " | " << r.help;
  }
  EXPECT_EQ(parameter_label("release.thickness_factor").second, "");  // declared "1" by the ensemble
  EXPECT_EQ(parameter_label("no.such_key").first, "no.such_key");
}

TEST(ReportEnsemble, HistogramCountsEveryMemberOnceInTheBinItsEdgesSay) {
  const std::vector<double> v{2537.7, 2555.1, 2571.0, 2590.0, 2604.4, 2608.0, 2608.0, 2630.2, 2645.7};
  const std::string svg = svg_distribution(v, {"run-out", "m"}, {{"P10", 2537.7}, {"P50", 2604.4}, {"P90", 2645.7}},
                                           "run-out of the members");
  const auto counts = attributes(svg, "data-count"), lows = attributes(svg, "data-lo");
  ASSERT_GE(counts.size(), 5u);  // at least five bins
  ASSERT_EQ(lows.size(), counts.size());
  double total = 0.0;
  for (double c : counts) total += c;
  EXPECT_EQ(total, static_cast<double>(v.size()));
  EXPECT_EQ(attributes(svg, "data-members").at(0), static_cast<double>(v.size()));
  // Recount: bin k holds the values in [lo_k, lo_k + width), the last one its upper edge too.
  const double width = lows[1] - lows[0];
  EXPECT_GT(width, 0.0);
  for (std::size_t k = 0; k < counts.size(); ++k) {
    const bool last = k + 1 == counts.size();
    const auto in = std::count_if(v.begin(), v.end(), [&](double x) {
      return x >= lows[k] - 1e-9 && (x < lows[k] + width - 1e-9 || (last && x <= lows[k] + width + 1e-9));
    });
    EXPECT_EQ(counts[k], static_cast<double>(in)) << "bin " << k << " from " << lows[k];
  }
  EXPECT_EQ(count(svg, "class=\"marker\""), 3u);
  EXPECT_NE(svg.find("P50 2604 m"), std::string::npos);
  EXPECT_NE(svg.find("run-out (m)"), std::string::npos);  // the axis title
  // One value repeated, and no value: still a drawable plot.
  const std::string same = svg_distribution({0.5, 0.5, 0.5}, {"H/L", ""}, {}, "same");
  EXPECT_EQ(same.find("nan"), std::string::npos);
  double same_total = 0.0;
  for (double c : attributes(same, "data-count")) same_total += c;
  EXPECT_EQ(same_total, 3.0);
  EXPECT_EQ(svg_distribution({}, {"H/L", ""}, {}, "none").find("nan"), std::string::npos);
}

TEST(ReportEnsemble, OverviewParametersPercentilesMapsAndDistributionsInReadingOrder) {
  const fs::path d = fs::temp_directory_path() /
                     ("geohaz_report_ens_" + std::to_string(::testing::UnitTest::GetInstance()->random_seed()));
  fs::remove_all(d);
  fs::create_directories(d / "ens");
  std::ofstream(d / "ens" / "summary.json") << R"({"model": "geohaz-ensemble", "members": 5, "succeeded": 4,
    "failed": [{"member": 2, "diagnosis": "injected failure", "values": [500.0]}],
    "sampling": "latin_hypercube", "seed": 3,
    "parameters": [{"key": "model.xi", "distribution": "uniform", "min": 200.0, "max": 1000.0},
                   {"key": "release.thickness_factor", "distribution": "normal", "mean": 1.0, "sd": 0.2,
                    "lower": 0.5}],
    "runout_length_along_path_m": {"p10": 100.0, "p50": 120.0, "p90": 140.0, "mean": 120.0, "min": 100.0,
                                   "max": 140.0},
    "fahrboeschung_ratio_H_over_L": {"p10": 0.4, "p50": 0.45, "p90": 0.5, "mean": 0.45, "min": 0.4, "max": 0.5},
    "area_affected_m2": {"p10": 1000.0, "p50": 1100.0, "p90": 1250.0, "mean": 1100.0, "min": 1000.0,
                         "max": 1250.0},
    "percentile_accuracy": {"max_relative_error_depth": 0.1274}})";
  std::ofstream(d / "ens" / "members.csv")
      << "member,status,model.xi,release.thickness_factor,runout_m,drop_height_m,reach_m,H_over_L,area_affected_m2,"
         "ended_by,diagnosis\n"
         "0,ok,300,1.1,100,40,100,0.4,1000,\"kinetic energy below the stop fraction, of its peak\",\"\"\n"
         "1,ok,900,0.9,140,40,140,0.5,1250,\"duration\",\"\"\n"
         "2,failed,500,1.0,0,0,0,0,0,\"\",\"injected failure, at step 1\"\n"
         "3,ok,700,1.0,120,40,120,0.45,1100,\"duration\",\"\"\n"
         "4,ok,450,1.2,125,40,125,0.46,1150,\"duration\",\"\"\n";
  for (const char* png : {"prob_max_pressure_gt_30000Pa.png", "prob_max_depth_gt_0.5m.png", "p90_max_depth.png",
                          "p10_max_depth.png", "mean_max_depth.png", "p50_max_speed.png"})
    std::ofstream(d / "ens" / png) << "x";
  const nlohmann::json sj = nlohmann::json::parse(std::ifstream(d / "ens" / "summary.json"));
  const RunPart p = ensemble_part(d / "ens", sj, "ens", "ens_");
  ASSERT_TRUE(p.present);
  std::size_t at = 0;
  for (const char* part :
       {"<h2>Ensemble (geohaz-ensemble)</h2>",
        "<table class=ensemble-overview>",
        "members that failed</td><td class=v>1",
        "<table class=ensemble-parameters>",
        "<td title=\"model.xi\">Voellmy turbulence coefficient ξ</td><td class=unit>m/s²</td><td>uniform on [200, "
        "1000]",
        "<td class=v>300 – 900</td>",  // drawn over the members that ran, not the failed one's 500 … nor below
        "<td title=\"release.thickness_factor\">release thickness factor</td><td class=unit></td>",
        "truncated to [0.5, ∞]",
        "<table class=ensemble-stats>",
        "data-key=\"runout_length_along_path_m.p10\" data-value=\"100.0\">100 m<",
        "<table class=ensemble-failed>",
        "injected failure",
        "src=\"ens/prob_max_depth_gt_0.5m.png\"",
        "src=\"ens/prob_max_pressure_gt_30000Pa.png\"",
        "peak dynamic pressure ρv² exceeds 30 kPa",
        "src=\"ens/mean_max_depth.png\"",
        "src=\"ens/p10_max_depth.png\"",
        "src=\"ens/p90_max_depth.png\"",
        "within 12.74%",
        "Mean and percentile maps of the peak speed",  // speed and pressure maps too (issue #33)
        "src=\"ens/p50_max_speed.png\"",
        "speed classes (output.map_speed_classes)",
        "src=\"report_files/ens_runout_m_distribution.svg\"",
        "of the 4 members that ran",
        "src=\"report_files/ens_H_over_L_distribution.svg\""}) {
    const auto next = p.html.find(part, at);
    EXPECT_NE(next, std::string::npos) << part;
    if (next != std::string::npos) at = next;
  }
  // Depth classes and the order of the probability maps: the summary's products order is not
  // given here, so by name; the map pictures are the part's, not shown again among the pictures.
  for (const char* f : {"prob_max_depth_gt_0.5m.png", "mean_max_depth.png", "p10_max_depth.png", "p50_max_speed.png"})
    EXPECT_NE(std::find(p.shown.begin(), p.shown.end(), f), p.shown.end()) << f;
  ASSERT_EQ(p.plots.size(), 2u);
  EXPECT_EQ(attributes(p.plots[0].second, "data-members").at(0), 4.0);  // the failed member left out
  ASSERT_EQ(p.headline.size(), 4u);
  EXPECT_EQ(p.headline[0].value, "4 of 5");
  EXPECT_EQ(p.headline[1].value, "100 m / 120 m / 140 m");
  EXPECT_EQ(p.headline[3].value, "1250 m²");
  // Not an ensemble: no part; an ensemble without its member table: an input error.
  EXPECT_FALSE(ensemble_part(d / "ens", nlohmann::json{{"model", "debris-runout"}}, "ens", "ens_").present);
  fs::remove(d / "ens" / "members.csv");
  EXPECT_THROW(ensemble_part(d / "ens", sj, "ens", "ens_"), geohaz::InputError);
  fs::remove_all(d);
}
