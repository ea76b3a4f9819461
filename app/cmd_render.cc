// confluent render: novel views of a run's animated scan (or template), projectively textured
// from the capture's camera images (render/projective_texture.h), along a camera path
// (render/camera_path.h), to PNG/EXR sequences and an H.264 MP4 (core/video_writer.h).

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <sstream>
#include <string>
#include <vector>

#include "app/commands.h"
#include "pipeline/frame_range.h"
#include "pipeline/finished_run.h"
#include "pipeline/run_folder.h"
#include "app/texture_args.h"
#include "calib/capture.h"
#include "calib/easymocap_io.h"
#include "calib/plate_colour.h"
#include "core/atomic_file.h"
#include "core/error.h"
#include "core/image_io.h"
#include "core/mesh_io.h"
#include "core/video_writer.h"
#include "render/camera_path.h"
#include "render/composite.h"
#include "render/projective_texture.h"

namespace confluent::app {
namespace {
namespace fs = std::filesystem;

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

int RunRender(const ParsedArgs& args, const Context& context) {
  const FinishedRun finished = OpenFinishedRun(args.get("run"), args.positionals().empty() ? "" : args.positionals()[0]);
  const RunFolder& run = finished.folder;
  const std::string out_dir = args.get("out");
  const std::string geometry = args.get("geometry", "scan");
  if (geometry != "scan" && geometry != "template")
    throw UsageError("--geometry: expected scan or template, got '" + geometry + "'");
  const std::string format = args.get("format", "png");
  if (format != "png" && format != "exr") throw UsageError("--format: expected png or exr, got '" + format + "'");
  const int width = args.get_int("width", 0), height = args.get_int("height", 0);
  if ((width > 0) != (height > 0) || width < 0 || height < 0 || width > 8192 || height > 8192)
    throw UsageError("--width and --height: give both, each in 1..8192");
  const bool write_mp4 = args.has("mp4");
  VideoWriterOptions video_options;
  video_options.fps = args.get_double("fps", finished.fps());
  video_options.Check();
  const ProjectiveTextureOptions texture_options = TextureOptionsFromArgs(args);

  CaptureOptions capture_options;
  capture_options.check_every_image_header = false;
  const Capture capture = Capture::Open(finished.capture_root, capture_options);
  const Rig& rig = capture.rig();
  const FrameRange range = ParseFrameRange(args.get("frames"), capture.num_frames());

  // Texturing cameras: never the ones the run held out, unless asked.
  std::string held_out_warning;
  const std::vector<std::string> excluded = TexturingExclusions(finished, rig, args.get_all("exclude-camera"),
                                                                args.has("texture-from-held-out"), &held_out_warning);
  if (!held_out_warning.empty()) std::fprintf(stderr, "confluent render: warning: %s\n", held_out_warning.c_str());
  std::vector<int> used;
  std::vector<Camera> used_cameras;
  for (int c = 0; c < rig.size(); ++c)
    if (std::find(excluded.begin(), excluded.end(), rig.cameras[c].name) == excluded.end()) {
      used.push_back(c);
      used_cameras.push_back(rig.cameras[c]);
    }

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
  const std::string path_text = args.get("path", "orbit");
  const int path_frames = args.get_int("path-frames", 0);
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
  const double edge_softness = args.get_double("edge-softness", 0.5);
  if (!(edge_softness >= 0.0 && edge_softness <= 5.0)) throw UsageError("--edge-softness: must be within [0, 5] pixels");
  if (args.has("over-plate")) {
    if (path_text.rfind("fixed:", 0) != 0 || path_text.find('/') != std::string::npos || width > 0)
      throw UsageError("--over-plate: needs --path fixed:NAME with a camera of the capture, at its own size (no --width/--height)");
    const int camera = rig.IndexOf(view);
    plate_path = capture.BackgroundPath(camera);
    if (plate_path.empty()) throw InputError(capture.root() + "/background", "no clean plate for camera " + view);
    plate = ToRgb8(ReadImage(plate_path));
    std::vector<std::string> unmatched;
    plate_gains = PlateColourGainsTo(capture, used, camera, plate, &unmatched);
    for (const std::string& name : unmatched)
      std::fprintf(stderr, "confluent render: warning: no colour match from %s to %s (no clean plate, or no floor both see)\n",
                   name.c_str(), view.c_str());
  }

  // Masks: the run's, else the capture's.
  auto mask_for = [&](int camera, int frame) -> Image {
    const std::string run_mask = run.MaskPath(rig.cameras[camera].name, frame);
    if (fs::exists(run_mask)) return ReadMaskFile(run_mask);
    if (capture.has_masks() && fs::exists(capture.MaskPath(camera, frame))) return capture.ReadMask(camera, frame);
    return Image();
  };

  ProjectiveTexturer texturer(reference, texture_options);
  const std::string view_dir = (fs::path(out_dir) / view).string();
  std::unique_ptr<VideoWriter> video;
  if (write_mp4) {
    if (!FfmpegAvailable(video_options))
      throw OutputError((fs::path(out_dir) / (view + ".mp4")).string(), "ffmpeg is not installed (needed for --mp4)");
    video = std::make_unique<VideoWriter>((fs::path(out_dir) / (view + ".mp4")).string(), sequence.front().camera.width,
                                          sequence.front().camera.height, video_options);
  }

  const ProgressCallback progress = context.make_progress();
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
      bool any_mask = false;
      for (int c : used) {
        images.push_back(capture.ReadFrame(c, entry.frame));
        masks.push_back(mask_for(c, entry.frame));
        any_mask = any_mask || !masks.back().empty();
      }
      if (!any_mask) masks.clear();
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

  auto median = [](std::vector<double> values) {
    if (values.empty()) return 0.0;
    std::nth_element(values.begin(), values.begin() + values.size() / 2, values.end());
    return values[values.size() / 2];
  };
  const Camera& first = sequence.front().camera;
  std::printf("rendered %d %dx%d view(s) '%s' of the %s (%zu of %zu capture cameras texturing) to %s/\n", written,
              first.width, first.height, view.c_str(), geometry.c_str(), used.size(), rig.cameras.size(),
              view_dir.c_str());
  std::printf("time per frame (median): texture setup %.1f ms, novel view %.1f ms\n", median(set_ms), median(render_ms));
  if (video) std::printf("video: %s (%d frames at %g fps)\n", video->path().c_str(), video->frames_written(), video_options.fps);
  if (!missing.empty()) {
    std::string list;
    for (int frame : missing) list += (list.empty() ? "" : " ") + std::to_string(frame);
    std::printf("missing %s meshes for %zu frame(s), not rendered: %s\n", geometry.c_str(), missing.size(), list.c_str());
  }
  return 0;
}

}  // namespace

CommandSpec MakeRenderCommand() {
  CommandSpec spec;
  spec.name = "render";
  spec.summary = "render novel views of a run's 3D video (projective texturing) to images and MP4";
  spec.usage = "[CAPTURE] --run RUN --out DIR [--path orbit|cameras:A,B,..|fixed:NAME|fixed:CALIB_DIR/NAME|bullet:FRAME] [options]";
  spec.description =
      "Textures the run's animated scan (RUN/scan/<frame>.ply; --geometry template for RUN/template/) from\n"
      "the capture's camera images: per-camera visibility from depth maps, unstructured-lumigraph weights\n"
      "over the best k cameras, feathering near silhouette edges and depth discontinuities, and the mesh's\n"
      "own colours where no camera sees the surface. Masks come from RUN/masks/ (else CAPTURE/masks/).\n"
      "Writes DIR/<view>/<frame:06d>.png (or .exr, linear) and with --mp4 DIR/<view>.mp4 (H.264).\n"
      "Paths: orbit (one turn around the actor over the frames), cameras:NAME,... (a smooth path through\n"
      "those input cameras), fixed:NAME or fixed:CALIB_DIR/NAME (a camera of the capture or of another\n"
      "intri.yml/extri.yml, e.g. a held-out camera), bullet:FRAME (frozen time, a sweep around the ring).\n"
      "--over-plate draws a capture camera's fixed view over its clean plate with the input cameras'\n"
      "colours matched to it (as `confluent evaluate` scores held-out views).\n"
      "Frames without geometry are skipped and listed. CAPTURE defaults to the one RUN/run.json names; the\n"
      "cameras the run held out never texture the view unless --texture-from-held-out is given.";
  spec.min_positionals = 0;
  spec.max_positionals = 1;
  spec.options = {
      {"run", "RUN", "the run folder (scan/, template/, masks/)", false, true},
      {"out", "DIR", "output folder (e.g. RUN/renders)", false, true},
      {"path", "PATH", "orbit (default), cameras:A,B,..., fixed:NAME, fixed:CALIB_DIR/NAME or bullet:FRAME"},
      {"geometry", "scan|template", "which meshes to texture (default scan)"},
      {"exclude-camera", "NAME", "do not texture from this camera (the run's held-out cameras never do)", true},
      {"texture-from-held-out", "", "texture from the cameras the run held out too (prints a warning)"},
      {"frames", "A:B", "frame range, B exclusive (default: all frames)"},
      {"format", "png|exr", "image format (default png)"},
      {"mp4", "", "also write DIR/<view>.mp4 (needs ffmpeg)"},
      {"fps", "F", "video frame rate (default: the run's, else 25)"},
      {"width", "W", "output width (with --height; default: the cameras' size)"},
      {"height", "H", "output height"},
      {"path-frames", "N", "cameras on the path (default: one per frame; bullet time: 60)"},
      {"over-plate", "", "with --path fixed:NAME: draw over that camera's clean plate, input colours matched to it"},
      {"edge-softness", "PX", "with --over-plate: Gaussian sigma of the outline's matting (default 0.5; 0 = binary)"},
  };
  for (const OptionSpec& option : TextureOptionSpecs()) spec.options.push_back(option);
  spec.run = RunRender;
  return spec;
}

}  // namespace confluent::app
