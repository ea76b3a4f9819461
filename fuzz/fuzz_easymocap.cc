// libFuzzer target: calib/easymocap_io.h ReadEasyMocap. The input is intri.yml, a NUL byte,
// then extri.yml.
#include "calib/easymocap_io.h"
#include "fuzz/fuzz_util.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace confluent;
  const auto [intri, extri] = fuzz::SplitAtNul(fuzz::Bytes(data, size));
  const std::string intri_path = fuzz::WriteScratch("intri.yml", intri);
  const std::string extri_path = fuzz::WriteScratch("extri.yml", extri);
  fuzz::ExpectTypedErrors([&] { ReadEasyMocap(intri_path, extri_path); });
  return 0;
}
