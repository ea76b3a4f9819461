#pragma once
// INTERNAL (render/renderer.cc only): the GLSL of MeshRenderer: the mesh pass (colour, camera
// depth, triangle ids, coverage mask) and the distortion remap pass, with the order of the
// render target's colour attachments that both write.

namespace confluent::mesh_renderer_internal {

// Colour attachments of a render target, in this order (= fragment output locations).
enum Attachment { kColor = 0, kCameraZ = 1, kTriangleId = 2, kMask = 3, kNumAttachments = 4 };

constexpr const char* kMeshVertexShader = R"(#version 430 core
layout(location = 0) in vec3 position_in_world;
layout(location = 1) in vec3 normal_in_world;
layout(location = 2) in vec3 albedo;
layout(location = 3) in vec2 uv;
uniform mat4 clip_from_world;
uniform mat4 cam_from_world;
out float camera_z;
out vec3 v_position;
out vec3 v_normal;
out vec3 v_albedo;
out vec2 v_uv;
void main() {
  gl_Position = clip_from_world * vec4(position_in_world, 1.0);
  camera_z = (cam_from_world * vec4(position_in_world, 1.0)).z;
  v_position = position_in_world;
  v_normal = normal_in_world;
  v_albedo = albedo;
  v_uv = uv;
}
)";

constexpr const char* kMeshFragmentShader = R"(
in float camera_z;
in vec3 v_position;
in vec3 v_normal;
in vec3 v_albedo;
in vec2 v_uv;
layout(location = 0) out vec4 out_color;
layout(location = 1) out float out_camera_z;
layout(location = 2) out int out_triangle_id;
layout(location = 3) out float out_mask;
uniform int id_offset;
#ifdef WITH_COLOR
uniform bool use_texture;
uniform sampler2D albedo_texture;
uniform bool lit;
uniform bool headlight;
uniform vec3 light_direction;
uniform vec3 camera_center;
uniform float ambient;
uniform float diffuse;
uniform bool srgb_output;
vec3 EncodeSrgb(vec3 c) {
  c = clamp(c, 0.0, 1.0);
  return mix(c * 12.92, 1.055 * pow(c, vec3(1.0 / 2.4)) - 0.055, step(vec3(0.0031308), c));
}
#endif
void main() {
  out_camera_z = camera_z;
  out_triangle_id = gl_PrimitiveID + id_offset;
  out_mask = 1.0;
#ifdef WITH_COLOR
  vec3 albedo = use_texture ? texture(albedo_texture, vec2(v_uv.x, 1.0 - v_uv.y)).rgb : v_albedo;
  vec3 color = albedo;
  if (lit) {
    vec3 view = normalize(camera_center - v_position);
    vec3 n = v_normal;
    float length_n = length(n);
    n = length_n > 0.0 ? n / length_n : view;
    if (dot(n, view) < 0.0) n = -n;  // two-sided lighting
    vec3 l = headlight ? view : light_direction;
    color = albedo * (ambient + diffuse * max(dot(n, l), 0.0));
  }
  out_color = vec4(srgb_output ? EncodeSrgb(color) : clamp(color, 0.0, 1.0), 1.0);
#else
  out_color = vec4(0.0);
#endif
}
)";


// Each output (distorted) pixel reads its position in the ideal buffer from `ideal_from_pixel`
// (RG32F, buffer coordinates with sample centres at integers) and interpolates the coverage
// mask of the 4 surrounding samples bilinearly: the pixel is covered when that is >= 0.5, which
// places the outline with sub-sample accuracy. A covered pixel takes depth and triangle id from
// the covered sample with the largest weight and colour from the weighted covered samples, so
// silhouette, depth, ids and colour stay mutually consistent.
constexpr const char* kRemapFragmentShader = R"(#version 430 core
layout(location = 0) out vec4 out_color;
layout(location = 1) out float out_camera_z;
layout(location = 2) out int out_triangle_id;
layout(location = 3) out float out_mask;
uniform sampler2D ideal_from_pixel;
uniform sampler2D ideal_color;
uniform sampler2D ideal_camera_z;
uniform isampler2D ideal_triangle_id;
uniform sampler2D ideal_mask;
uniform ivec2 ideal_size;  // region of the ideal buffers that was rendered
uniform vec4 background;
void main() {
  vec2 ideal = texelFetch(ideal_from_pixel, ivec2(gl_FragCoord.xy), 0).xy;
  ivec2 base = ivec2(floor(ideal));
  vec2 f = ideal - vec2(base);
  float coverage = 0.0;
  float best_weight = -1.0;
  ivec2 best = ivec2(0);
  vec4 color = vec4(0.0);
  for (int k = 0; k < 4; ++k) {
    ivec2 offset = ivec2(k & 1, k >> 1);
    ivec2 p = base + offset;
    if (any(lessThan(p, ivec2(0))) || any(greaterThanEqual(p, ideal_size))) continue;
    float weight = (offset.x == 1 ? f.x : 1.0 - f.x) * (offset.y == 1 ? f.y : 1.0 - f.y);
    if (texelFetch(ideal_mask, p, 0).r < 0.5) continue;
    coverage += weight;
    color += weight * texelFetch(ideal_color, p, 0);
    if (weight > best_weight) {
      best_weight = weight;
      best = p;
    }
  }
  if (coverage < 0.5) {
    out_color = background;
    out_camera_z = 0.0;
    out_triangle_id = -1;
    out_mask = 0.0;
    return;
  }
  out_color = color / coverage;
  out_camera_z = texelFetch(ideal_camera_z, best, 0).r;
  out_triangle_id = texelFetch(ideal_triangle_id, best, 0).r;
  out_mask = 1.0;
}
)";

}  // namespace confluent::mesh_renderer_internal
