#include "export/player_writer.h"

#include <nlohmann/json.hpp>

#include "core/atomic_file.h"
#include "core/error.h"
#include "export/player_files.h"

namespace confluent {

void PlayerOptions::Check() const {
  if (scene_url.empty()) throw UsageError("PlayerOptions.scene_url: must not be empty");
  if (video_url.empty()) throw UsageError("PlayerOptions.video_url: must not be empty");
}

std::vector<std::string> WritePlayer(const std::string& dir, const PlayerOptions& options) {
  options.Check();
  std::vector<std::string> written;
  for (const internal::EmbeddedFile& file : internal::EmbeddedPlayerFiles()) {
    WriteAtomically(dir + "/" + file.path,
                    [&](const std::string& temporary) { WriteFileBytes(temporary, file.data, file.size); });
    written.push_back(file.path);
  }
  const nlohmann::json config = {{"scene", options.scene_url}, {"video", options.video_url}};
  WriteTextFile(dir + "/config.json", config.dump(1) + "\n");
  written.push_back("config.json");
  return written;
}

}  // namespace confluent
