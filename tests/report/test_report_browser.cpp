// The report page in a real browser (issue #16, docs/report.md "Tested in a browser"): a small
// results folder (a run-out run with a map, a time series and a force CSV, a biaxial run with two
// crack pictures) → geohaz-report → headless Chromium. The page marks itself on load (an inline
// script counts the <img> elements that decoded and any load or script error in #page-check's
// attributes); --dump-dom prints the DOM after load, so the test reads the marks there. Chromium's
// own log (--enable-logging=stderr) must hold no console message. A screenshot is taken and must
// show the page. As a control, one picture is then deleted and the page must report it.
// A geohaz-calibrate folder's back-analysis part is checked the same way, and a geohaz-ensemble
// folder made by the app on a small case (its overview, maps and distributions, the percentiles
// recomputed from its members.csv).
// Skipped (with a message) only when no chromium is installed; scripts/setup installs it.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <memory>
#include <sstream>
#include <string>
#include <vector>

#include "calibration_results.hpp"
#ifdef GEOHAZ_ENSEMBLE_EXE
#include "ensemble_case.hpp"
#endif
#include "geohaz/core/app.hpp"
#include "geohaz/core/config.hpp"
#include "geohaz/core/errors.hpp"
#include "geohaz/core/raster.hpp"
#include "geohaz/core/raster_extra.hpp"
#include "geohaz/report/report.hpp"
#include "geohaz/runout/run.hpp"
#include "run_command.hpp"

namespace fs = std::filesystem;
using geohaz::testing::run_command;

namespace {

void write_file(const fs::path& p, const std::string& text) {
  std::ofstream out(p);
  out << text;
}

std::string slurp(const fs::path& p) {
  std::ifstream in(p);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

std::string find_chromium() {
  for (const char* name : {"chromium", "chromium-browser", "google-chrome"}) {
    const auto r = run_command(std::string("command -v ") + name);
    if (r.code == 0 && !r.output.empty()) return r.output.substr(0, r.output.find('\n'));
  }
  return "";
}

/// The attribute `name` of #page-check in a dumped DOM (-1 when absent). Plain string search:
/// std::regex trips GCC 12's -Wmaybe-uninitialized in the sanitizer build (-Werror in CI).
int page_mark(const std::string& dom, const std::string& name) {
  const auto open = dom.find("<div id=\"page-check\"");
  if (open == std::string::npos) return -1;
  const auto close = dom.find('>', open);
  if (close == std::string::npos) return -1;
  const std::string tag = dom.substr(open, close - open);
  const std::string key = " " + name + "=\"";
  const auto at = tag.find(key);
  if (at == std::string::npos) return -1;
  const auto first = at + key.size(), last = tag.find('"', first);
  if (last == std::string::npos || last == first) return -1;
  const std::string digits = tag.substr(first, last - first);
  if (digits.find_first_not_of("0123456789") != std::string::npos) return -1;
  return std::stoi(digits);
}

/// A small results folder with what the apps write.
/// A north-up grid of nx × ny cells of 5 m in UTM (the maps of the report's test folders), all 0.
geohaz::Raster grid_5m(int nx, int ny) {
  geohaz::Raster g;
  g.nx = nx;
  g.ny = ny;
  g.geotransform = {600000.0, 5.0, 0.0, 5100000.0, 0.0, -5.0};
  g.data.resize(static_cast<std::size_t>(nx) * ny);
  return g;
}

void make_results(const fs::path& root) {
  const fs::path run = root / "1-runout", lab = root / "2-rock-biaxial";
  fs::create_directories(run);
  fs::create_directories(lab);
  write_file(run / "summary.json", R"({"model": "debris-runout", "area_affected_m2": 138975.0,
    "fahrboeschung": {"ratio_H_over_L": 0.5132, "reach_m": 2802.2, "drop_height_m": 1438.0},
    "max_pressure_pa": 970929.6, "max_speed_m_per_s": 22.6, "simulated_time_s": 402.9,
    "volumes_m3": {"release_read": 17700.0, "deposit_raster": 17678.4}, "barrier_peak_force_N": 1.2e5,
    "wall_time_s": 35.9})");
  write_file(run / "config.resolved.toml", "[model]\nfriction = 'voellmy'\nmu = 0.2\nxi = 500.0\ndensity = 2000.0\n");
  write_file(run / "series.csv",
             "time_s,step,front_travel_m,max_speed_m_per_s,mobile_volume_m3,deposited_volume_m3\n"
             "0,0,0,0,100,0\n10,5,150,12,80,20\n20,9,260,8,30,70\n30,12,300,1,0,100\n");
  write_file(run / "barrier_forces.csv", "time_s,force_N\n0,0\n10,1.2e5\n20,4e4\n30,0\n");
  // A map as debris-runout draws it: a cone with a flow over one flank.
  geohaz::Raster dem = grid_5m(120, 90);
  geohaz::Raster depth = dem;
  for (int r = 0; r < dem.ny; ++r)
    for (int c = 0; c < dem.nx; ++c) {
      dem.at(c, r) = 1500.0 - 2.0 * std::hypot(c - 60.0, r - 45.0);
      depth.at(c, r) = (c > 60 && c < 100 && std::abs(r - 45) < 10) ? 0.5 + 0.05 * (c - 60) : 0.0;
    }
  geohaz::QuicklookOptions o;
  o.title = "peak flow depth";
  o.unit = "m";
  o.overlay_min = 0.01;
  o.crop_margin_m = 100.0;
  o.scale_bar = true;
  o.north_arrow = true;
  o.lines = {{{600400.0, 4999850.0 + 200.0}, {600400.0, 4999850.0 + 260.0}}};
  geohaz::write_quicklook_png(run / "max_depth.png", dem, &depth, o);
  // The biaxial run: two crack pictures named so that a plain sort puts 10 MPa before 5 MPa.
  write_file(lab / "summary.json", R"({"model": "dem-avalanche", "test": "biaxial-compression",
    "mohr_coulomb": {"cohesion_Pa": 2.14e7, "friction_angle_deg": 33.6},
    "tests": [{"name": "sigma3_5MPa", "confining_stress_Pa": 5e6, "peak_stress_Pa": 9.76e7},
              {"name": "sigma3_10MPa", "confining_stress_Pa": 1e7, "peak_stress_Pa": 1.146e8}]})");
  write_file(
      lab / "curve_sigma3_5MPa.csv",
      "time_s,axial_strain,axial_stress_Pa,lateral_stress_Pa\n0,0,5e6,5e6\n1e-3,1e-3,5e7,5e6\n2e-3,2e-3,9e7,5e6\n");
  for (const char* name : {"cracks_sigma3_10MPa.png", "cracks_sigma3_5MPa.png"}) {
    geohaz::Image img(80, 120);
    img.fill_circle(40, 60, 20, {220, 30, 30});
    geohaz::write_png(lab / name, img);
  }
}

}  // namespace

