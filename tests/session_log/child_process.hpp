#pragma once
// Runs a piece of a test in a forked child (a file size limit, a mount namespace, a SIGKILL), which
// reports back through a pipe. The child never returns into GoogleTest: it ends with _exit.

#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cerrno>
#include <cstdint>
#include <functional>
#include <stdexcept>
#include <type_traits>
#include <vector>

namespace furuta::session_log::testing {

// Exit code of a child that found its environment unable to run the test (not a failure).
inline constexpr int kChildSkip = 77;

// Owns the two ends of a pipe.
class Pipe {
 public:
  Pipe() {
    if (::pipe(fds_) != 0) throw std::runtime_error("pipe failed");
  }
  ~Pipe() {
    close_read();
    close_write();
  }
  Pipe(const Pipe&) = delete;
  Pipe& operator=(const Pipe&) = delete;

  int read_fd() const { return fds_[0]; }
  int write_fd() const { return fds_[1]; }
  void close_read() { close_end(0); }
  void close_write() { close_end(1); }

  // Writes one fixed-size record; records up to PIPE_BUF bytes arrive whole.
  template <typename T>
  bool send(const T& value) const {
    static_assert(std::is_trivially_copyable_v<T> && sizeof(T) <= 512);
    return ::write(fds_[1], &value, sizeof value) == static_cast<ssize_t>(sizeof value);
  }

  // Reads one record; false at end of file (every writer gone).
  template <typename T>
  bool receive(T& value) const {
    std::size_t done = 0;
    auto* bytes = reinterpret_cast<unsigned char*>(&value);
    while (done < sizeof value) {
      const ssize_t n = ::read(fds_[0], bytes + done, sizeof value - done);
      if (n < 0 && errno == EINTR) continue;
      if (n <= 0) return false;
      done += static_cast<std::size_t>(n);
    }
    return true;
  }

 private:
  void close_end(int i) {
    if (fds_[i] >= 0) ::close(fds_[i]);
    fds_[i] = -1;
  }
  int fds_[2] = {-1, -1};
};

// Forks; the child runs `body` (its return value is the exit code) and never comes back.
inline pid_t fork_child(const std::function<int()>& body) {
  const pid_t pid = ::fork();
  if (pid < 0) throw std::runtime_error("fork failed");
  if (pid == 0) {
    int code = 1;
    try {
      code = body();
    } catch (...) {
      code = 2;
    }
    ::_exit(code);
  }
  return pid;
}

// The child's exit code, or 128 + signal when a signal ended it.
inline int wait_child(pid_t pid) {
  int status = 0;
  while (::waitpid(pid, &status, 0) < 0) {
    if (errno != EINTR) return -1;
  }
  if (WIFEXITED(status)) return WEXITSTATUS(status);
  if (WIFSIGNALED(status)) return 128 + WTERMSIG(status);
  return -1;
}

}  // namespace furuta::session_log::testing
