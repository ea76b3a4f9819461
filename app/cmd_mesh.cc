// confluent mesh info FILE: read a mesh, summarise it and print its validation report.

#include <cstdio>
#include <string>

#include "app/commands.h"
#include "core/error.h"
#include "core/mesh_io.h"
#include "core/mesh_ops.h"
#include "core/mesh_validation.h"

namespace confluent::app {
namespace {

int RunMeshInfo(const ParsedArgs& args, const Context&) {
  const std::string path = args.positionals()[0];
  const Mesh mesh = ReadMesh(path);
  std::printf("file          %s\n", path.c_str());
  std::printf("vertices      %d\nfaces         %d\n", mesh.num_vertices(), mesh.num_faces());
  std::printf("colours       %s\n", mesh.has_colors() ? "yes" : "no");
  if (mesh.has_uvs())
    std::printf("uvs           yes (%d)\n", static_cast<int>(mesh.uvs.rows()));
  else
    std::printf("uvs           no\n");
  std::printf("texture       %s\n", mesh.texture_path.empty() ? "-" : mesh.texture_path.c_str());
  std::printf("face labels   %s\n", mesh.has_face_labels() ? "yes" : "no");
  const Eigen::AlignedBox3d box = BoundingBox(mesh);
  if (!box.isEmpty()) {
    const Eigen::Vector3d size = box.sizes();
    std::printf("bounding box  min (%.6g, %.6g, %.6g)  max (%.6g, %.6g, %.6g)  size (%.6g, %.6g, %.6g)\n",
                box.min().x(), box.min().y(), box.min().z(), box.max().x(), box.max().y(), box.max().z(), size.x(),
                size.y(), size.z());
    if (mesh.num_faces() > 0) std::printf("surface area  %.6g\n", FaceAreas(mesh).sum());
  }
  const MeshReport report = ValidateMesh(mesh);
  std::printf("\n%s", report.ToString().c_str());
  if (args.has("strict") && !report.is_clean())
    throw InputError(path, "mesh is not clean (non-manifold, degenerate, duplicate or invalid elements)");
  return 0;
}

}  // namespace

CommandSpec MakeMeshInfoCommand() {
  CommandSpec spec;
  spec.name = "mesh info";
  spec.summary = "summarise an OBJ/PLY mesh and check it (manifoldness, holes, components)";
  spec.usage = "FILE [--strict]";
  spec.description =
      "Reads FILE (.obj or .ply), prints its vertex and face counts, whether it has colours, UVs, a texture\n"
      "and face labels, its bounding box (file units, normally metres), and a validation report:\n"
      "non-manifold edges and vertices, degenerate and duplicate faces, unreferenced and non-finite\n"
      "vertices, connected components and boundary loops. Exits 1 if the file cannot be read, and with\n"
      "--strict also when the mesh is not clean.";
  spec.min_positionals = spec.max_positionals = 1;
  spec.options = {{"strict", "", "exit 1 when the mesh is not clean"}};
  spec.run = RunMeshInfo;
  return spec;
}

}  // namespace confluent::app
