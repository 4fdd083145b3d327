#include "case_support.hpp"

#include <filesystem>
#include <iomanip>
#include <sstream>

#include "geohaz/runout/run.hpp"

namespace geohaz::runout::detail {

std::string fmt(double v, int prec) {
  std::ostringstream o;
  o << std::setprecision(prec) << v;
  return o.str();
}

std::string resolve_path(const ConfigReader& cfg, std::string p) {
  namespace fs = std::filesystem;
  if (!p.empty() && !cfg.source().empty() && fs::path(p).is_relative() && !fs::exists(p))
    return (cfg.base_dir() / p).string();
  return p;
}

std::string origin(const ConfigReader& cfg) {
  return cfg.source().empty() ? "command line" : cfg.source();
}

std::set<std::string> numeric_case_keys() {
  ConfigReader d = ConfigReader::describe();
  read_config(d);
  std::set<std::string> keys;
  for (const KeyReference& r : d.reference())
    if (r.type == "number" || r.type == "integer") keys.insert(r.key);
  return keys;
}

}  // namespace geohaz::runout::detail
