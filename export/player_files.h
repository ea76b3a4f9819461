#pragma once
// The web player's files, embedded into the binary at build time (export/player_embed.cmake
// generates the definition from export/player/ and the npm-installed three.js). Internal to
// export/; WritePlayer (export/player_writer.h) is the public entry point.

#include <cstddef>
#include <vector>

namespace confluent::internal {

// One embedded file: its path inside the written player folder ("index.html",
// "three/three.module.min.js", ...) and its bytes.
struct EmbeddedFile {
  const char* path;
  const char* data;
  std::size_t size;
};

// Every file of the player, in a fixed order.
const std::vector<EmbeddedFile>& EmbeddedPlayerFiles();

}  // namespace confluent::internal
