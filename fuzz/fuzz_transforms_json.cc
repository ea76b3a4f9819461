// libFuzzer target: calib/importers.h ImportCalibration(kTransformsJson) on a transforms.json
// (nerfstudio / Blender). No image lies beside it, so a file without a size must be refused.
#include "calib/importers.h"
#include "fuzz/fuzz_util.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace confluent;
  const std::string path = fuzz::WriteScratch("transforms/transforms.json", fuzz::Bytes(data, size));
  fuzz::ExpectTypedErrors([&] { ImportCalibration(CalibFormat::kTransformsJson, path); });
  return 0;
}
