#include "core/image_io.h"

#include <OpenImageIO/filesystem.h>
#include <OpenImageIO/imageio.h>

#include <algorithm>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <vector>

#include "core/atomic_file.h"
#include "core/error.h"

namespace confluent {
namespace {

OIIO::TypeDesc OiioType(PixelType type) {
  switch (type) {
    case PixelType::kUInt8: return OIIO::TypeDesc::UINT8;
    case PixelType::kUInt16: return OIIO::TypeDesc::UINT16;
    case PixelType::kFloat32: return OIIO::TypeDesc::FLOAT;
  }
  return OIIO::TypeDesc::UINT8;
}

// Whether `file` starts with the `length` bytes of `magic`; if so, `*size` is the file's size
// in bytes.
bool StartsWithMagic(std::ifstream& file, const char* magic, std::size_t length, std::streamoff* size) {
  char start[8] = {};
  if (length > sizeof(start) || !file.read(start, static_cast<std::streamsize>(length)) ||
      std::memcmp(start, magic, length) != 0)
    return false;
  file.seekg(0, std::ios::end);
  *size = file.tellg();
  return true;
}

// OpenEXR 3.1 believes the sizes of header attributes: a corrupt one makes it allocate up to
// 2 GB before reading a byte of it (found by fuzzing). Walks the attribute list of an .exr file
// (every header of a multi-part file; magic 76 2f 31 01) and throws InputError when an attribute
// claims more bytes than the file holds. Other files are left to OpenImageIO.
void CheckExrHeader(const std::string& path) {
  std::ifstream file(path, std::ios::binary);
  std::streamoff size = 0;
  if (!StartsWithMagic(file, "\x76\x2f\x31\x01", 4, &size)) return;
  // Headers are small: the first 16 MiB hold any real one.
  file.seekg(0);
  std::vector<char> bytes(static_cast<std::size_t>(std::min<std::streamoff>(size, std::streamoff{1} << 24)));
  file.read(bytes.data(), static_cast<std::streamsize>(bytes.size()));
  const std::size_t end = static_cast<std::size_t>(file.gcount());
  std::size_t at = 8;  // magic and version
  if (end < at) throw InputError(path, "truncated EXR header");
  const bool multi_part = (static_cast<unsigned char>(bytes[5]) & 0x10) != 0;  // version bit 12
  auto read_name = [&](std::string* name) {
    const std::size_t stop = std::min(end, at + 256);
    const std::size_t nul = static_cast<std::size_t>(std::find(bytes.begin() + at, bytes.begin() + stop, '\0') - bytes.begin());
    if (nul >= stop) throw InputError(path, "corrupt EXR header (attribute name not terminated)");
    name->assign(bytes.data() + at, nul - at);
    at = nul + 1;
  };
  for (;;) {  // each header: attributes (name, type, int32 size, value) up to an empty name
    std::string name, type;
    read_name(&name);
    if (name.empty()) break;  // an empty header ends the list of a multi-part file
    while (!name.empty()) {
      read_name(&type);
      if (end - at < 4) throw InputError(path, "truncated EXR header");
      std::int32_t value_size = 0;
      std::memcpy(&value_size, bytes.data() + at, 4);  // little-endian, as EXR
      at += 4;
      if (value_size < 0 || static_cast<std::streamoff>(at) + value_size > size)
        throw InputError(path, "corrupt EXR header: attribute '" + name + "' claims " + std::to_string(value_size) +
                                   " bytes, more than the file holds");
      if (static_cast<std::size_t>(value_size) > end - at) return;  // past the first 16 MiB: left to OpenEXR
      at += static_cast<std::size_t>(value_size);
      read_name(&name);
    }
    if (!multi_part) break;
  }
}

// A PNG whose data ends before its IEND chunk makes libpng long-jump out of OpenImageIO 2.4's
// read callback, leaking the error text it holds. Walks the chunk list of a .png file (magic
// 89 50 4E 47) by its lengths, reading 8 bytes per chunk, and throws InputError when the file
// ends before IEND. Other files are left to OpenImageIO.
void CheckPngComplete(const std::string& path) {
  std::ifstream file(path, std::ios::binary);
  std::streamoff size = 0;
  if (!StartsWithMagic(file, "\x89PNG\r\n\x1a\n", 8, &size)) return;
  std::streamoff at = 8;
  while (at + 8 <= size) {
    unsigned char header[8];
    file.seekg(at);
    if (!file.read(reinterpret_cast<char*>(header), 8)) break;
    const std::streamoff length = (std::streamoff{header[0]} << 24) | (header[1] << 16) | (header[2] << 8) | header[3];
    if (std::memcmp(header + 4, "IEND", 4) == 0) return;
    at += 12 + length;  // length, type, data, CRC
  }
  throw InputError(path, "truncated PNG (the file ends before its IEND chunk)");
}

std::unique_ptr<OIIO::ImageInput> OpenInput(const std::string& path) {
  std::error_code error;
  if (!std::filesystem::exists(path, error)) throw InputError(path, "no such file");
  CheckExrHeader(path);
  // Keep alpha as stored (no premultiplication), so RGBA files round-trip exactly.
  OIIO::ImageSpec config;
  config.attribute("oiio:UnassociatedAlpha", 1);
  auto input = OIIO::ImageInput::open(path, &config);
  if (!input) {
    std::string message = OIIO::geterror();
    throw InputError(path, "cannot read image" + (message.empty() ? std::string() : ": " + message));
  }
  return input;
}

// A byte count for messages, whole; `bytes` may exceed every integer type (a corrupt header).
std::string FormatBytes(double bytes) {
  char text[64];
  std::snprintf(text, sizeof text, "%.0f", bytes);
  return text;
}

}  // namespace

Image ReadImage(const std::string& path, std::size_t max_pixel_bytes) {
  auto input = OpenInput(path);
  CheckPngComplete(path);
  const OIIO::ImageSpec& spec = input->spec();
  if (spec.width <= 0 || spec.height <= 0 || spec.nchannels <= 0)
    throw InputError(path, "image has no pixels");
  PixelType type = PixelType::kFloat32;
  if (spec.format == OIIO::TypeDesc::UINT8) type = PixelType::kUInt8;
  else if (spec.format == OIIO::TypeDesc::UINT16) type = PixelType::kUInt16;
  // The header's size is believed only up to `max_pixel_bytes`, in the type we return and in
  // the stored type (decoders buffer the latter): a corrupt or hostile header must not make
  // us allocate without bound. OpenImageIO reads scanlines in blocks of 256 rows, so an image
  // of a few rows counts as 256 (a 6-row PPM 6.7 million pixels wide asked for 5 GB).
  constexpr int kRowsPerReadBlock = 256;
  const double pixels = static_cast<double>(spec.width) * std::max(spec.height, kRowsPerReadBlock) * spec.nchannels;
  const double bytes = pixels * std::max<double>(BytesPerChannel(type), static_cast<double>(spec.format.size()));
  if (bytes > static_cast<double>(max_pixel_bytes))
    throw InputError(path, "image too large: " + std::to_string(spec.width) + "x" + std::to_string(spec.height) + " with " +
                               std::to_string(spec.nchannels) + " channels needs " + FormatBytes(bytes) +
                               " bytes, more than the limit of " + std::to_string(max_pixel_bytes) +
                               " (corrupt header?)");
  Image image(spec.width, spec.height, spec.nchannels, type);
  const bool ok = input->read_image(0, 0, 0, spec.nchannels, OiioType(type), image.data.data());
  std::string message = input->geterror();
  input->close();
  // Retrieve what close() and the global queue add too: unretrieved errors are printed later.
  input->geterror();
  OIIO::geterror();
  // OIIO reports truncated PNG/JPEG data through geterror() even when read_image succeeds.
  if (!ok || !message.empty()) throw InputError(path, "corrupt or truncated image" + (message.empty() ? "" : ": " + message));
  return image;
}

ImageInfo ReadImageInfo(const std::string& path) {
  auto input = OpenInput(path);
  const OIIO::ImageSpec& spec = input->spec();
  ImageInfo info{spec.width, spec.height, spec.nchannels};
  input->close();
  return info;
}

void WriteImage(const std::string& path, const Image& image) {
  if (image.empty()) throw OutputError(path, "refusing to write an empty image");
  WriteAtomically(path, [&](const std::string& temporary) {
    auto output = OIIO::ImageOutput::create(path);  // format from the real extension
    if (!output) throw OutputError(path, "unsupported image format: " + OIIO::geterror());
    OIIO::ImageSpec spec(image.width, image.height, image.channels, OiioType(image.type));
    spec.attribute("oiio:UnassociatedAlpha", 1);  // our alpha is straight, not premultiplied
    const std::string extension = std::filesystem::path(path).extension().string();
    if (extension == ".png" || extension == ".PNG") spec.attribute("png:compressionLevel", 1);  // fast: frames are written by the thousand
    if (extension == ".jpg" || extension == ".jpeg") spec.attribute("CompressionQuality", 95);
    // Encode into memory, then write the bytes with checked writes: OIIO's PNG writer does not
    // report a short write (a full disk or a file-size limit left a truncated file behind).
    OIIO::Filesystem::IOVecOutput encoded;
    const bool in_memory = output->supports("ioproxy") && output->set_ioproxy(&encoded);
    if (!output->open(temporary, spec)) throw OutputError(path, "cannot open for writing: " + output->geterror());
    if (!output->write_image(OiioType(image.type), image.data.data()))
      throw OutputError(path, "write failed (disk full?): " + output->geterror());
    if (!output->close()) throw OutputError(path, "write failed (disk full?): " + output->geterror());
    if (in_memory) WriteFileBytes(temporary, encoded.buffer().data(), encoded.buffer().size());
  });
}

}  // namespace confluent
