// libFuzzer target: core/bvh_io.h ReadBvh.
#include "core/bvh_io.h"
#include "fuzz/fuzz_util.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace confluent;
  const std::string path = fuzz::WriteScratch("motion.bvh", fuzz::Bytes(data, size));
  fuzz::ExpectTypedErrors([&] { ReadBvh(path, BvhReadOptions{0.01, true, true}); });
  return 0;
}
