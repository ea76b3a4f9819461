#pragma once
// Compositing a rendered view over a background image, such as a camera's clean plate: the novel
// view as that camera would see the studio.

#include <string>

#include "core/image.h"
#include "render/renderer.h"

namespace confluent {

// The rendered RGB8 colour over `background` (an RGB8 image of the same size). With
// edge_softness_px = 0 the silhouette decides per pixel. Above 0, the silhouette is blurred by a
// Gaussian of that sigma (pixels) into an alpha (boundary matting): pixels next to the outline mix
// the rendered colour (outside the silhouette, the mean of the nearby rendered pixels) with the
// background, which hides the staircase of a binary outline and, where the outline is uncertain
// by a fraction of a pixel, lowers the expected error (held-out studio default: +0.15 dB PSNR at
// 0.5 px, less above 0.6). `rendered` needs its silhouette. Throws InputError(background_name) when
// sizes or pixel formats differ.
Image CompositeOverBackground(const RenderResult& rendered, const Image& background, const std::string& background_name,
                              double edge_softness_px = 0.0);

}  // namespace confluent
