#pragma once
// A check that the renderer rasterises where it should, for `confluent render-info`.

#include "render/renderer.h"

namespace confluent {

struct RenderSelfTest {
  bool ok = false;
  int covered_px = 0;   // of the expected 400
  int expected_px = 400;
};

// Renders a 0.5 m square 1 m in front of a 64x48 camera (focal 40 px) with `renderer` and checks
// that it covers exactly its known 20x20-pixel rectangle (columns 22..41, rows 14..33).
RenderSelfTest RunRenderSelfTest(MeshRenderer& renderer);

}  // namespace confluent
