#include "studio/synth.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <condition_variable>
#include <cstdio>
#include <deque>
#include <exception>
#include <filesystem>
#include <functional>
#include <memory>
#include <mutex>
#include <random>
#include <sstream>
#include <thread>

#include "calib/easymocap_io.h"
#include "core/atomic_file.h"
#include "core/error.h"
#include "core/image_io.h"
#include "core/mesh_io.h"
#include "render/renderer.h"
#include "studio/skin_io.h"

namespace confluent {
namespace {

namespace fs = std::filesystem;

// A small fixed pool of worker threads with a bounded queue. The first exception thrown by a
// task is rethrown by Wait().
class WorkQueue {
 public:
  WorkQueue(int threads, std::size_t capacity) : capacity_(capacity) {
    for (int t = 0; t < std::max(1, threads); ++t) workers_.emplace_back([this] { Loop(); });
  }
  ~WorkQueue() {
    {
      std::lock_guard<std::mutex> lock(mutex_);
      stop_ = true;
    }
    ready_.notify_all();
    for (auto& worker : workers_) worker.join();
  }
  void Push(std::function<void()> task) {
    std::unique_lock<std::mutex> lock(mutex_);
    space_.wait(lock, [this] { return tasks_.size() < capacity_; });
    tasks_.push_back(std::move(task));
    ready_.notify_one();
  }
  // Waits until every task has run; rethrows the first failure.
  void Wait() {
    std::unique_lock<std::mutex> lock(mutex_);
    idle_.wait(lock, [this] { return tasks_.empty() && running_ == 0; });
    if (error_) std::rethrow_exception(error_);
  }

 private:
  void Loop() {
    for (;;) {
      std::function<void()> task;
      {
        std::unique_lock<std::mutex> lock(mutex_);
        ready_.wait(lock, [this] { return stop_ || !tasks_.empty(); });
        if (tasks_.empty()) return;
        task = std::move(tasks_.front());
        tasks_.pop_front();
        ++running_;
        space_.notify_one();
      }
      try {
        if (!failed()) task();
      } catch (...) {
        std::lock_guard<std::mutex> lock(mutex_);
        if (!error_) error_ = std::current_exception();
      }
      std::lock_guard<std::mutex> lock(mutex_);
      --running_;
      if (tasks_.empty() && running_ == 0) idle_.notify_all();
    }
  }
  bool failed() {
    std::lock_guard<std::mutex> lock(mutex_);
    return static_cast<bool>(error_);
  }

