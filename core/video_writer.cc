#include "core/video_writer.h"

#include <fcntl.h>
#include <spawn.h>
#include <sys/socket.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <vector>

#include "core/atomic_file.h"
#include "core/error.h"

extern char** environ;

namespace confluent {
namespace fs = std::filesystem;
namespace {

std::string FfmpegExecutable(const VideoWriterOptions& options) {
  const char* override_path = std::getenv("CONFLUENT_FFMPEG");
  return override_path != nullptr && override_path[0] != '\0' ? std::string(override_path) : options.ffmpeg;
}

// The last `max_lines` non-empty lines of a text file, joined with " | ".
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

// Spawns `argv` with stdin from `stdin_fd` (or /dev/null when -1), stdout to /dev/null and
// stderr to `stderr_path`. Returns the pid, or -1 with errno-like code in *error.
pid_t Spawn(const std::vector<std::string>& args, int stdin_fd, int close_fd, const std::string& stderr_path,
            int* error) {
  std::vector<char*> argv;
  for (const auto& arg : args) argv.push_back(const_cast<char*>(arg.c_str()));
  argv.push_back(nullptr);
  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  if (stdin_fd >= 0) {
    posix_spawn_file_actions_adddup2(&actions, stdin_fd, 0);
  } else {
    posix_spawn_file_actions_addopen(&actions, 0, "/dev/null", O_RDONLY, 0);
  }
  if (close_fd >= 0) posix_spawn_file_actions_addclose(&actions, close_fd);
  posix_spawn_file_actions_addopen(&actions, 1, "/dev/null", O_WRONLY, 0);
  posix_spawn_file_actions_addopen(&actions, 2, stderr_path.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
  pid_t pid = -1;
  *error = posix_spawnp(&pid, argv[0], &actions, nullptr, argv.data(), environ);
  posix_spawn_file_actions_destroy(&actions);
  return *error == 0 ? pid : -1;
}

// Waits for `pid`; returns its exit status, or 128 + signal, or -1.
int WaitFor(pid_t pid) {
  int status = 0;
  while (waitpid(pid, &status, 0) < 0) {
    if (errno != EINTR) return -1;
  }
  if (WIFEXITED(status)) return WEXITSTATUS(status);
  if (WIFSIGNALED(status)) return 128 + WTERMSIG(status);
  return -1;
}

}  // namespace

void VideoWriterOptions::Check() const {
  const std::string owner = "VideoWriterOptions.";
  RequireOption(fps > 0.0 && fps <= 1000.0, owner + "fps", fps, "in (0, 1000]");
  RequireOption(crf >= 0 && crf <= 51, owner + "crf", crf, "in 0..51");
  if (preset.empty()) throw UsageError(owner + "preset = '': must not be empty");
  if (ffmpeg.empty()) throw UsageError(owner + "ffmpeg = '': must not be empty (the ffmpeg executable)");
}

struct VideoWriter::Impl {
  std::string path;
  std::string temporary_path;
  std::string log_path;
  int width = 0;         // frame size accepted by Write
  int height = 0;
  int encoded_width = 0;  // padded to even sizes
  int encoded_height = 0;
  int socket_fd = -1;    // our end of the socket ffmpeg reads from
  pid_t pid = -1;
  int frames = 0;
  bool closed = false;
  std::vector<std::uint8_t> buffer;  // one padded RGB frame

  // Sends the whole buffer; false when ffmpeg is gone.
  bool SendAll(const std::uint8_t* data, std::size_t size) {
    while (size > 0) {
      const ssize_t sent = send(socket_fd, data, size, MSG_NOSIGNAL);
      if (sent < 0) {
        if (errno == EINTR) continue;
        return false;
      }
      data += sent;
      size -= static_cast<std::size_t>(sent);
    }
    return true;
  }

