// libFuzzer target: calib/importers.h ImportCalibration(kPlainText) on per-camera text blocks.
#include "calib/importers.h"
#include "fuzz/fuzz_util.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace confluent;
  const std::string path = fuzz::WriteScratch("CalibParams.txt", fuzz::Bytes(data, size));
  fuzz::ExpectTypedErrors([&] { ImportCalibration(CalibFormat::kPlainText, path); });
  return 0;
}