  std::size_t capacity_;
  std::vector<std::thread> workers_;
  std::deque<std::function<void()>> tasks_;
  std::mutex mutex_;
  std::condition_variable ready_, space_, idle_;
  int running_ = 0;
  bool stop_ = false;
  std::exception_ptr error_;
};

// Sensor model of one camera: gain per channel and additive Gaussian noise (8-bit levels).
struct Sensor {
  Eigen::Vector3f gain = Eigen::Vector3f::Ones();
  float noise_sigma = 0.0f;
};

// Applies gain and noise in place. `stream` picks the noise realisation (deterministic).
void ApplySensor(const Sensor& sensor, const std::vector<float>& noise_table, std::uint64_t stream, Image* image) {
  std::uint64_t state = stream * 0x9E3779B97F4A7C15ull + 0x632BE59BD9B4E019ull;
  const std::size_t mask = noise_table.size() - 1;
  std::uint8_t* p = image->data.data();
  const std::size_t pixels = static_cast<std::size_t>(image->width) * image->height;
  for (std::size_t i = 0; i < pixels; ++i) {
    state ^= state << 13;
    state ^= state >> 7;
    state ^= state << 17;
    for (int c = 0; c < 3; ++c) {
      const float noise = sensor.noise_sigma * noise_table[(state >> (c * 20)) & mask];
      const float v = p[3 * i + c] * sensor.gain[c] + noise + 0.5f;
      p[3 * i + c] = static_cast<std::uint8_t>(std::clamp(v, 0.0f, 255.0f));
    }
  }
}

std::string FrameName(int frame) {
  char name[32];
  std::snprintf(name, sizeof(name), "%06d", frame);
  return name;
}

std::string JsonNumber(double v) {
  char text[32];
  std::snprintf(text, sizeof(text), "%.6g", v);
  return text;
}

std::string JsonVector(const Eigen::Vector3d& v) {
  return "[" + JsonNumber(v.x()) + ", " + JsonNumber(v.y()) + ", " + JsonNumber(v.z()) + "]";
}

std::string SkeletonJson(const Skeleton& skeleton, const StudioActor& actor) {
  std::ostringstream out;
  const std::vector<Eigen::Vector3d> rest = skeleton.RestPositions();
  out << "{\n  \"frame\": \"world Z up, metres; the actor faces +y at rest\",\n  \"joints\": [\n";
  for (int j = 0; j < skeleton.size(); ++j)
    out << "    {\"name\": \"" << skeleton.joints[j].name << "\", \"parent\": " << skeleton.joints[j].parent
        << ", \"offset_in_parent\": " << JsonVector(skeleton.joints[j].offset_in_parent)
        << ", \"rest_position\": " << JsonVector(rest[j]) << "}" << (j + 1 < skeleton.size() ? "," : "") << "\n";
  out << "  ],\n  \"segments\": [\n";
  for (int s = 0; s < kNumBodySegments; ++s)
    out << "    {\"name\": \"" << BodySegmentName(s) << "\", \"label\": " << s << ", \"joint\": \""
        << skeleton.joints[actor.segment_joint[s]].name << "\"}" << (s + 1 < kNumBodySegments ? "," : "") << "\n";
  out << "  ]\n}\n";
  return out.str();
}

// Lists the mesh files of a sequence folder in name order.
std::vector<std::string> SequenceFiles(const std::string& dir) {
  std::error_code error;
  if (!fs::is_directory(dir, error)) throw InputError(dir, "actor sequence: not a folder");
  std::vector<std::string> files;
  for (const auto& entry : fs::directory_iterator(dir)) {
    std::string ext = entry.path().extension().string();
    std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return std::tolower(c); });
    if (entry.is_regular_file() && (ext == ".obj" || ext == ".ply")) files.push_back(entry.path().string());
  }
  std::sort(files.begin(), files.end());
  if (files.empty()) throw InputError(dir, "actor sequence: no .obj or .ply files");
  return files;
}

// Procedural colours for a mesh without any: bands by height with a check pattern and noise.
void ColorSequenceMesh(Mesh* mesh, unsigned seed) {
  const double zmin = mesh->vertices.col(2).minCoeff(), zmax = mesh->vertices.col(2).maxCoeff();
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> jitter(0.93, 1.07);
  mesh->colors.resize(mesh->num_vertices(), 3);
  for (int v = 0; v < mesh->num_vertices(); ++v) {
    const Eigen::Vector3d p = mesh->vertices.row(v).transpose();
    const double h = (p.z() - zmin) / std::max(1e-9, zmax - zmin);
    Eigen::Vector3d c;
    if (h < 0.04) c = {0.05, 0.05, 0.06};
    else if (h < 0.30) c = {0.60, 0.42, 0.32};
    else if (h < 0.55) c = {0.55, 0.06, 0.08};
    else if (h < 0.85) c = {0.08, 0.20, 0.55};
    else c = {0.60, 0.42, 0.32};
    if (h >= 0.30 && h < 0.85) {
      const bool check = (static_cast<int>(std::floor(p.x() / 0.05)) + static_cast<int>(std::floor(p.y() / 0.05)) +
                          static_cast<int>(std::floor(p.z() / 0.05))) & 1;
      if (check) c *= 0.6;
    }
    mesh->colors.row(v) = (c * jitter(rng)).cwiseMin(1.0).cast<float>().transpose();
  }
}

// Source of the per-frame actor geometry.
class ActorSource {
 public:
  virtual ~ActorSource() = default;
  virtual const Mesh& rest_mesh() const = 0;
  virtual RowMatrixX3d FrameVertices(int frame) = 0;
  virtual int num_frames() const = 0;
};

// A skinned actor (the procedural one, or a rigged mesh) performing the studio's motion.
class SkinnedActor : public ActorSource {
 public:
  SkinnedActor(StudioActor actor, const StudioSynthOptions& options)
      : actor_(std::move(actor)), method_(options.skinning) {
    poses_ = StudioPerformance(actor_.skeleton, options.motion);
    if (!options.motion.bvh_path.empty()) {
      // A BVH performance may travel: centre it in the ring, or say that it does not fit.
      const double height = actor_.mesh.vertices.col(2).maxCoeff() - actor_.mesh.vertices.col(2).minCoeff();
      const double radius = CaptureVolumeRadius(MakeStudioRig(options.rig), options.rig.num_ring_cameras,
                                                options.rig.target_in_world, height);
      KeepPerformanceInVolume(&poses_, actor_.skeleton, options.rig.target_in_world.head<2>(), radius,
                              options.motion.fps, options.motion.bvh_in_place, options.motion.bvh_path);
    }
  }
  const Mesh& rest_mesh() const override { return actor_.mesh; }
  RowMatrixX3d FrameVertices(int frame) override {
    return SkinVertices(actor_.mesh.vertices, actor_.weights, actor_.skeleton, poses_[frame], method_);
  }
  int num_frames() const override { return static_cast<int>(poses_.size()); }
  const StudioActor& actor() const { return actor_; }
  const std::vector<Pose>& poses() const { return poses_; }

