// geohaz-report: one self-contained HTML page (report.html) from the output folders of a geohaz
// run: every run folder's summary.json as a table, its quick-look PNGs embedded (base64), links to
// its GeoTIFF maps, CSV curves and ParaView files, and a table of the key numbers on top.
//
//   geohaz-report RESULTS_DIR [--title TEXT]
//
// A run folder is any sub-folder (searched two levels deep) holding a summary.json.
#include <algorithm>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>
#include <vector>

#include "geohaz/core/app.hpp"
#include "geohaz/core/errors.hpp"
#include "geohaz/core/output.hpp"

namespace fs = std::filesystem;
using nlohmann::json;

namespace {

std::string base64(const std::string& in) {
  static const char* tbl = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  std::string out;
  out.reserve((in.size() + 2) / 3 * 4);
  std::size_t i = 0;
  for (; i + 2 < in.size(); i += 3) {
    const unsigned v = (static_cast<unsigned char>(in[i]) << 16) | (static_cast<unsigned char>(in[i + 1]) << 8) |
                       static_cast<unsigned char>(in[i + 2]);
    out += tbl[(v >> 18) & 63];
    out += tbl[(v >> 12) & 63];
    out += tbl[(v >> 6) & 63];
    out += tbl[v & 63];
  }
  if (i < in.size()) {
    unsigned v = static_cast<unsigned char>(in[i]) << 16;
    if (i + 1 < in.size()) v |= static_cast<unsigned char>(in[i + 1]) << 8;
    out += tbl[(v >> 18) & 63];
    out += tbl[(v >> 12) & 63];
    out += i + 1 < in.size() ? tbl[(v >> 6) & 63] : '=';
    out += '=';
  }
  return out;
}

std::string slurp(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

std::string escape(const std::string& s) {
  std::string o;
  for (char c : s) {
    switch (c) {
      case '<':
        o += "&lt;";
        break;
      case '>':
        o += "&gt;";
        break;
      case '&':
        o += "&amp;";
        break;
      case '"':
        o += "&quot;";
        break;
      default:
        o += c;
    }
  }
  return o;
}

std::string format_value(const json& v) {
  if (v.is_number_float()) {
    std::ostringstream s;
    s.precision(4);
    s << v.get<double>();
    return s.str();
  }
  if (v.is_string()) return v.get<std::string>();
  return v.dump();
}

// Flatten nested objects to dotted keys; short arrays are printed inline, long ones skipped.
void flatten(const json& j, const std::string& prefix, std::vector<std::pair<std::string, std::string>>& out) {
  for (auto it = j.begin(); it != j.end(); ++it) {
    const std::string key = prefix.empty() ? it.key() : prefix + "." + it.key();
    if (it->is_object()) {
      flatten(*it, key, out);
    } else if (it->is_array()) {
      // Short arrays of tables (e.g. one entry per confining stress) are flattened with their
      // index; short arrays of numbers are shown inline; long arrays are left to the files.
      if (it->size() > 8) continue;
      if (!it->empty() && it->front().is_object()) {
        for (std::size_t k = 0; k < it->size(); ++k) flatten((*it)[k], key + "[" + std::to_string(k) + "]", out);
      } else {
        out.emplace_back(key, it->dump());
      }
    } else {
      out.emplace_back(key, format_value(*it));
    }
  }
}

// Keys worth lifting into the table of key numbers.
bool is_key_number(const std::string& k) {
  static const char* words[] = {"runout",   "run_out",   "volume",        "max_speed", "peak_stress",    "h_over_l",
                                "strength", "deposited", "area_affected", "youngs",    "friction_angle", "cohesion"};
  std::string lower = k;
  std::transform(lower.begin(), lower.end(), lower.begin(), ::tolower);
  if (lower.find("error") != std::string::npos) return lower.find("mass_balance") != std::string::npos;
  for (const char* w : words)
    if (lower.find(w) != std::string::npos) return true;
  return false;
}

}  // namespace

int main(int argc, char** argv) {
  return geohaz::run_main("geohaz-report", [&]() -> int {
    namespace po = boost::program_options;
    std::string dir, title = "geohaz results";
    po::options_description desc("Options");
    desc.add_options()("help,h", "print this help and exit")("version", "print the version and exit")(
        "results", po::value<std::string>(&dir)->required(), "results folder (holds one sub-folder per run)")(
        "title", po::value<std::string>(&title), "page title");
    po::positional_options_description pos;
    pos.add("results", 1);
    if (!geohaz::parse_command_line(argc, argv, "geohaz-report",
                                    "one self-contained HTML page from the output folders of geohaz runs", desc, &pos))
      return 0;
    const fs::path root(dir);
    if (!fs::is_directory(root)) throw geohaz::InputError("not a directory", "", "RESULTS_DIR", dir);

    std::vector<fs::path> runs;
    for (auto it = fs::recursive_directory_iterator(root); it != fs::recursive_directory_iterator(); ++it) {
      if (it.depth() > 2) it.disable_recursion_pending();
      if (it->is_regular_file() && it->path().filename() == "summary.json") runs.push_back(it->path().parent_path());
    }
    std::sort(runs.begin(), runs.end());
    if (runs.empty()) throw geohaz::InputError("no run folder with a summary.json found", dir);

    std::ostringstream key_rows, body;
    for (const auto& run : runs) {
      json summary;
      try {
        summary = json::parse(slurp(run / "summary.json"));
      } catch (const json::exception& e) {
        throw geohaz::InputError(std::string("summary.json does not parse: ") + e.what(),
                                 (run / "summary.json").string());
      }
      const std::string name = fs::relative(run, root).string();
      std::vector<std::pair<std::string, std::string>> rows;
      flatten(summary, "", rows);
      body << "<section><h2>" << escape(name) << "</h2>\n<div class=row><table>\n";
      for (const auto& [k, v] : rows) {
        body << "<tr><td>" << escape(k) << "</td><td>" << escape(v) << "</td></tr>\n";
        if (is_key_number(k))
          key_rows << "<tr><td>" << escape(name) << "</td><td>" << escape(k) << "</td><td>" << escape(v)
                   << "</td></tr>\n";
      }
      body << "</table>\n<div class=files><b>Files</b><ul>\n";
      std::vector<fs::path> files, pngs;
      for (const auto& e : fs::directory_iterator(run)) {
        if (!e.is_regular_file()) continue;
        (e.path().extension() == ".png" ? pngs : files).push_back(e.path());
      }
      std::sort(files.begin(), files.end());
      std::sort(pngs.begin(), pngs.end());
      for (const auto& f : files) {
        const std::string rel = fs::relative(f, root).string();
        body << "<li><a href=\"" << escape(rel) << "\">" << escape(f.filename().string()) << "</a></li>\n";
      }
      body << "</ul></div></div>\n";
      for (const auto& p : pngs)
        body << "<figure><img alt=\"" << escape(p.filename().string()) << "\" src=\"data:image/png;base64,"
             << base64(slurp(p)) << "\"><figcaption>" << escape(p.filename().string()) << "</figcaption></figure>\n";
      body << "</section>\n";
    }

    std::ostringstream html;
    html << "<!DOCTYPE html>\n<html lang=en><head><meta charset=utf-8><title>" << escape(title) << "</title>\n"
         << "<style>body{font-family:sans-serif;margin:2em;max-width:1400px}table{border-collapse:collapse;margin:0 "
            "2em 1em 0}"
            "td,th{border:1px solid #ccc;padding:2px "
            "8px;font-size:90%}th{background:#eee}.row{display:flex;flex-wrap:wrap}"
            "figure{display:inline-block;margin:0.5em}img{max-width:640px;border:1px solid #ddd}"
            "figcaption{font-size:80%;color:#555}section{border-top:2px solid "
            "#444;margin-top:2em}</style></head><body>\n"
         << "<h1>" << escape(title) << "</h1>\n<p>Generated by geohaz " << GEOHAZ_VERSION
         << ". ParaView opens the <code>.xmf</code> files; QGIS the <code>.tif</code> maps.</p>\n"
         << "<h2>Key numbers</h2>\n<table><tr><th>run</th><th>quantity</th><th>value</th></tr>\n"
         << key_rows.str() << "</table>\n"
         << body.str() << "</body></html>\n";
    geohaz::write_text_file(root / "report.html", html.str());
    std::cout << (root / "report.html").string() << "\n";
    return 0;
  });
}
