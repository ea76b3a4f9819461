#pragma once
// Video frame decoding through OpenCV/FFmpeg.

#include <memory>
#include <string>

#include "core/image.h"

namespace confluent {

// Reads frames of a video file by index. Sequential reads are fast; seeking backwards reopens.
class VideoReader {
 public:
  // Opens `path`. Throws InputError naming the file if it is missing or cannot be decoded.
  explicit VideoReader(const std::string& path);
  ~VideoReader();
  VideoReader(VideoReader&&) noexcept;
  VideoReader& operator=(VideoReader&&) noexcept;

  // Number of frames actually decodable (counted once, on first call, by decoding).
  int num_frames();
  int width() const;
  int height() const;
  double fps() const;
  // Frame `index` (0-based) as 8-bit RGB. Throws InputError if the frame cannot be decoded.
  Image ReadFrame(int index);

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace confluent
