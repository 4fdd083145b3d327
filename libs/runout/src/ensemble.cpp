// Ensembles of debris-runout runs (ensemble.hpp, docs/ensemble.md): plan, members, aggregation.
#include "geohaz/runout/ensemble.hpp"

#include <unistd.h>

#include <algorithm>
#include <boost/math/special_functions/erf.hpp>
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
#include "geohaz/runout/run.hpp"

namespace fs = std::filesystem;

namespace geohaz::runout {

using detail::fmt;
using detail::numeric_case_keys;
using detail::origin;
using detail::resolve_path;

namespace {

std::uint64_t splitmix64(std::uint64_t x) noexcept {
  x += 0x9e3779b97f4a7c15ULL;
  x = (x ^ (x >> 30)) * 0xbf58476d1ce4e5b9ULL;
  x = (x ^ (x >> 27)) * 0x94d049bb133111ebULL;
  return x ^ (x >> 31);
}

double normal_cdf(double z) {
  return 0.5 * std::erfc(-z / std::sqrt(2.0));
}
double normal_quantile(double p) {
  return std::sqrt(2.0) * boost::math::erf_inv(2.0 * p - 1.0);
}

const char* const kFieldNames[3] = {"max_depth", "max_speed", "max_pressure"};
const char* const kFieldUnits[3] = {"m", "m/s", "Pa"};
const char* const kFieldDescriptions[3] = {"peak flow depth, normal to the bed", "peak surface speed",
                                           "peak dynamic pressure rho v^2"};

}  // namespace

const char* to_string(DistributionKind k) noexcept {
  switch (k) {
    case DistributionKind::Uniform:
      return "uniform";
    case DistributionKind::Normal:
      return "normal";
    case DistributionKind::LogNormal:
      return "lognormal";
    case DistributionKind::Discrete:
      return "discrete";
    case DistributionKind::Fixed:
      return "fixed";
  }
  return "?";
}

double ParameterDistribution::quantile(double u) const {
  switch (kind) {
    case DistributionKind::Fixed:
      return a;
    case DistributionKind::Uniform:
      return a + u * (b - a);
    case DistributionKind::Normal:
    case DistributionKind::LogNormal: {
      // Standardised bounds of the truncation; u is mapped into [F(lo), F(hi)].
      const bool log = kind == DistributionKind::LogNormal;
      const double mu = log ? std::log(a) : a;
      const auto z_of = [&](double x) {
        if (log) return x > 0.0 ? (std::log(x) - mu) / b : -std::numeric_limits<double>::infinity();
        return (x - mu) / b;
      };
      const double f_lo = std::isfinite(lower) ? normal_cdf(z_of(lower)) : 0.0;
      const double f_hi = std::isfinite(upper) ? normal_cdf(z_of(upper)) : 1.0;
      const double p = std::clamp(f_lo + u * (f_hi - f_lo), 1e-300, 1.0 - 1e-16);
      const double x = mu + b * normal_quantile(p);
      return std::clamp(log ? std::exp(x) : x, lower, upper);
    }
    case DistributionKind::Discrete: {
      double total = 0.0;
      for (double w : weights) total += w;
      double acc = 0.0;
      for (std::size_t k = 0; k < values.size(); ++k) {
        acc += weights[k] / total;
        if (u < acc) return values[k];
      }
      return values.back();
    }
  }
  return a;
}

double counter_uniform(std::uint64_t seed, std::uint64_t a, std::uint64_t b, std::uint64_t c) noexcept {
  const std::uint64_t h = splitmix64(splitmix64(splitmix64(splitmix64(seed) ^ a) ^ b) ^ c);
  return (static_cast<double>(h >> 11) + 0.5) * 0x1.0p-53;  // in (0, 1)
}

std::vector<std::vector<double>> sample_plan(const EnsemblePlan& plan) {
  const int n = plan.members;
  const std::size_t np = plan.parameters.size();
  std::vector<std::vector<double>> out(static_cast<std::size_t>(n), std::vector<double>(np));
  for (std::size_t d = 0; d < np; ++d) {
    std::vector<int> stratum(static_cast<std::size_t>(n));
    for (int i = 0; i < n; ++i) stratum[static_cast<std::size_t>(i)] = i;
    if (plan.sampling == SamplingMethod::LatinHypercube) {
      // Fisher–Yates with the counter generator: stream 1 = permutations, stream 2 = jitter.
      for (int i = n - 1; i > 0; --i) {
        const double u = counter_uniform(plan.seed, 1, d, static_cast<std::uint64_t>(i));
        const int j = std::min(i, static_cast<int>(u * (i + 1)));
        std::swap(stratum[static_cast<std::size_t>(i)], stratum[static_cast<std::size_t>(j)]);
      }
    }
    for (int i = 0; i < n; ++i) {
      const double jitter = counter_uniform(plan.seed, 2, d, static_cast<std::uint64_t>(i));
      const double u = plan.sampling == SamplingMethod::LatinHypercube
                           ? (stratum[static_cast<std::size_t>(i)] + jitter) / n
                           : jitter;
      out[static_cast<std::size_t>(i)][d] = plan.parameters[d].quantile(u);
    }
  }
  return out;
}

template <class Count>
double histogram_percentile(double q, std::uint32_t zeros, std::uint32_t below, const Count* counts, int bins,
                            std::uint32_t above, HistogramRange range, double vmin, double vmax) {
  std::uint64_t n = static_cast<std::uint64_t>(zeros) + below + above;
  for (int j = 0; j < bins; ++j) n += counts[j];
  if (n == 0) return 0.0;
  const std::uint64_t k = std::max<std::uint64_t>(1, static_cast<std::uint64_t>(std::ceil(q / 100.0 * n - 1e-9)));
  if (k <= zeros) return 0.0;
  std::uint64_t acc = zeros + below;
  if (k <= acc) return vmin;
  const double ratio = std::log(range.hi / range.lo) / bins;
  for (int j = 0; j < bins; ++j) {
    if (counts[j] == 0) continue;
    if (k <= acc + counts[j]) {
      const double m = static_cast<double>(k - acc) - 0.5;  // mid-position of the rank in the bin
      const double v = range.lo * std::exp(ratio * (j + m / counts[j]));
      return std::clamp(v, vmin, vmax);
    }
    acc += counts[j];
  }
  return vmax;
}
template double histogram_percentile<std::uint16_t>(double, std::uint32_t, std::uint32_t, const std::uint16_t*, int,
                                                    std::uint32_t, HistogramRange, double, double);
template double histogram_percentile<std::uint32_t>(double, std::uint32_t, std::uint32_t, const std::uint32_t*, int,
                                                    std::uint32_t, HistogramRange, double, double);

// ---- member peaks on disk -------------------------------------------------------------------

namespace {
constexpr char kPeaksMagic[8] = {'G', 'H', 'Z', 'P', 'E', 'A', 'K', '1'};
}

void write_member_peaks(const fs::path& path, const MemberPeaks& p) {
  const fs::path tmp = path.string() + ".partial";
  {
    std::ofstream o(tmp, std::ios::binary);
    const std::int32_t hdr[6] = {p.nx, p.ny, p.c0, p.r0, p.w, p.h};
    o.write(kPeaksMagic, 8);
    o.write(reinterpret_cast<const char*>(hdr), sizeof hdr);
    o.write(reinterpret_cast<const char*>(&p.density), sizeof(double));
    for (const auto* v : {&p.depth, &p.speed, &p.pressure})
      o.write(reinterpret_cast<const char*>(v->data()), static_cast<std::streamsize>(v->size() * sizeof(double)));
    o.flush();
    if (!o) {
      std::error_code ec;
      fs::remove(tmp, ec);
      throw IoError("cannot write the member's peak maps", path.string());
    }
  }
  fs::rename(tmp, path);
}

MemberPeaks read_member_peaks(const fs::path& path, bool header_only) {
  std::ifstream in(path, std::ios::binary);
  char magic[8];
  std::int32_t hdr[6];
  MemberPeaks p;
  in.read(magic, 8);
  in.read(reinterpret_cast<char*>(hdr), sizeof hdr);
  in.read(reinterpret_cast<char*>(&p.density), sizeof(double));
  if (!in || std::memcmp(magic, kPeaksMagic, 8) != 0)
    throw InputError("not a member peak file (damaged? delete the member's folder to rerun it)", path.string());
  p.nx = hdr[0], p.ny = hdr[1], p.c0 = hdr[2], p.r0 = hdr[3], p.w = hdr[4], p.h = hdr[5];
  if (header_only) return p;
  const std::size_t cells = static_cast<std::size_t>(p.w) * static_cast<std::size_t>(p.h);
  for (auto* v : {&p.depth, &p.speed, &p.pressure}) {
    v->resize(cells);
    in.read(reinterpret_cast<char*>(v->data()), static_cast<std::streamsize>(cells * sizeof(double)));
  }
  if (!in) throw InputError("member peak file is truncated (delete the member's folder to rerun it)", path.string());
  return p;
}

// ---- aggregation ----------------------------------------------------------------------------

EnsembleAggregator::EnsembleAggregator(int nx, int ny, int c0, int r0, int w, int h, AggregationSettings s)
    : nx_(nx), ny_(ny), c0_(c0), r0_(r0), w_(w), h_(h), s_(std::move(s)) {
  const std::size_t cells = static_cast<std::size_t>(w) * static_cast<std::size_t>(h);
  sum_.assign(3 * cells, 0.0);
  vmin_.assign(3 * cells, std::numeric_limits<double>::infinity());
  vmax_.assign(3 * cells, 0.0);
  zeros_.assign(3 * cells, 0);
  hist_.assign(3 * cells * static_cast<std::size_t>(s_.bins + 2), 0);
  for (double t : s_.depth_thresholds) thresholds_.emplace_back(0, t);
  for (double t : s_.speed_thresholds) thresholds_.emplace_back(1, t);
  for (double t : s_.pressure_thresholds) thresholds_.emplace_back(2, t);
  for (int k : s_.intensity_classes) thresholds_.emplace_back(3, static_cast<double>(k));
  exceed_.assign(thresholds_.size() * cells, 0);
}

HistogramRange EnsembleAggregator::range_of(int field) {
  return field == 0 ? kDepthRange : field == 1 ? kSpeedRange : kPressureRange;
}

int EnsembleAggregator::bin_of(int field, double v) const {
  const HistogramRange r = range_of(field);
  if (v < r.lo) return 0;
  if (v >= r.hi) return s_.bins + 1;
  const int j = static_cast<int>(std::log(v / r.lo) / std::log(r.hi / r.lo) * s_.bins);
  return 1 + std::clamp(j, 0, s_.bins - 1);
}

std::size_t EnsembleAggregator::bytes_per_cell() const noexcept {
  return 3 * (3 * sizeof(double) + sizeof(std::uint32_t) + (s_.bins + 2) * sizeof(std::uint16_t)) +
         thresholds_.size() * sizeof(std::uint32_t);
}

void EnsembleAggregator::add(const MemberPeaks& p) {
  if (p.nx != nx_ || p.ny != ny_) throw std::logic_error("member peaks on another grid");
  if (n_ >= 65535) throw std::logic_error("more than 65535 members: histogram counts would overflow");
  ++n_;
  const std::size_t cells = static_cast<std::size_t>(w_) * static_cast<std::size_t>(h_);
  const std::size_t nb = static_cast<std::size_t>(s_.bins + 2);
  // Intensity classes of the member on its own window.
  std::vector<double> cls;
  if (s_.intensity_classes.size() && p.w > 0) cls = intensity_classes(p.depth, p.speed, p.density, s_.intensity);
  for (int r = 0; r < h_; ++r)
    for (int c = 0; c < w_; ++c) {
      const std::size_t k = static_cast<std::size_t>(r) * w_ + c;
      const int gc = c0_ + c - p.c0, gr = r0_ + r - p.r0;  // in the member's window
      const bool inside = gc >= 0 && gr >= 0 && gc < p.w && gr < p.h;
      const std::size_t m = inside ? static_cast<std::size_t>(gr) * p.w + gc : 0;
      double v[3] = {0.0, 0.0, 0.0};
      if (inside) v[0] = p.depth[m], v[1] = p.speed[m], v[2] = p.pressure[m];
      for (int f = 0; f < 3; ++f) {
        const std::size_t kf = 3 * k + f;
        const double x = std::isfinite(v[f]) && v[f] > 0.0 ? v[f] : 0.0;
        sum_[kf] += x;
        if (x == 0.0) {
          ++zeros_[kf];
          continue;
        }
        vmin_[kf] = std::min(vmin_[kf], x);
        vmax_[kf] = std::max(vmax_[kf], x);
        ++hist_[kf * nb + static_cast<std::size_t>(bin_of(f, x))];
      }
      for (std::size_t t = 0; t < thresholds_.size(); ++t) {
        const auto [f, thr] = thresholds_[t];
        const bool hit = f == 3 ? (inside && cls[m] >= thr) : v[f] > thr;
        if (hit) ++exceed_[t * cells + k];
      }
    }
}

std::vector<double> EnsembleAggregator::mean(int field) const {
  std::vector<double> out(static_cast<std::size_t>(nx_) * ny_, 0.0);
  if (n_ == 0) return out;
  for (int r = 0; r < h_; ++r)
    for (int c = 0; c < w_; ++c)
      out[static_cast<std::size_t>(r0_ + r) * nx_ + c0_ + c] =
          sum_[3 * (static_cast<std::size_t>(r) * w_ + c) + field] / n_;
  return out;
}

std::vector<double> EnsembleAggregator::percentile(int field, double q) const {
  std::vector<double> out(static_cast<std::size_t>(nx_) * ny_, 0.0);
  const std::size_t nb = static_cast<std::size_t>(s_.bins + 2);
  for (int r = 0; r < h_; ++r)
    for (int c = 0; c < w_; ++c) {
      const std::size_t kf = 3 * (static_cast<std::size_t>(r) * w_ + c) + field;
      const std::uint16_t* hst = &hist_[kf * nb];
      out[static_cast<std::size_t>(r0_ + r) * nx_ + c0_ + c] = histogram_percentile(
          q, zeros_[kf], hst[0], hst + 1, s_.bins, hst[nb - 1], range_of(field), vmin_[kf], vmax_[kf]);
    }
  return out;
}

std::vector<double> EnsembleAggregator::exceedance(int field, double threshold) const {
  std::vector<double> out(static_cast<std::size_t>(nx_) * ny_, 0.0);
  const std::size_t cells = static_cast<std::size_t>(w_) * static_cast<std::size_t>(h_);
  for (std::size_t t = 0; t < thresholds_.size(); ++t) {
    if (thresholds_[t].first != field || thresholds_[t].second != threshold) continue;
    if (n_ == 0) return out;
    for (int r = 0; r < h_; ++r)
      for (int c = 0; c < w_; ++c)
        out[static_cast<std::size_t>(r0_ + r) * nx_ + c0_ + c] =
            static_cast<double>(exceed_[t * cells + static_cast<std::size_t>(r) * w_ + c]) / n_;
    return out;
  }
  throw std::logic_error("exceedance of a threshold that was not configured");
}

// ---- member records -------------------------------------------------------------------------

std::string member_json(const MemberRecord& r, const EnsemblePlan& plan) {
  nlohmann::json j;
  j["member"] = r.index;
  j["status"] = r.ok ? "ok" : "failed";
  j["diagnosis"] = r.diagnosis;
  nlohmann::json params = nlohmann::json::object();
  for (std::size_t d = 0; d < plan.parameters.size() && d < r.values.size(); ++d)
    params[plan.parameters[d].key] = r.values[d];
  j["parameters"] = params;
  j["values"] = r.values;
  j["runout_length_along_path_m"] = r.runout_m;
  j["drop_height_m"] = r.drop_height_m;
  j["reach_m"] = r.reach_m;
  j["ratio_H_over_L"] = r.hl;
  j["angle_deg"] = r.hl_deg;
  j["volumes_m3"] = {
      {"release", r.release_m3}, {"deposited", r.deposited_m3}, {"mobile", r.mobile_m3}, {"lost", r.lost_m3}};
  j["max_speed_m_per_s"] = r.max_speed;
  j["area_affected_m2"] = r.affected_area_m2;
  j["simulated_time_s"] = r.simulated_time_s;
  j["steps"] = r.steps;
  j["ended_by"] = r.ended_by;
  j["unfinished"] = r.unfinished;
  j["wall_time_s"] = r.wall_time_s;
  j["cpu_time_s"] = r.cpu_time_s;
  j["rank"] = r.rank;
  j["threads"] = r.threads;
  return j.dump(2);
}

MemberRecord parse_member_json(const std::string& text) {
  const nlohmann::json j = nlohmann::json::parse(text);
  MemberRecord r;
  r.index = j.at("member").get<int>();
  r.ok = j.at("status").get<std::string>() == "ok";
  r.diagnosis = j.at("diagnosis").get<std::string>();
  r.values = j.at("values").get<std::vector<double>>();
  r.runout_m = j.at("runout_length_along_path_m").get<double>();
  r.drop_height_m = j.at("drop_height_m").get<double>();
  r.reach_m = j.at("reach_m").get<double>();
  r.hl = j.at("ratio_H_over_L").get<double>();
  r.hl_deg = j.at("angle_deg").get<double>();
  const auto& v = j.at("volumes_m3");
  r.release_m3 = v.at("release").get<double>();
  r.deposited_m3 = v.at("deposited").get<double>();
  r.mobile_m3 = v.at("mobile").get<double>();
  r.lost_m3 = v.at("lost").get<double>();
  // members/ of a folder written before the key rule (docs/python.md, Migration) still resume
  r.max_speed = j.at(j.contains("max_speed_m_per_s") ? "max_speed_m_per_s" : "max_speed_m_s").get<double>();
  r.affected_area_m2 = j.at("area_affected_m2").get<double>();
  r.simulated_time_s = j.at("simulated_time_s").get<double>();
  r.steps = j.at("steps").get<std::int64_t>();
  r.ended_by = j.at("ended_by").get<std::string>();
  r.unfinished = j.at("unfinished").get<bool>();
  r.wall_time_s = j.at("wall_time_s").get<double>();
  r.cpu_time_s = j.at("cpu_time_s").get<double>();
  r.rank = j.at("rank").get<int>();
  r.threads = j.at("threads").get<int>();
  return r;
}

// ---- configuration --------------------------------------------------------------------------

namespace {

void read_parameter_keys(ConfigReader& t, ParameterDistribution& p, bool describe) {
  const auto kind = t.get_choice("distribution", "uniform", {"uniform", "normal", "lognormal", "discrete", "fixed"},
                                 {"",
                                  "uniform (min, max), normal (mean, sd), lognormal (median, sigma), discrete "
                                  "(values, weights) or fixed (value: the same for every member)"});
  p.kind = kind == "normal"      ? DistributionKind::Normal
           : kind == "lognormal" ? DistributionKind::LogNormal
           : kind == "discrete"  ? DistributionKind::Discrete
           : kind == "fixed"     ? DistributionKind::Fixed
                                 : DistributionKind::Uniform;
  const Range any = Range::closed(-1e12, 1e12);
  if (describe || p.kind == DistributionKind::Uniform) {
    p.a = t.require("min", any, {"key's unit", "uniform: lower end a"});
    p.b = t.require("max", any, {"key's unit", "uniform: upper end b (≥ min)"});
  }
  if (describe || p.kind == DistributionKind::Normal) {
    p.a = t.require("mean", any, {"key's unit", "normal: mean"});
    p.b = t.require("sd", Range::positive(), {"key's unit", "normal: standard deviation (> 0)"});
  }
  if (describe || p.kind == DistributionKind::LogNormal) {
    p.a = t.require("median", Range::positive(), {"key's unit", "lognormal: median e^μ (> 0)"});
    p.b = t.require("sigma", Range::positive(), {"1", "lognormal: standard deviation σ of ln X (> 0)"});
  }
  if (describe || p.kind == DistributionKind::Normal || p.kind == DistributionKind::LogNormal) {
    p.lower = t.get("lower", p.lower, Range{}, {"key's unit", "normal, lognormal: truncate below (optional)"});
    p.upper = t.get("upper", p.upper, Range{}, {"key's unit", "normal, lognormal: truncate above (optional)"});
  }
  if (describe || p.kind == DistributionKind::Fixed) p.a = t.require("value", any, {"key's unit", "fixed: the value"});
  if (describe || p.kind == DistributionKind::Discrete) {
    p.values = t.require_array("values", any, {"key's unit", "discrete: the values"});
    p.weights = t.get_array("weights", {}, Range::non_negative(),
                            {"1", "discrete: relative weights, one per value (default: equal)"});
  }
}

/// The ensemble keys, declared once: describe_ensemble (--help-config, the summary's labels) and
/// read_ensemble read them through the functions below, so default, range, unit and help are
/// written in one place.
constexpr KeyDoc kBaseDoc{"", "the debris-runout config of the base case (DSM, release, law, numerics)"};
constexpr KeyDoc kParameterTablesDoc{
    "", "uncertain parameters: key (a numeric debris-runout key, release.thickness_factor) and distribution"};
constexpr KeyDoc kParameterKeyDoc{"", "numeric debris-runout key (model.mu, model.n, ...) or release.thickness_factor"};
constexpr KeyDoc kAlternativeTablesDoc{"",
                                       "alternative release files: member picks one (parameter release.alternative)"};
constexpr KeyDoc kAlternativeFileDoc{"", "release polygons or thickness raster (path relative to this file)"};
constexpr KeyDoc kAlternativeWeightDoc{"1", "relative probability of this release"};

/// ensemble.members, sampling, seed and inject_failure.
void read_plan_keys(ConfigReader& cfg, EnsemblePlan& plan, std::vector<int>& inject_failure) {
  plan.members =
      static_cast<int>(cfg.get_int("ensemble.members", 10, Range::closed(1, 65535), {"1", "number of members N"}));
  plan.sampling = cfg.get_choice("ensemble.sampling", "latin_hypercube", {"latin_hypercube", "monte_carlo"},
                                 {"", "sampling plan: Latin hypercube (McKay et al. 1979) or plain Monte Carlo",
                                  "sampling"}) == "monte_carlo"
                      ? SamplingMethod::MonteCarlo
                      : SamplingMethod::LatinHypercube;
  plan.seed =
      static_cast<std::uint64_t>(cfg.get_int("ensemble.seed", 1, Range::closed(0, 9.0e15),
                                             {"1", "seed of the plan: member i's values depend on (seed, i)", "seed"}));
  for (double v : cfg.get_array("ensemble.inject_failure", {}, Range::closed(0, 65535),
                                {"1",
                                 "test hook: these member indices fail on purpose (a SimulationError at their "
                                 "first step)"}))
    inject_failure.push_back(static_cast<int>(v));
}

/// The products.* keys: the probability, intensity and percentile maps.
void read_product_keys(ConfigReader& cfg, AggregationSettings& a) {
  const std::string src = origin(cfg);
  a.depth_thresholds =
      cfg.get_array("products.depth_thresholds", {0.5}, Range::positive(), {"m", "P(peak depth > t) maps, t > 0"});
  a.speed_thresholds =
      cfg.get_array("products.speed_thresholds", {}, Range::positive(), {"m/s", "P(peak speed > t) maps, t > 0"});
  a.pressure_thresholds = cfg.get_array("products.pressure_thresholds", {30e3}, Range::positive(),
                                        {"Pa", "P(peak pressure > t) maps, t > 0"});
  a.intensity_classes.clear();
  for (double k : cfg.get_array("products.intensity_classes", {2}, Range::closed(1, 3),
                                {"1", "P(intensity class ≥ k) maps, k = 1 low, 2 medium, 3 strong"})) {
    if (k != std::floor(k))
      throw InputError("intensity classes are 1, 2 or 3", src, "products.intensity_classes", fmt(k));
    a.intensity_classes.push_back(static_cast<int>(k));
  }
  a.percentiles = cfg.get_array("products.percentiles", {10, 50, 90}, Range::open_closed(0, 100),
                                {"%", "percentile maps (0, 100]"});
  a.bins = static_cast<int>(
      cfg.get_int("products.bins", 96, Range::closed(8, 1024),
                  {"1", "log-spaced histogram bins per cell and field (percentile accuracy, docs/ensemble.md)",
                   "percentile maps: histogram bins"}));
}

}  // namespace

void describe_ensemble(ConfigReader& cfg) {
  cfg.require_string("ensemble.base", kBaseDoc);
  EnsemblePlan plan;
  std::vector<int> inject;
  read_plan_keys(cfg, plan, inject);
  for (ConfigReader& t : cfg.tables("ensemble.parameter", kParameterTablesDoc)) {
    t.require_string("key", kParameterKeyDoc);
    ParameterDistribution p;
    read_parameter_keys(t, p, true);
  }
  for (ConfigReader& t : cfg.tables("ensemble.release_alternative", kAlternativeTablesDoc)) {
    t.require_string("file", kAlternativeFileDoc);
    t.get("weight", 1.0, Range::positive(), kAlternativeWeightDoc);
  }
  AggregationSettings a;
  read_product_keys(cfg, a);
}

EnsembleSetup read_ensemble(ConfigReader& cfg) {
  EnsembleSetup s;
  const std::string src = origin(cfg);
  s.base_config = resolve_path(cfg, cfg.require_string("ensemble.base", kBaseDoc));
  EnsemblePlan& plan = s.plan;
  read_plan_keys(cfg, plan, s.inject_failure);

  const std::set<std::string> numeric = numeric_case_keys();
  auto tables = cfg.tables("ensemble.parameter", kParameterTablesDoc);
  for (std::size_t k = 0; k < tables.size(); ++k) {
    ConfigReader& t = tables[k];
    const std::string where = "ensemble.parameter[" + std::to_string(k) + "]";
    ParameterDistribution p;
    p.key = t.require_string("key", kParameterKeyDoc);
    if (p.key != kThicknessFactorKey && !numeric.count(p.key)) {
      std::string list = kThicknessFactorKey;
      for (const auto& n : numeric) list += ", " + n;
      throw InputError("unknown parameter name (a numeric debris-runout key or " + std::string(kThicknessFactorKey) +
                           "; release alternatives come from [[ensemble.release_alternative]]); allowed: " + list,
                       src, where + ".key", p.key);
    }
    for (const auto& q : plan.parameters)
      if (q.key == p.key) throw InputError("parameter given twice", src, where + ".key", p.key);
    read_parameter_keys(t, p, false);
    if (p.kind == DistributionKind::Uniform && !(p.a <= p.b))
      throw InputError("uniform distribution needs min ≤ max (min = " + fmt(p.a) + ", max = " + fmt(p.b) + ")", src,
                       where + ".min", fmt(p.a));
    if (!(p.lower < p.upper)) throw InputError("truncation needs lower < upper", src, where + ".lower", fmt(p.lower));
    if (p.kind == DistributionKind::Discrete) {
      if (p.weights.empty()) p.weights.assign(p.values.size(), 1.0);
      if (p.weights.size() != p.values.size())
        throw InputError("weights needs one entry per value (" + std::to_string(p.values.size()) + ")", src,
                         where + ".weights", std::to_string(p.weights.size()) + " entries");
      double total = 0.0;
      for (double w : p.weights) total += w;
      if (!(total > 0.0)) throw InputError("weights must not all be zero", src, where + ".weights");
    }
    if (p.kind == DistributionKind::LogNormal && p.lower < 0.0) p.lower = 0.0;
    plan.parameters.push_back(p);
  }
  auto alts = cfg.tables("ensemble.release_alternative", kAlternativeTablesDoc);
  if (!alts.empty()) {
    ParameterDistribution p;
    p.key = kReleaseAlternativeKey;
    p.kind = DistributionKind::Discrete;
    for (std::size_t k = 0; k < alts.size(); ++k) {
      const std::string file = resolve_path(cfg, alts[k].require_string("file", kAlternativeFileDoc));
      if (!fs::exists(file))
        throw InputError("release file not found", src, "ensemble.release_alternative[" + std::to_string(k) + "].file",
                         file);
      plan.release_alternatives.push_back(file);
      p.values.push_back(static_cast<double>(k));
      p.weights.push_back(alts[k].get("weight", 1.0, Range::positive(), kAlternativeWeightDoc));
    }
    plan.parameters.push_back(p);
  }

  AggregationSettings& a = s.aggregation;
  read_product_keys(cfg, a);
  cfg.finish();
  s.resolved_config = cfg.resolved();
  if (!fs::exists(s.base_config))
    throw InputError("base case config not found", src, "ensemble.base", s.base_config.string());

  // The base case, checked once; then every member's case (a value outside its key's range is an
  // input error naming the member, before anything is written).
  {
    ConfigReader base = ConfigReader::from_file(s.base_config);
    const RunConfig c = read_config(base);
    base.finish();
    s.base_resolved = base.resolved();
    s.dsm = c.dsm;
    a.intensity = c.output.intensity;
    a.map_depth_classes = c.output.map_depth_classes;
    a.map_speed_classes = c.output.map_speed_classes;
    a.profile_half_width = c.output.profile_half_width;
    a.map_pressure_classes = c.output.map_pressure_classes;
    a.map_margin = c.output.map_margin;
    a.attribution = c.output.attribution;
  }
  s.values = sample_plan(plan);
  for (int i = 0; i < plan.members; ++i) {
    ConfigReader m = ConfigReader::from_file(s.base_config);
    for (std::size_t d = 0; d < plan.parameters.size(); ++d) {
      const std::string& key = plan.parameters[d].key;
      const double v = s.values[static_cast<std::size_t>(i)][d];
      if (key == kThicknessFactorKey) {
        if (!(v > 0.0))
          throw InputError("member " + std::to_string(i) +
                               " draws a release thickness factor ≤ 0: the factor must be "
                               "> 0 (set 'lower' to truncate the distribution)",
                           src, "ensemble.parameter[" + std::to_string(d) + "]", fmt(v));
        continue;
      }
      if (key == kReleaseAlternativeKey) continue;
      std::ostringstream o;
      o << key << '=' << std::setprecision(17) << v;
      m.apply_override(o.str(),
                       src + " (ensemble.parameter[" + std::to_string(d) + "], member " + std::to_string(i) + ")");
    }
    (void)read_config(m);
  }
  return s;
}

std::string plan_csv(const EnsembleSetup& s) {
  std::ostringstream o;
  o << "member";
  for (const auto& p : s.plan.parameters) o << ',' << p.key;
  o << '\n' << std::setprecision(17);
  for (std::size_t i = 0; i < s.values.size(); ++i) {
    o << i;
    for (double v : s.values[i]) o << ',' << v;
    o << '\n';
  }
  return o.str();
}

namespace {
std::string slurp(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}
}  // namespace

std::vector<int> prepare_output(const EnsembleSetup& s, const fs::path& out) {
  const std::string plan = plan_csv(s);
  if (fs::exists(out / "plan.csv") &&
      (slurp(out / "plan.csv") != plan || slurp(out / "base.resolved.toml") != s.base_resolved))
    throw InputError(
        "the output folder holds another ensemble (plan.csv or base.resolved.toml differ): choose "
        "another --out or delete it",
        "command line", "--out", out.string());
  make_output_dir(out);
  fs::create_directories(out / "members");
  for (const auto& e : fs::directory_iterator(out / "members"))
    if (e.path().filename().string().find(".partial") != std::string::npos) fs::remove_all(e.path());
  write_text_file(out / "plan.csv", plan);
  write_text_file(out / "base.resolved.toml", s.base_resolved);
  write_text_file(out / "config.resolved.toml", s.resolved_config);
  std::vector<int> pending;
  for (int i = 0; i < s.plan.members; ++i)
    if (!member_done(out, i)) pending.push_back(i);
  return pending;
}

void run_ensemble_serial(const EnsembleSetup& s, const fs::path& out, int threads, bool quiet,
                         MemberObserver* observer) {
  const std::vector<int> pending = prepare_output(s, out);
  const auto wall0 = std::chrono::steady_clock::now();
  MemberRunner runner(s);
  const int planned = static_cast<int>(pending.size());
  int done = 0;
  for (int i : pending) {
    RunObserver* steps = observer ? observer->member_started(i, done, planned) : nullptr;
    const MemberRecord r = runner.run(i, out, 0, threads, steps);
    if (observer) observer->member_finished(r, ++done, planned);
    if (!quiet)
      std::cerr << "geohaz-ensemble: member " << i << "/" << s.plan.members << (r.ok ? " done" : " FAILED: ")
                << r.diagnosis << "\n";
  }
  const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - wall0).count();
  aggregate_ensemble(s, out, 1, threads, wall, quiet);
}

