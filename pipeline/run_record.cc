#include "pipeline/run_record.h"

#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <fstream>

#include "core/error.h"
#include "core/mesh_io.h"
#include "core/mesh_validation.h"
#include "pipeline/run_manifest.h"

namespace confluent {
namespace fs = std::filesystem;

namespace {

// FNV-1a 64-bit checksum of a file's bytes, as 16 hex digits ("" when the path is empty).
std::string FileChecksum(const std::string& path) {
  if (path.empty()) return "";
  std::ifstream in(path, std::ios::binary);
  if (!in) throw InputError(path, "cannot be read");
  std::uint64_t hash = 1469598103934665603ull;
  char buffer[1 << 16];
  while (in.read(buffer, sizeof buffer) || in.gcount() > 0) {
    for (std::streamsize i = 0; i < in.gcount(); ++i) hash = (hash ^ static_cast<unsigned char>(buffer[i])) * 1099511628211ull;
    if (!in) break;
  }
  char text[20];
  std::snprintf(text, sizeof text, "%016llx", static_cast<unsigned long long>(hash));
  return text;
}

// The identity of the inputs: a resumed run must have the same.
nlohmann::json InputChecksums(const Capture& capture, const RunInputs& inputs) {
  nlohmann::json json;
  json["intri.yml"] = FileChecksum((fs::path(capture.root()) / "intri.yml").string());
  json["extri.yml"] = FileChecksum((fs::path(capture.root()) / "extri.yml").string());
  json["scan"] = FileChecksum(inputs.scan_path);
  json["correspondences"] = FileChecksum(inputs.correspondences_path);
  json["frames"] = capture.num_frames();
  json["cameras"] = capture.rig().names();
  return json;
}

}  // namespace

void RecordRun(const RunInputs& inputs, const nlohmann::json& options, const std::string& version) {
  const nlohmann::json checksums = InputChecksums(*inputs.capture, inputs);
  const std::string path = RunManifestPath(inputs.folder.root);
  if (fs::exists(path)) {
    const RunManifest previous = ReadRunManifest(path);
    if (previous.input_checksums != checksums)
      throw InputError(path, "this run folder was made from other inputs (calibration, scan or correspondences differ); "
                             "use a new --out folder");
    if (previous.held_out_cameras != inputs.cameras.held_out_names())
      throw InputError(path, "this run folder was made with other --exclude-camera names; use a new --out folder");
    if (previous.fps > 0 && previous.fps != inputs.fps)
      throw InputError(path, "this run folder was made at " + std::to_string(previous.fps) +
                                 " fps; give the same --fps or use a new --out folder");
    return;
  }
  RunManifest manifest;
  manifest.version = version;
  manifest.capture = fs::absolute(inputs.capture->root()).string();
  manifest.scan = inputs.scan_path.empty() ? "" : fs::absolute(inputs.scan_path).string();
  if (!inputs.correspondences_path.empty()) manifest.correspondences = fs::absolute(inputs.correspondences_path).string();
  if (!inputs.masks_dir.empty()) manifest.masks = fs::absolute(inputs.masks_dir).string();
  manifest.held_out_cameras = inputs.cameras.held_out_names();
  manifest.frames = inputs.frames;
  manifest.fps = inputs.fps;
  manifest.options = options;
  manifest.input_checksums = checksums;
  WriteRunManifest(path, manifest);
}

Mesh ReadCheckedScan(const std::string& path, bool allow_open) {
  if (!fs::exists(path)) throw InputError(path, "scan not found");
  Mesh scan = ReadMesh(path);
  const MeshReport report = ValidateMesh(scan);
  if (report.num_faces == 0) throw InputError(path, "the scan has no faces");
  if (!report.invalid_vertices.empty())
    throw InputError(path, std::to_string(report.invalid_vertices.size()) + " vertices with NaN or infinite coordinates");
  if (!report.is_manifold())
    throw InputError(path, "the scan is not manifold (" + std::to_string(report.non_manifold_edges.size()) +
                               " edges shared by more than 2 faces, " + std::to_string(report.non_manifold_vertices.size()) +
                               " non-manifold vertices); repair it, e.g. in MeshLab");
  if (!allow_open && report.num_boundary_edges > 0)
    throw InputError(path, "the scan is not watertight (" + std::to_string(report.num_boundary_edges) + " boundary edges in " +
                               std::to_string(report.num_boundary_loops) +
                               " holes); close the holes, or pass --allow-open-scan to animate it anyway");
  return scan;
}

}  // namespace confluent
