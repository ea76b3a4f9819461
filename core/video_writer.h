#pragma once
// Writing H.264 MP4 videos: raw RGB8 frames are piped to the `ffmpeg` executable
// (libx264, yuv420p, +faststart), so the file plays in standard players.

#include <memory>
#include <string>
#include <vector>

#include "core/image.h"

namespace confluent {

// Options of a VideoWriter.
struct VideoWriterOptions {
  double fps = 25.0;  // frames per second of the output
  int crf = 18;       // libx264 constant rate factor (0 = lossless .. 51 = worst); 18 ~ visually lossless
  std::string preset = "veryfast";  // libx264 speed/size preset (ultrafast .. veryslow)
  // The ffmpeg executable: a path, or a name looked up on $PATH. $CONFLUENT_FFMPEG overrides it.
  std::string ffmpeg = "ffmpeg";
  // Throws UsageError when a value is out of range (fps <= 0, crf outside 0..51, empty names).
  void Check() const;
};

// Streams RGB frames into an H.264 MP4. The file is written to a temporary name beside `path`
// and renamed on Close(), so an interrupted video never looks complete. yuv420p needs even
// sizes: odd widths/heights are padded by one black column/row. Not copyable.
class VideoWriter {
 public:
  // Starts ffmpeg for a `width_px` x `height_px` video at `path` (parent folders are created).
  // Throws OutputError(path) when ffmpeg cannot be found or started, UsageError for bad sizes
  // or options.
  VideoWriter(const std::string& path, int width_px, int height_px, const VideoWriterOptions& options = {});
  // Closes the video if Close() was not called (errors are swallowed; the temporary file is
  // removed, so `path` is not written).
  ~VideoWriter();
  VideoWriter(const VideoWriter&) = delete;
  VideoWriter& operator=(const VideoWriter&) = delete;

  // Appends one frame: 8-bit, 3 (RGB) or 4 (RGBA; alpha dropped) or 1 (grey) channels, of the
  // size given at construction. Throws UsageError for a wrong size/type and OutputError(path)
  // when ffmpeg died (its last stderr lines are in the message).
  void Write(const Image& frame);

  // Finishes the file: waits for ffmpeg and renames the temporary file to `path`. Throws
  // OutputError(path) with ffmpeg's stderr tail when ffmpeg failed or no frame was written.
  void Close();

  int frames_written() const;
  const std::string& path() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

// True when the ffmpeg executable (options.ffmpeg / $CONFLUENT_FFMPEG) can be run.
bool FfmpegAvailable(const VideoWriterOptions& options = {});

// Writes a whole video at once (see VideoWriter). Throws as VideoWriter.
void WriteVideo(const std::string& path, const std::vector<Image>& frames, const VideoWriterOptions& options = {});

}  // namespace confluent
