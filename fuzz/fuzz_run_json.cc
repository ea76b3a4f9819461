// libFuzzer target: run.json as the app reads it back: `confluent view` (app/viewer_run.cc
// OpenViewerRun) and `confluent run` on an existing run folder (app/run_json.cc ReadRunRecord);
// app/ is an executable, so both sources are compiled into this target. The run folder holds the
// fuzzed run.json and one (empty) frame file, so that the frame-range part is read as well.
#include "app/run_json.h"
#include "app/viewer_run.h"
#include "fuzz/fuzz_util.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace confluent;
  const std::string json_path = fuzz::WriteScratch("run/run.json", fuzz::Bytes(data, size));
  static const std::string frame = fuzz::WriteScratch("run/scan/000003.ply", "");
  const std::string root = std::filesystem::path(json_path).parent_path().string();
  fuzz::ExpectTypedErrors([&] { app::OpenViewerRun(root); });
  fuzz::ExpectTypedErrors([&] { app::ReadRunRecord(json_path); });
  return 0;
}
