// Plain text (tsinghua_lkB CalibParamsB.txt): blocks of camera index, K (3x3), k1 k2, [R|t]
// (3x4, cam_from_world). Names are "cam" + two-digit index. No image size is stored: it comes
// from the options, else 1024x768 (the size of the dataset this format comes from).

#include <fstream>
#include <sstream>

#include "calib/importers_internal.h"
#include "core/atomic_file.h"
#include "core/error.h"

namespace confluent {
namespace importers_internal {

Rig ReadPlainText(const std::string& path, const ImportOptions& options) {
  std::istringstream in(ReadTextFile(path));
  std::vector<std::string> tokens;
  std::string line;
  while (std::getline(in, line)) {
    const std::size_t comment = line.find('#');
    if (comment != std::string::npos) line.resize(comment);
    for (const auto& token : SplitWhitespace(line)) tokens.push_back(token);
  }
  constexpr std::size_t kBlock = 1 + 9 + 2 + 12;
  if (tokens.empty()) throw InputError(path, "no cameras");
  if (tokens.size() % kBlock != 0)
    throw InputError(path, "expected blocks of 24 numbers (index, K 3x3, k1 k2, [R|t] 3x4), got " +
                               std::to_string(tokens.size()) + " numbers");
  Rig rig;
  for (std::size_t block = 0; block < tokens.size() / kBlock; ++block) {
    const std::size_t base = block * kBlock;
    const std::string where = "camera block " + std::to_string(block + 1);
    const int index = ParseInt(tokens[base], path, where + " index");
    char name[32];
    std::snprintf(name, sizeof(name), "cam%02d", index);
    Camera camera;
    camera.name = name;
    const std::string camera_where = "camera " + camera.name;
    for (int i = 0; i < 9; ++i) camera.K(i / 3, i % 3) = ParseNumber(tokens[base + 1 + i], path, camera_where + " K");
    camera.dist[0] = ParseNumber(tokens[base + 10], path, camera_where + " k1");
    camera.dist[1] = ParseNumber(tokens[base + 11], path, camera_where + " k2");
    Eigen::Matrix3d rotation;
    for (int i = 0; i < 12; ++i) {
      const double value = ParseNumber(tokens[base + 12 + i], path, camera_where + " [R|t]");
      if (i % 4 == 3) {
        camera.translation[i / 4] = value;
      } else {
        rotation(i / 4, i % 4) = value;
      }
    }
    camera.rotation = Orthonormalize(rotation);
    camera.width = options.default_width > 0 ? options.default_width : 1024;
    camera.height = options.default_height > 0 ? options.default_height : 768;
    rig.cameras.push_back(camera);
  }
  return rig;
}

}  // namespace importers_internal
}  // namespace confluent
