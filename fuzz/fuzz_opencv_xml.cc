// libFuzzer target: calib/importers.h ImportCalibration(kOpenCvXml) on one OpenCV FileStorage
// XML file (CameraMatrix, DistortionCoeffs, rvec/tvec).
#include "calib/importers.h"
#include "fuzz/fuzz_util.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace confluent;
  const std::string path = fuzz::WriteScratch("cam0.xml", fuzz::Bytes(data, size));
  fuzz::ExpectTypedErrors([&] { ImportCalibration(CalibFormat::kOpenCvXml, path); });
  return 0;
}