 private:
  StudioActor actor_;
  SkinningMethod method_;
  std::vector<Pose> poses_;
};

class SequenceActor : public ActorSource {
 public:
  SequenceActor(const StudioSynthOptions& options) : up_(options.sequence_up_axis) {
    files_ = SequenceFiles(options.actor_sequence_dir);
    if (static_cast<int>(files_.size()) > options.motion.num_frames) files_.resize(options.motion.num_frames);
    rest_ = ReadMesh(files_[0]);
    ToWorld(&rest_.vertices);
    const Eigen::Vector3d lo = rest_.vertices.colwise().minCoeff().transpose();
    const Eigen::Vector3d hi = rest_.vertices.colwise().maxCoeff().transpose();
    shift_ = Eigen::Vector3d(-(lo.x() + hi.x()) / 2, -(lo.y() + hi.y()) / 2, -lo.z());
    rest_.vertices.rowwise() += shift_.transpose();
    if (!rest_.has_colors()) ColorSequenceMesh(&rest_, options.actor.seed);
    rest_.uvs.resize(0, 2);
    rest_.face_uvs.resize(0, 3);
    rest_.texture_path.clear();
  }
  const Mesh& rest_mesh() const override { return rest_; }
  RowMatrixX3d FrameVertices(int frame) override {
    Mesh mesh = ReadMesh(files_[frame]);
    if (mesh.num_vertices() != rest_.num_vertices() || mesh.num_faces() != rest_.num_faces())
      throw InputError(files_[frame], "actor sequence: " + std::to_string(mesh.num_vertices()) + " vertices and " +
                                          std::to_string(mesh.num_faces()) + " faces, but the first frame has " +
                                          std::to_string(rest_.num_vertices()) + " and " +
                                          std::to_string(rest_.num_faces()) + " (the topology must be fixed)");
    ToWorld(&mesh.vertices);
    mesh.vertices.rowwise() += shift_.transpose();
    return mesh.vertices;
  }
  int num_frames() const override { return static_cast<int>(files_.size()); }

 private:
  void ToWorld(RowMatrixX3d* vertices) const {
    if (up_ != 'y') return;
    // Y up -> Z up: rotate +90 degrees about x: (x, y, z) -> (x, -z, y).
    for (int v = 0; v < vertices->rows(); ++v) {
      const double y = (*vertices)(v, 1), z = (*vertices)(v, 2);
      (*vertices)(v, 1) = -z;
      (*vertices)(v, 2) = y;
    }
  }
  char up_;
  std::vector<std::string> files_;
  Mesh rest_;
  Eigen::Vector3d shift_ = Eigen::Vector3d::Zero();
};

std::string OptionsJson(const StudioSynthOptions& o, const StudioSynthSummary& s, const std::string& gl_renderer) {
  std::ostringstream out;
  out << "{\n  \"capture\": \"" << s.capture_dir << "\",\n  \"frames\": " << s.num_frames
      << ",\n  \"fps\": " << JsonNumber(o.motion.fps) << ",\n  \"cameras\": " << s.num_cameras
      << ",\n  \"ring_cameras\": " << o.rig.num_ring_cameras << ",\n  \"heldout_cameras\": " << o.rig.num_heldout_cameras
      << ",\n  \"width\": " << o.rig.width_px << ",\n  \"height\": " << o.rig.height_px
      << ",\n  \"actor\": \""
      << (!o.actor_sequence_dir.empty() ? o.actor_sequence_dir
                                        : o.actor_mesh_path.empty() ? std::string("procedural") : o.actor_mesh_path)
      << "\""
      << ",\n  \"motion\": \"" << (o.motion.bvh_path.empty() ? "default" : o.motion.bvh_path) << "\""
      << ",\n  \"bvh_start_s\": " << JsonNumber(o.motion.bvh_start_s)
      << ",\n  \"bvh_in_place\": " << (o.motion.bvh_in_place ? "true" : "false")
      << ",\n  \"scan_frame\": " << o.scan_frame
      << ",\n  \"actor_vertices\": " << s.num_vertices << ",\n  \"actor_triangles\": " << s.num_triangles
      << ",\n  \"skinning\": \"" << (o.skinning == SkinningMethod::kLinear ? "linear" : "dual_quaternion") << "\""
      << ",\n  \"green_screen\": " << (o.scene.green_screen ? "true" : "false")
      << ",\n  \"noise_sigma\": " << JsonNumber(o.noise_sigma) << ",\n  \"gain_spread\": " << JsonNumber(o.gain_spread)
      << ",\n  \"seed\": " << o.seed << ",\n  \"renderer\": \"" << gl_renderer << "\",\n  \"seconds\": "
      << JsonNumber(s.seconds) << "\n}\n";
  return out.str();
}

}  // namespace

