// libFuzzer target: calib/importers.h ImportCalibration(kPose2Sim) on a Pose2Sim Calib_*.toml.
#include "calib/importers.h"
#include "fuzz/fuzz_util.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace confluent;
  const std::string path = fuzz::WriteScratch("Calib.toml", fuzz::Bytes(data, size));
  fuzz::ExpectTypedErrors([&] { ImportCalibration(CalibFormat::kPose2Sim, path); });
  return 0;
}
