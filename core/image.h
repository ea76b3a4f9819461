#pragma once
// A plain interleaved image buffer: 8-bit, 16-bit or float channels, RGB(A) order.

#include <cstddef>
#include <cstdint>
#include <cstring>
#include <vector>

namespace confluent {

enum class PixelType { kUInt8, kUInt16, kFloat32 };

// Bytes per channel value of `type`.
inline std::size_t BytesPerChannel(PixelType type) {
  return type == PixelType::kUInt8 ? 1 : type == PixelType::kUInt16 ? 2 : 4;
}

// Row-major, tightly packed, channels interleaved (RGB or RGBA order; 1 channel = grey/mask).
// Pixel (x, y) has its centre at integer coordinates (x, y), x right, y down.
struct Image {
  int width = 0;
  int height = 0;
  int channels = 0;
  PixelType type = PixelType::kUInt8;
  std::vector<std::uint8_t> data;

  Image() = default;
  Image(int width_px, int height_px, int num_channels, PixelType pixel_type = PixelType::kUInt8)
      : width(width_px), height(height_px), channels(num_channels), type(pixel_type),
        data(static_cast<std::size_t>(width_px) * height_px * num_channels * BytesPerChannel(pixel_type), 0) {}

  bool empty() const { return width == 0 || height == 0 || channels == 0; }
  std::size_t row_bytes() const { return static_cast<std::size_t>(width) * channels * BytesPerChannel(type); }

  // Typed access; T must match `type` (uint8_t, uint16_t or float).
  template <typename T> T* ptr() { return reinterpret_cast<T*>(data.data()); }
  template <typename T> const T* ptr() const { return reinterpret_cast<const T*>(data.data()); }
  template <typename T> T& at(int x, int y, int c = 0) {
    return ptr<T>()[(static_cast<std::size_t>(y) * width + x) * channels + c];
  }
  template <typename T> const T& at(int x, int y, int c = 0) const {
    return ptr<T>()[(static_cast<std::size_t>(y) * width + x) * channels + c];
  }
};

}  // namespace confluent
