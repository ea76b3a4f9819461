// confluent animate: Confluent Motion, a scan animated by a template mesh sequence
// (deform/confluent_motion.h).

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <set>
#include <string>
#include <vector>

#include "app/commands.h"
#include "core/error.h"
#include "core/mesh_io.h"
#include "deform/confluent_motion.h"
#include "deform/correspondences.h"
#include "deform/point_cache.h"

namespace confluent::app {
namespace {

std::string Lower(std::string text) {
  std::transform(text.begin(), text.end(), text.begin(), [](unsigned char c) { return std::tolower(c); });
  return text;
}

// The .obj/.ply files of `dir`, in name order.
std::vector<std::string> SequenceFiles(const std::string& dir) {
  std::error_code error;
  if (!std::filesystem::is_directory(dir, error)) throw InputError(dir, "not a folder");
  std::vector<std::string> files;
  for (const auto& entry : std::filesystem::directory_iterator(dir, error)) {
    const std::string extension = Lower(entry.path().extension().string());
    if (entry.is_regular_file() && (extension == ".obj" || extension == ".ply")) files.push_back(entry.path().string());
  }
  if (error) throw InputError(dir, "cannot list the folder: " + error.message());
  std::sort(files.begin(), files.end());
  if (files.empty()) throw InputError(dir, "no .obj or .ply meshes in the template sequence folder");
  return files;
}

int RunAnimate(const ParsedArgs& args, const Context& context) {
  const std::string scan_path = args.get("scan");
  const std::string correspondences_path = args.get("correspondences");
  const std::string sequence_dir = args.get("template-sequence");
  const std::string out_dir = args.get("out");
  const std::string format = Lower(args.get("format", "ply"));
  if (format != "ply" && format != "obj") throw UsageError("--format: expected ply or obj, got '" + format + "'");
  const std::vector<std::string> frames = SequenceFiles(sequence_dir);
  const int reference_frame = args.get_int("reference-frame", 0);
  if (reference_frame < 0 || reference_frame >= static_cast<int>(frames.size()))
    throw UsageError("--reference-frame: must be in [0, " + std::to_string(frames.size() - 1) + "], got " +
                     std::to_string(reference_frame));

  const Mesh scan = ReadMesh(scan_path);
  const Mesh reference = ReadMesh(frames[reference_frame]);
  Correspondences correspondences = ReadCorrespondences(correspondences_path);
  ValidateCorrespondences(correspondences, reference.num_faces(), scan.num_faces(), correspondences_path);
  std::filesystem::create_directories(out_dir);
  if (args.has("augment")) {
    const std::size_t given = correspondences.pairs.size();
    correspondences = AugmentCorrespondences(reference, scan, correspondences);
    correspondences.scan_path = std::filesystem::absolute(scan_path).string();
    WriteCorrespondences(out_dir + "/correspondences.json", correspondences);
    std::fprintf(stderr, "augmented %zu given pairs to %zu (written to %s/correspondences.json)\n", given,
                 correspondences.pairs.size(), out_dir.c_str());
  }
  ConfluentMotionOptions options;
  options.intermediate_reference = !args.has("no-intermediate-reference");
  ConfluentMotion motion(scan, reference, correspondences, options, scan_path, correspondences_path);
  for (const std::string& warning : motion.setup_summary().warnings)
    std::fprintf(stderr, "warning: %s: %s\n", scan_path.c_str(), warning.c_str());

  std::unique_ptr<PointCacheWriter> cache;
  if (args.has("pc2")) {
    WriteMesh(out_dir + "/rest.ply", scan);
    cache = std::make_unique<PointCacheWriter>(out_dir + "/scan.pc2", scan.num_vertices());
  }
  const ProgressCallback progress = context.make_progress ? context.make_progress() : ProgressCallback();
  std::set<std::string> warned;
  int singular_frames = 0;
  double deform_seconds = 0.0;
  Mesh output = scan;
  for (std::size_t i = 0; i < frames.size(); ++i) {
    const Mesh frame = i == static_cast<std::size_t>(reference_frame) ? reference : ReadMesh(frames[i]);
    if (frame.num_vertices() != reference.num_vertices() || frame.num_faces() != reference.num_faces() ||
        frame.faces != reference.faces)
      throw InputError(frames[i], "topology differs from the reference frame " + frames[reference_frame] + " (" +
                                      std::to_string(frame.num_vertices()) + " vs " +
                                      std::to_string(reference.num_vertices()) + " vertices, " +
                                      std::to_string(frame.num_faces()) + " vs " +
                                      std::to_string(reference.num_faces()) + " faces)");
    DeformSummary summary;
    const auto start = std::chrono::steady_clock::now();
    output.vertices = motion.Deform(frame.vertices, &summary);
    deform_seconds += std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    singular_frames += summary.reference_frame >= 0;
    for (const std::string& warning : summary.warnings)
      if (warned.insert(warning.substr(0, 40)).second)
        std::fprintf(stderr, "warning: frame %zu (%s): %s\n", i, frames[i].c_str(), warning.c_str());
    char name[32];
    std::snprintf(name, sizeof(name), "/%06zu.%s", i, format.c_str());
    WriteMesh(out_dir + name, output);
    if (cache) cache->Append(output.vertices);
    ReportProgress(progress, "animate", i + 1, frames.size(), std::filesystem::path(frames[i]).filename().string());
  }
  if (cache) cache->Finish();
  std::printf("animated %s (%d vertices, %d faces) with %zu frames of %s\n", scan_path.c_str(), scan.num_vertices(),
              scan.num_faces(), frames.size(), sequence_dir.c_str());
  std::printf("pairs %d, factorisation %.3f s, deformation %.2f ms per frame, %d frames with an intermediate "
              "reference\n",
              motion.setup_summary().num_pairs, motion.setup_summary().factor_seconds,
              1e3 * deform_seconds / frames.size(), singular_frames);
  std::printf("wrote %s/000000.%s .. %06zu.%s%s\n", out_dir.c_str(), format.c_str(), frames.size() - 1, format.c_str(),
              cache ? " and scan.pc2 + rest.ply" : "");
  return 0;
}

}  // namespace

CommandSpec MakeAnimateCommand() {
  CommandSpec spec;
  spec.name = "animate";
  spec.summary = "animate a scan from a template mesh sequence (Confluent Motion)";
  spec.usage = "--scan S --correspondences C --template-sequence DIR [--reference-frame N] --out DIR";
  spec.description =
      "Transfers the motion of an animated template (one .obj/.ply per frame in DIR, name order, fixed\n"
      "topology) onto the scan S through the triangle correspondences C (correspondences.json), following\n"
      "de Aguiar et al. 2006: harmonic interpolation of the correspondence rotations and a Poisson\n"
      "reconstruction, both factored once. The scan and the reference frame (default 0) must be roughly\n"
      "aligned. Writes DIR/<frame:06d>.ply (frames numbered from 0, vertex colours kept), atomically;\n"
      "--pc2 also writes scan.pc2 with rest.ply for Blender's Mesh Cache modifier.";
  spec.options = {
      {"scan", "S", "the scan (.obj/.ply) in its reference pose", false, true},
      {"correspondences", "C", "correspondences.json (template <-> scan triangles)", false, true},
      {"template-sequence", "DIR", "folder of template meshes, one per frame", false, true},
      {"reference-frame", "N", "template frame in the scan's reference pose (default 0)"},
      {"out", "DIR", "output folder", false, true},
      {"format", "ply|obj", "output mesh format (default ply)"},
      {"augment", "", "add pairs on cylindrical parts (report section 4.2) and write DIR/correspondences.json"},
      {"pc2", "", "also write DIR/scan.pc2 and DIR/rest.ply"},
      {"no-intermediate-reference", "", "do not switch reference near 180-degree rotations"},
  };
  spec.run = RunAnimate;
  return spec;
}

}  // namespace confluent::app