TEST(ReportInBrowser, EveryImageDecodesWithoutErrorsAndTheScreenshotShowsThePage) {
  const fs::path root = fs::temp_directory_path() /
                        ("geohaz_report_browser_" + std::to_string(::testing::UnitTest::GetInstance()->random_seed()));
  fs::remove_all(root);
  make_results(root / "results");
  const fs::path results = root / "results";

  const auto gen =
      run_command(std::string("'") + GEOHAZ_REPORT_EXE + "' '" + results.string() + "' --title 'test page'");
  ASSERT_EQ(gen.code, 0) << gen.output;
  const std::string html = slurp(results / "report.html");
  // Crack maps in stress order, the maps before the plots, every CSV with a time column plotted.
  const auto p5 = html.find("cracks_sigma3_5MPa.png"), p10 = html.find("cracks_sigma3_10MPa.png");
  ASSERT_NE(p5, std::string::npos);
  ASSERT_NE(p10, std::string::npos);
  EXPECT_LT(p5, p10);
  EXPECT_TRUE(fs::exists(results / "report_files" / "1-runout_series.svg"));
  EXPECT_TRUE(fs::exists(results / "report_files" / "1-runout_barrier_forces.svg"));
  EXPECT_TRUE(fs::exists(results / "report_files" / "2-rock-biaxial_curve_sigma3_5MPa.svg"));
  EXPECT_NE(html.find("Coulomb friction coefficient μ"), std::string::npos);
  EXPECT_NE(html.find(">barrier_peak_force_N<"), std::string::npos);  // an undeclared key still shows, as named
  EXPECT_EQ(html.find("http://"), html.find("http://www.w3.org"));    // no network (SVG namespace only)
  EXPECT_EQ(html.find("https://"), std::string::npos);
  std::size_t images = 0;
  for (auto p = html.find("<img"); p != std::string::npos; p = html.find("<img", p + 1)) ++images;
  EXPECT_EQ(images, 3u + 3u);  // 3 PNGs, 3 SVG plots

  const std::string chromium = find_chromium();
  if (chromium.empty()) GTEST_SKIP() << "chromium is not installed (scripts/setup installs the Debian package)";
  // No D-Bus in CI containers: say so rather than let Chromium wait for it.
  const std::string common = "DBUS_SESSION_BUS_ADDRESS=disabled: '" + chromium +
                             "' --headless --no-sandbox --disable-gpu --hide-scrollbars "
                             "--user-data-dir='" +
                             (root / "profile").string() + "' --virtual-time-budget=10000 ";
  const std::string url = "'file://" + (results / "report.html").string() + "'";

  // One Chromium run prints the DOM after load, its log, and takes the screenshot.
  const fs::path shot = root / "report.png";
  const auto dom =
      run_command(common + "--enable-logging=stderr --v=0 --window-size=1280,1600 --dump-dom --screenshot='" +
                  shot.string() + "' " + url);
  ASSERT_EQ(dom.code, 0) << dom.output;
  EXPECT_EQ(page_mark(dom.output, "data-images"), static_cast<int>(images)) << dom.output;
  EXPECT_EQ(page_mark(dom.output, "data-decoded"), static_cast<int>(images)) << dom.output;
  EXPECT_EQ(page_mark(dom.output, "data-errors"), 0) << dom.output;
  // Every map carries its legend, coordinate ticks and scale bar (issue #33).
  EXPECT_EQ(page_mark(dom.output, "data-map-problems"), 0) << dom.output;
  EXPECT_TRUE(geohaz::check_map_png(results / "1-runout" / "max_depth.png").empty());
  EXPECT_EQ(dom.output.find(":CONSOLE"), std::string::npos) << dom.output;  // nothing logged by the page

  const geohaz::Image img = geohaz::read_image(shot);
  EXPECT_EQ(img.width, 1280);
  EXPECT_EQ(img.height, 1600);
  // The page is drawn: dark text and the hillshade's greys, not a blank window.
  int dark = 0, mid_grey = 0;
  for (std::size_t i = 0; i < img.rgb.size(); i += 3) {
    const int r = img.rgb[i], g = img.rgb[i + 1], b = img.rgb[i + 2];
    dark += r < 60 && g < 60 && b < 60;
    mid_grey += r == g && g == b && r > 80 && r < 200;
  }
  EXPECT_GT(dark, 2000);
  EXPECT_GT(mid_grey, 2000);

  // Control: maps drawn without a scale bar, without coordinates, or with the legend box blanked
  // are each reported by the map check, and the page shows it.
  {
    geohaz::Raster dem;
    dem.nx = 120;
    dem.ny = 90;
    dem.geotransform = {600000.0, 5.0, 0.0, 5100000.0, 0.0, -5.0};
    dem.data.resize(static_cast<std::size_t>(dem.nx) * dem.ny);
    for (int r = 0; r < dem.ny; ++r)
      for (int c = 0; c < dem.nx; ++c) dem.at(c, r) = 1500.0 - 2.0 * std::hypot(c - 60.0, r - 45.0);
    geohaz::QuicklookOptions o;
    o.title = "peak flow depth";
    o.unit = "m";
    o.scale_bar = true;
    const fs::path bad = root / "bad";
    fs::create_directories(bad);
    o.scale_bar = false;
    geohaz::write_quicklook_png(bad / "no_scale.png", dem, &dem, o);
    o.scale_bar = true;
    o.coordinates = false;
    geohaz::write_quicklook_png(bad / "no_ticks.png", dem, &dem, o);
    o.coordinates = true;
    const geohaz::MapLayout lay = geohaz::write_quicklook_png(bad / "no_legend.png", dem, &dem, o);
    geohaz::Image img = geohaz::read_image(bad / "no_legend.png");
    for (int y = lay.legend_y; y < lay.legend_y + lay.legend_h; ++y)
      for (int x = lay.legend_x; x < lay.legend_x + lay.legend_w; ++x) img.set(x, y, {255, 255, 255});
    const auto text = [&] {  // keep the recorded layout: rewrite with the same text chunk
      return std::vector<std::pair<std::string, std::string>>{
          {"geohaz_map", "frame=" + std::to_string(lay.frame_x) + "," + std::to_string(lay.frame_y) + "," +
                             std::to_string(lay.frame_w) + "," + std::to_string(lay.frame_h) +
                             ";legend=" + std::to_string(lay.legend_x) + "," + std::to_string(lay.legend_y) + "," +
                             std::to_string(lay.legend_w) + "," + std::to_string(lay.legend_h) +
                             ";scale_bar=" + std::to_string(lay.scale_bar_x) + "," + std::to_string(lay.scale_bar_y) +
                             "," + std::to_string(lay.scale_bar_px) + ";ticks=" + std::to_string(lay.x_ticks) + "," +
                             std::to_string(lay.y_ticks) + ";scale=1"}};
    }();
    geohaz::write_png(bad / "no_legend.png", img, text);
    const auto has = [](const std::vector<std::string>& v, const std::string& what) {
      return std::find(v.begin(), v.end(), what) != v.end();
    };
    const auto p1 = geohaz::check_map_png(bad / "no_scale.png"), p2 = geohaz::check_map_png(bad / "no_ticks.png"),
               p3 = geohaz::check_map_png(bad / "no_legend.png");
    EXPECT_TRUE(has(p1, "no scale bar")) << p1.size();
    EXPECT_FALSE(has(p1, "no legend"));
    EXPECT_TRUE(has(p2, "no coordinate ticks")) << p2.size();
    EXPECT_FALSE(has(p2, "no scale bar"));
    EXPECT_TRUE(has(p3, "no legend")) << p3.size();
    EXPECT_FALSE(has(p3, "no coordinate ticks"));
    // In the page: the map without a scale bar among the run's pictures is flagged.
    fs::copy_file(bad / "no_scale.png", results / "1-runout" / "max_speed.png");
    ASSERT_EQ(run_command(std::string("'") + GEOHAZ_REPORT_EXE + "' '" + results.string() + "'").code, 0);
    const auto flagged = run_command(common + "--dump-dom " + url);
    EXPECT_EQ(page_mark(flagged.output, "data-map-problems"), 1) << flagged.output;
    fs::remove(results / "1-runout" / "max_speed.png");
    ASSERT_EQ(run_command(std::string("'") + GEOHAZ_REPORT_EXE + "' '" + results.string() + "'").code, 0);
  }

  // Control: a picture that is gone is reported by the page (so the marks above can fail).
  fs::remove(results / "2-rock-biaxial" / "cracks_sigma3_10MPa.png");
  const auto broken = run_command(common + "--dump-dom " + url);
  ASSERT_EQ(broken.code, 0) << broken.output;
  EXPECT_EQ(page_mark(broken.output, "data-decoded"), static_cast<int>(images) - 1);
  EXPECT_GE(page_mark(broken.output, "data-errors"), 1);
  EXPECT_NE(broken.output.find("cracks_sigma3_10MPa.png"), std::string::npos);

  std::error_code ec;
  fs::remove_all(root, ec);
}

