// geohaz._geohaz's report part: the report page of geohaz-report (libs/report, geohaz/report/report.hpp)
// written from Python, from the same library as the app, so a notebook hands on the same page
// (python/geohaz/report.py documents the Python signature).
#include "geohaz/report/report.hpp"

#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <filesystem>
#include <string>

#include "geohaz/core/errors.hpp"

namespace py = pybind11;
namespace fs = std::filesystem;

namespace geohaz::python {

namespace {

/// geohaz._geohaz.report_write: report.html (and report.pdf with `pdf`) in `results`; returns
/// (html path, pdf path or None). Chromium is looked for before anything is written.
py::tuple report_write(const std::string& results, const std::string& title, bool pdf) {
  const fs::path pdf_path = pdf ? fs::path(results) / "report.pdf" : fs::path();
  if (pdf && report::find_chromium().empty())
    throw IoError("no Chromium to print the PDF with (install the Debian package chromium)", pdf_path.string());
  fs::path html;
  {
    py::gil_scoped_release nogil;
    html = report::write_report(results, title, pdf_path);
  }
  return py::make_tuple(html.string(), pdf ? py::object(py::str(pdf_path.string())) : py::object(py::none()));
}

}  // namespace

void add_report(py::module_& m) {
  m.def("report_write", &report_write, py::arg("results"), py::arg("title"), py::arg("pdf"));
}

}  // namespace geohaz::python
