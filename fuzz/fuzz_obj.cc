// libFuzzer target: core/mesh_io.h ReadMesh on an .obj file.
#include "core/mesh_io.h"
#include "fuzz/fuzz_util.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace confluent;
  const std::string path = fuzz::WriteScratch("mesh.obj", fuzz::Bytes(data, size));
  fuzz::ExpectTypedErrors([&] { ReadMesh(path); });
  return 0;
}
