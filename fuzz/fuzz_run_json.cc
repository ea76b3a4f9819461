// libFuzzer target: run.json as it is read back: pipeline/run_manifest.h ReadRunManifest (the
// one reader: `run` on an existing folder, `render`, `evaluate`) and `confluent view`
// (viewer/viewer_run.h OpenViewerRun). The run folder holds the fuzzed run.json and one (empty)
// frame file, so that the frame-range part is read as well.
#include "fuzz/fuzz_util.h"
#include "pipeline/run_manifest.h"
#include "viewer/viewer_run.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace confluent;
  const std::string json_path = fuzz::WriteScratch("run/run.json", fuzz::Bytes(data, size));
  static const std::string frame = fuzz::WriteScratch("run/scan/000003.ply", "");
  const std::string root = std::filesystem::path(json_path).parent_path().string();
  fuzz::ExpectTypedErrors([&] { OpenViewerRun(root); });
  fuzz::ExpectTypedErrors([&] { ReadRunManifest(json_path); });
  return 0;
}
