// libFuzzer target: deform/correspondences.h ReadCorrespondences (correspondences.json), then
// ValidateCorrespondences against small face counts as `confluent run` does.
#include "deform/correspondences.h"
#include "fuzz/fuzz_util.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace confluent;
  const std::string path = fuzz::WriteScratch("correspondences.json", fuzz::Bytes(data, size));
  fuzz::ExpectTypedErrors([&] {
    const Correspondences correspondences = ReadCorrespondences(path);
    ValidateCorrespondences(correspondences, 64, 64, path);
  });
  return 0;
}
