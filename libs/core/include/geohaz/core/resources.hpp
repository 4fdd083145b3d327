#pragma once
/// \file resources.hpp
/// What an input asks of the machine, checked before anything is allocated: an input that would
/// need more memory than the machine has is bad input (InputError, exit code 2) naming the key or
/// file that asked for it and the estimate, instead of a std::bad_alloc (or the kernel's OOM
/// killer) in the middle of a run.
///
/// Estimates are made from the config and the raster headers alone (counts × bytes per item), so
/// they are cheap and happen before the output directory exists. They are lower bounds of what a
/// run needs; the check is against the memory available now (MemAvailable in /proc/meminfo, or the
/// address-space limit of the process if that is smaller).

#include <cstdint>
#include <string>

namespace geohaz {

/// Memory this process can still allocate, in bytes: the smaller of the system's available memory
/// and the room left under RLIMIT_AS. Unknown parts count as unlimited.
double available_memory_bytes();

/// "1.5 GB", "230 MB", "12 kB" (decimal units).
std::string format_bytes(double bytes);

/// Throws InputError when `bytes` (the estimate; may be inf or NaN for an absurd input) exceeds
/// what is available. The message states the estimate, what it counts (`what`, e.g.
/// "3.2e9 particles × 600 B") and the memory available.
/// \param file, key, value as InputError: where the request came from.
void check_memory(double bytes, const std::string& what, std::string file, std::string key, std::string value = {});

}  // namespace geohaz
