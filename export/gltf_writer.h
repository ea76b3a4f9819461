#pragma once
// The animated, textured scan as one binary glTF 2.0 file (scene.glb) that Blender's glTF
// importer and three.js both play.
//
// Layout. The scan is split at its UV seams (export/seam_split.h). Every frame is a mesh of its
// own that shares the index and UV accessors and has its own POSITION and NORMAL; each is the
// child node "frame_NNNNNN" of one node "scan", whose translation and uniform scale undo the
// position quantisation; its parent, the root "confluent_z_up", rotates confluent's world
// (Z up) into glTF's (Y up), so Blender shows the actor standing. One animation ("frames")
// keys the frame nodes' scale with STEP interpolation: 1 while the node's frame is shown, 0
// otherwise, so exactly one frame is visible at any time (frame k from k / fps to (k + 1) / fps;
// the clip lasts frames / fps).
// The scene's extras hold {"fps", "frames"} for players, and "source_vertex_accessor": the index
// of a uint32 accessor with each vertex's scan vertex (not a vertex attribute).
//
// Why not morph targets, one per frame: three.js uploads morph targets as a float32 RGBA
// texture array with one layer per target (WebGL2 guarantees only 256 layers) and a uniform
// float per target in the vertex shader, i.e. 16 bytes per vertex per attribute per frame:
// 400 MB of GPU memory for 250 frames of a 50K-vertex scan with normals, and a 10 s capture
// already exceeds the guaranteed limits. Blender imports hundreds of shape keys but evaluates
// all of them. Frame nodes have no count limit, stay quantised on the GPU (12 bytes per vertex
// per frame) and import into Blender as one object per frame with keyed scale.
//
// Encoding. KHR_mesh_quantization: positions int16 (steps of GltfOptions::position_step_m from
// the centre; the scan node's translation and scale map them to metres), normals int8
// normalised, UVs uint16 normalised (float when a UV lies outside [0, 1]). Optionally
// EXT_meshopt_compression (meshoptimizer's vertex and index codecs) on every vertex and index
// stream: three.js reads it with its MeshoptDecoder; Blender's importer does not (3.4, Debian
// 12's, refuses the file), so GltfOptions::meshopt_compression = false writes a quantised file
// without it, which Blender imports and plays (one object per frame; glTF time t is Blender
// frame t * fps, from frame 0). When used, the
// extension is listed as required, as the file carries no uncompressed fallback. The base colour is an embedded JPEG or PNG on an unlit
// material (KHR_materials_unlit): the atlas already holds the captured light.

#include <cstdint>
#include <string>
#include <vector>

#include "core/image.h"
#include "core/mesh.h"

namespace confluent {

struct GltfOptions {
  double fps = 25.0;                // frames per second of the animation
  // Quantisation step of the positions, metres (int16 steps from the box centre); coarser
  // when int16 cannot span the frames' bounding box at this step (65534 steps).
  double position_step_m = 0.0002;
  // A NORMAL per frame (smooth across seams); false shares frame 0's normals between all
  // frames: a third smaller, and the unlit material does not use them.
  bool per_frame_normals = true;
  bool meshopt_compression = true;  // EXT_meshopt_compression (three.js: yes; Blender: no)
  // Decimate the seam-split mesh to about this many triangles (export/mesh_decimate.h) for a
  // streamable variant; 0 keeps the full resolution.
  int decimate_triangles = 0;
  bool jpeg_texture = true;         // base colour as JPEG (smaller) instead of PNG (lossless)
  int jpeg_quality = 90;            // 1..100
  std::string generator = "confluent";  // asset.generator
  // Throws UsageError when a value is out of range.
  void Check() const;
};

struct GltfSummary {
  int frames = 0;
  int vertices = 0;               // vertices per frame after seam splitting (and decimation)
  int triangles = 0;
  double position_step_m = 0.0;   // quantisation step of the positions (metres)
  double decimation_error = 0.0;  // meshoptimizer's relative error; 0 without decimation
  std::size_t bytes = 0;          // size of the .glb
};

// Encodes the animated scan as GLB bytes. `scan` is the scan with per-corner UVs (faces,
// uvs, face_uvs; its vertices are not used), `frames` its vertex positions per frame (each
// scan.num_vertices() x 3, world frame, metres; at least one), `base_color` the texture (8-bit
// RGB or RGBA; top row = v = 1). Throws InputError("scan") for a mesh without UVs or with
// out-of-range indices, InputError("frames") for a wrong vertex count or a non-finite position,
// InputError("base colour") for an empty or non-8-bit image, UsageError for bad options.
std::vector<std::uint8_t> EncodeGlb(const Mesh& scan, const std::vector<RowMatrixX3d>& frames,
                                    const Image& base_color, const GltfOptions& options = {},
                                    GltfSummary* summary = nullptr);

// EncodeGlb, written atomically to `path` (core/atomic_file.h). Throws what EncodeGlb throws,
// and OutputError(path) when the file cannot be written.
GltfSummary WriteGlb(const std::string& path, const Mesh& scan, const std::vector<RowMatrixX3d>& frames,
                     const Image& base_color, const GltfOptions& options = {});

}  // namespace confluent
