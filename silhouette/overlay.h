#pragma once
// Pictures for checking masks at a glance: a camera image with its mask's contour, and contact
// sheets that tile several such images.

#include <string>
#include <vector>

#include "core/image.h"

namespace confluent {

// `image` (8-bit RGB) scaled to `width_px` wide (0 = unscaled), the foreground slightly tinted
// and the mask's (1-channel 0/255, same size as `image`) contour drawn in a bright colour, with
// `label` written in the top-left corner.
Image DrawMaskOverlay(const Image& image, const Image& mask, int width_px = 0, const std::string& label = {});

// Tiles 8-bit RGB images of any sizes into a grid with `columns` columns (0 = about square);
// each cell is as large as the largest tile, tiles are centred on a dark background.
Image TileImages(const std::vector<Image>& tiles, int columns = 0);

}  // namespace confluent
