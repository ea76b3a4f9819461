#include "core/video.h"

#include <filesystem>
#include <opencv2/imgproc.hpp>
#include <opencv2/videoio.hpp>

#include "core/cv_interop.h"
#include "core/error.h"

namespace confluent {

struct VideoReader::Impl {
  std::string path;
  cv::VideoCapture capture;
  int next_index = 0;  // index of the frame the next read() returns
  int num_frames = -1;

  void Open() {
    capture.release();
    if (!capture.open(path, cv::CAP_FFMPEG) || !capture.isOpened())
      throw InputError(path, "cannot open video (unsupported codec or corrupt file)");
    next_index = 0;
  }
};

VideoReader::VideoReader(const std::string& path) : impl_(std::make_unique<Impl>()) {
  impl_->path = path;
  std::error_code error;
  if (!std::filesystem::exists(path, error)) throw InputError(path, "no such file");
  impl_->Open();
}

VideoReader::~VideoReader() = default;
VideoReader::VideoReader(VideoReader&&) noexcept = default;
VideoReader& VideoReader::operator=(VideoReader&&) noexcept = default;

int VideoReader::width() const { return static_cast<int>(impl_->capture.get(cv::CAP_PROP_FRAME_WIDTH)); }
int VideoReader::height() const { return static_cast<int>(impl_->capture.get(cv::CAP_PROP_FRAME_HEIGHT)); }
double VideoReader::fps() const { return impl_->capture.get(cv::CAP_PROP_FPS); }

int VideoReader::num_frames() {
  if (impl_->num_frames >= 0) return impl_->num_frames;
  // Container frame counts are often wrong; count what actually decodes (grab only).
  cv::VideoCapture counter(impl_->path, cv::CAP_FFMPEG);
  int count = 0;
  while (counter.grab()) ++count;
  impl_->num_frames = count;
  return count;
}

Image VideoReader::ReadFrame(int index) {
  if (index < 0) throw InputError(impl_->path, "negative frame index " + std::to_string(index));
  if (index < impl_->next_index) impl_->Open();
  while (impl_->next_index < index) {
    if (!impl_->capture.grab())
      throw InputError(impl_->path, "frame " + std::to_string(index) + " cannot be decoded (video has " +
                                        std::to_string(impl_->next_index) + " frames)");
    ++impl_->next_index;
  }
  cv::Mat bgr;
  if (!impl_->capture.read(bgr) || bgr.empty())
    throw InputError(impl_->path, "frame " + std::to_string(index) + " cannot be decoded (video has " +
                                      std::to_string(impl_->next_index) + " frames)");
  ++impl_->next_index;
  cv::Mat rgb;
  cv::cvtColor(bgr, rgb, cv::COLOR_BGR2RGB);
  return ImageFromCvMat(rgb);
}

}  // namespace confluent