  // Closes the input, waits for ffmpeg; returns its exit status.
  int Finish() {
    if (socket_fd >= 0) {
      close(socket_fd);
      socket_fd = -1;
    }
    int status = -1;
    if (pid > 0) {
      status = WaitFor(pid);
      pid = -1;
    }
    return status;
  }

  void RemoveTemporaries() {
    std::error_code error;
    fs::remove(temporary_path, error);
    fs::remove(log_path, error);
  }
};

VideoWriter::VideoWriter(const std::string& path, int width_px, int height_px, const VideoWriterOptions& options)
    : impl_(std::make_unique<Impl>()) {
  options.Check();
  if (width_px <= 0 || height_px <= 0 || width_px > 16384 || height_px > 16384)
    throw UsageError("video size must be in 1..16384 pixels, got " + std::to_string(width_px) + "x" +
                     std::to_string(height_px));
  Impl& s = *impl_;
  s.path = path;
  s.width = width_px;
  s.height = height_px;
  s.encoded_width = width_px + (width_px % 2);
  s.encoded_height = height_px + (height_px % 2);
  s.buffer.assign(static_cast<std::size_t>(s.encoded_width) * s.encoded_height * 3, 0);

  const fs::path target(path);
  std::error_code error;
  if (target.has_parent_path()) {
    fs::create_directories(target.parent_path(), error);
    if (error) throw OutputError(path, "cannot create folder " + target.parent_path().string() + ": " + error.message());
  }
  const std::string stem = ".tmp" + std::to_string(getpid()) + "_" + target.filename().string();
  s.temporary_path = (target.parent_path() / stem).string();
  s.log_path = (target.parent_path() / (stem + ".log")).string();

  // A socket instead of a pipe: send(MSG_NOSIGNAL) reports a dead reader as an error instead
  // of raising SIGPIPE in the whole process.
  int fds[2];
  // Close-on-exec: another writer's ffmpeg must not inherit this socket, or this ffmpeg never
  // sees the end of its input while the other one runs (two videos written at once hang).
  if (socketpair(AF_UNIX, SOCK_STREAM | SOCK_CLOEXEC, 0, fds) != 0)
    throw OutputError(path, std::string("cannot create a socket for ffmpeg: ") + std::strerror(errno));
  const std::string ffmpeg = FfmpegExecutable(options);
  char fps_text[32];
  std::snprintf(fps_text, sizeof(fps_text), "%.6g", options.fps);
  const std::vector<std::string> args = {
      ffmpeg, "-hide_banner", "-loglevel", "error", "-nostdin", "-y",
      "-f", "rawvideo", "-pix_fmt", "rgb24",
      "-s", std::to_string(s.encoded_width) + "x" + std::to_string(s.encoded_height),
      "-r", fps_text, "-i", "pipe:0",
      "-an", "-c:v", "libx264", "-preset", options.preset, "-crf", std::to_string(options.crf),
      "-pix_fmt", "yuv420p", "-movflags", "+faststart", "-f", "mp4", s.temporary_path};
  int spawn_error = 0;
  s.pid = Spawn(args, fds[1], fds[0], s.log_path, &spawn_error);
  close(fds[1]);
  if (s.pid < 0) {
    close(fds[0]);
    s.RemoveTemporaries();
    throw OutputError(path, "cannot run '" + ffmpeg + "' to encode the video (" + std::strerror(spawn_error) +
                                "); install FFmpeg or set $CONFLUENT_FFMPEG");
  }
  s.socket_fd = fds[0];
}

VideoWriter::~VideoWriter() {
  if (impl_ && !impl_->closed) {
    impl_->Finish();
    impl_->RemoveTemporaries();
  }
}

void VideoWriter::Write(const Image& frame) {
  Impl& s = *impl_;
  if (s.closed) throw UsageError("VideoWriter::Write after Close (" + s.path + ")");
  if (frame.width != s.width || frame.height != s.height)
    throw UsageError("video frame is " + std::to_string(frame.width) + "x" + std::to_string(frame.height) +
                     ", expected " + std::to_string(s.width) + "x" + std::to_string(s.height) + " (" + s.path + ")");
  if (frame.type != PixelType::kUInt8 || (frame.channels != 1 && frame.channels != 3 && frame.channels != 4))
    throw UsageError("video frames must be 8-bit grey, RGB or RGBA (" + s.path + ")");
  const std::uint8_t* source = frame.data.data();
  for (int y = 0; y < s.height; ++y) {
    std::uint8_t* row = s.buffer.data() + static_cast<std::size_t>(y) * s.encoded_width * 3;
    const std::uint8_t* in = source + static_cast<std::size_t>(y) * frame.width * frame.channels;
    if (frame.channels == 3) {
      std::memcpy(row, in, static_cast<std::size_t>(s.width) * 3);
    } else {
      for (int x = 0; x < s.width; ++x)
        for (int c = 0; c < 3; ++c) row[x * 3 + c] = in[x * frame.channels + (frame.channels == 1 ? 0 : c)];
    }
  }
  if (!s.SendAll(s.buffer.data(), s.buffer.size())) {
    const int status = s.Finish();
    s.closed = true;
    const std::string tail = TailOfFile(s.log_path, 3);
    s.RemoveTemporaries();
    throw OutputError(s.path, "ffmpeg stopped while encoding (exit status " + std::to_string(status) + ")" +
                                  (tail.empty() ? "" : ": " + tail));
  }
  ++s.frames;
}

void VideoWriter::Close() {
  Impl& s = *impl_;
  if (s.closed) return;
  const int status = s.Finish();
  s.closed = true;
  if (s.frames == 0) {
    s.RemoveTemporaries();
    throw OutputError(s.path, "no frames were written to the video");
  }
  if (status != 0) {
    const std::string tail = TailOfFile(s.log_path, 3);
    s.RemoveTemporaries();
    throw OutputError(s.path, (status == 127 ? "ffmpeg could not be run" : "ffmpeg failed with exit status " +
                                                                               std::to_string(status)) +
                                  (tail.empty() ? "" : ": " + tail));
  }
  // ffmpeg (5.1) exits 0 when writing the file fails at the end ("Error writing trailer of ...:
  // File too large"), leaving a truncated file: its log (errors only) must name no error.
  const std::string log = TailOfFile(s.log_path, 3);
  if (log.find("Error") != std::string::npos || log.find("error") != std::string::npos) {
    s.RemoveTemporaries();
    throw OutputError(s.path, "ffmpeg could not write the video: " + log);
  }
  std::error_code error;
  if (!fs::exists(s.temporary_path, error)) {
    s.RemoveTemporaries();
    throw OutputError(s.path, "ffmpeg produced no output file");
  }
  KillHookBeforeRename(s.path);
  fs::rename(s.temporary_path, s.path, error);
  if (error) {
    s.RemoveTemporaries();
    throw OutputError(s.path, "cannot rename temporary video: " + error.message());
  }
  fs::remove(s.log_path, error);
}

int VideoWriter::frames_written() const { return impl_->frames; }
const std::string& VideoWriter::path() const { return impl_->path; }

bool FfmpegAvailable(const VideoWriterOptions& options) {
  const std::string log = (fs::temp_directory_path() / (".confluent_ffmpeg_probe" + std::to_string(getpid()))).string();
  int error = 0;
  const pid_t pid = Spawn({FfmpegExecutable(options), "-hide_banner", "-version"}, -1, -1, log, &error);
  bool ok = false;
  if (pid > 0) ok = WaitFor(pid) == 0;
  std::error_code ignored;
  fs::remove(log, ignored);
  return ok;
}

void WriteVideo(const std::string& path, const std::vector<Image>& frames, const VideoWriterOptions& options) {
  if (frames.empty()) throw OutputError(path, "no frames were written to the video");
  VideoWriter writer(path, frames.front().width, frames.front().height, options);
  for (const Image& frame : frames) writer.Write(frame);
  writer.Close();
}

}  // namespace confluent
