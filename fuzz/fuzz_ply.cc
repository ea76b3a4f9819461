// libFuzzer target: core/mesh_io.h ReadMesh on a .ply file (the header picks ascii, binary
// little-endian or binary big-endian; the seeds hold all three).
#include "core/mesh_io.h"
#include "fuzz/fuzz_util.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace confluent;
  const std::string path = fuzz::WriteScratch("mesh.ply", fuzz::Bytes(data, size));
  fuzz::ExpectTypedErrors([&] { ReadMesh(path); });
  return 0;
}
