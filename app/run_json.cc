#include "app/run_json.h"

#include "core/atomic_file.h"
#include "core/error.h"

namespace confluent::app {

RunRecord ReadRunRecord(const std::string& path) {
  RunRecord record;
  try {
    const nlohmann::json json = nlohmann::json::parse(ReadTextFile(path));
    if (!json.is_object()) throw InputError(path, "not a run.json: expected a JSON object");
    record.input_checksums = json.value("input_checksums", nlohmann::json());
    record.excluded_cameras = json.value("excluded_cameras", std::vector<std::string>{});
  } catch (const nlohmann::json::exception& e) {
    throw InputError(path, std::string("not a run.json: ") + e.what());
  }
  return record;
}

}  // namespace confluent::app
