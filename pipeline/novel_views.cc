#include "pipeline/novel_views.h"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <memory>
#include <sstream>

#include "calib/easymocap_io.h"
#include "calib/plate_colour.h"
#include "core/statistics.h"
#include "core/atomic_file.h"
#include "core/error.h"
#include "core/image_io.h"
#include "core/mesh_io.h"
#include "core/video_writer.h"
#include "render/camera_path.h"
#include "render/composite.h"

namespace confluent {
namespace fs = std::filesystem;

namespace {

std::vector<std::string> Split(const std::string& text, char separator) {
  std::vector<std::string> parts;
  std::stringstream stream(text);
  std::string part;
  while (std::getline(stream, part, separator))
    if (!part.empty()) parts.push_back(part);
  return parts;
}

// An 8-bit sRGB image as float linear RGB (for EXR output).
Image ToLinearFloat(const Image& rgb8) {
  Image out(rgb8.width, rgb8.height, 3, PixelType::kFloat32);
  float table[256];
  for (int v = 0; v < 256; ++v) {
    const double c = v / 255.0;
    table[v] = static_cast<float>(c <= 0.04045 ? c / 12.92 : std::pow((c + 0.055) / 1.055, 2.4));
  }
  float* dst = out.ptr<float>();
  for (std::size_t i = 0; i < rgb8.data.size(); ++i) dst[i] = table[rgb8.data[i]];
  return out;
}

// The camera at width x height (itself when width <= 0 or the size is unchanged).
Camera Resized(const Camera& camera, int width, int height) {
  if (width <= 0 || (width == camera.width && height == camera.height)) return camera;
  return ResizedCamera(camera, width, height);
}

}  // namespace

void NovelViewOptions::Check() const {
  if (geometry != "scan" && geometry != "template")
    throw UsageError("NovelViewOptions.geometry = '" + geometry + "': must be scan or template");
  if (format != "png" && format != "exr")
    throw UsageError("NovelViewOptions.format = '" + format + "': must be png or exr");
  RequireOption((width > 0) == (height > 0), "NovelViewOptions.width", width, "given with a height (both or neither)");
  RequireOption(width >= 0 && width <= 8192, "NovelViewOptions.width", width, "in 0..8192");
  RequireOption(height >= 0 && height <= 8192, "NovelViewOptions.height", height, "in 0..8192");
  RequireOption(path_frames >= 0, "NovelViewOptions.path_frames", path_frames, ">= 0");
  RequireOption(fps >= 0.0, "NovelViewOptions.fps", fps, ">= 0");
  RequireOption(edge_softness_px >= 0.0 && edge_softness_px <= 5.0, "NovelViewOptions.edge_softness_px",
                edge_softness_px, "in [0, 5] pixels");
  texturing.Check();
}

NovelViewSummary RenderNovelViews(const FinishedRun& finished, const Capture& capture, const FrameRange& range,
                                  const std::string& out_dir, const NovelViewOptions& options,
                                  const ProgressCallback& progress) {
  options.Check();
  NovelViewSummary summary;
  const RunFolder& run = finished.folder;
  const Rig& rig = capture.rig();
  const std::string& geometry = options.geometry;
  const std::string& format = options.format;
  const int width = options.width, height = options.height;
  VideoWriterOptions video_options;
  video_options.fps = options.fps > 0.0 ? options.fps : finished.fps();
  video_options.Check();

  // Texturing cameras: never the ones the run held out, unless asked.
  std::string held_out_warning;
  const TexturingCameras texturing =
      SelectTexturingCameras(finished, rig, options.excluded, options.texture_from_held_out, &held_out_warning);
  if (!held_out_warning.empty()) summary.warnings.push_back(held_out_warning);
  const std::vector<int>& used = texturing.indices;
  const std::vector<Camera>& used_cameras = texturing.cameras;

  // Geometry present in the run.
  auto mesh_path = [&](int frame) { return geometry == "scan" ? run.ScanPath(frame) : run.TemplatePath(frame); };
  std::vector<int> present, missing;
  for (int frame = range.first; frame < range.end; ++frame)
    (fs::exists(mesh_path(frame)) ? present : missing).push_back(frame);
  if (present.empty())
    throw InputError(run.Path(geometry), "no " + geometry + " mesh for frames " + std::to_string(range.first) + ":" +
                                             std::to_string(range.end) + " (run `confluent run` first)");
  Mesh reference = ReadMesh(mesh_path(present.front()));
  if (!reference.has_colors() && !capture.scan_path().empty() && geometry == "scan") {
    const Mesh scan = ReadMesh(capture.scan_path());
    if (scan.has_colors() && scan.num_vertices() == reference.num_vertices()) reference.colors = scan.colors;
  }
  // Centre of the actor (for orbits and sweeps): the first frame's bounding box.
  const Eigen::Vector3d centre =
      0.5 * (reference.vertices.colwise().minCoeff() + reference.vertices.colwise().maxCoeff()).transpose();

  // The camera path and which frame each output shows.
  const std::string& path_text = options.path;
  const int path_frames = options.path_frames;
  if (path_frames < 0) throw UsageError("--path-frames: must be >= 0");
  std::vector<PathFrame> sequence;
  std::string view;
  bool frozen = false;
  const int sequence_length = static_cast<int>(present.size());
  if (path_text == "orbit") {
    OrbitPathOptions orbit = OrbitAroundCameras(used_cameras, centre);
    if (width > 0) {
      orbit.width_px = width;
      orbit.height_px = height;
    }
    orbit.num_frames = path_frames > 0 ? path_frames : sequence_length;
    sequence = AlongSequence(OrbitPath(orbit), present);
    view = "orbit";
  } else if (path_text.rfind("cameras:", 0) == 0) {
    std::vector<Camera> keys;
    for (const std::string& name : Split(path_text.substr(8), ',')) keys.push_back(rig.Get(name));
    if (keys.empty()) throw UsageError("--path cameras: name at least one camera, e.g. cameras:cam01,cam03");
    KeyCameraPathOptions options;
    options.num_frames = std::max<int>(path_frames > 0 ? path_frames : sequence_length, static_cast<int>(keys.size()));
    options.width_px = width;
    options.height_px = height;
    sequence = AlongSequence(PathThroughCameras(keys, options), present);
    view = "path";
  } else if (path_text.rfind("fixed:", 0) == 0) {
    const std::string spec = path_text.substr(6);
    Camera camera;
    const std::size_t slash = spec.rfind('/');
    if (slash == std::string::npos) {
      camera = rig.Get(spec);
    } else {
      const std::string dir = spec.substr(0, slash), name = spec.substr(slash + 1);
      const Rig calibration = ReadEasyMocap(dir + "/intri.yml", dir + "/extri.yml");
      camera = calibration.Get(name);
    }
    sequence = AlongSequence(FixedPath(Resized(camera, width, height), 1), present);
    view = camera.name;
  } else if (path_text.rfind("bullet:", 0) == 0) {
    int frame = 0;
    try {
      std::size_t used_chars = 0;
      frame = std::stoi(path_text.substr(7), &used_chars);
      if (used_chars != path_text.size() - 7) throw std::invalid_argument("trailing text");
    } catch (const std::exception&) {
      throw UsageError("--path bullet:FRAME: expected a frame number, got '" + path_text.substr(7) + "'");
    }
    if (frame < 0 || frame >= capture.num_frames())
      throw UsageError("--path bullet:" + std::to_string(frame) + ": the capture has frames 0.." +
                       std::to_string(capture.num_frames() - 1));
    if (!fs::exists(mesh_path(frame)))
      throw InputError(mesh_path(frame), "no " + geometry + " mesh for the bullet-time frame");
    KeyCameraPathOptions options;
    options.closed = true;
    options.num_frames = std::max<int>(path_frames > 0 ? path_frames : 60, static_cast<int>(used_cameras.size()));
    options.width_px = width;
    options.height_px = height;
    const std::vector<Camera> ring = SortByAzimuth(used_cameras, centre);
    sequence = FrozenTime(used_cameras.size() >= 2 ? PathThroughCameras(ring, options) : FixedPath(ring[0], 1), frame);
    view = "bullet_" + FrameStem(frame);
    frozen = true;
    missing.clear();
    present = {frame};
  } else {
    throw UsageError("--path: expected orbit, cameras:NAME,NAME,..., fixed:NAME, fixed:CALIB_DIR/NAME or bullet:FRAME, got '" +
                     path_text + "'");
  }

  // --over-plate: a capture camera's view over its clean plate, the input colours matched to it.
  Image plate;
  std::string plate_path;
  std::vector<Eigen::Vector3d> plate_gains;
  const double edge_softness = options.edge_softness_px;
  if (options.over_plate) {
    if (path_text.rfind("fixed:", 0) != 0 || path_text.find('/') != std::string::npos || width > 0)
      throw UsageError("--over-plate: needs --path fixed:NAME with a camera of the capture, at its own size (no --width/--height)");
    const int camera = rig.IndexOf(view);
    plate_path = capture.BackgroundPath(camera);
    if (plate_path.empty()) throw InputError(capture.root() + "/background", "no clean plate for camera " + view);
    plate = ToRgb8(ReadImage(plate_path));
    std::vector<std::string> unmatched;
    plate_gains = PlateColourGainsTo(capture, used, camera, plate, &unmatched);
    for (const std::string& name : unmatched)
      summary.warnings.push_back("no colour match from " + name + " to " + view +
                                 " (no clean plate, or no floor both see)");
  }

  ProjectiveTexturer texturer(reference, options.texturing);
  const std::string view_dir = (fs::path(out_dir) / view).string();
  std::unique_ptr<VideoWriter> video;
  if (options.write_mp4) {
    if (!FfmpegAvailable(video_options))
      throw OutputError((fs::path(out_dir) / (view + ".mp4")).string(), "ffmpeg is not installed (needed for --mp4)");
    video = std::make_unique<VideoWriter>((fs::path(out_dir) / (view + ".mp4")).string(), sequence.front().camera.width,
                                          sequence.front().camera.height, video_options);
  }

  std::vector<double> set_ms, render_ms;
  int current_frame = -1;
  int written = 0;
  for (std::size_t j = 0; j < sequence.size(); ++j) {
    const PathFrame& entry = sequence[j];
    if (entry.frame != current_frame) {
      const Mesh mesh = ReadMesh(mesh_path(entry.frame));
      if (mesh.num_vertices() != reference.num_vertices() || mesh.faces != reference.faces)
        throw InputError(mesh_path(entry.frame), "topology differs from " + mesh_path(present.front()));
      std::vector<Image> images, masks;
      ReadTexturingFrame(finished, capture, texturing, entry.frame, &images, &masks);
      const double start = NowSeconds();
      texturer.SetFrame(mesh.vertices, used_cameras, images, masks);
      if (!plate_gains.empty()) texturer.SetViewGains(plate_gains);
      set_ms.push_back(1e3 * (NowSeconds() - start));
      current_frame = entry.frame;
    }
    const double start = NowSeconds();
    RenderResult result = texturer.Render(entry.camera, !plate.empty());
    if (!plate.empty()) result.color = CompositeOverBackground(result, plate, plate_path, edge_softness);
    render_ms.push_back(1e3 * (NowSeconds() - start));
    const int number = frozen ? static_cast<int>(j) : entry.frame;
    const std::string path = (fs::path(view_dir) / (FrameStem(number) + "." + format)).string();
    const Image output = format == "exr" ? ToLinearFloat(result.color) : result.color;
    WriteAtomically(path, [&](const std::string& temporary) { WriteImage(temporary, output); });
    if (video) video->Write(result.color);
    ++written;
    ReportProgress(progress, "render " + view, j + 1, sequence.size(), "frame " + std::to_string(entry.frame));
  }
  if (video) video->Close();

  const Camera& first = sequence.front().camera;
  summary.view = view;
  summary.view_dir = view_dir;
  summary.written = written;
  summary.width = first.width;
  summary.height = first.height;
  summary.texturing_cameras = static_cast<int>(used.size());
  summary.median_setup_ms = Median(set_ms);
  summary.median_render_ms = Median(render_ms);
  if (video) {
    summary.video_path = video->path();
    summary.video_frames = video->frames_written();
  }
  summary.fps = video_options.fps;
  summary.missing = missing;
  return summary;
}

}  // namespace confluent