// Issue #31: a geohaz-calibrate folder in the page — the best set, the acceptable-set table and
// score plot, the Morris ranking, the comparison map and the observed-against-modelled thalweg
// profile, all in the run's section; every picture decodes in Chromium, no error, no map problem.
TEST(ReportInBrowser, CalibrationShowsBestSetAcceptableSetMorrisMapAndProfile) {
  const fs::path root = fs::temp_directory_path() /
                        ("geohaz_report_cal_" + std::to_string(::testing::UnitTest::GetInstance()->random_seed()));
  fs::remove_all(root);
  const fs::path results = root / "results";
  calibration_results::make(results / "calibrate-alr");
  const auto gen = run_command(std::string("'") + GEOHAZ_REPORT_EXE + "' '" + results.string() + "'");
  ASSERT_EQ(gen.code, 0) << gen.output;
  const std::string html = slurp(results / "report.html");
  const auto section = html.find("<section id=\"calibrate-alr\">");
  ASSERT_NE(section, std::string::npos);
  // In reading order inside the run's section: best set, misfit, acceptable set, Morris, the score
  // plot, the map, the profile plots.
  std::size_t at = section;
  for (const char* part :
       {"<h2>Back-analysis (geohaz-calibrate)</h2>", "<table class=calibration-best>",
        "<table class=calibration-misfit>", "<table class=calibration-acceptable>", "<table class=calibration-morris>",
        "src=\"calibrate-alr/acceptable.svg\"", "src=\"calibrate-alr/comparison.png\"",
        "src=\"report_files/calibrate-alr_thalweg_width.svg\"",
        "src=\"report_files/calibrate-alr_thalweg_deposit.svg\"", "</section>"}) {
    const auto next = html.find(part, at);
    EXPECT_NE(next, std::string::npos) << part;
    if (next != std::string::npos) at = next;
  }
  // The overview carries the best set; nothing is shown twice (the map and the profile CSV are
  // the part's, not repeated by the generic pictures and plots).
  EXPECT_NE(html.find("calibration: best critical slope gradient i_cr</td><td class=v>0.1707"), std::string::npos);
  std::size_t images = 0;
  for (auto p = html.find("<img"); p != std::string::npos; p = html.find("<img", p + 1)) ++images;
  EXPECT_EQ(images, 4u);
  EXPECT_FALSE(fs::exists(results / "report_files" / "calibrate-alr_thalweg_profile.svg"));
  EXPECT_TRUE(fs::exists(results / "report_files" / "calibrate-alr_thalweg_width.svg"));

  const std::string chromium = find_chromium();
  if (chromium.empty()) GTEST_SKIP() << "chromium is not installed (scripts/setup installs the Debian package)";
  const auto dom = run_command(
      "DBUS_SESSION_BUS_ADDRESS=disabled: '" + chromium + "' --headless --no-sandbox --disable-gpu --user-data-dir='" +
      (root / "profile").string() + "' --virtual-time-budget=10000 --enable-logging=stderr --v=0 --dump-dom 'file://" +
      (results / "report.html").string() + "'");
  ASSERT_EQ(dom.code, 0) << dom.output;
  EXPECT_EQ(page_mark(dom.output, "data-images"), static_cast<int>(images)) << dom.output;
  EXPECT_EQ(page_mark(dom.output, "data-decoded"), static_cast<int>(images)) << dom.output;
  EXPECT_EQ(page_mark(dom.output, "data-errors"), 0) << dom.output;
  EXPECT_EQ(page_mark(dom.output, "data-map-problems"), 0) << dom.output;
  EXPECT_EQ(dom.output.find(":CONSOLE"), std::string::npos) << dom.output;
  // Control: the score plot gone, the page says so.
  fs::remove(results / "calibrate-alr" / "acceptable.svg");
  const auto broken =
      run_command("DBUS_SESSION_BUS_ADDRESS=disabled: '" + chromium +
                  "' --headless --no-sandbox --disable-gpu --user-data-dir='" + (root / "profile").string() +
                  "' --virtual-time-budget=10000 --dump-dom 'file://" + (results / "report.html").string() + "'");
  EXPECT_EQ(page_mark(broken.output, "data-decoded"), static_cast<int>(images) - 1) << broken.output;
  std::error_code ec;
  fs::remove_all(root, ec);
}

