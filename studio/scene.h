#pragma once
// The studio's static scene: a room with a tiled floor and textured walls (or a green screen),
// and the soft contact shadow of the actor on the floor.

#include <vector>

#include "core/image.h"
#include "core/mesh.h"

namespace confluent {

// A mesh with UVs and its albedo texture (8-bit, linear RGB), for MeshRenderer::AddMesh.
struct TexturedMesh {
  Mesh mesh;
  Image texture;
};

// Size and look of the studio room. The room is centred on the origin, floor at z = 0.
struct StudioSceneOptions {
  double half_size_m = 4.6;    // the floor spans [-half_size, half_size]^2, walls stand on its edges
  double wall_height_m = 4.5;
  double tile_size_m = 0.5;    // floor tiles
  bool green_screen = false;   // uniform chroma-green floor and walls instead of tiles and posters
  int floor_texture_px = 2048; // floor texture is square
  unsigned seed = 1;
  // Throws UsageError when a value is out of range.
  void Check() const;
};

// The floor and the four walls (normals facing the inside), each with its texture.
std::vector<TexturedMesh> MakeStudioScene(const StudioSceneOptions& options = {});

// Soft shadow of a body on the floor, in a floor-aligned grid centred on the origin.
struct FloorShadowOptions {
  double half_size_m = 1.8;   // grid spans [-half_size, half_size]^2
  double cell_m = 0.01;
  double blur_m = 0.10;       // box-blur radius (three passes, about Gaussian)
  double strength = 0.55;     // darkening where the body is dense and close to the floor
  double falloff_m = 0.5;     // a point at height h contributes exp(-h / falloff)
  // Horizontal shift per metre of height (the light's direction; a point at height h darkens
  // the floor at its xy + h * offset_per_m).
  double offset_x_per_m = -0.08;
  double offset_y_per_m = 0.12;
  // Throws UsageError when a value is out of range.
  void Check() const;
};

// A grid of floor attenuation factors in (0, 1]: 1 = no shadow.
struct FloorShadow {
  FloorShadowOptions options;
  int size = 0;                // cells per side
  std::vector<float> factor;   // size x size, row = y index, column = x index
  // The attenuation at floor point (x, y) (nearest cell); 1 outside the grid.
  float At(double x, double y) const;
};

// Computes the shadow of the points `vertices` (n x 3, world, metres).
FloorShadow ComputeFloorShadow(const RowMatrixX3d& vertices, const FloorShadowOptions& options = {});

}  // namespace confluent
