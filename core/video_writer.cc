#include "core/video_writer.h"

#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <memory>
#include <sstream>
#include <system_error>
#include <vector>

#include "core/atomic_file.h"
#include "core/child_process.h"
#include "core/error.h"

namespace confluent {
namespace fs = std::filesystem;
namespace {

std::string FfmpegExecutable(const VideoWriterOptions& options) {
  const char* override_path = std::getenv("CONFLUENT_FFMPEG");
  return override_path != nullptr && override_path[0] != '\0' ? std::string(override_path) : options.ffmpeg;
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
  std::unique_ptr<ChildProcess> ffmpeg;  // reads the frames from its stdin
  int frames = 0;
  bool closed = false;
  std::vector<std::uint8_t> buffer;  // one padded RGB frame

  // Closes the input, waits for ffmpeg; returns its exit status.
  int Finish() {
    if (!ffmpeg) return -1;
    const int status = ffmpeg->Finish();
    ffmpeg.reset();
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
  try {
    s.ffmpeg = std::make_unique<ChildProcess>(args, s.log_path, /*stdout_to_socket=*/false);
  } catch (const std::system_error& error) {
    s.RemoveTemporaries();
    throw OutputError(path, "cannot run '" + ffmpeg + "' to encode the video (" + std::strerror(error.code().value()) +
                                "); install FFmpeg or set $CONFLUENT_FFMPEG");
  }
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
  if (!s.ffmpeg->Send(s.buffer.data(), s.buffer.size())) {
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
  bool ok = false;
  try {
    ok = ChildProcess({FfmpegExecutable(options), "-hide_banner", "-version"}, log, false).Finish() == 0;
  } catch (const std::system_error&) {
  }
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