// Issue #33 item 6: `geohaz-report --pdf` prints the page to an A4 PDF, each run from a new page.
// pdfinfo gives the page count and size, pdftoppm renders the first page, which must not be blank.
namespace {

// Adds to a run's summary a table the report shows open (the barriers), 12 columns of values that
// do not break on screen (td.v is nowrap there), about 1,700 px wide: as the SPH run's tables of
// structure loads and materials, which made Chromium lay the printed page out wider than A4 and
// scale it down, so a map limited by the page's height came out at 0.67 of it.
void write_wide_table(const fs::path& summary) {
  nlohmann::json j = nlohmann::json::parse(std::ifstream(summary));
  for (const char* name : {"check dam upstream", "check dam downstream"}) {
    nlohmann::json row = {{"name", name}};
    for (int k = 0; k < 11; ++k) row["load_" + std::to_string(k)] = std::to_string(k + 1) + "23.456 kN/m at 12.5 s";
    j["barriers"].push_back(row);
  }
  write_file(summary, j.dump(1));
}

// A map taller than wide, as a valley running north-south gives (the demo's run-out): printed at
// the page's width it would be taller than A4.
void write_tall_map(const fs::path& png) {
  geohaz::Raster tall = grid_5m(40, 160);
  geohaz::Raster speed = tall;
  for (int r = 0; r < tall.ny; ++r)
    for (int c = 0; c < tall.nx; ++c) {
      tall.at(c, r) = 1500.0 - 4.0 * r + 0.5 * std::abs(c - 20.0);
      speed.at(c, r) = std::abs(c - 20) < 4 ? 0.1 * r : 0.0;
    }
  geohaz::QuicklookOptions o;
  o.title = "peak speed";
  o.unit = "m/s";
  o.overlay_min = 0.01;
  o.scale_bar = true;
  o.north_arrow = true;
  geohaz::write_quicklook_png(png, tall, &speed, o);
}

}  // namespace

