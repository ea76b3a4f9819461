#pragma once
// Named presets of the synthetic studio, shared by `confluent synth` and `confluent demo`.

#include <string>

#include "studio/synth.h"

namespace confluent {

// "default": the embedded default capture (8 ring + 2 held-out cameras, 1024x768, the built-in
// performance, ~120K-triangle actor). "tiny": a few-second test fixture (4 + 2 cameras,
// 160x120, 10 frames over the whole performance, ~12K triangles).
// Throws UsageError naming the accepted presets; `flag` (e.g. "--preset") prefixes the message.
StudioSynthOptions StudioSynthPreset(const std::string& name, const std::string& flag = "preset");

}  // namespace confluent
