// libFuzzer target: core/image_io.h ReadImageInfo and ReadImage (OpenImageIO): the size and
// format checks around the decoders. The first byte picks the file's extension (0 png, 1 jpg,
// 2 exr, 3 tif, 4 ppm; modulo 5); the rest is the file. ReadImage runs with a 64 MiB pixel
// limit instead of the default 512 MiB: the limit is what is under test, and the decoders'
// own buffers at the default size (a second copy, ASan's shadow) would pass libFuzzer's 2 GB
// memory limit with valid headers.
//
// Leak checking is off during the calls: OpenImageIO 2.4's PNG reader leaks its error message
// when libpng longjmps out of PNGInput::PngReadCallback on a truncated file (a few dozen bytes
// per bad file, in the library; a suppression cannot match it because the fast unwinder stops
// in the uninstrumented library). image_io.cc itself allocates only through RAII owners.
#include <sanitizer/lsan_interface.h>

#include "core/image_io.h"
#include "fuzz/fuzz_util.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace confluent;
  if (size < 1) return 0;
  static const char* const kExtensions[] = {"png", "jpg", "exr", "tif", "ppm"};
  const std::string name = std::string("image.") + kExtensions[data[0] % 5];
  const std::string path = fuzz::WriteScratch(name, fuzz::Bytes(data + 1, size - 1));
  __lsan::ScopedDisabler no_leak_checks;
  fuzz::ExpectTypedErrors([&] { ReadImageInfo(path); });
  fuzz::ExpectTypedErrors([&] { ReadImage(path, std::size_t{64} << 20); });
  return 0;
}
