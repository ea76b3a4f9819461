#include "core/image_io.h"

#include <OpenImageIO/filesystem.h>
#include <OpenImageIO/imageio.h>

#include <filesystem>

#include "core/atomic_file.h"
#include "core/error.h"

namespace confluent {
namespace {

// ReadImage refuses images whose pixels would need more memory than this.
constexpr std::size_t kMaxImageBytes = std::size_t{1} << 30;

OIIO::TypeDesc OiioType(PixelType type) {
  switch (type) {
    case PixelType::kUInt8: return OIIO::TypeDesc::UINT8;
    case PixelType::kUInt16: return OIIO::TypeDesc::UINT16;
    case PixelType::kFloat32: return OIIO::TypeDesc::FLOAT;
  }
  return OIIO::TypeDesc::UINT8;
}

std::unique_ptr<OIIO::ImageInput> OpenInput(const std::string& path) {
  std::error_code error;
  if (!std::filesystem::exists(path, error)) throw InputError(path, "no such file");
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

}  // namespace

Image ReadImage(const std::string& path) {
  auto input = OpenInput(path);
  const OIIO::ImageSpec& spec = input->spec();
  if (spec.width <= 0 || spec.height <= 0 || spec.nchannels <= 0)
    throw InputError(path, "image has no pixels");
  PixelType type = PixelType::kFloat32;
  if (spec.format == OIIO::TypeDesc::UINT8) type = PixelType::kUInt8;
  else if (spec.format == OIIO::TypeDesc::UINT16) type = PixelType::kUInt16;
  // The header's size is believed only up to 1 GiB of pixels (an 8K RGBA float image): a
  // corrupt or hostile header must not make us allocate without bound.
  const double bytes = static_cast<double>(spec.width) * spec.height * spec.nchannels * BytesPerChannel(type);
  if (bytes > static_cast<double>(kMaxImageBytes))
    throw InputError(path, "image too large: " + std::to_string(spec.width) + "x" + std::to_string(spec.height) + " with " +
                               std::to_string(spec.nchannels) + " channels needs more than 1 GiB (corrupt header?)");
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
