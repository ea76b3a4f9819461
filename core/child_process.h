#pragma once
// A child process that this one talks to through a socket: the child's stdin, and optionally
// its stdout, is the other end. A socket rather than a pipe: sending to a child that has died
// is reported as a failed Send instead of raising SIGPIPE in the whole process.

#include <sys/types.h>

#include <cstddef>
#include <string>
#include <vector>

namespace confluent {

class ChildProcess {
 public:
  // Runs args[0] (looked up in $PATH) with `args`. Its stderr goes to `stderr_path` (created or
  // truncated), its stdout to the socket when `stdout_to_socket`, else to /dev/null. Throws
  // std::system_error when it cannot be started (errno: ENOENT for a program not found).
  ChildProcess(const std::vector<std::string>& args, const std::string& stderr_path, bool stdout_to_socket);
  // Closes the socket and waits for the child.
  ~ChildProcess();
  ChildProcess(const ChildProcess&) = delete;
  ChildProcess& operator=(const ChildProcess&) = delete;

  // Sends all `size` bytes; false when the child no longer reads.
  bool Send(const void* data, std::size_t size);
  // Receives exactly `size` bytes; false when the child closes its end first.
  bool Receive(void* data, std::size_t size);
  // Closes this end (the child sees the end of its input) and waits for the child. Returns its
  // exit status, 128 + signal when a signal ended it, -1 when unknown. Later calls return -1.
  int Finish();

 private:
  int socket_fd_ = -1;
  pid_t pid_ = -1;
};

// The last `max_lines` non-empty lines of a text file (a child's stderr log), joined with " | ".
std::string TailOfFile(const std::string& path, int max_lines);

}  // namespace confluent
