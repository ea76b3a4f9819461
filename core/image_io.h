#pragma once
// Image files through OpenImageIO: PNG, JPEG, EXR, TIFF, ... (8/16-bit and float).

#include <cstddef>
#include <string>

#include "core/image.h"

namespace confluent {

// Reads an image file with all its channels in their stored type (8-bit, 16-bit or float;
// other types become float). Throws InputError naming the file when it is missing,
// truncated, not an image, or larger than `max_pixel_bytes` of pixels in the stored or the
// returned type (a corrupt header). The default admits 8K RGBA at 16 bits; a caller that
// reads untrusted files in bulk (the fuzzer) may lower it.
inline constexpr std::size_t kMaxImagePixelBytes = std::size_t{512} << 20;
Image ReadImage(const std::string& path, std::size_t max_pixel_bytes = kMaxImagePixelBytes);

// Reads only the header: width, height and channels. Throws InputError like ReadImage.
struct ImageInfo {
  int width = 0;
  int height = 0;
  int channels = 0;
};
ImageInfo ReadImageInfo(const std::string& path);

// Writes `image` in the format of the path's extension, atomically (temporary file, then
// rename). Float images written to 8-bit formats are clamped to [0,1] and scaled.
// Throws OutputError on failure.
void WriteImage(const std::string& path, const Image& image);

}  // namespace confluent
