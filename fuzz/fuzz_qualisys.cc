// libFuzzer target: calib/importers.h ImportCalibration(kQualisys) on a Qualisys .qca.txt XML.
#include "calib/importers.h"
#include "fuzz/fuzz_util.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace confluent;
  const std::string path = fuzz::WriteScratch("Calib.qca.txt", fuzz::Bytes(data, size));
  fuzz::ExpectTypedErrors([&] { ImportCalibration(CalibFormat::kQualisys, path); });
  return 0;
}
