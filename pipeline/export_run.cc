// confluent export: atlas, per-frame bake into H.264, glTF, player and mesh sequences.

#include "pipeline/export_run.h"

#include <algorithm>
#include <filesystem>
#include <memory>

#include <nlohmann/json.hpp>
#include <opencv2/imgproc.hpp>

#include "core/statistics.h"
#include "core/atomic_file.h"
#include "core/cv_interop.h"
#include "core/error.h"
#include "core/image_io.h"
#include "core/mesh_io.h"
#include "deform/point_cache.h"
#include "export/atlas_bake.h"
#include "export/player_writer.h"
#include "pipeline/run_folder.h"

namespace confluent {
namespace {

namespace fs = std::filesystem;

Image ResizedTo(const Image& image, int size_px) {
  cv::Mat resized;
  cv::resize(AsCvMat(image), resized, cv::Size(size_px, size_px), 0, 0, cv::INTER_AREA);
  return ImageFromCvMat(resized);
}

std::size_t FileBytes(const std::string& path) {
  std::error_code error;
  const auto size = fs::file_size(path, error);
  return error ? 0 : static_cast<std::size_t>(size);
}

// A glTF + video pair in `dir`: the videos are fed frame by frame, the glb written at the end.
struct StreamWriter {
  std::string dir;
  int atlas_px = 0;
  std::unique_ptr<VideoWriter> video;

  StreamWriter(const std::string& folder, int size_px, const VideoWriterOptions& options)
      : dir(folder), atlas_px(size_px),
        video(std::make_unique<VideoWriter>((fs::path(folder) / "atlas.mp4").string(), size_px, size_px, options)) {}