TEST(ReportInBrowser, PdfIsA4WithARunPerPageAndAFirstPageThatShowsSomething) {
  if (geohaz::report::find_chromium().empty()) GTEST_SKIP() << "chromium is not installed (scripts/setup)";
  if (run_command("command -v pdfinfo && command -v pdftoppm").code != 0)
    GTEST_SKIP() << "poppler-utils is not installed (scripts/setup)";
  const fs::path root = fs::temp_directory_path() /
                        ("geohaz_report_pdf_" + std::to_string(::testing::UnitTest::GetInstance()->random_seed()));
  fs::remove_all(root);
  make_results(root / "results");
  const fs::path results = root / "results";
  write_tall_map(results / "1-runout" / "max_speed.png");
  write_wide_table(results / "1-runout" / "summary.json");
  const auto gen = run_command(std::string("'") + GEOHAZ_REPORT_EXE + "' '" + results.string() + "' --pdf");
  ASSERT_EQ(gen.code, 0) << gen.output;
  ASSERT_TRUE(fs::exists(results / "report.pdf"));
  EXPECT_FALSE(fs::exists(results / "report.pdf.partial"));
  const auto info = run_command("pdfinfo '" + (results / "report.pdf").string() + "'");
  ASSERT_EQ(info.code, 0) << info.output;
  // A4 is 595 × 842 pt (210 × 297 mm); pdfinfo names it.
  EXPECT_NE(info.output.find(" pts (A4)"), std::string::npos) << info.output;
  const auto pages_at = info.output.find("Pages:");
  ASSERT_NE(pages_at, std::string::npos);
  const int pages = std::stoi(info.output.substr(pages_at + 6));
  // The title and overview, then each of the two runs from a new page; the biaxial run fits one.
  EXPECT_GE(pages, 3) << info.output;
  EXPECT_LE(pages, 8) << info.output;
  const auto text = run_command("pdftotext -f 2 -l 2 '" + (results / "report.pdf").string() + "' -");
  EXPECT_EQ(text.output.rfind("1-runout", 0), 0u) << text.output.substr(0, 200);  // page 2 opens the first run
  // No picture is cut by a page break: a cut leaves the rest of the picture (a map's legend) alone on
  // the next page, a page without text; every page of the report carries a heading or a caption.
  for (int p = 1; p <= pages; ++p) {
    const auto page = run_command("pdftotext -f " + std::to_string(p) + " -l " + std::to_string(p) + " '" +
                                  (results / "report.pdf").string() + "' -");
    EXPECT_NE(page.output.find_first_not_of(" \t\n\f"), std::string::npos) << "page " << p << " has no text";
  }
  // The tall map printed at its full size, 230 mm high (the print style's max-height), not shrunk
  // with the whole page to fit a wide table: its printed height from pdfimages' resolution.
  const geohaz::Image tall = geohaz::read_image(results / "1-runout" / "max_speed.png");
  const auto list = run_command("pdfimages -list '" + (results / "report.pdf").string() + "'");
  ASSERT_EQ(list.code, 0) << list.output;
  std::istringstream rows(list.output);
  std::string line;
  double printed_mm = -1.0;
  while (std::getline(rows, line)) {
    // page num type width height color comp bpc enc interp object ID x-ppi y-ppi size ratio
    std::istringstream f(line);
    std::string page, num, type, enc, interp, object, id, colour;
    int width = 0, height = 0, comp = 0, bpc = 0;
    double xppi = 0.0, yppi = 0.0;
    if (!(f >> page >> num >> type >> width >> height >> colour >> comp >> bpc >> enc >> interp >> object >> id >>
          xppi >> yppi))
      continue;
    if (type == "image" && width == tall.width && height == tall.height && yppi > 0.0)
      printed_mm = height / yppi * 25.4;
  }
  EXPECT_NEAR(printed_mm, 230.0, 230.0 * 0.03) << list.output;
  const auto ppm = run_command("pdftoppm -f 1 -l 1 -r 40 -png '" + (results / "report.pdf").string() + "' '" +
                               (root / "page").string() + "'");
  ASSERT_EQ(ppm.code, 0) << ppm.output;
  fs::path first;
  for (const auto& e : fs::directory_iterator(root))
    if (e.path().extension() == ".png") first = e.path();
  ASSERT_FALSE(first.empty());
  const geohaz::Image img = geohaz::read_image(first);
  int dark = 0;
  for (std::size_t i = 0; i < img.rgb.size(); i += 3) dark += img.rgb[i] < 100 && img.rgb[i + 1] < 100;
  EXPECT_GT(dark, 200);  // the title and the overview table, not a white page
  std::error_code ec;
  fs::remove_all(root, ec);
}

