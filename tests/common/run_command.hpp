#pragma once
// Test helper shared by the app regression tests: run a shell command (an app with its arguments)
// and return its exit status with everything it printed on stdout and stderr.
#include <sys/wait.h>

#include <cstdio>
#include <string>

namespace geohaz::testing {

struct CommandResult {
  int code = -1;       ///< exit status; -1 when the process did not exit normally
  std::string output;  ///< stdout and stderr, interleaved
};

inline CommandResult run_command(const std::string& command) {
  CommandResult r;
  FILE* p = popen((command + " 2>&1").c_str(), "r");
  if (!p) return r;
  char buf[4096];
  while (std::size_t n = std::fread(buf, 1, sizeof buf, p)) r.output.append(buf, n);
  const int status = pclose(p);
  r.code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  return r;
}

}  // namespace geohaz::testing
