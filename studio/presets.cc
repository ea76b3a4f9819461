#include "studio/presets.h"

#include "core/error.h"

namespace confluent {

StudioSynthOptions StudioSynthPreset(const std::string& name, const std::string& flag) {
  StudioSynthOptions options;
  if (name == "tiny") {
    options.rig.num_ring_cameras = 4;
    options.rig.num_heldout_cameras = 2;
    options.rig.width_px = 160;
    options.rig.height_px = 120;
    options.motion.num_frames = 10;
    options.motion.fps = 2.5;
    options.actor.target_triangles = 12000;
    options.scene.floor_texture_px = 512;
    options.threads = 1;
  } else if (name != "default") {
    throw UsageError(flag + ": unknown studio preset '" + name + "' (expected default or tiny)");
  }
  return options;
}

}  // namespace confluent
