#pragma once
// `confluent export`: a finished run's 3D video out of the tool. The scan gets a UV atlas once
// (export/uv_atlas.h); every frame's projective texture from the run's cameras is baked into it
// (export/atlas_bake.h) and encoded as an H.264 video whose frames align with the mesh frames;
// the animated scan goes into a glTF 2.0 file (export/gltf_writer.h) with the first atlas frame
// as its base colour, and a web player (export/player_writer.h) plays both. Written into OUT:
//
//   OUT/scene.glb  OUT/atlas.mp4  OUT/atlas.png (first atlas frame)  OUT/player/index.html
//   OUT/stream/{scene.glb, atlas.mp4, player/}   with stream_triangles: decimated mesh, smaller atlas
//   OUT/ply/<frame>.ply  OUT/obj/<frame>.obj (+ .mtl, atlas UVs)  OUT/scan.pc2 + OUT/rest.ply
//                                                on request
//   OUT/export.json                              what was written, sizes, bitrates, atlas figures

#include <string>
#include <vector>

#include "calib/capture.h"
#include "core/progress.h"
#include "core/video_writer.h"
#include "export/gltf_writer.h"
#include "export/uv_atlas.h"
#include "pipeline/finished_run.h"
#include "pipeline/frame_range.h"
#include "render/projective_texture.h"

namespace confluent {

struct ExportOptions {
  UvAtlasOptions atlas;           // the full-resolution atlas (2048 px by default)
  GltfOptions gltf;               // fps and decimate_triangles are set from the fields below
  VideoWriterOptions video;       // the atlas videos (crf, preset); its fps is set from `fps`
  double fps = 0.0;               // of the videos and the glTF animation; 0: the run's
  ProjectiveTextureOptions texturing;
  std::vector<std::string> excluded;   // cameras that do not texture (besides the run's held-out ones)
  bool texture_from_held_out = false;  // let the run's held-out cameras texture too
  int stream_triangles = 0;       // > 0: OUT/stream/ with the mesh decimated to about this many triangles
  int stream_atlas_px = 1024;     // the stream variant's atlas size (the full atlas resized)
  // H.264 quality of the stream variant's atlas: crf 23 keeps the demo's stream (10K-triangle
  // mesh, 1024 px atlas) under 16 Mbit/s in all (crf 18: 17.3).
  int stream_crf = 23;
  bool player = true;             // OUT/player/ (and OUT/stream/player/)
  bool ply = false;               // OUT/ply/<frame>.ply with the scan's vertex colours
  bool obj = false;               // OUT/obj/<frame>.obj with the atlas UVs and atlas.png
  bool pc2 = false;               // OUT/scan.pc2 and OUT/rest.ply (Blender's Mesh Cache)
  void Check() const;             // throws UsageError naming the bad field
};

// One glTF + atlas video pair.
struct ExportedStream {
  std::string glb_path, video_path;
  GltfSummary glb;
  int atlas_px = 0;
  std::size_t video_bytes = 0;
  double megabits_per_second = 0.0;  // (glb + video) bytes * 8 / duration
};

struct ExportSummary {
  int first_frame = 0;
  int frames = 0;
  double fps = 0.0;
  int texturing_cameras = 0;
  UvAtlasStats atlas;
  ExportedStream full;
  ExportedStream stream;          // glb_path empty without stream_triangles
  double median_bake_ms = 0.0;    // one frame's atlas
  std::vector<std::string> warnings;
};

// Exports `frames` of `run` (made from `capture`) into `out_dir`. Every frame of the range needs
// its scan mesh (RUN/scan/<frame>.ply). Throws UsageError for bad options or camera names,
// InputError naming a missing or inconsistent mesh, OutputError naming a file that could not be
// written (ffmpeg missing included).
ExportSummary ExportRun(const FinishedRun& run, const Capture& capture, const FrameRange& frames,
                        const std::string& out_dir, const ExportOptions& options, const ProgressCallback& progress);

}  // namespace confluent