// Issue #29 item 6: the report written into a run folder names the run after the folder, writes
// nothing hidden, and lists its files in the run's manifest, so the next run into the folder
// (run_in_output_dir, the --out policy of every app) cleans them instead of refusing.
TEST(ReportInRunFolder, NamesTheRunAfterItsFolderAndTheNextRunAcceptsTheFolder) {
  const fs::path root = fs::temp_directory_path() /
                        ("geohaz_report_run_" + std::to_string(::testing::UnitTest::GetInstance()->random_seed()));
  fs::remove_all(root);
  const fs::path run = root / "my-run";
  const auto body = [&] {
    write_file(run / "summary.json", R"({"model": "debris-runout", "max_speed_m_s": 12.5})");
    write_file(run / "series.csv", "time_s,max_speed_m_s\n0,0\n1,5\n2,12.5\n");
    return 0;
  };
  fs::create_directories(run);
  ASSERT_EQ(geohaz::run_in_output_dir(run, "debris-runout", {}, body), 0);
  geohaz::report::write_report(run, "one run");
  const std::string html = slurp(run / "report.html");
  EXPECT_NE(html.find("<h2>my-run</h2>"), std::string::npos);
  EXPECT_EQ(html.find("<h2>.</h2>"), std::string::npos);
  for (auto it = fs::recursive_directory_iterator(run); it != fs::recursive_directory_iterator(); ++it)
    EXPECT_NE(it->path().filename().string().front(), '.') << it->path();
  EXPECT_TRUE(fs::exists(run / "report_files" / "my-run_series.svg"));
  const std::string manifest = slurp(run / geohaz::kOutputManifest);
  EXPECT_NE(manifest.find("report.html\n"), std::string::npos) << manifest;
  EXPECT_NE(manifest.find("report_files/my-run_series.svg\n"), std::string::npos) << manifest;
  // The next run into the folder: accepted, and the old report is gone with the old run.
  EXPECT_NO_THROW(geohaz::run_in_output_dir(run, "debris-runout", {}, body));
  EXPECT_FALSE(fs::exists(run / "report.html"));
  EXPECT_FALSE(fs::exists(run / "report_files"));
  // Control: a file the run did not write still stops the next run (exit 2).
  write_file(run / "notes.txt", "mine");
  EXPECT_THROW(geohaz::run_in_output_dir(run, "debris-runout", {}, body), geohaz::InputError);
  std::error_code ec;
  fs::remove_all(root, ec);
}

