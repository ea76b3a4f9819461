// libFuzzer target: calib/importers.h ImportCalibration(kColmap). The input is cameras.txt,
// a NUL byte, then images.txt.
#include "calib/importers.h"
#include "fuzz/fuzz_util.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace confluent;
  const auto [cameras, images] = fuzz::SplitAtNul(fuzz::Bytes(data, size));
  const std::string cameras_path = fuzz::WriteScratch("colmap/cameras.txt", cameras);
  fuzz::WriteScratch("colmap/images.txt", images);
  fuzz::ExpectTypedErrors([&] { ImportCalibration(CalibFormat::kColmap, cameras_path); });
  return 0;
}