  ExportedStream Finish(const Mesh& scan_with_uvs, const std::vector<RowMatrixX3d>& frames, const Image& first_atlas,
                        const GltfOptions& gltf, bool player, double seconds) {
    video->Close();
    ExportedStream result;
    result.atlas_px = atlas_px;
    result.video_path = video->path();
    result.glb_path = (fs::path(dir) / "scene.glb").string();
    result.glb = WriteGlb(result.glb_path, scan_with_uvs, frames, first_atlas, gltf);
    result.video_bytes = FileBytes(result.video_path);
    result.megabits_per_second = 8.0 * static_cast<double>(result.glb.bytes + result.video_bytes) / seconds / 1e6;
    if (player) WritePlayer((fs::path(dir) / "player").string());
    return result;
  }
};

nlohmann::json StreamJson(const ExportedStream& stream, const std::string& out_dir) {
  return {{"scene", fs::relative(stream.glb_path, out_dir).string()},
          {"video", fs::relative(stream.video_path, out_dir).string()},
          {"atlas_px", stream.atlas_px},
          {"vertices", stream.glb.vertices},
          {"triangles", stream.glb.triangles},
          {"position_step_m", stream.glb.position_step_m},
          {"decimation_error", stream.glb.decimation_error},
          {"glb_bytes", stream.glb.bytes},
          {"video_bytes", stream.video_bytes},
          {"megabits_per_second", stream.megabits_per_second}};
}

void WriteSummaryJson(const ExportSummary& summary, const ExportOptions& options, const std::string& out_dir) {
  nlohmann::json json;
  json["first_frame"] = summary.first_frame;
  json["frames"] = summary.frames;
  json["fps"] = summary.fps;
  json["texturing_cameras"] = summary.texturing_cameras;
  json["atlas"] = {{"size_px", options.atlas.size_px},
                   {"charts", summary.atlas.charts},
                   {"texel_use", summary.atlas.texel_use},
                   {"stretch_mean", summary.atlas.stretch_mean},
                   {"stretch_max", summary.atlas.stretch_max}};
  json["median_bake_ms"] = summary.median_bake_ms;
  json["full"] = StreamJson(summary.full, out_dir);
  if (!summary.stream.glb_path.empty()) json["stream"] = StreamJson(summary.stream, out_dir);
  json["warnings"] = summary.warnings;
  WriteTextFile((fs::path(out_dir) / "export.json").string(), json.dump(2) + "\n");
}

}  // namespace

void ExportOptions::Check() const {
  atlas.Check();
  gltf.Check();
  video.Check();
  texturing.Check();
  if (!(fps >= 0.0)) throw UsageError("ExportOptions.fps must be >= 0 (0 = the run's)");
  if (stream_crf < 0 || stream_crf > 51) throw UsageError("ExportOptions.stream_crf must be within 0..51");
  if (stream_triangles < 0) throw UsageError("ExportOptions.stream_triangles must be >= 0 (0 = no stream variant)");
  if (stream_atlas_px < 64 || stream_atlas_px > atlas.size_px)
    throw UsageError("ExportOptions.stream_atlas_px = " + std::to_string(stream_atlas_px) +
                     ": must be 64 .. the atlas size (" + std::to_string(atlas.size_px) + ")");
}

ExportSummary ExportRun(const FinishedRun& finished, const Capture& capture, const FrameRange& range,
                        const std::string& out_dir, const ExportOptions& options, const ProgressCallback& progress) {
  options.Check();
  const RunFolder& run = finished.folder;
  const Rig& rig = capture.rig();
  ExportSummary summary;
  summary.first_frame = range.first;
  summary.frames = range.size();
  summary.fps = options.fps > 0.0 ? options.fps : finished.fps();

  // Every frame of the range needs its mesh: the glTF animation and the video have no gaps.
  for (int frame = range.first; frame < range.end; ++frame)
    if (!fs::exists(run.ScanPath(frame)))
      throw InputError(run.ScanPath(frame), "missing: export needs the scan of every frame of " +
                                                std::to_string(range.first) + ":" + std::to_string(range.end) +
                                                " (run `confluent run`, or give --frames)");

  std::string held_out_warning;
  const TexturingCameras texturing =
      SelectTexturingCameras(finished, rig, options.excluded, options.texture_from_held_out, &held_out_warning);
  if (!held_out_warning.empty()) summary.warnings.push_back(held_out_warning);
  summary.texturing_cameras = static_cast<int>(texturing.indices.size());

  // The scan: topology from the run's first frame; colours and segment labels from the
  // capture's scan when the run's meshes lack them (the labels make better charts).
  Mesh scan = ReadMesh(run.ScanPath(range.first));
  if (!capture.scan_path().empty() && fs::exists(capture.scan_path())) {
    const Mesh original = ReadMesh(capture.scan_path());
    if (original.num_vertices() == scan.num_vertices() && original.faces == scan.faces) {
      if (!scan.has_colors() && original.has_colors()) scan.colors = original.colors;
      if (!scan.has_face_labels() && original.has_face_labels()) scan.face_labels = original.face_labels;
    }
  }

  ReportProgress(progress, "export: atlas", 0, 1);
  const UvAtlas atlas = BuildUvAtlas(scan, options.atlas);
  summary.atlas = atlas.stats;
  ReportProgress(progress, "export: atlas", 1, 1, std::to_string(atlas.stats.charts) + " charts");
  Mesh scan_with_uvs = WithAtlasUvs(scan, atlas);

  fs::create_directories(out_dir);
  VideoWriterOptions video_options = options.video;
  video_options.fps = summary.fps;
  if (!FfmpegAvailable(video_options))
    throw OutputError((fs::path(out_dir) / "atlas.mp4").string(), "ffmpeg is not installed (needed for the atlas video)");
  StreamWriter full(out_dir, options.atlas.size_px, video_options);
  std::unique_ptr<StreamWriter> stream;
  if (options.stream_triangles > 0) {
    fs::create_directories(fs::path(out_dir) / "stream");
    VideoWriterOptions stream_video = video_options;
    stream_video.crf = options.stream_crf;
    stream = std::make_unique<StreamWriter>((fs::path(out_dir) / "stream").string(), options.stream_atlas_px,
                                            stream_video);
  }
  std::unique_ptr<PointCacheWriter> cache;
  if (options.pc2) {
    cache = std::make_unique<PointCacheWriter>((fs::path(out_dir) / "scan.pc2").string(), scan.num_vertices(),
                                               range.first);
    WriteMesh((fs::path(out_dir) / "rest.ply").string(), scan);
  }

  AtlasBaker baker(scan, atlas, options.texturing);
  std::vector<RowMatrixX3d> vertices;
  Image first_atlas;
  std::vector<double> bake_ms;
  const std::string atlas_png = (fs::path(out_dir) / "atlas.png").string();
  for (int frame = range.first; frame < range.end; ++frame) {
    const Mesh mesh = ReadMesh(run.ScanPath(frame));
    if (mesh.num_vertices() != scan.num_vertices() || mesh.faces != scan.faces)
      throw InputError(run.ScanPath(frame), "topology differs from " + run.ScanPath(range.first));
    std::vector<Image> images, masks;
    ReadTexturingFrame(finished, capture, texturing, frame, &images, &masks);
    const double start = NowSeconds();
    const Image baked = baker.Bake(mesh.vertices, texturing.cameras, images, masks);
    bake_ms.push_back(1e3 * (NowSeconds() - start));
    full.video->Write(baked);
    if (stream) stream->video->Write(ResizedTo(baked, options.stream_atlas_px));
    if (frame == range.first) {
      first_atlas = baked;
      WriteImage(atlas_png, baked);
    }
    vertices.push_back(mesh.vertices);

    Mesh out = mesh;
    if (!out.has_colors() && scan.has_colors()) out.colors = scan.colors;
    if (options.ply) WriteMesh((fs::path(out_dir) / "ply" / (FrameStem(frame) + ".ply")).string(), out);
    if (options.obj) {
      Mesh textured = scan_with_uvs;
      textured.vertices = mesh.vertices;
      textured.texture_path = fs::absolute(atlas_png).string();
      WriteMesh((fs::path(out_dir) / "obj" / (FrameStem(frame) + ".obj")).string(), textured);
    }
    if (cache) cache->Append(mesh.vertices);
    ReportProgress(progress, "export: bake", static_cast<std::size_t>(frame - range.first + 1),
                   static_cast<std::size_t>(range.size()), "frame " + std::to_string(frame));
  }
  if (cache) cache->Finish();
  summary.median_bake_ms = Median(bake_ms);

  ReportProgress(progress, "export: glTF", 0, stream ? 2 : 1);
  const double seconds = range.size() / summary.fps;
  GltfOptions gltf = options.gltf;
  gltf.fps = summary.fps;
  gltf.decimate_triangles = 0;
  summary.full = full.Finish(scan_with_uvs, vertices, first_atlas, gltf, options.player, seconds);
  ReportProgress(progress, "export: glTF", 1, stream ? 2 : 1);
  if (stream) {
    gltf.decimate_triangles = options.stream_triangles;
    gltf.per_frame_normals = false;  // the material is unlit: frame 0's normals do, at 40% fewer bytes
    summary.stream = stream->Finish(scan_with_uvs, vertices, ResizedTo(first_atlas, options.stream_atlas_px), gltf,
                                    options.player, seconds);
    ReportProgress(progress, "export: glTF", 2, 2);
  }
  WriteSummaryJson(summary, options, out_dir);
  return summary;
}

}  // namespace confluent
