#pragma once
// Synthetic silhouette scenes with exact ground truth: a textured plate (tiled floor, wall
// with posters), an actor made of coloured ellipses, a soft floor shadow, sensor noise, and a
// green-screen variant with spill and tracking markers.

#include <cstdint>

#include "core/image.h"

namespace confluent::testing {

// A textured studio background, 8-bit RGB, deterministic for `seed`.
Image MakeTexturedPlate(int width, int height, unsigned seed);

// A chroma-green screen with folds (brightness bands) and small white tracking markers.
Image MakeGreenScreen(int width, int height, unsigned seed);

// Where and how big the actor is: feet centre at (feet_x, feet_y) pixels, height in pixels.
struct ActorPlacement {
  double feet_x = 160;
  double feet_y = 220;
  double height_px = 170;
  bool hand_detached = false;  // draw one hand as a separate blob a few pixels from the arm
};

// Draws the actor into `image` (8-bit RGB) and returns its exact mask (0/255). With
// `spill` > 0, the actor's outermost 2 pixels reflect green light from the screen: their green
// channel is multiplied by (1 + spill) (reflected light scales with the surface's albedo).
Image DrawActor(Image* image, const ActorPlacement& placement, double spill = 0.0);

// Multiplies the pixels within an ellipse (centre, semi-axes) by a factor that goes smoothly
// from `darkest` in the centre to 1 at the rim.
void DarkenEllipse(Image* image, double cx, double cy, double ax, double ay, double darkest);

// Adds Gaussian noise (sigma in grey levels) to every channel, clamped to [0, 255].
void AddNoise(Image* image, double sigma, unsigned seed);

// IoU of two 0/255 masks.
double Iou(const Image& a, const Image& b);

}  // namespace confluent::testing
