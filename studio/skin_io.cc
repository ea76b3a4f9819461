#include "studio/skin_io.h"

#include <cmath>
#include <cstdio>
#include <nlohmann/json.hpp>
#include <sstream>

#include "core/atomic_file.h"
#include "core/error.h"
#include "core/mesh_io.h"

namespace confluent {
namespace {

std::string Number(double value) {
  char text[32];
  std::snprintf(text, sizeof(text), "%.9g", value);
  return text;
}

// The joint `name` of `skeleton`, or an InputError naming `path`.
int RequireJoint(const Skeleton& skeleton, const std::string& name, const std::string& path) {
  const int index = skeleton.IndexOf(name);
  if (index < 0) throw InputError(path, "the skeleton has no joint '" + name + "' (the studio's joints are needed)");
  return index;
}

Skeleton ReadJoints(const nlohmann::json& joints, const std::string& path) {
  if (!joints.is_array() || joints.empty()) throw InputError(path, "\"joints\" must be a non-empty array");
  Skeleton skeleton;
  std::vector<Eigen::Vector3d> rest;
  for (std::size_t j = 0; j < joints.size(); ++j) {
    const nlohmann::json& entry = joints[j];
    const std::string where = "joint " + std::to_string(j);
    if (!entry.is_object() || !entry.contains("name") || !entry["name"].is_string())
      throw InputError(path, where + ": needs a \"name\"");
    if (!entry.contains("parent") || !entry["parent"].is_number_integer())
      throw InputError(path, where + " (" + entry["name"].get<std::string>() + "): needs an integer \"parent\"");
    const nlohmann::json& position = entry.value("rest_position", nlohmann::json());
    if (!position.is_array() || position.size() != 3 || !position[0].is_number() || !position[1].is_number() ||
        !position[2].is_number())
      throw InputError(path, where + " (" + entry["name"].get<std::string>() + "): \"rest_position\" must be [x, y, z]");
    Joint joint;
    joint.name = entry["name"].get<std::string>();
    joint.parent = entry["parent"].get<int>();
    const Eigen::Vector3d p(position[0].get<double>(), position[1].get<double>(), position[2].get<double>());
    if (!p.allFinite()) throw InputError(path, where + " (" + joint.name + "): non-finite rest position");
    if (joint.parent >= static_cast<int>(j) || (j > 0 && joint.parent < 0) || (j == 0 && joint.parent != -1))
      throw InputError(path, where + " (" + joint.name + "): parent " + std::to_string(joint.parent) +
                                 " must be an earlier joint (joint 0 alone is the root, parent -1)");
    joint.offset_in_parent = joint.parent < 0 ? p : Eigen::Vector3d(p - rest[joint.parent]);
    rest.push_back(p);
    skeleton.joints.push_back(joint);
  }
  return skeleton;
}

SkinWeights ReadWeights(const nlohmann::json& rows, int num_vertices, int num_joints, const std::string& path) {
  if (!rows.is_array()) throw InputError(path, "\"weights\" must be an array with one row per mesh vertex");
  if (static_cast<int>(rows.size()) != num_vertices)
    throw InputError(path, "\"weights\" has " + std::to_string(rows.size()) + " rows but the mesh has " +
                               std::to_string(num_vertices) + " vertices");
  SkinWeights weights;
  weights.joints.setConstant(num_vertices, SkinWeights::kMaxInfluences, -1);
  weights.weights.setZero(num_vertices, SkinWeights::kMaxInfluences);
  for (int v = 0; v < num_vertices; ++v) {
    const nlohmann::json& row = rows[v];
    if (!row.is_array() || row.size() % 2 != 0 || row.empty() || row.size() > 2 * SkinWeights::kMaxInfluences)
      throw InputError(path, "weights row " + std::to_string(v) + ": expected 1 to 4 (joint, weight) pairs");
    for (std::size_t k = 0; k < row.size() / 2; ++k) {
      if (!row[2 * k].is_number_integer() || !row[2 * k + 1].is_number())
        throw InputError(path, "weights row " + std::to_string(v) + ": pairs are (integer joint, number weight)");
      weights.joints(v, k) = row[2 * k].get<int>();
      weights.weights(v, k) = row[2 * k + 1].get<double>();
    }
  }
  weights.Check(num_joints, path);  // indices, signs and sums
  return weights;
}

}  // namespace

std::string StudioSkinJson(const StudioActor& actor) {
  const Skeleton& skeleton = actor.skeleton;
  const std::vector<Eigen::Vector3d> rest = skeleton.RestPositions();
  std::ostringstream out;
  out << "{\n  \"frame\": \"world Z up, metres; the actor faces +y at rest\",\n  \"joints\": [\n";
  for (int j = 0; j < skeleton.size(); ++j)
    out << "    {\"name\": \"" << skeleton.joints[j].name << "\", \"parent\": " << skeleton.joints[j].parent
        << ", \"rest_position\": [" << Number(rest[j].x()) << ", " << Number(rest[j].y()) << ", "
        << Number(rest[j].z()) << "]}" << (j + 1 < skeleton.size() ? "," : "") << "\n";
  out << "  ],\n  \"weights\": [\n";
  const SkinWeights& weights = actor.weights;
  for (int v = 0; v < weights.num_vertices(); ++v) {
    out << "    [";
    bool first = true;
    for (int k = 0; k < SkinWeights::kMaxInfluences; ++k) {
      if (weights.joints(v, k) < 0) continue;
      out << (first ? "" : ", ") << weights.joints(v, k) << ", " << Number(weights.weights(v, k));
      first = false;
    }
    out << "]" << (v + 1 < weights.num_vertices() ? "," : "") << "\n";
  }
  out << "  ]\n}\n";
  return out.str();
}

StudioActor ReadRiggedActor(const std::string& mesh_path, const std::string& skin_path) {
  StudioActor actor;
  actor.mesh = ReadMesh(mesh_path);
  if (actor.mesh.num_faces() == 0) throw InputError(mesh_path, "the actor mesh has no faces");
  if (!actor.mesh.vertices.allFinite()) throw InputError(mesh_path, "the actor mesh has non-finite coordinates");
  if (!actor.mesh.has_colors()) actor.mesh.colors = RowMatrixX3f::Constant(actor.mesh.num_vertices(), 3, 0.6f);
  nlohmann::json json;
  try {
    json = nlohmann::json::parse(ReadTextFile(skin_path));
  } catch (const nlohmann::json::exception& error) {
    throw InputError(skin_path, std::string("not valid JSON: ") + error.what());
  }
  if (!json.is_object() || !json.contains("joints") || !json.contains("weights"))
    throw InputError(skin_path, "expected an object with \"joints\" and \"weights\"");
  actor.skeleton = ReadJoints(json["joints"], skin_path);
  const std::vector<std::string>& names = BodyJointNames();
  const std::array<int, kNumBodySegments> segment_joints = StudioSegmentJoints();
  for (const std::string& name : names) RequireJoint(actor.skeleton, name, skin_path);
  for (int s = 0; s < kNumBodySegments; ++s)
    actor.segment_joint[s] = actor.skeleton.IndexOf(names[segment_joints[s]]);
  actor.weights = ReadWeights(json["weights"], actor.mesh.num_vertices(), actor.skeleton.size(), skin_path);
  return actor;
}

}  // namespace confluent
