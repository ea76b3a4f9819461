#include "core/child_process.h"

#include <fcntl.h>
#include <spawn.h>
#include <sys/socket.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <fstream>
#include <system_error>

extern char** environ;

namespace confluent {

ChildProcess::ChildProcess(const std::vector<std::string>& args, const std::string& stderr_path,
                           bool stdout_to_socket) {
  if (args.empty()) throw std::system_error(EINVAL, std::generic_category(), "no program to run");
  int fds[2];
  // Close-on-exec: another child must not inherit this socket, or this child never sees the
  // end of its input while the other one runs.
  if (socketpair(AF_UNIX, SOCK_STREAM | SOCK_CLOEXEC, 0, fds) != 0)
    throw std::system_error(errno, std::generic_category(), "cannot create a socket");
  std::vector<char*> argv;
  for (const auto& arg : args) argv.push_back(const_cast<char*>(arg.c_str()));
  argv.push_back(nullptr);
  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  posix_spawn_file_actions_adddup2(&actions, fds[1], 0);  // dup2 clears close-on-exec
  if (stdout_to_socket) {
    posix_spawn_file_actions_adddup2(&actions, fds[1], 1);
  } else {
    posix_spawn_file_actions_addopen(&actions, 1, "/dev/null", O_WRONLY, 0);
  }
  posix_spawn_file_actions_addopen(&actions, 2, stderr_path.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
  pid_t pid = -1;
  const int error = posix_spawnp(&pid, argv[0], &actions, nullptr, argv.data(), environ);
  posix_spawn_file_actions_destroy(&actions);
  close(fds[1]);
  if (error != 0) {
    close(fds[0]);
    throw std::system_error(error, std::generic_category(), "cannot run " + args[0]);
  }
  socket_fd_ = fds[0];
  pid_ = pid;
}

ChildProcess::~ChildProcess() { Finish(); }

bool ChildProcess::Send(const void* data, std::size_t size) {
  const char* bytes = static_cast<const char*>(data);
  while (size > 0) {
    if (socket_fd_ < 0) return false;
    const ssize_t sent = send(socket_fd_, bytes, size, MSG_NOSIGNAL);
    if (sent < 0) {
      if (errno == EINTR) continue;
      return false;
    }
    bytes += sent;
    size -= static_cast<std::size_t>(sent);
  }
  return true;
}

bool ChildProcess::Receive(void* data, std::size_t size) {
  char* bytes = static_cast<char*>(data);
  while (size > 0) {
    if (socket_fd_ < 0) return false;
    const ssize_t got = recv(socket_fd_, bytes, size, 0);
    if (got < 0 && errno == EINTR) continue;
    if (got <= 0) return false;
    bytes += got;
    size -= static_cast<std::size_t>(got);
  }
  return true;
}

std::string TailOfFile(const std::string& path, int max_lines) {
  std::ifstream in(path);
  std::vector<std::string> lines;
  std::string line;
  while (std::getline(in, line)) {
    while (!line.empty() && (line.back() == '\r' || line.back() == ' ')) line.pop_back();
    if (!line.empty()) lines.push_back(line);
  }
  std::string tail;
  const int first = std::max(0, static_cast<int>(lines.size()) - max_lines);
  for (int i = first; i < static_cast<int>(lines.size()); ++i) tail += (tail.empty() ? "" : " | ") + lines[i];
  return tail;
}


int ChildProcess::Finish() {
  if (socket_fd_ >= 0) {
    close(socket_fd_);
    socket_fd_ = -1;
  }
  if (pid_ <= 0) return -1;
  int status = 0;
  int result = -1;
  while (waitpid(pid_, &status, 0) < 0) {
    if (errno != EINTR) {
      pid_ = -1;
      return -1;
    }
  }
  if (WIFEXITED(status)) result = WEXITSTATUS(status);
  if (WIFSIGNALED(status)) result = 128 + WTERMSIG(status);
  pid_ = -1;
  return result;
}

}  // namespace confluent
