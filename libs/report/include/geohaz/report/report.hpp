#pragma once
/// \file report.hpp
/// The pieces of geohaz-report (docs/report.md), kept apart from its main so the tests can check
/// them one by one: quantity names and units from column and key names, CSV reading, SVG plots,
/// the grouped table of a summary.json, the input parameters of a resolved config, and the page.

#include <filesystem>
#include <nlohmann/json.hpp>
#include <span>
#include <string>
#include <utility>
#include <vector>

#include "geohaz/core/output.hpp"
#include "geohaz/core/summary_keys.hpp"

namespace geohaz::report {

/// A quantity as a reader sees it: "mean speed" in "m/s", from a name such as "mean_speed_m_per_s" (or the older
/// "mean_speed_m_s").
struct Quantity {
  std::string label;  ///< words, e.g. "mean speed"
  std::string unit;   ///< unit for display, e.g. "m/s", "m³", "°" ("" when dimensionless or unknown)
};

/// Split a column or key name into words and unit: the longest trailing run of "_"-separated
/// tokens that names a unit (m, m2, m3, s, m_s or m_per_s, m_per_s2, Pa, N, N_per_m, J, J_per_m,
/// kg, deg, per_m, Hz, …) is the unit; the rest, "_" read as spaces, is the label.
Quantity quantity_from_name(const std::string& name);

/// A value with its unit for a table: 4 significant digits, thousands grouped with thin spaces,
/// Pa and J shown as kPa/MPa/GPa and kJ/MJ/GJ when large. Returns the text "value unit".
std::string format_quantity(double value, const std::string& unit);

/// A CSV file of numbers with a header line.
struct Csv {
  std::vector<std::string> names;            ///< column names from the header
  std::vector<std::vector<double>> columns;  ///< one vector per column (NaN where not a number)
  std::vector<bool> numeric;                 ///< whether every cell of the column is a number
};
/// Read a CSV (comma-separated, a header line, no quoting). InputError when it cannot be opened.
Csv read_csv(const std::filesystem::path& path);

/// Whether a CSV is worth a plot: its first column is the abscissa (time_s, or a distance x_m /
/// s_m / distance_m for profiles), it has at least two rows, and every column is numeric (event
/// lists with a text column, such as the acoustic-emission files, are left to the files).
bool is_plottable(const Csv& csv);

/// The ticks and ranges of the SVG plots are core's (nice_ticks in raster.hpp, nice_range in plot.hpp), as
/// in the PNG figures. A tick's number (6 significant digits; 0 when within 1e-12 of the span).
std::string tick_text(double v, double span);

/// An SVG plot of a plottable CSV: one panel per unit of the other columns (columns sharing a unit
/// share a panel, with a legend), axes with nice ticks and labels "quantity (unit)" from the
/// column names. Step counters, map coordinates (…x_m, …y_m) and columns that are zero throughout
/// are left out. `title` heads the picture. Width 760 px; the height grows with the panels.
std::string svg_plot(const Csv& csv, const std::string& title);

/// A row of a key-number table.
struct Row {
  std::string key;    ///< the flattened summary.json key ("fahrboeschung.ratio_H_over_L")
  std::string label;  ///< what a reader calls it ("H/L (Fahrböschung)")
  std::string value;  ///< the value with its unit
};
/// A group of rows under a heading ("Volumes and areas", …, "Run bookkeeping / other").
struct Group {
  std::string title;
  std::vector<Row> rows;
};
/// A table of an array of objects in summary.json (one row per entry, e.g. per biaxial test).
struct SubTable {
  std::string title;
  std::vector<std::string> headers;  ///< "label (unit)"
  std::vector<std::vector<std::string>> cells;
  bool folded = false;  ///< bookkeeping (derived model constants): shown folded, after the pictures
};
/// The key numbers of a summary.json, grouped by meaning. Label, unit, group and headline come
/// from the declarations of the library that wrote the summary (declared_summary_keys); a key it
/// does not declare still appears, under its own name and without a unit, in "Run bookkeeping /
/// other". Arrays of objects become SubTables (title and columns declared as "name[]" and
/// "name[].column"); long number arrays are left out.
struct Summary {
  std::vector<Group> groups;  ///< in display order, empty groups left out
  std::vector<SubTable> tables;
  std::vector<Row> headline;  ///< the few numbers for the overview at the top of the page
};
Summary summarise(const nlohmann::json& summary);

/// The input parameters of a run in the user's terms (c, φ, ψ, E, ν; n, i_cr or μ, ξ; bond
/// strengths …) from its config.resolved.toml: rows "symbol — meaning", value with unit. Only the
/// keys of the parameter table are shown (the whole file is linked). Empty when there is no file.
std::vector<Row> input_parameters(const std::filesystem::path& resolved_config);

/// A debris-runout, ensemble or calibration parameter key in the user's terms with its unit for
/// display: from the declarations of the runout config reader (runout::parameter_key: "model.xi" →
/// {"Voellmy turbulence coefficient ξ", "m/s²"}), else from the input parameter table of the other
/// apps; {key, ""} when neither names it.
std::pair<std::string, std::string> parameter_label(const std::string& key);

/// A declared unit as a reader writes it: "kg/m^3" → "kg/m³", "m/s^2" → "m/s²", "Pa*s" → "Pa·s",
/// "1" (dimensionless) → "".
std::string display_unit(const std::string& declared);

/// The back-analysis of a geohaz-calibrate output folder (docs/calibration.md) as a part of the
/// page: the best set (values, search bounds, acceptable ranges, link to best.toml) and its misfit;
/// the acceptable set as a table and its score/scatter plot (acceptable.svg); the Morris ranking;
/// the comparison map (true positive, false positive, false negative over the hillshade) and the
/// thalweg profile, observed against modelled width and deposit, as SVG plots.
struct RunPart {
  bool present = false;                                    ///< whether the run folder is of that kind
  std::vector<Row> headline;                               ///< the numbers for the page's overview
  std::string html;                                        ///< the part (img and link paths relative to the page)
  std::vector<std::pair<std::string, std::string>> plots;  ///< SVG file name (in report_files/), SVG text
  std::vector<std::string> shown;  ///< files of the run folder the part shows (not repeated elsewhere)
};
using CalibrationPart = RunPart;
/// The part of `run_dir` (whose summary.json is `summary`; empty unless its model is
/// geohaz-calibrate). `page_dir` is run_dir relative to the page, `svg_prefix` names its plots.
/// InputError when a table the summary lists does not read.
CalibrationPart calibration_part(const std::filesystem::path& run_dir, const nlohmann::json& summary,
                                 const std::string& page_dir, const std::string& svg_prefix);

/// The ensemble of a geohaz-ensemble output folder (docs/ensemble.md) as the top of its section
/// (report_ensemble.cpp): an overview (members run, succeeded and failed, sampling, the largest
/// area reached), the parameters varied with their distributions (labels and units from the
/// declarations, parameter_label), the run-out, H/L and area P10/P50/P90 with mean, min and max
/// as summary.json gives them; the probability maps (prob_*.png) and the mean and percentile maps
/// of the peak depth; the run-out and H/L distributions of the successful members (members.csv)
/// as histogram and CDF with the summary's P10/P50/P90 marked (svg_distribution). Empty unless
/// the summary's model is geohaz-ensemble. InputError when members.csv does not read.
RunPart ensemble_part(const std::filesystem::path& run_dir, const nlohmann::json& summary, const std::string& page_dir,
                      const std::string& svg_prefix);

/// A marked value on a distribution plot ("P50", 2608).
struct Marker {
  std::string name;
  double value;
};
/// An SVG histogram of `values` (bins of a nice width on multiples of it, at least √N and 5 of them)
/// with the empirical CDF (right axis, 0–1) and a dashed line at each marker; the axis titled
/// "quantity (unit)". Each bar is a <rect class="bin" data-count="…">, the root carries
/// data-members (N).
std::string svg_distribution(std::vector<double> values, const Quantity& quantity, const std::vector<Marker>& markers,
                             const std::string& title);

/// The declared summary keys of the library that wrote `summary` (by its "model": runout for
/// debris-runout, geohaz-ensemble and geohaz-calibrate, dem for dem-avalanche, else sph).
std::span<const SummaryKey> declared_summary_keys(const nlohmann::json& summary);

/// The label and display unit a summary.json key gets in the key-number tables, from `keys` (a
/// key matched by a "*" pattern gets what the star stands for after its label); the key itself
/// and no unit when it is not declared.
Quantity summary_label(std::span<const SummaryKey> keys, const std::string& key);

/// The red "map check" lines under a map drawn by write_quicklook_png that lacks its legend,
/// ticks or scale bar ("" when it has them or is not such a map).
std::string map_check_html(const std::filesystem::path& png);

/// Write RESULTS/report.html and RESULTS/report_files/*.svg from every run folder (RESULTS itself
/// or a sub-folder, up to two levels deep, holding a summary.json); with `pdf` not empty, print
/// the page to that PDF too (print_pdf). A run folder given itself is named after the folder, and
/// when RESULTS holds a run's geohaz-manifest.txt the report's files are added to it, so the next
/// run into the folder cleans them. InputError when there is no run or a summary.json does not
/// parse; IoError when the PDF cannot be made. Returns the path of report.html.
std::filesystem::path write_report(const std::filesystem::path& results, const std::string& title,
                                   const std::filesystem::path& pdf = {});

/// Chromium's path ("" when none is installed).
std::string find_chromium();

/// Print an HTML page to PDF with headless Chromium (A4 from the page's @page rule, no header or
/// footer), written as PDF.partial and renamed. IoError when no Chromium is installed or it fails.
void print_pdf(const std::filesystem::path& html, const std::filesystem::path& pdf);

}  // namespace geohaz::report
