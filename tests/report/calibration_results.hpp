#pragma once
// A geohaz-calibrate output folder as the report reads it (docs/calibration.md "The outputs"), made
// without running a calibration: summary.json, acceptable.csv (25 members, score rising from the
// best), sensitivity.csv, thalweg_profile.csv, acceptable.svg, comparison.png (the three classes
// over a hillshade, drawn as geohaz-calibrate draws it), best.toml. The real folder is checked
// against the report in tests/runout/test_calibrate_app.cpp.
#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

#include "geohaz/core/raster.hpp"

namespace calibration_results {

namespace fs = std::filesystem;

constexpr int kAcceptable = 25;  ///< members in acceptable.csv (more than the page shows)

inline void write(const fs::path& p, const std::string& text) {
  std::ofstream(p) << text;
}

inline void make(const fs::path& dir) {
  fs::create_directories(dir);
  write(dir / "summary.json", R"({"model": "geohaz-calibrate", "version": "test",
    "parameters": [{"key": "model.n", "min": 0.03, "max": 0.12, "scale": "log"},
                   {"key": "model.icr", "min": 0.08, "max": 0.3, "scale": "linear"}],
    "best": {"member": 37, "stage": "local0", "parameters": {"model.n": 0.0517, "model.icr": 0.1707},
             "values": [0.0517, 0.1707],
             "misfit": {"tp_m2": 41250.0, "fp_m2": 300.0, "fn_m2": 275.0, "tversky": 0.9931,
                        "runout_s_m": 905.0, "runout_diff_m": -5.0, "depth_rmse_m": 0.21, "volume_m3": 40.5,
                        "terms": {"footprint": 0.0069, "runout": 0.0055, "depth": 0.139, "volume": 0.0},
                        "score": 0.1514}},
    "observation": {"footprint_area_m2": 41525.0, "runout_s_m": 910.0, "runout_from": "footprint",
                    "deposit_raster": true, "volume_m3": 0.0},
    "score": {"acceptable_tolerance": 0.05, "depth_threshold_m": 0.1},
    "members": 44, "design_members": 12, "morris_members": 6, "local_members": 26,
    "local_search": {"algorithm": "bobyqa", "starts": 2, "stops": ["xtol", "xtol"]},
    "failed": [{"member": 2, "values": [0.03, 0.3], "diagnosis": "injected failure"}],
    "acceptable_members": 25,
    "acceptable_range": {"model.n": [0.0513, 0.0526], "model.icr": [0.1689, 0.1726]},
    "sensitivity": [{"key": "model.icr", "mu_star": 3.66, "mu": 3.1, "sigma": 1.2, "effects": 2},
                    {"key": "model.n", "mu_star": 0.17, "mu": -0.1, "sigma": 0.08, "effects": 2}],
    "ranks": 1, "threads_per_rank": 1, "wall_time_s": 792.0})");
  std::ostringstream acc;
  acc << "member,stage,status,model.n,model.icr,score,tversky,tp_m2,fp_m2,fn_m2,runout_s_m,runout_diff_m,depth_rmse_"
         "m,volume_m3,term_footprint,term_runout,term_depth,term_volume,diagnosis\n";
  for (int k = 0; k < kAcceptable; ++k)
    acc << 37 + k << ',' << (k == 0 ? "local0" : "design") << ",ok," << 0.0517 + 1e-5 * k << ',' << 0.1707 - 1e-4 * k
        << ',' << 0.1514 + 0.002 * k << ",0.99,41250,300,275,905," << -5 - k
        << ",0.21,40.5,0.0069,0.0055,0.139,0,\"\"\n";
  write(dir / "acceptable.csv", acc.str());
  write(dir / "members.csv", acc.str());
  write(dir / "sensitivity.csv",
        "rank,key,mu_star,mu,sigma,effects\n1,model.icr,3.66,3.1,1.2,2\n2,model.n,0.17,-0.1,0.08,2\n");
  std::ostringstream prof;
  prof << "s_m,observed_area_m2,modelled_area_m2,tp_m2,fp_m2,fn_m2,observed_width_m,modelled_width_m,observed_max_"
          "deposit_m,modelled_max_deposit_m,modelled_max_depth_m\n";
  for (int b = 0; b < 10; ++b) {
    const double s = 5.0 + 10.0 * b, w = 40.0 + 2.0 * b, d = b > 6 ? 1.0 + 0.2 * b : 0.0;
    prof << s << ',' << 10 * w << ',' << 10 * (w + 1) << ',' << 10 * w << ",10,0," << w << ',' << w + 1 << ',' << d
         << ',' << 0.9 * d << ',' << 2.0 << '\n';
  }
  write(dir / "thalweg_profile.csv", prof.str());
  write(dir / "acceptable.svg",
        "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"400\" height=\"300\"><rect width=\"400\" height=\"300\" "
        "fill=\"white\"/><circle cx=\"200\" cy=\"150\" r=\"6\" fill=\"none\" stroke=\"red\"/></svg>\n");
  write(dir / "best.toml", "[model]\nfriction = \"manning\"\nn = 0.0517\nicr = 0.1707\n");
  // The comparison map: a cone with the three classes along one flank.
  geohaz::Raster dem;
  dem.nx = 120, dem.ny = 90;
  dem.geotransform = {600000.0, 5.0, 0.0, 5100000.0, 0.0, -5.0};
  dem.data.resize(static_cast<std::size_t>(dem.nx) * dem.ny);
  geohaz::Raster cls = dem;
  for (int r = 0; r < dem.ny; ++r)
    for (int c = 0; c < dem.nx; ++c) {
      dem.at(c, r) = 1500.0 - 2.0 * std::hypot(c - 60.0, r - 45.0);
      const bool obs = c > 60 && c < 100 && std::abs(r - 45)<10, mod = c> 62 && c < 104 && std::abs(r - 44) < 10;
      cls.at(c, r) = obs && mod ? 1.0 : mod ? 2.0 : obs ? 3.0 : 0.0;
    }
  geohaz::QuicklookOptions o;
  o.title = "best member against the observation";
  o.classes = {{1.0, "true positive (both)", {44, 160, 44}},
               {2.0, "false positive (modelled only)", {214, 39, 40}},
               {3.0, "false negative (observed only)", {31, 119, 180}}};
  o.overlay_min = 0.5;
  o.crop_margin_m = 50.0;
  o.scale_bar = true;
  o.north_arrow = true;
  geohaz::write_quicklook_png(dir / "comparison.png", dem, &cls, o);
}

}  // namespace calibration_results
