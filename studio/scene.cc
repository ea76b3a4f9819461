#include "studio/scene.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <random>

#include "core/error.h"

namespace confluent {
namespace {

double Hash2(std::int64_t x, std::int64_t y, unsigned seed) {
  std::uint64_t h = static_cast<std::uint64_t>(x) * 0x9E3779B97F4A7C15ull ^ static_cast<std::uint64_t>(y) * 0xC2B2AE3D27D4EB4Full ^
                    (static_cast<std::uint64_t>(seed) << 29);
  h ^= h >> 31;
  h *= 0xbf58476d1ce4e5b9ull;
  h ^= h >> 27;
  h *= 0x94d049bb133111ebull;
  h ^= h >> 31;
  return static_cast<double>(h >> 11) / static_cast<double>(1ull << 53);
}

double Noise2(double x, double y, unsigned seed) {
  const double fx = std::floor(x), fy = std::floor(y);
  const double tx = x - fx, ty = y - fy;
  const double wx = tx * tx * (3 - 2 * tx), wy = ty * ty * (3 - 2 * ty);
  const auto ix = static_cast<std::int64_t>(fx), iy = static_cast<std::int64_t>(fy);
  return (1 - wy) * ((1 - wx) * Hash2(ix, iy, seed) + wx * Hash2(ix + 1, iy, seed)) +
         wy * ((1 - wx) * Hash2(ix, iy + 1, seed) + wx * Hash2(ix + 1, iy + 1, seed));
}

double ToLinear(double c) { return c <= 0.04045 ? c / 12.92 : std::pow((c + 0.055) / 1.055, 2.4); }

void SetPixel(Image* image, int x, int y, const Eigen::Vector3d& srgb) {
  for (int c = 0; c < 3; ++c)
    image->at<std::uint8_t>(x, y, c) =
        static_cast<std::uint8_t>(std::clamp(ToLinear(std::clamp(srgb(c), 0.0, 1.0)) * 255.0 + 0.5, 0.0, 255.0));
}

// A quad a, b, c, d (counter-clockwise seen from the front) with UVs.
void AddQuad(Mesh* mesh, const Eigen::Vector3d& a, const Eigen::Vector3d& b, const Eigen::Vector3d& c,
             const Eigen::Vector3d& d, const Eigen::Vector2d& uv_a, const Eigen::Vector2d& uv_c) {
  const int v0 = mesh->num_vertices();
  mesh->vertices.conservativeResize(v0 + 4, 3);
  mesh->vertices.row(v0) = a.transpose();
  mesh->vertices.row(v0 + 1) = b.transpose();
  mesh->vertices.row(v0 + 2) = c.transpose();
  mesh->vertices.row(v0 + 3) = d.transpose();
  const int t0 = static_cast<int>(mesh->uvs.rows());
  mesh->uvs.conservativeResize(t0 + 4, 2);
  mesh->uvs.row(t0) << uv_a.x(), uv_a.y();
  mesh->uvs.row(t0 + 1) << uv_c.x(), uv_a.y();
  mesh->uvs.row(t0 + 2) << uv_c.x(), uv_c.y();
  mesh->uvs.row(t0 + 3) << uv_a.x(), uv_c.y();
  const int f0 = mesh->num_faces();
  mesh->faces.conservativeResize(f0 + 2, 3);
  mesh->face_uvs.conservativeResize(f0 + 2, 3);
  mesh->faces.row(f0) << v0, v0 + 1, v0 + 2;
  mesh->faces.row(f0 + 1) << v0, v0 + 2, v0 + 3;
  mesh->face_uvs.row(f0) << t0, t0 + 1, t0 + 2;
  mesh->face_uvs.row(f0 + 1) << t0, t0 + 2, t0 + 3;
}

Image FloorTexture(const StudioSceneOptions& o) {
  const int n = o.floor_texture_px;
  Image image(n, n, 3);
  const double size = 2.0 * o.half_size_m;
  for (int r = 0; r < n; ++r)
    for (int col = 0; col < n; ++col) {
      // Texel centre in world metres (v up = +y; row 0 is the top of the image).
      const double x = -o.half_size_m + (col + 0.5) / n * size;
      const double y = o.half_size_m - (r + 0.5) / n * size;
      Eigen::Vector3d c;
      if (o.green_screen) {
        c = Eigen::Vector3d(0.16, 0.62, 0.26) * (0.95 + 0.1 * Noise2(x / 0.3, y / 0.3, o.seed));
      } else {
        const double tx = x / o.tile_size_m, ty = y / o.tile_size_m;
        const auto ix = static_cast<std::int64_t>(std::floor(tx)), iy = static_cast<std::int64_t>(std::floor(ty));
        const double fx = tx - std::floor(tx), fy = ty - std::floor(ty);
        const bool grout = fx < 0.012 || fx > 0.988 || fy < 0.012 || fy > 0.988;
        const bool dark = ((ix + iy) & 1) != 0;
        const double tint = Hash2(ix, iy, o.seed + 3);
        c = dark ? Eigen::Vector3d(0.55, 0.50, 0.44) : Eigen::Vector3d(0.74, 0.70, 0.63);
        c *= 0.94 + 0.12 * tint;
        // Marble-like veins and fine speckle.
        const double vein = std::abs(std::sin(9.0 * x + 6.0 * Noise2(x / 0.25, y / 0.25, o.seed + ix * 31 + iy)));
        c *= 0.93 + 0.07 * vein;
        c *= 0.92 + 0.16 * Noise2(x / 0.006, y / 0.006, o.seed + 11);
        if (grout) c = Eigen::Vector3d(0.30, 0.29, 0.28);
        // A capture-area circle painted on the floor.
        const double rad = std::sqrt(x * x + y * y);
        if (std::abs(rad - 1.5) < 0.02) c = Eigen::Vector3d(0.85, 0.75, 0.20);
      }
      SetPixel(&image, col, r, c);
    }
  return image;
}

Image WallTexture(const StudioSceneOptions& o, int width, int height, double perimeter) {
  Image image(width, height, 3);
  std::mt19937 rng(o.seed * 101u + 5u);
  std::uniform_real_distribution<double> uni(0.0, 1.0);
  struct Poster {
    double u0, u1, z0, z1;
    Eigen::Vector3d color;
  };
  std::vector<Poster> posters;
  const Eigen::Vector3d palette[] = {{0.85, 0.25, 0.20}, {0.20, 0.45, 0.80}, {0.95, 0.75, 0.15},
                                     {0.25, 0.65, 0.35}, {0.55, 0.30, 0.65}, {0.15, 0.15, 0.15}};
  for (int i = 0; i < 18 && !o.green_screen; ++i) {
    const double u = perimeter * (i + 0.2 + 0.6 * uni(rng)) / 18.0;
    const double w = 0.4 + 0.8 * uni(rng), h = 0.4 + 0.9 * uni(rng), z = 0.9 + 1.4 * uni(rng);
    posters.push_back({u, u + w, z, z + h, palette[static_cast<int>(uni(rng) * 6) % 6]});
  }
  for (int r = 0; r < height; ++r)
    for (int col = 0; col < width; ++col) {
      const double u = (col + 0.5) / width * perimeter;  // metres along the walls
      const double z = (1.0 - (r + 0.5) / height) * o.wall_height_m;
      Eigen::Vector3d c;
      if (o.green_screen) {
        c = Eigen::Vector3d(0.16, 0.62, 0.26) * (0.95 + 0.1 * Noise2(u / 0.4, z / 0.4, o.seed + 1));
      } else {
        c = Eigen::Vector3d(0.66, 0.70, 0.74) * (0.95 + 0.08 * Noise2(u / 0.5, z / 0.5, o.seed + 2));
        c *= 0.95 + 0.08 * Noise2(u / 0.01, z / 0.01, o.seed + 4);
        // Vertical acoustic panels every 1.2 m.
        const double fu = u / 1.2 - std::floor(u / 1.2);
        if (fu < 0.015) c *= 0.8;
        if (z < 0.15) c = Eigen::Vector3d(0.18, 0.18, 0.20);  // skirting board
        if (std::abs(z - 2.6) < 0.03) c = Eigen::Vector3d(0.35, 0.35, 0.38);
        for (const auto& p : posters)
          if (u > p.u0 && u < p.u1 && z > p.z0 && z < p.z1) {
            const bool frame = u < p.u0 + 0.03 || u > p.u1 - 0.03 || z < p.z0 + 0.03 || z > p.z1 - 0.03;
            const bool stripe = std::fmod((u - p.u0) + (z - p.z0), 0.2) < 0.06;
            c = frame ? Eigen::Vector3d(0.95, 0.95, 0.95) : (stripe ? Eigen::Vector3d(p.color * 0.6) : p.color);
          }
      }
      SetPixel(&image, col, r, c);
    }
  return image;
}

void BoxBlur(std::vector<float>* grid, int n, int radius) {
  std::vector<float> tmp(grid->size());
  for (int pass = 0; pass < 3; ++pass) {
    for (int dim = 0; dim < 2; ++dim) {
      for (int line = 0; line < n; ++line) {
        double sum = 0.0;
        auto at = [&](int i) -> float {
          if (i < 0 || i >= n) return 0.0f;
          return dim == 0 ? (*grid)[static_cast<std::size_t>(line) * n + i] : (*grid)[static_cast<std::size_t>(i) * n + line];
        };
        for (int i = -radius; i <= radius; ++i) sum += at(i);
        for (int i = 0; i < n; ++i) {
          const float value = static_cast<float>(sum / (2 * radius + 1));
          (dim == 0 ? tmp[static_cast<std::size_t>(line) * n + i] : tmp[static_cast<std::size_t>(i) * n + line]) = value;
          sum += at(i + radius + 1) - at(i - radius);
        }
      }
      grid->swap(tmp);
    }
  }
}

}  // namespace

void StudioSceneOptions::Check() const {
  const std::string owner = "StudioSceneOptions.";
  RequireOption(half_size_m > 1.0 && half_size_m < 100.0, owner + "half_size_m", half_size_m, "in (1, 100) metres");
  RequireOption(wall_height_m > 0.5, owner + "wall_height_m", wall_height_m, "> 0.5 metres");
  RequireOption(tile_size_m > 0.01, owner + "tile_size_m", tile_size_m, "> 0.01 metres");
  RequireOption(floor_texture_px >= 16 && floor_texture_px <= 8192, owner + "floor_texture_px", floor_texture_px,
                "in [16, 8192] pixels");
}

std::vector<TexturedMesh> MakeStudioScene(const StudioSceneOptions& o) {
  o.Check();
  const double h = o.half_size_m, top = o.wall_height_m;
  std::vector<TexturedMesh> scene(2);
  AddQuad(&scene[0].mesh, {-h, -h, 0}, {h, -h, 0}, {h, h, 0}, {-h, h, 0}, {0, 0}, {1, 1});
  scene[0].texture = FloorTexture(o);
  const double side = 2 * h, perimeter = 4 * side;
  // Walls, counter-clockwise seen from inside: u runs along the perimeter.
  const Eigen::Vector3d corners[5] = {{-h, -h, 0}, {-h, h, 0}, {h, h, 0}, {h, -h, 0}, {-h, -h, 0}};
  for (int w = 0; w < 4; ++w) {
    const Eigen::Vector3d a = corners[w], b = corners[w + 1];
    // Inside view: a at the left, b at the right when the normal faces the room centre.
    AddQuad(&scene[1].mesh, a, b, b + Eigen::Vector3d(0, 0, top), a + Eigen::Vector3d(0, 0, top),
            {w * side / perimeter, 0.0}, {(w + 1) * side / perimeter, 1.0});
  }
  const int wall_width = o.floor_texture_px * 2;
  scene[1].texture = WallTexture(o, wall_width, std::max(16, static_cast<int>(wall_width * top / perimeter)), perimeter);
  return scene;
}

void FloorShadowOptions::Check() const {
  const std::string owner = "FloorShadowOptions.";
  RequireOption(half_size_m > 0.1, owner + "half_size_m", half_size_m, "> 0.1 metres");
  RequireOption(cell_m > 0.0, owner + "cell_m", cell_m, "> 0");
  RequireOptions(!(half_size_m / cell_m > 4000), owner + "half_size_m", half_size_m, owner + "cell_m", cell_m,
                 "half_size_m / cell_m <= 4000");
  RequireOption(blur_m >= 0.0, owner + "blur_m", blur_m, ">= 0");
  RequireOption(strength >= 0.0 && strength <= 1.0, owner + "strength", strength, "in [0, 1]");
  RequireOption(falloff_m > 0.0, owner + "falloff_m", falloff_m, "> 0");
}

float FloorShadow::At(double x, double y) const {
  const int i = static_cast<int>(std::floor((x + options.half_size_m) / options.cell_m));
  const int j = static_cast<int>(std::floor((y + options.half_size_m) / options.cell_m));
  if (i < 0 || j < 0 || i >= size || j >= size) return 1.0f;
  return factor[static_cast<std::size_t>(j) * size + i];
}

FloorShadow ComputeFloorShadow(const RowMatrixX3d& vertices, const FloorShadowOptions& options) {
  options.Check();
  FloorShadow shadow;
  shadow.options = options;
  shadow.size = static_cast<int>(std::ceil(2 * options.half_size_m / options.cell_m));
  std::vector<float> density(static_cast<std::size_t>(shadow.size) * shadow.size, 0.0f);
  for (int v = 0; v < vertices.rows(); ++v) {
    const double z = std::max(0.0, vertices(v, 2));
    const double x = vertices(v, 0) + z * options.offset_x_per_m, y = vertices(v, 1) + z * options.offset_y_per_m;
    const int i = static_cast<int>(std::floor((x + options.half_size_m) / options.cell_m));
    const int j = static_cast<int>(std::floor((y + options.half_size_m) / options.cell_m));
    if (i < 0 || j < 0 || i >= shadow.size || j >= shadow.size) continue;
    density[static_cast<std::size_t>(j) * shadow.size + i] += static_cast<float>(std::exp(-z / options.falloff_m));
  }
  // Normalise by the vertex density so that the look does not depend on the mesh resolution:
  // a 1 m^2 patch of body surface covered by about (vertices / 2.2 m^2) vertices.
  const double per_area = std::max<double>(1.0, vertices.rows() / 2.2);
  const double cell_area = options.cell_m * options.cell_m;
  BoxBlur(&density, shadow.size, std::max(1, static_cast<int>(std::lround(options.blur_m / options.cell_m))));
  shadow.factor.resize(density.size());
  for (std::size_t k = 0; k < density.size(); ++k) {
    const double coverage = density[k] / (per_area * cell_area);  // body area above per floor area
    shadow.factor[k] = static_cast<float>(1.0 - options.strength * (1.0 - std::exp(-2.0 * coverage)));
  }
  return shadow;
}

}  // namespace confluent