void StudioSynthOptions::Check() const {
  const std::string owner = "StudioSynthOptions.";
  if (capture_dir.empty()) throw UsageError(owner + "capture_dir = '': must name the capture folder to write (--out)");
  if (actor_sequence_dir.empty() && actor_mesh_path.empty()) actor.Check();
  if (actor_mesh_path.empty() != actor_skin_path.empty())
    throw UsageError(owner + "actor_mesh_path = '" + actor_mesh_path + "' and " + owner + "actor_skin_path = '" +
                     actor_skin_path + "': must be given together (--actor-mesh and --actor-skin: a rigged actor "
                     "needs both)");
  if (!actor_mesh_path.empty() && !actor_sequence_dir.empty())
    throw UsageError(owner + "actor_mesh_path = '" + actor_mesh_path + "' and " + owner + "actor_sequence_dir = '" +
                     actor_sequence_dir + "': must not both be given (--actor-mesh and --actor-sequence are "
                     "alternatives)");
  motion.Check();
  rig.Check();
  scene.Check();
  shadow.Check();
  if (sequence_up_axis != 'y' && sequence_up_axis != 'z')
    throw UsageError(owner + "sequence_up_axis = '" + sequence_up_axis + "': must be 'y' or 'z' (--up)");
  RequireOption(noise_sigma >= 0.0 && noise_sigma <= 50.0, owner + "noise_sigma", noise_sigma,
                "in [0, 50] grey levels (--noise)");
  RequireOption(gain_spread >= 0.0 && gain_spread < 0.5, owner + "gain_spread", gain_spread, "in [0, 0.5)");
  RequireOption(threads >= 1 && threads <= 64, owner + "threads", threads, "in [1, 64]");
  RequireOption(scan_frame >= -1, owner + "scan_frame", scan_frame, ">= -1 (-1: the rest mesh; --scan-frame)");
}

std::string DefaultGroundTruthDir(const std::string& capture_dir) {
  fs::path path = fs::path(capture_dir).lexically_normal();
  if (path.filename().empty()) path = path.parent_path();
  return (path.parent_path() / (path.filename().string() + "_gt")).string();
}

