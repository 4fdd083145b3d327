// geohaz-report: one report page (report.html) from the output folders of geohaz runs, as an
// engineer would hand it on: key numbers with labels and units grouped by meaning, the input
// parameters in the user's terms, the maps and pictures, SVG plots of every time series (see
// report.hpp and docs/report.md).
//
//   geohaz-report RESULTS_DIR [--title TEXT] [--pdf]
//
// A run folder is any sub-folder (searched two levels deep) holding a summary.json.
#include <iostream>
#include <string>

#include "geohaz/core/app.hpp"
#include "geohaz/core/errors.hpp"
#include "geohaz/report/report.hpp"

int main(int argc, char** argv) {
  return geohaz::run_main("geohaz-report", [&]() -> int {
    namespace po = boost::program_options;
    std::string dir, title = "geohaz results";
    bool pdf = false;
    po::options_description desc("Options");
    desc.add_options()("help,h", "print this help and exit")("version", "print the version and exit")(
        "results", po::value<std::string>(&dir)->required(),
        "results folder (holds one sub-folder per run); report.html and report_files/ are written there")(
        "title", po::value<std::string>(&title), "page title")(
        "pdf", po::bool_switch(&pdf),
        "also print the page to RESULTS_DIR/report.pdf (A4, each run from a new page) with headless Chromium");
    po::positional_options_description pos;
    pos.add("results", 1);
    if (argc < 2)
      throw geohaz::InputError(
          "no results folder given: geohaz-report RESULTS_DIR [--title TEXT] [--pdf] (see geohaz-report --help)",
          "command line");
    if (!geohaz::parse_command_line(
            argc, argv, "geohaz-report",
            "one self-contained HTML report page from the output folders of geohaz runs.\n"
            "Usage: geohaz-report RESULTS_DIR [--title TEXT] [--pdf]\n"
            "RESULTS_DIR is one run's --out folder or a folder holding several (searched two levels deep for "
            "summary.json).\n"
            "Example: geohaz-report results/demo --title \"geohaz demo\" --pdf",
            desc, &pos,
            "Exit codes: 0 done (the page's path printed, then the PDF's); 2 bad input (no such folder, no run "
            "in it), nothing written; 3 an I/O or system failure (a file could not be written, no Chromium for "
            "--pdf)."))
      return 0;
    const std::filesystem::path pdf_path = pdf ? std::filesystem::path(dir) / "report.pdf" : std::filesystem::path();
    if (pdf && geohaz::report::find_chromium().empty())  // before anything is written
      throw geohaz::IoError("no Chromium to print the PDF with (install the Debian package chromium)",
                            pdf_path.string());
    std::cout << geohaz::report::write_report(dir, title, pdf_path).string() << "\n";
    if (pdf) std::cout << pdf_path.string() << "\n";
    return 0;
  });
}
