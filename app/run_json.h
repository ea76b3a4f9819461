#pragma once
// Reading back the run.json that `confluent run` writes into a run folder (the viewer reads its
// own fields in viewer_run.cc).

#include <string>
#include <vector>

#include <nlohmann/json.hpp>

namespace confluent::app {

// What `confluent run` compares when it finds an existing run.json.
struct RunRecord {
  nlohmann::json input_checksums;             // null when absent
  std::vector<std::string> excluded_cameras;  // empty when absent
};

// Reads an existing run.json. Throws InputError naming the file when it is not JSON, not an
// object, or "excluded_cameras" is not a list of names.
RunRecord ReadRunRecord(const std::string& path);

}  // namespace confluent::app