StudioSynthSummary SynthesizeCapture(const StudioSynthOptions& options, const ProgressCallback& progress) {
  options.Check();
  const auto start = std::chrono::steady_clock::now();
  StudioSynthSummary summary;
  summary.capture_dir = options.capture_dir;
  summary.ground_truth_dir = options.ground_truth_dir.empty() ? DefaultGroundTruthDir(options.capture_dir)
                                                              : options.ground_truth_dir;
  const std::string& capture = summary.capture_dir;
  const std::string& gt = summary.ground_truth_dir;

  ReportProgress(progress, "actor", 0, 1);
  std::unique_ptr<ActorSource> source;
  SkinnedActor* procedural = nullptr;
  if (options.actor_sequence_dir.empty()) {
    auto actor = std::make_unique<SkinnedActor>(
        options.actor_mesh_path.empty() ? BuildStudioActor(options.actor)
                                        : ReadRiggedActor(options.actor_mesh_path, options.actor_skin_path),
        options);
    procedural = actor.get();
    source = std::move(actor);
  } else {
    source = std::make_unique<SequenceActor>(options);
  }
  ReportProgress(progress, "actor", 1, 1);
  const Mesh& rest = source->rest_mesh();
  summary.num_frames = source->num_frames();
  summary.num_vertices = rest.num_vertices();
  summary.num_triangles = rest.num_faces();
  if (options.scan_frame >= summary.num_frames)
    throw UsageError("StudioSynthOptions.scan_frame = " + std::to_string(options.scan_frame) +
                     ": must be below the number of frames, " + std::to_string(summary.num_frames) + " (--scan-frame)");

  const Rig rig = MakeStudioRig(options.rig);
  summary.num_cameras = rig.size();
  WriteEasyMocap(rig, capture);
  WriteEasyMocap(rig, gt);
  Mesh scan = rest;
  if (options.scan_frame >= 0) scan.vertices = source->FrameVertices(options.scan_frame);
  WriteMesh(capture + "/scan.ply", scan);
  WriteMesh(gt + "/scan.ply", scan);
  if (procedural) {
    WriteTextFile(gt + "/skeleton.json", SkeletonJson(procedural->actor().skeleton, procedural->actor()));
    WriteTextFile(gt + "/skin.json", StudioSkinJson(procedural->actor()));
  }

  MeshRenderer renderer;
  const std::vector<TexturedMesh> scene = MakeStudioScene(options.scene);
  std::vector<int> scene_handles;
  for (std::size_t i = 0; i < scene.size(); ++i)
    scene_handles.push_back(renderer.AddMesh(scene[i].mesh, "studio scene " + std::to_string(i), scene[i].texture));
  Mesh actor_mesh = rest;
  const int actor_handle = renderer.AddMesh(actor_mesh, "actor");

  RenderRequest background_request;
  background_request.color = true;
  background_request.depth = true;
  background_request.meshes = scene_handles;
  background_request.shading.light_direction_in_world = Eigen::Vector3d(0.1, 0.25, 1.0);
  background_request.shading.ambient = 0.6;
  background_request.shading.diffuse = 0.4;
  background_request.shading.background = Eigen::Vector3d(0.05, 0.05, 0.05);
  RenderRequest actor_request;
  actor_request.color = true;
  actor_request.silhouette = true;
  actor_request.meshes = {actor_handle};
  actor_request.shading.light_direction_in_world = Eigen::Vector3d(0.15, 0.3, 1.0);
  actor_request.shading.ambient = 0.42;
  actor_request.shading.diffuse = 0.62;

  // Sensor model per camera and the shared noise table.
  std::mt19937 rng(options.seed * 2654435761u + 17u);
  std::normal_distribution<float> normal(0.0f, 1.0f);
  std::vector<float> noise_table(1 << 20);
  for (float& v : noise_table) v = normal(rng);
  std::uniform_real_distribution<float> spread(-1.0f, 1.0f);
  std::vector<Sensor> sensors(rig.size());
  for (auto& sensor : sensors) {
    const float gain = 1.0f + static_cast<float>(options.gain_spread) * spread(rng);
    for (int c = 0; c < 3; ++c) sensor.gain[c] = gain * (1.0f + 0.02f * spread(rng));
    sensor.noise_sigma = static_cast<float>(options.noise_sigma);
  }

  WorkQueue queue(options.threads, static_cast<std::size_t>(2 * rig.size()));
  // Clean plates, and for every pixel the floor point it sees (for the shadow), or NaN.
  std::vector<Image> plates(rig.size());
  std::vector<std::vector<Eigen::Vector2f>> floor_points(rig.size());
  for (int c = 0; c < rig.size(); ++c) {
    const Camera& camera = rig.cameras[c];
    RenderResult result = renderer.Render(camera, background_request);
    plates[c] = std::move(result.color);
    auto& points = floor_points[c];
    points.assign(static_cast<std::size_t>(camera.width) * camera.height, Eigen::Vector2f::Constant(NAN));
    for (int y = 0; y < camera.height; ++y)
      for (int x = 0; x < camera.width; ++x) {
        const float depth = result.depth.at<float>(x, y);
        if (depth <= 0.0f) continue;
        const Eigen::Vector3d p = camera.Unproject(Eigen::Vector2d(x, y), depth);
        if (std::abs(p.z()) < 0.01) points[static_cast<std::size_t>(y) * camera.width + x] = p.head<2>().cast<float>();
      }
    Image plate = plates[c];
    const std::string path = capture + "/background/" + camera.name + ".png";
    queue.Push([plate = std::move(plate), path, sensor = sensors[c], &noise_table, c]() mutable {
      ApplySensor(sensor, noise_table, 0x5eedull * 1000003ull + c, &plate);
      WriteImage(path, plate);
    });
  }

  std::ostringstream joints_json;
  if (procedural) {
    const Skeleton& skeleton = procedural->actor().skeleton;
    joints_json << "{\n  \"fps\": " << JsonNumber(options.motion.fps) << ",\n  \"joint_names\": [";
    for (int j = 0; j < skeleton.size(); ++j) joints_json << (j ? ", " : "") << "\"" << skeleton.joints[j].name << "\"";
    joints_json << "],\n  \"parents\": [";
    for (int j = 0; j < skeleton.size(); ++j) joints_json << (j ? ", " : "") << skeleton.joints[j].parent;
    joints_json << "],\n  \"frames\": [\n";
  }
  const int total = summary.num_frames;
  for (int frame = 0; frame < total; ++frame) {
    ReportProgress(progress, "synth", frame, total, "frame " + std::to_string(frame));
    const RowMatrixX3d vertices = source->FrameVertices(frame);
    renderer.UpdateVertices(actor_handle, vertices);
    const auto shadow = std::make_shared<FloorShadow>(ComputeFloorShadow(vertices, options.shadow));
    for (int c = 0; c < rig.size(); ++c) {
      const Camera& camera = rig.cameras[c];
      auto result = std::make_shared<RenderResult>(renderer.Render(camera, actor_request));
      const std::string name = FrameName(frame);
      queue.Push([=, &plates, &floor_points, &noise_table, &sensors]() {
        const Image& plate = plates[c];
        Image image = plate;
        const auto& points = floor_points[c];
        const std::uint8_t* actor = result->color.data.data();
        const std::uint8_t* mask = result->silhouette.data.data();
        std::uint8_t* out = image.data.data();
        const std::size_t pixels = static_cast<std::size_t>(image.width) * image.height;
        for (std::size_t i = 0; i < pixels; ++i) {
          if (mask[i]) {
            out[3 * i] = actor[3 * i];
            out[3 * i + 1] = actor[3 * i + 1];
            out[3 * i + 2] = actor[3 * i + 2];
          } else if (!std::isnan(points[i].x())) {
            const float f = shadow->At(points[i].x(), points[i].y());
            if (f < 1.0f)
              for (int k = 0; k < 3; ++k) out[3 * i + k] = static_cast<std::uint8_t>(out[3 * i + k] * f + 0.5f);
          }
        }
        ApplySensor(sensors[c], noise_table, (static_cast<std::uint64_t>(frame) + 1) * 7919ull + c, &image);
        WriteImage(capture + "/images/" + camera.name + "/" + name + ".png", image);
        WriteImage(gt + "/masks/" + camera.name + "/" + name + ".png", result->silhouette);
      });
    }
    Mesh posed;
    posed.vertices = vertices;
    posed.faces = rest.faces;
    const std::string mesh_path = gt + "/meshes/" + FrameName(frame) + ".ply";
    queue.Push([posed = std::move(posed), mesh_path]() { WriteMesh(mesh_path, posed); });
    if (procedural) {
      const Skeleton& skeleton = procedural->actor().skeleton;
      const Pose& pose = procedural->poses()[frame];
      const std::vector<Eigen::Vector3d> positions = JointPositions(skeleton, pose);
      joints_json << "    {\"frame\": " << frame << ", \"positions\": [";
      for (std::size_t j = 0; j < positions.size(); ++j) joints_json << (j ? ", " : "") << JsonVector(positions[j]);
      joints_json << "],\n     \"root_translation\": " << JsonVector(pose.root_translation) << ", \"local_rotations_wxyz\": [";
      for (std::size_t j = 0; j < pose.local_rotations.size(); ++j) {
        const auto& q = pose.local_rotations[j];
        joints_json << (j ? ", " : "") << "[" << JsonNumber(q.w()) << ", " << JsonNumber(q.x()) << ", "
                    << JsonNumber(q.y()) << ", " << JsonNumber(q.z()) << "]";
      }
      joints_json << "]}" << (frame + 1 < total ? "," : "") << "\n";
    }
  }
  queue.Wait();
  if (procedural) {
    joints_json << "  ]\n}\n";
    WriteTextFile(gt + "/joints.json", joints_json.str());
  }
  ReportProgress(progress, "synth", total, total);
  summary.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  WriteTextFile(gt + "/synth.json", OptionsJson(options, summary, renderer.context_info().gl_renderer));
  return summary;
}

}  // namespace confluent