fs::path member_dir(const fs::path& out, int i) {
  std::ostringstream o;
  o << std::setw(6) << std::setfill('0') << i;
  return out / "members" / o.str();
}

bool member_done(const fs::path& out, int i) {
  return fs::exists(member_dir(out, i) / "member.json");
}

// ---- aggregation and products ---------------------------------------------------------------

namespace {

/// Quantile of a sorted sample (nearest rank).
double sample_quantile(const std::vector<double>& sorted, double q) {
  if (sorted.empty()) return std::numeric_limits<double>::quiet_NaN();
  const std::size_t n = sorted.size();
  const std::size_t k = std::max<std::size_t>(1, static_cast<std::size_t>(std::ceil(q / 100.0 * n - 1e-9)));
  return sorted[std::min(n, k) - 1];
}

std::string threshold_name(double t) {
  std::ostringstream o;
  o << t;
  return o.str();
}

/// The product rasters on the DSM grid with description, unit, nodata and a QGIS style beside
/// each, and the maps for the report (docs/ensemble.md "Products"). Returns the GeoTIFFs' names.
std::vector<std::string> write_products(const AggregationSettings& a, const EnsembleAggregator& agg, const Raster& dsm,
                                        const fs::path& out) {
  std::vector<std::string> products;
  const std::vector<double> probability_classes{0.1, 0.3, 0.5, 0.7, 0.9};
  const auto put = [&](const std::string& name, const std::vector<double>& v, const std::string& description,
                       const std::string& unit, ColourRamp ramp, const std::vector<double>& breaks) {
    Raster r = dsm.like(0.0, -9999.0);
    double vmax = 0.0;
    for (std::size_t k = 0; k < v.size(); ++k) {
      r.data[k] = dsm.is_nodata(dsm.data[k]) ? -9999.0 : v[k];
      if (r.data[k] != -9999.0) vmax = std::max(vmax, r.data[k]);
    }
    r.description = description;
    r.unit = unit;
    write_geotiff(out / (name + ".tif"), r);
    if (!breaks.empty())  // the classes and colours of its map
      write_qgis_classed_style(out / (name + ".qml"), ramp, breaks, unit, 0.0);
    else
      write_qgis_ramp_style(out / (name + ".qml"), ramp, 0.0, vmax > 0.0 ? vmax : 1.0, unit, 0.0);
    products.push_back(name + ".tif");
    return r;
  };
  const std::string of_n = " over " + std::to_string(agg.members()) + " members";
  struct Map {
    std::string name, title, unit;
    Raster raster;
    std::vector<double> breaks;  ///< its classes (the probability classes for prob_*)
  };
  std::vector<Map> maps;  // drawn below, every one on the same extent
  const auto prob = [&](int field, double t, const std::string& name, std::string what) {
    Raster r = put(name, agg.exceedance(field, t), what + of_n, "1", ColourRamp::Viridis, probability_classes);
    for (std::size_t k; (k = what.find(" >= ")) != std::string::npos;) what.replace(k, 4, " \u2265 ");
    maps.push_back({name, what, "", std::move(r), probability_classes});
  };
  for (double t : a.depth_thresholds)
    prob(0, t, "prob_max_depth_gt_" + threshold_name(t) + "m", "probability peak depth > " + threshold_name(t) + " m");
  for (double t : a.speed_thresholds)
    prob(1, t, "prob_max_speed_gt_" + threshold_name(t) + "m_per_s",
         "probability peak speed > " + threshold_name(t) + " m/s");
  for (double t : a.pressure_thresholds)
    prob(2, t, "prob_max_pressure_gt_" + threshold_name(t) + "Pa",
         "probability peak pressure > " + threshold_name(t) + " Pa");
  for (int k : a.intensity_classes)
    prob(3, k, "prob_intensity_ge_" + std::to_string(k),
         "probability intensity class >= " + std::to_string(k) + " (" + to_string(a.intensity.scheme) + ")");
  Raster any_reached;  // the sum of the members' peak depths (N × the mean)
  // The mean and percentile maps of each field in the base case's classes, as its own maps: depth
  // (m), speed (m/s), pressure drawn in kPa (issue #33).
  const char* const map_titles[3] = {"peak flow depth", "peak speed", "peak dynamic pressure"};
  const char* const map_units[3] = {"m", "m/s", "kPa"};
  std::vector<double> kpa_breaks;
  for (double b : a.map_pressure_classes) kpa_breaks.push_back(b * 1e-3);
  const std::vector<double>* map_breaks[3] = {&a.map_depth_classes, &a.map_speed_classes, &kpa_breaks};
  const auto add_map = [&](int f, std::string name, std::string title, Raster r) {
    if (f == 2)
      for (double& v : r.data)
        if (v != -9999.0) v *= 1e-3;
    maps.push_back({std::move(name), std::move(title), map_units[f], std::move(r), *map_breaks[f]});
  };
  for (int f = 0; f < 3; ++f) {
    const ColourRamp ramp = f == 0 ? ColourRamp::Viridis : ColourRamp::Magma;
    const std::vector<double> none, &breaks = f == 0 ? a.map_depth_classes : none;
    Raster mean = put(std::string("mean_") + kFieldNames[f], agg.mean(f),
                      std::string("mean ") + kFieldDescriptions[f] + of_n, kFieldUnits[f], ramp, breaks);
    if (f == 0) {
      any_reached = mean;
      for (double& v : any_reached.data) v = v == -9999.0 ? v : v * agg.members();
    }
    add_map(f, std::string("mean_") + kFieldNames[f], std::string("mean ") + map_titles[f] + of_n, std::move(mean));
    for (double q : a.percentiles) {
      std::string name = "p";  // built step by step: GCC 12 warns (-Wrestrict, a false positive) on "p" + string
      name += threshold_name(q);
      name += '_';
      name += kFieldNames[f];
      Raster pr =
          put(name, agg.percentile(f, q),
              "percentile " + threshold_name(q) + " of the " + kFieldDescriptions[f] + of_n + " (log-binned histogram)",
              kFieldUnits[f], ramp, breaks);
      add_map(f, name, "percentile " + threshold_name(q) + " of " + map_titles[f], std::move(pr));
    }
  }
  if (agg.members() == 0) return products;
  // The maps on one extent: the cells where the members' peak depths add up to more than 1 cm
  // (every cell a member reached with 1 cm, as the single runs' maps), the base case's
  // output.map_margin around; probabilities in classes of 0.1 … 0.9 on a sequential ramp, depths
  // in the base case's depth classes (issue #33).
  QuicklookOptions o;
  o.ramp = ColourRamp::Viridis;
  o.extent = map_extent(any_reached, 0.01, a.map_margin);
  o.scale_bar = true;
  o.north_arrow = true;
  o.attribution = !a.attribution.empty()     ? a.attribution
                  : !dsm.attribution.empty() ? "Terrain: " + dsm.attribution
                                             : "";
  for (const Map& m : maps) {
    QuicklookOptions d = o;
    d.title = m.title;
    d.unit = m.unit;
    const bool probability = m.name.rfind("prob_", 0) == 0;
    d.overlay_min = probability ? 1e-9 : 0.01;
    d.vmin = 0.0;
    d.vmax = probability ? 1.0 : 0.0;
    d.class_breaks = m.breaks;
    if (!probability && m.name.find("max_depth") == std::string::npos) d.ramp = ColourRamp::Magma;
    write_quicklook_png(out / (m.name + ".png"), dsm, &m.raster, d);
  }
  return products;
}

/// members.csv: one row per member.
void write_members_csv(const EnsembleSetup& s, const std::vector<MemberRecord>& recs, const fs::path& out) {
  AtomicTextFile csv(out / "members.csv");
  csv << "member,status";
  for (const auto& p : s.plan.parameters) csv << ',' << p.key;
  csv << ",runout_m,drop_height_m,reach_m,H_over_L,angle_deg,release_m3,deposited_m3,mobile_m3,lost_m3,max_speed_m_"
         "s,area_affected_m2,simulated_time_s,steps,ended_by,unfinished,wall_time_s,cpu_time_s,rank,threads,"
         "diagnosis\n";
  csv.stream() << std::setprecision(10);
  for (const auto& r : recs) {
    csv << r.index << ',' << (r.ok ? "ok" : "failed");
    for (double v : r.values) csv << ',' << v;
    std::string diag = r.diagnosis;
    std::replace(diag.begin(), diag.end(), '"', '\'');
    std::replace(diag.begin(), diag.end(), '\n', ' ');
    csv << ',' << r.runout_m << ',' << r.drop_height_m << ',' << r.reach_m << ',' << r.hl << ',' << r.hl_deg << ','
        << r.release_m3 << ',' << r.deposited_m3 << ',' << r.mobile_m3 << ',' << r.lost_m3 << ',' << r.max_speed << ','
        << r.affected_area_m2 << ',' << r.simulated_time_s << ',' << r.steps << ",\"" << r.ended_by << "\","
        << (r.unfinished ? 1 : 0) << ',' << r.wall_time_s << ',' << r.cpu_time_s << ',' << r.rank << ',' << r.threads
        << ",\"" << diag << "\"\n";
  }
  csv.commit();
}

}  // namespace