#ifdef GEOHAZ_ENSEMBLE_EXE
namespace {

/// The numbers of a members.csv column over the members with status ok (the test's own reading:
/// no quoted cell before the columns it reads).
std::vector<double> ok_column(const fs::path& csv, const std::string& name) {
  std::ifstream in(csv);
  std::string line;
  std::getline(in, line);
  std::vector<std::string> head;
  std::stringstream hs(line);
  for (std::string c; std::getline(hs, c, ',');) head.push_back(c);
  const auto col = static_cast<std::size_t>(std::find(head.begin(), head.end(), name) - head.begin());
  const auto st = static_cast<std::size_t>(std::find(head.begin(), head.end(), "status") - head.begin());
  std::vector<double> v;
  while (std::getline(in, line)) {
    std::vector<std::string> cells;
    std::stringstream ls(line);
    for (std::string c; std::getline(ls, c, ',');) cells.push_back(c);
    if (cells.size() > std::max(col, st) && cells[st] == "ok") v.push_back(std::stod(cells[col]));
  }
  return v;
}

/// The number in data-value of the page's cell data-key="KEY" (NaN when absent).
double page_value(const std::string& html, const std::string& key) {
  const std::string k = "data-key=\"" + key + "\" data-value=\"";
  const auto at = html.find(k);
  return at == std::string::npos ? std::nan("") : std::stod(html.substr(at + k.size()));
}

/// The text of the page's cell data-key="KEY".
std::string page_text(const std::string& html, const std::string& key) {
  const auto at = html.find("data-key=\"" + key + "\"");
  if (at == std::string::npos) return "";
  const auto open = html.find('>', at) + 1;
  return html.substr(open, html.find('<', open) - open);
}

}  // namespace

