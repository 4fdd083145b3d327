#include "geohaz/core/resources.hpp"

#include <sys/resource.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <limits>
#include <sstream>

#include "geohaz/core/errors.hpp"

namespace geohaz {

double available_memory_bytes() {
  double avail = std::numeric_limits<double>::infinity();
  std::ifstream meminfo("/proc/meminfo");
  std::string name;
  double kb = 0.0;
  std::string unit;
  while (meminfo >> name >> kb >> unit) {
    if (name == "MemAvailable:") {
      avail = kb * 1024.0;
      break;
    }
  }
  rlimit lim{};
  if (getrlimit(RLIMIT_AS, &lim) == 0 && lim.rlim_cur != RLIM_INFINITY)
    avail = std::min(avail, static_cast<double>(lim.rlim_cur));
  return avail;
}

std::string format_bytes(double bytes) {
  if (!std::isfinite(bytes)) return "an unbounded amount";
  const char* units[] = {"B", "kB", "MB", "GB", "TB", "PB", "EB"};
  int u = 0;
  while (bytes >= 1000.0 && u < 6) {
    bytes /= 1000.0;
    ++u;
  }
  char buf[48];
  std::snprintf(buf, sizeof buf, bytes < 10.0 && u > 0 ? "%.1f %s" : "%.0f %s", bytes, units[u]);
  return buf;
}

void check_memory(double bytes, const std::string& what, std::string file, std::string key, std::string value) {
  const double avail = available_memory_bytes();
  if (bytes <= avail) return;  // NaN (an absurd input) fails too
  throw InputError("needs about " + format_bytes(bytes) + " of memory (" + what + "), more than the " +
                       format_bytes(avail) + " available",
                   std::move(file), std::move(key), std::move(value));
}

}  // namespace geohaz
