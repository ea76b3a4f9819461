// The render stage of `confluent run`: the frames of the 3D video (pipeline/orbit_frames.h) still
// missing, then the video over all of them.

#include <filesystem>

#include "pipeline/orbit_frames.h"
#include "core/image_io.h"
#include "core/mesh_io.h"
#include "core/parallel.h"
#include "core/video_writer.h"
#include "render/camera_path.h"

namespace confluent {
namespace fs = std::filesystem;

namespace {

// A point the orbit looks at: the centre of the used cameras' ring, at mid-body height.
Eigen::Vector3d RingCentre(const std::vector<Camera>& cameras) {
  Eigen::Vector3d sum = Eigen::Vector3d::Zero();
  for (const Camera& camera : cameras) sum += camera.center_in_world();
  Eigen::Vector3d centre = sum / std::max<std::size_t>(1, cameras.size());
  centre.z() = 0.95;
  return centre;
}

}  // namespace


OrbitFrames::OrbitFrames(const RunInputs& inputs, const RenderStageOptions& options, const Mesh& topology)
    : inputs_(inputs), options_(options), used_(inputs.cameras.used()),
      used_cameras_(inputs.cameras.UsedCameras(inputs.capture->rig())) {
  OrbitPathOptions orbit = OrbitAroundCameras(used_cameras_, RingCentre(used_cameras_));
  orbit.num_frames = inputs.capture->num_frames();  // the whole capture is one turn, so shards agree
  orbit.width_px = options.width;
  orbit.height_px = options.height;
  path_ = OrbitPath(orbit);
  texturer_ = std::make_unique<ProjectiveTexturer>(topology);
  fs::create_directories(inputs.folder.Path("renders/" + options.view));
}

OrbitFrames::~OrbitFrames() = default;

void OrbitFrames::Render(int frame, const RowMatrixX3d& vertices, const std::vector<Image>& images,
                         const std::vector<Image>& masks, TimingLog* timings) {
  const double render_start = NowSeconds();
  texturer_->SetFrame(vertices, used_cameras_, images, masks);
  const RenderResult result = texturer_->Render(path_[frame]);
  const double write_start = NowSeconds();
  WriteImage(inputs_.folder.RenderPath(options_.view, frame), result.color);
  timings->Add("render", frame, write_start - render_start);
  timings->Add("render_write", frame, NowSeconds() - write_start);
}

StageReport RunRenderStage(const RunInputs& inputs, const RenderStageOptions& options, const ProgressCallback& progress,
                           TimingLog* timings) {
  StageReport report("render");
  const double start = NowSeconds();
  const RunFolder& folder = inputs.folder;
  const Capture& capture = *inputs.capture;
  const bool use_scan = inputs.scan != nullptr;
  auto geometry_path = [&](int frame) { return use_scan ? folder.ScanPath(frame) : folder.TemplatePath(frame); };

  std::vector<int> todo;
  for (int frame = inputs.frames.first; frame < inputs.frames.end; ++frame) {
    if (fs::exists(folder.RenderPath(options.view, frame))) {
      ++report.skipped;
    } else if (!fs::exists(geometry_path(frame))) {
      report.notes.push_back("missing geometry, frame not rendered: " + geometry_path(frame));
    } else {
      todo.push_back(frame);
    }
  }
  if (!todo.empty()) {
    // Topology and colours: the scan's own, or the posed template's.
    OrbitFrames frames(inputs, options, use_scan ? *inputs.scan : ReadMesh(geometry_path(todo.front())));
    const std::vector<int>& used = frames.used();
    int done = 0;
    for (int frame : todo) {
      const double frame_start = NowSeconds();
      const Mesh mesh = ReadMesh(geometry_path(frame));
      const std::vector<Image> images = capture.ReadFrames(used, frame, inputs.threads);
      std::vector<Image> masks(used.size());
      ParallelFor(static_cast<int>(used.size()), inputs.threads, [&](int i) {
        const std::string mask_path = RunMaskPath(inputs, used[i], frame);
        if (fs::exists(mask_path)) masks[i] = ReadMaskFile(mask_path);
      });
      timings->Add("render_read", frame, NowSeconds() - frame_start);
      frames.Render(frame, mesh.vertices, images, masks, timings);
      ++report.computed;
      ReportProgress(progress, "render", ++done, todo.size(), "frame " + std::to_string(frame));
    }
    timings->Save();
  }
  // The video over every rendered frame of the capture, in order.
  std::vector<std::string> frames;
  for (int frame = 0; frame < capture.num_frames(); ++frame)
    if (fs::exists(folder.RenderPath(options.view, frame))) frames.push_back(folder.RenderPath(options.view, frame));
  const std::string video = folder.VideoPath(options.view);
  if (static_cast<int>(frames.size()) < capture.num_frames()) {
    report.notes.push_back(std::to_string(capture.num_frames() - frames.size()) +
                           " frame(s) of the capture not rendered yet: " + video + " is written once all are");
  } else if (report.computed > 0 || !fs::exists(video)) {
    VideoWriterOptions video_options;
    video_options.fps = inputs.fps;
    if (!FfmpegAvailable(video_options)) {
      report.notes.push_back("ffmpeg not found: no " + video + " (the PNG frames are written)");
    } else {
      const double video_start = NowSeconds();
      VideoWriter writer(video, options.width, options.height, video_options);
      for (const std::string& file : frames) writer.Write(ReadImage(file));
      writer.Close();
      timings->Add("video", -1, NowSeconds() - video_start);
      report.notes.push_back("video: " + video + " (" + std::to_string(frames.size()) + " frames)");
    }
  }
  timings->Save();
  report.seconds = NowSeconds() - start;
  return report;
}

}  // namespace confluent