void aggregate_ensemble(const EnsembleSetup& s, const fs::path& out, int ranks, int threads, double wall_time_s,
                        bool quiet) {
  const auto agg_wall0 = std::chrono::steady_clock::now();
  const int n = s.plan.members;
  // 1. Member records in index order; the union window of the successful members' peak maps.
  std::vector<MemberRecord> recs;
  recs.reserve(static_cast<std::size_t>(n));
  const Raster dsm = read_raster(s.dsm);
  int c0 = dsm.nx, r0 = dsm.ny, c1 = -1, r1 = -1;
  for (int i = 0; i < n; ++i) {
    const fs::path d = member_dir(out, i);
    std::ifstream in(d / "member.json");
    if (!in) throw std::logic_error("member " + std::to_string(i) + " has not finished");
    std::stringstream text;
    text << in.rdbuf();
    recs.push_back(parse_member_json(text.str()));
    if (!recs.back().ok) continue;
    const MemberPeaks p = read_member_peaks(d / "peaks.bin", true);
    if (p.nx != dsm.nx || p.ny != dsm.ny)
      throw InputError("member peaks on another grid than the DSM", (d / "peaks.bin").string());
    if (p.w > 0) {
      c0 = std::min(c0, p.c0), r0 = std::min(r0, p.r0);
      c1 = std::max(c1, p.c0 + p.w - 1), r1 = std::max(r1, p.r0 + p.h - 1);
    }
  }
  if (c1 < 0) c0 = r0 = 0, c1 = r1 = -1;
  // 2. Stream the peak maps (one member in memory at a time).
  EnsembleAggregator agg(dsm.nx, dsm.ny, c0, r0, c1 - c0 + 1, r1 - r0 + 1, s.aggregation);
  for (const MemberRecord& r : recs)
    if (r.ok) agg.add(read_member_peaks(member_dir(out, r.index) / "peaks.bin"));

  // 3. The products and their maps; 4. the member table, the summary.
  const std::vector<std::string> products = write_products(s.aggregation, agg, dsm, out);
  write_members_csv(s, recs, out);
  std::vector<double> runout, hl, area, member_wall, member_cpu;
  nlohmann::json failed = nlohmann::json::array();
  int unfinished = 0;
  for (const auto& r : recs) {
    member_wall.push_back(r.wall_time_s);
    member_cpu.push_back(r.cpu_time_s);
    if (!r.ok) {
      failed.push_back({{"member", r.index}, {"diagnosis", r.diagnosis}, {"values", r.values}});
      continue;
    }
    runout.push_back(r.runout_m);
    hl.push_back(r.hl);
    area.push_back(r.affected_area_m2);
    unfinished += r.unfinished ? 1 : 0;
  }
  const auto stats = [](std::vector<double> v) {
    std::sort(v.begin(), v.end());
    nlohmann::json j;
    double mean = 0.0;
    for (double x : v) mean += x;
    j["mean"] = v.empty() ? 0.0 : mean / v.size();
    j["min"] = v.empty() ? 0.0 : v.front();
    j["p10"] = v.empty() ? 0.0 : sample_quantile(v, 10);
    j["p50"] = v.empty() ? 0.0 : sample_quantile(v, 50);
    j["p90"] = v.empty() ? 0.0 : sample_quantile(v, 90);
    j["max"] = v.empty() ? 0.0 : v.back();
    return j;
  };
  nlohmann::json j;
  j["model"] = "geohaz-ensemble";
  j["version"] = GEOHAZ_VERSION;
  j["base_case"] = s.base_config.string();
  j["dsm"] = s.dsm;
  j["members"] = n;
  j["succeeded"] = agg.members();
  j["failed"] = failed;
  j["unfinished_members"] = unfinished;
  j["sampling"] = s.plan.sampling == SamplingMethod::LatinHypercube ? "latin_hypercube" : "monte_carlo";
  j["seed"] = s.plan.seed;
  nlohmann::json params = nlohmann::json::array();
  for (const auto& p : s.plan.parameters) {
    nlohmann::json q = {{"key", p.key}, {"distribution", to_string(p.kind)}};
    if (p.kind == DistributionKind::Uniform) q.update({{"min", p.a}, {"max", p.b}});
    if (p.kind == DistributionKind::Normal) q.update({{"mean", p.a}, {"sd", p.b}});
    if (p.kind == DistributionKind::LogNormal) q.update({{"median", p.a}, {"sigma", p.b}});
    if (p.kind == DistributionKind::Discrete) q.update({{"values", p.values}, {"weights", p.weights}});
    if (p.kind == DistributionKind::Fixed) q["value"] = p.a;
    if (std::isfinite(p.lower)) q["lower"] = p.lower;
    if (std::isfinite(p.upper)) q["upper"] = p.upper;
    params.push_back(q);
  }
  j["parameters"] = params;
  j["release_alternatives"] = s.plan.release_alternatives;
  j["runout_length_along_path_m"] = stats(runout);
  j["fahrboeschung_ratio_H_over_L"] = stats(hl);
  j["area_affected_m2"] = stats(area);
  j["member_wall_time_s"] = stats(member_wall);
  j["member_cpu_time_s"] = stats(member_cpu);
  double cpu_total = 0.0;
  for (double c : member_cpu) cpu_total += c;
  j["members_cpu_time_total_s"] = cpu_total;
  j["products"] = products;
  const AggregationSettings& a = s.aggregation;
  const auto ratio = [&](HistogramRange r) { return std::pow(r.hi / r.lo, 1.0 / a.bins) - 1.0; };
  j["percentile_accuracy"] = {{"method", "log-binned histogram per cell, clamped to the cell's exact extremes"},
                              {"bins", a.bins},
                              {"max_relative_error_depth", ratio(kDepthRange)},
                              {"max_relative_error_speed", ratio(kSpeedRange)},
                              {"max_relative_error_pressure", ratio(kPressureRange)},
                              {"depth_range_m", {kDepthRange.lo, kDepthRange.hi}},
                              {"speed_range_m_per_s", {kSpeedRange.lo, kSpeedRange.hi}},
                              {"pressure_range_pa", {kPressureRange.lo, kPressureRange.hi}}};
  j["aggregation_window_cells"] = static_cast<std::int64_t>(std::max(0, c1 - c0 + 1)) * std::max(0, r1 - r0 + 1);
  j["aggregation_bytes_per_cell"] = agg.bytes_per_cell();
  j["ranks"] = ranks;
  j["threads_per_rank"] = threads;
  j["wall_time_s"] = wall_time_s;
  j["aggregation_wall_time_s"] = std::chrono::duration<double>(std::chrono::steady_clock::now() - agg_wall0).count();
  write_text_file(out / "summary.json", j.dump(2) + "\n");
  if (!quiet)
    std::cerr << "geohaz-ensemble: " << agg.members() << " of " << n << " members aggregated (" << failed.size()
              << " failed); run-out P10/P50/P90 " << fmt(j["runout_length_along_path_m"]["p10"].get<double>(), 5)
              << " / " << fmt(j["runout_length_along_path_m"]["p50"].get<double>(), 5) << " / "
              << fmt(j["runout_length_along_path_m"]["p90"].get<double>(), 5) << " m; products in " << out.string()
              << "\n";
}

}  // namespace geohaz::runout
