#include "export/player_writer.h"

#include <nlohmann/json.hpp>
#include <sstream>

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

std::string PlayerCameraQuery(const Camera& camera, int frame) {
  if (frame < 0) throw UsageError("PlayerCameraQuery: frame " + std::to_string(frame) + " must be >= 0");
  std::ostringstream query;
  query.precision(17);
  query << "fx=" << camera.K(0, 0) << "&fy=" << camera.K(1, 1) << "&cx=" << camera.K(0, 2) << "&cy=" << camera.K(1, 2)
        << "&width=" << camera.width << "&height=" << camera.height << "&R=";
  for (int i = 0; i < 9; ++i) query << (i ? "," : "") << camera.rotation(i / 3, i % 3);
  query << "&t=" << camera.translation.x() << "," << camera.translation.y() << "," << camera.translation.z()
        << "&frame=" << frame;
  return query.str();
}

}  // namespace confluent
