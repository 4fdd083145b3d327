#pragma once
// Test helper: run an app (or a function) in a child process with a time limit and an optional
// file size limit, and report how it ended. A file size limit (RLIMIT_FSIZE, with SIGXFSZ ignored so
// that write() fails with EFBIG instead of killing the process) is how the tests simulate a full
// disk: it needs no root, no mount and no real disk filling, and works the same in CI.
#include <fcntl.h>
#include <poll.h>
#include <signal.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cstdlib>
#include <functional>
#include <string>
#include <vector>

namespace geohaz::testing {

struct ChildLimits {
  double timeout_s = 60.0;   ///< killed (SIGKILL, whole process group) after this
  long long file_size = -1;  ///< RLIMIT_FSIZE in bytes (< 0: none)
  std::string stdin_path = "/dev/null";
};

struct ChildResult {
  bool exited = false;     ///< ended through exit()
  int code = -1;           ///< exit status when exited
  int signal = 0;          ///< terminating signal otherwise
  bool timed_out = false;  ///< killed by us after timeout_s
  std::string out, err;    ///< what it printed
  double seconds = 0.0;    ///< wall time
  /// "exit 2", "signal 11", "timeout"
  std::string describe() const {
    if (timed_out) return "timeout";
    return exited ? "exit " + std::to_string(code) : "signal " + std::to_string(signal);
  }
};

namespace detail {
inline void apply_limits_in_child(const ChildLimits& lim) {
  setpgid(0, 0);  // own process group, so a timeout kills the app's helpers too
  if (lim.file_size >= 0) {
    signal(SIGXFSZ, SIG_IGN);
    rlimit r{static_cast<rlim_t>(lim.file_size), static_cast<rlim_t>(lim.file_size)};
    setrlimit(RLIMIT_FSIZE, &r);
  }
}

/// Read both pipes until they close or the deadline passes; then reap the child.
inline ChildResult collect(pid_t pid, int out_fd, int err_fd, double timeout_s) {
  ChildResult r;
  const auto t0 = std::chrono::steady_clock::now();
  auto elapsed = [&] { return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count(); };
  pollfd fds[2] = {{out_fd, POLLIN, 0}, {err_fd, POLLIN, 0}};
  int open_fds = 2;
  char buf[4096];
  while (open_fds > 0) {
    const double left = timeout_s - elapsed();
    if (left <= 0) {
      r.timed_out = true;
      kill(-pid, SIGKILL);
      kill(pid, SIGKILL);
      break;
    }
    const int n = poll(fds, 2, static_cast<int>(left * 1000) + 1);
    if (n < 0) continue;
    for (int k = 0; k < 2; ++k) {
      if (fds[k].fd < 0 || !(fds[k].revents & (POLLIN | POLLHUP | POLLERR))) continue;
      const ssize_t got = read(fds[k].fd, buf, sizeof buf);
      if (got <= 0) {
        close(fds[k].fd);
        fds[k].fd = -1;
        --open_fds;
      } else {
        (k == 0 ? r.out : r.err).append(buf, static_cast<std::size_t>(got));
      }
    }
  }
  for (auto& f : fds)
    if (f.fd >= 0) close(f.fd);
  int status = 0;
  // The pipes close at exit; a child that closed them early and hangs is caught here.
  while (true) {
    const pid_t w = waitpid(pid, &status, WNOHANG);
    if (w == pid) break;
    if (elapsed() > timeout_s && !r.timed_out) {
      r.timed_out = true;
      kill(-pid, SIGKILL);
      kill(pid, SIGKILL);
    }
    usleep(2000);
  }
  r.seconds = elapsed();
  if (WIFEXITED(status)) {
    r.exited = true;
    r.code = WEXITSTATUS(status);
  } else if (WIFSIGNALED(status)) {
    r.signal = WTERMSIG(status);
  }
  return r;
}
}  // namespace detail

/// Run argv[0] (a path) with its arguments; stdout and stderr captured separately.
inline ChildResult run_process(const std::vector<std::string>& argv, const ChildLimits& lim = {}) {
  int out_pipe[2], err_pipe[2];
  if (pipe(out_pipe) != 0 || pipe(err_pipe) != 0) return {};
  const pid_t pid = fork();
  if (pid == 0) {
    detail::apply_limits_in_child(lim);
    const int in = open(lim.stdin_path.c_str(), O_RDONLY);
    if (in >= 0) dup2(in, 0);
    dup2(out_pipe[1], 1);
    dup2(err_pipe[1], 2);
    close(out_pipe[0]);
    close(err_pipe[0]);
    std::vector<char*> args;
    for (const auto& a : argv) args.push_back(const_cast<char*>(a.c_str()));
    args.push_back(nullptr);
    execv(args[0], args.data());
    _exit(127);
  }
  close(out_pipe[1]);
  close(err_pipe[1]);
  return detail::collect(pid, out_pipe[0], err_pipe[0], lim.timeout_s);
}

/// Run `body` in a forked child under the limits; its return value is the exit code. For unit
/// tests of code that must fail cleanly on a full disk (the test process itself keeps no limit).
inline ChildResult run_in_child(const std::function<int()>& body, const ChildLimits& lim = {}) {
  int out_pipe[2], err_pipe[2];
  if (pipe(out_pipe) != 0 || pipe(err_pipe) != 0) return {};
  const pid_t pid = fork();
  if (pid == 0) {
    detail::apply_limits_in_child(lim);
    dup2(out_pipe[1], 1);
    dup2(err_pipe[1], 2);
    close(out_pipe[0]);
    close(err_pipe[0]);
    int code = 100;
    try {
      code = body();
    } catch (...) {
      code = 101;  // an exception the body did not expect
    }
    std::fflush(nullptr);
    _exit(code);
  }
  close(out_pipe[1]);
  close(err_pipe[1]);
  return detail::collect(pid, out_pipe[0], err_pipe[0], lim.timeout_s);
}

}  // namespace geohaz::testing