// Issue #33 item 4: the ensemble's section draws the ensemble. A real geohaz-ensemble folder (the
// one-particle case of tests/runout/ensemble_case.hpp: 7 Monte Carlo members, one failing on
// purpose, μ uniform, the density fixed) → geohaz-report → Chromium.
TEST(ReportInBrowser, EnsembleSectionDrawsMapsAndDistributionsOfTheMembers) {
  const fs::path root = fs::temp_directory_path() /
                        ("geohaz_report_ens_" + std::to_string(::testing::UnitTest::GetInstance()->random_seed()));
  fs::remove_all(root);
  const fs::path work = root / "case", results = root / "results", out = results / "ens";
  fs::create_directories(work);
  ensemble_case::make_case(work);
  ensemble_case::write_ensemble(work / "ens.toml", 7, "monte_carlo", "inject_failure = [2]",
                                "[[ensemble.parameter]]\nkey = \"model.density\"\ndistribution = \"fixed\"\n"
                                "value = 2000.0\n");
  const auto ens = run_command(std::string("'") + GEOHAZ_ENSEMBLE_EXE + "' '" + (work / "ens.toml").string() +
                               "' --threads 1 --quiet --out '" + out.string() + "'");
  ASSERT_EQ(ens.code, 0) << ens.output;
  const auto gen = run_command(std::string("'") + GEOHAZ_REPORT_EXE + "' '" + results.string() + "'");
  ASSERT_EQ(gen.code, 0) << gen.output;
  const std::string html = slurp(results / "report.html");
  const auto section = html.find("<section id=\"ens\">");
  ASSERT_NE(section, std::string::npos);
  // In reading order: the overview, the parameters, the percentiles, the probability maps (every
  // one), the mean and percentile maps, the two distributions.
  std::size_t at = section;
  for (const char* part : {"<div class=ensemble>",
                           "<table class=ensemble-overview>",
                           "members that failed</td><td class=v>1",
                           "<table class=ensemble-parameters>",
                           "<table class=ensemble-stats>",
                           "src=\"ens/prob_max_depth_gt_1e-06m.png\"",
                           "src=\"ens/prob_max_pressure_gt_1000Pa.png\"",
                           "src=\"ens/prob_intensity_ge_2.png\"",
                           "src=\"ens/mean_max_depth.png\"",
                           "src=\"ens/p10_max_depth.png\"",
                           "src=\"ens/p50_max_depth.png\"",
                           "src=\"ens/p90_max_depth.png\"",
                           "src=\"ens/mean_max_speed.png\"",
                           "src=\"ens/p10_max_speed.png\"",
                           "src=\"ens/p50_max_speed.png\"",
                           "src=\"ens/p90_max_speed.png\"",
                           "src=\"ens/mean_max_pressure.png\"",
                           "src=\"ens/p10_max_pressure.png\"",
                           "src=\"ens/p50_max_pressure.png\"",
                           "src=\"ens/p90_max_pressure.png\"",
                           "src=\"report_files/ens_runout_m_distribution.svg\"",
                           "src=\"report_files/ens_H_over_L_distribution.svg\"",
                           "</section>"}) {
    const auto next = html.find(part, at);
    EXPECT_NE(next, std::string::npos) << part;
    if (next != std::string::npos) at = next;
  }
  std::size_t images = 0;
  for (auto p = html.find("<img"); p != std::string::npos; p = html.find("<img", p + 1)) ++images;
  EXPECT_EQ(images, 3u + 3u * 4u + 2u);  // no picture shown twice
  // The speed and pressure mean and percentile maps (issue #33) decode, 1800 px wide, and carry a
  // legend, coordinate ticks and a scale bar (check_map_png probes the layout they record).
  for (const char* field : {"max_speed", "max_pressure"})
    for (const char* stat : {"mean_", "p10_", "p50_", "p90_"}) {
      const fs::path png = out / (std::string(stat) + field + ".png");
      ASSERT_TRUE(fs::exists(png)) << png;
      EXPECT_EQ(geohaz::read_image(png).width, 1800) << png;
      EXPECT_TRUE(geohaz::check_map_png(png).empty()) << png;
    }

  // P10/P50/P90 in the page = the nearest-rank percentiles of the members' CSV, recomputed here.
  const auto nearest_rank = [](std::vector<double> v, double q) {
    std::sort(v.begin(), v.end());
    const auto k = static_cast<std::size_t>(std::ceil(q / 100.0 * static_cast<double>(v.size()) - 1e-9));
    return v[std::max<std::size_t>(k, 1) - 1];
  };
  for (const auto& [column, key, unit] :
       {std::tuple<const char*, const char*, const char*>{"runout_m", "runout_length_along_path_m", "m"},
        {"H_over_L", "fahrboeschung_ratio_H_over_L", ""}}) {
    const std::vector<double> v = ok_column(out / "members.csv", column);
    ASSERT_EQ(v.size(), 6u) << column;
    std::vector<double> sorted = v;
    std::sort(sorted.begin(), sorted.end());
    ASSERT_LT(sorted[0], sorted[1]) << column;  // an interpolating P10 would differ from the nearest rank
    for (const double q : {10.0, 50.0, 90.0}) {
      const std::string k = std::string(key) + ".p" + std::to_string(static_cast<int>(q));
      const double want = nearest_rank(v, q);
      EXPECT_NEAR(page_value(html, k), want, 1e-8 * std::max(1.0, std::abs(want))) << k;
      EXPECT_EQ(page_text(html, k), geohaz::report::format_quantity(want, unit)) << k;
    }
    // The histogram counts every member that ran once; P10, P50, P90 marked.
    const std::string svg = slurp(results / "report_files" / (std::string("ens_") + column + "_distribution.svg"));
    int total = 0;
    for (auto p = svg.find(" data-count=\""); p != std::string::npos; p = svg.find(" data-count=\"", p + 1))
      total += std::stoi(svg.substr(p + 13));
    EXPECT_EQ(total, 6) << column;
    EXPECT_NE(svg.find("data-members=\"6\""), std::string::npos);
    std::size_t markers = 0;
    for (auto p = svg.find("class=\"marker\""); p != std::string::npos; p = svg.find("class=\"marker\"", p + 1))
      ++markers;
    EXPECT_EQ(markers, 3u) << column;
  }
  // The parameters' labels and units are the config reader's declarations (read here from it).
  geohaz::ConfigReader d = geohaz::ConfigReader::describe();
  (void)geohaz::runout::read_config(d);
  for (const auto& r : d.reference())
    if (r.key == "model.density" || r.key == "model.mu") {
      const auto row = html.find("<td title=\"" + r.key + "\">");
      ASSERT_NE(row, std::string::npos) << r.key;
      const auto label_end = html.find("</td>", row);
      const std::string label = html.substr(html.find('>', row) + 1, label_end - html.find('>', row) - 1);
      EXPECT_EQ(r.help.rfind(label, 0), 0u) << label << " | " << r.help;
      const std::string unit_cell = "<td class=unit>" + geohaz::report::display_unit(r.unit) + "</td>";
      EXPECT_EQ(html.find(unit_cell, label_end), label_end + 5) << r.key << " " << r.unit;
    }

  const std::string chromium = find_chromium();
  if (chromium.empty()) GTEST_SKIP() << "chromium is not installed (scripts/setup installs the Debian package)";
  const fs::path shot = root / "ensemble.png";
  const auto dom = run_command("DBUS_SESSION_BUS_ADDRESS=disabled: '" + chromium +
                               "' --headless --no-sandbox --disable-gpu --hide-scrollbars --user-data-dir='" +
                               (root / "profile").string() +
                               "' --virtual-time-budget=10000 --enable-logging=stderr --v=0 --window-size=1280,2400 "
                               "--dump-dom --screenshot='" +
                               shot.string() + "' 'file://" + (results / "report.html").string() + "'");
  ASSERT_EQ(dom.code, 0) << dom.output;
  EXPECT_EQ(page_mark(dom.output, "data-images"), static_cast<int>(images)) << dom.output;
  EXPECT_EQ(page_mark(dom.output, "data-decoded"), static_cast<int>(images)) << dom.output;
  EXPECT_EQ(page_mark(dom.output, "data-errors"), 0) << dom.output;
  EXPECT_EQ(page_mark(dom.output, "data-map-problems"), 0) << dom.output;
  EXPECT_EQ(dom.output.find(":CONSOLE"), std::string::npos) << dom.output;
  // The screenshot shows the section: its text and the first map's hillshade.
  const geohaz::Image img = geohaz::read_image(shot);
  int dark = 0, mid_grey = 0;
  for (std::size_t i = 0; i < img.rgb.size(); i += 3) {
    const int r = img.rgb[i], g = img.rgb[i + 1], b = img.rgb[i + 2];
    dark += r < 60 && g < 60 && b < 60;
    mid_grey += r == g && g == b && r > 80 && r < 200;
  }
  EXPECT_GT(dark, 2000);
  EXPECT_GT(mid_grey, 2000);
  std::error_code ec;
  fs::remove_all(root, ec);
}
#endif
