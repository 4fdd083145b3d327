#pragma once
// What the app tests of geohaz-ensemble and geohaz-calibrate share (both run members over MPI ranks
// through apps/member-queue): a fresh work folder, the app alone or under mpirun, the output's
// summary.json, and a run killed with SIGKILL once some members are on disk.
#include <fcntl.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <filesystem>
#include <fstream>
#include <functional>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "geohaz/runout/summary_keys.hpp"
#include "summary_keys_check.hpp"

namespace member_app {

namespace fs = std::filesystem;

/// A new, empty folder build/tests/runout/<area>/<name>_<pid>.
inline fs::path work_dir(const std::string& area, const std::string& name) {
  const fs::path d =
      fs::path(GEOHAZ_BINARY_DIR) / "tests" / "runout" / area / (name + "_" + std::to_string(::getpid()));
  fs::remove_all(d);
  fs::create_directories(d);
  return d;
}

/// The shell command running `exe` with `args`.
inline std::string command(const std::string& exe, const std::string& args) {
  return exe + " " + args;
}

/// The same under the MPI launcher with `np` ranks (more ranks than cores allowed; as root in CI
/// containers). GEOHAZ_MPIEXEC is empty when the apps were built without MPI.
inline std::string mpirun(const std::string& exe, int np, const std::string& args) {
  std::string cmd = std::string(GEOHAZ_MPIEXEC) + " --oversubscribe -np " + std::to_string(np) + " ";
  if (::geteuid() == 0) cmd += "--allow-run-as-root ";
  return cmd + command(exe, args);
}

inline bool have_mpi() {
  return !std::string(GEOHAZ_MPIEXEC).empty();
}

inline std::string slurp(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

inline nlohmann::json summary(const fs::path& out) {
  const auto j = nlohmann::json::parse(slurp(out / "summary.json"));
  EXPECT_SUMMARY_KEYS_DECLARED(j, geohaz::runout::summary_keys());  // every number labelled (issue #33)
  return j;
}

/// Start `exe` with `args` (no shell, so that the signal hits the app itself; output discarded),
/// wait until `enough()` holds (at most `timeout_s`), then SIGKILL it. Returns whether the signal
/// ended it (false: the run finished before).
inline bool kill_when(const std::string& exe, const std::vector<std::string>& args, const std::function<bool()>& enough,
                      double timeout_s = 120.0) {
  const pid_t pid = ::fork();
  if (pid < 0) return false;
  if (pid == 0) {
    const int null = ::open("/dev/null", O_WRONLY);
    ::dup2(null, 1), ::dup2(null, 2);
    std::vector<char*> argv{const_cast<char*>(exe.c_str())};
    for (const auto& a : args) argv.push_back(const_cast<char*>(a.c_str()));
    argv.push_back(nullptr);
    ::execv(exe.c_str(), argv.data());
    ::_exit(127);
  }
  const auto t0 = std::chrono::steady_clock::now();
  while (!enough() && std::chrono::steady_clock::now() - t0 < std::chrono::duration<double>(timeout_s))
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  ::kill(pid, SIGKILL);
  int status = 0;
  ::waitpid(pid, &status, 0);
  return WIFSIGNALED(status);
}

}  // namespace member_app
