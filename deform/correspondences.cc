#include "deform/correspondences.h"

#include <Eigen/Eigenvalues>
#include <Eigen/Geometry>
#include <cmath>
#include <cstdlib>
#include <limits>
#include <map>
#include <nlohmann/json.hpp>
#include <queue>
#include <set>
#include <utility>

#include "core/atomic_file.h"
#include "core/error.h"

namespace confluent {

namespace {

std::string PairName(std::size_t index, const CorrespondencePair& pair) {
  return "pair " + std::to_string(index) + " (template_triangle " + std::to_string(pair.template_triangle) +
         ", scan_triangle " + std::to_string(pair.scan_triangle) + ")";
}

int ReadIndex(const nlohmann::json& item, const char* key, const std::string& path, std::size_t index) {
  if (!item.contains(key)) throw InputError(path, "pair " + std::to_string(index) + " has no \"" + key + "\"");
  const nlohmann::json& value = item.at(key);
  if (!value.is_number_integer())
    throw InputError(path, "pair " + std::to_string(index) + ": \"" + key + "\" must be an integer, got " + value.dump());
  const long long v = value.get<long long>();
  if (v < 0 || v > std::numeric_limits<int>::max())
    throw InputError(path, "pair " + std::to_string(index) + ": \"" + key + "\" out of range: " + std::to_string(v));
  return static_cast<int>(v);
}

}  // namespace

Correspondences ReadCorrespondences(const std::string& path) {
  const std::string text = ReadTextFile(path);
  nlohmann::json root;
  try {
    root = nlohmann::json::parse(text);
  } catch (const nlohmann::json::exception& error) {
    throw InputError(path, std::string("invalid JSON: ") + error.what());
  }
  if (!root.is_object() || !root.contains("pairs") || !root.at("pairs").is_array())
    throw InputError(path, "expected an object with a \"pairs\" array");
  Correspondences result;
  if (root.contains("template") && root.at("template").is_string()) result.template_path = root.at("template");
  if (root.contains("scan") && root.at("scan").is_string()) result.scan_path = root.at("scan");
  const nlohmann::json& pairs = root.at("pairs");
  for (std::size_t i = 0; i < pairs.size(); ++i) {
    const nlohmann::json& item = pairs[i];
    if (!item.is_object()) throw InputError(path, "pair " + std::to_string(i) + " is not an object");
    CorrespondencePair pair;
    pair.template_triangle = ReadIndex(item, "template_triangle", path, i);
    pair.scan_triangle = ReadIndex(item, "scan_triangle", path, i);
    if (item.contains("segment")) {
      if (!item.at("segment").is_string())
        throw InputError(path, PairName(i, pair) + ": \"segment\" must be a string");
      pair.segment = item.at("segment").get<std::string>();
    }
    if (item.contains("weight")) {
      if (!item.at("weight").is_number() || !std::isfinite(item.at("weight").get<double>()) ||
          item.at("weight").get<double>() <= 0.0)
        throw InputError(path, PairName(i, pair) + ": \"weight\" must be a positive number, got " +
                                   item.at("weight").dump());
      pair.weight = item.at("weight").get<double>();
    }
    result.pairs.push_back(pair);
  }
  return result;
}

void WriteCorrespondences(const std::string& path, const Correspondences& correspondences) {
  nlohmann::json root = nlohmann::json::object();
  if (!correspondences.template_path.empty()) root["template"] = correspondences.template_path;
  if (!correspondences.scan_path.empty()) root["scan"] = correspondences.scan_path;
  nlohmann::json pairs = nlohmann::json::array();
  for (const CorrespondencePair& pair : correspondences.pairs) {
    nlohmann::json item = {{"template_triangle", pair.template_triangle}, {"scan_triangle", pair.scan_triangle}};
    if (!pair.segment.empty()) item["segment"] = pair.segment;
    if (pair.weight != 1.0) item["weight"] = pair.weight;
    pairs.push_back(item);
  }
  root["pairs"] = pairs;
  WriteTextFile(path, root.dump(1) + "\n");
}

void ValidateCorrespondences(const Correspondences& correspondences, int num_template_faces, int num_scan_faces,
                             const std::string& source) {
  if (correspondences.pairs.empty()) throw InputError(source, "no correspondence pairs");
  std::map<int, std::size_t> pair_of_scan_triangle;
  for (std::size_t i = 0; i < correspondences.pairs.size(); ++i) {
    const CorrespondencePair& pair = correspondences.pairs[i];
    if (pair.template_triangle < 0 || pair.template_triangle >= num_template_faces)
      throw InputError(source, PairName(i, pair) + ": template triangle out of range (the template has " +
                                   std::to_string(num_template_faces) + " faces)");
    if (pair.scan_triangle < 0 || pair.scan_triangle >= num_scan_faces)
      throw InputError(source, PairName(i, pair) + ": scan triangle out of range (the scan has " +
                                   std::to_string(num_scan_faces) + " faces)");
    if (!(pair.weight > 0.0) || !std::isfinite(pair.weight))
      throw InputError(source, PairName(i, pair) + ": weight must be a positive number");
    const auto [it, inserted] = pair_of_scan_triangle.emplace(pair.scan_triangle, i);
    if (!inserted) {
      const CorrespondencePair& other = correspondences.pairs[it->second];
      if (other.template_triangle == pair.template_triangle)
        throw InputError(source, PairName(i, pair) + " repeats " + PairName(it->second, other));
      throw InputError(source, PairName(i, pair) + ": scan triangle is also tied to template triangle " +
                                   std::to_string(other.template_triangle) + " by pair " +
                                   std::to_string(it->second));
    }
  }
}

std::vector<std::string> SegmentsWithoutPairs(const Correspondences& correspondences,
                                              const std::vector<std::string>& segment_names) {
  std::set<std::string> used;
  for (const CorrespondencePair& pair : correspondences.pairs) used.insert(pair.segment);
  std::vector<std::string> missing;
  for (const std::string& name : segment_names)
    if (!used.count(name)) missing.push_back(name);
  return missing;
}

void AugmentOptions::Check() const {
  RequireOption(directions >= 1, "AugmentOptions.directions", directions, ">= 1");
  RequireOption(neighbourhood_radius_m > 0.0, "AugmentOptions.neighbourhood_radius_m", neighbourhood_radius_m, "> 0");
  RequireOption(max_radius_factor > 1.0, "AugmentOptions.max_radius_factor", max_radius_factor, "> 1");
}

namespace {

// The axis and cross-section of a roughly cylindrical part around one triangle.
struct PartFrame {
  Eigen::Vector3d axis;    // unit
  Eigen::Vector3d centre;  // on the axis, in the cross-sectional plane through the triangle
  Eigen::Vector3d start;   // unit direction from centre towards the triangle
  double radius = 0.0;
};

Eigen::Vector3d Centroid(const Mesh& mesh, int f) {
  return (mesh.vertices.row(mesh.faces(f, 0)) + mesh.vertices.row(mesh.faces(f, 1)) +
          mesh.vertices.row(mesh.faces(f, 2))).transpose() / 3.0;
}

Eigen::Vector3d AreaNormal(const Mesh& mesh, int f) {
  const Eigen::Vector3d a = mesh.vertices.row(mesh.faces(f, 0)), b = mesh.vertices.row(mesh.faces(f, 1)),
                        c = mesh.vertices.row(mesh.faces(f, 2));
  return 0.5 * (b - a).cross(c - a);
}

// Faces connected to `seed` (through shared vertices) with centroids within `radius` of its centroid.
std::vector<int> Patch(const Mesh& mesh, const std::vector<std::vector<int>>& faces_of_vertex, int seed,
                       double radius) {
  const Eigen::Vector3d c = Centroid(mesh, seed);
  std::vector<int> patch{seed};
  std::set<int> seen{seed};
  std::queue<int> queue;
  queue.push(seed);
  while (!queue.empty()) {
    const int f = queue.front();
    queue.pop();
    for (int k = 0; k < 3; ++k)
      for (int g : faces_of_vertex[mesh.faces(f, k)]) {
        if (!seen.insert(g).second) continue;
        if ((Centroid(mesh, g) - c).norm() > radius) continue;
        patch.push_back(g);
        queue.push(g);
      }
  }
  return patch;
}

bool EstimatePart(const Mesh& mesh, const std::vector<std::vector<int>>& faces_of_vertex, int seed,
                  const AugmentOptions& options, PartFrame* frame) {
  const std::vector<int> patch = Patch(mesh, faces_of_vertex, seed, options.neighbourhood_radius_m);
  Eigen::Matrix3d scatter = Eigen::Matrix3d::Zero();
  for (int f : patch) {
    const Eigen::Vector3d an = AreaNormal(mesh, f);
    const double area = an.norm();
    if (!(area > 0.0) || !std::isfinite(area)) continue;
    scatter += an * an.transpose() / area;  // area-weighted n n^T
  }
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eigen(scatter);
  const Eigen::Vector3d values = eigen.eigenvalues();  // ascending
  if (!(values(2) > 0.0) || values(1) < 0.02 * values(2)) return false;  // flat patch: no axis
  frame->axis = eigen.eigenvectors().col(0).normalized();
  // Centre: least-squares intersection of the face normal lines projected into the plane.
  const Eigen::Vector3d c = Centroid(mesh, seed);
  const Eigen::Matrix3d in_plane = Eigen::Matrix3d::Identity() - frame->axis * frame->axis.transpose();
  Eigen::Matrix3d a = frame->axis * frame->axis.transpose();  // pins the axial coordinate to c
  Eigen::Vector3d b = a * c;
  for (int f : patch) {
    const Eigen::Vector3d an = AreaNormal(mesh, f);
    Eigen::Vector3d n = in_plane * an;
    if (!(n.norm() > 0.0)) continue;
    const double w = an.norm();
    n.normalize();
    const Eigen::Matrix3d off_line = in_plane - n * n.transpose();
    a += w * off_line;
    b += w * off_line * Centroid(mesh, f);
  }
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> check(a);
  if (!(check.eigenvalues()(0) > 1e-9 * check.eigenvalues()(2))) return false;
  frame->centre = a.ldlt().solve(b);
  Eigen::Vector3d start = in_plane * (c - frame->centre);
  frame->radius = start.norm();
  if (!(frame->radius > 0.0) || !frame->centre.allFinite()) return false;
  frame->start = start / frame->radius;
  return true;
}

// The first face hit by the ray origin + t * direction, t > 0, or -1; `t_hit` receives t.
int CastRay(const Mesh& mesh, const Eigen::Vector3d& origin, const Eigen::Vector3d& direction, double* t_hit) {
  int best = -1;
  double best_t = std::numeric_limits<double>::infinity();
  for (int f = 0; f < mesh.num_faces(); ++f) {  // Moeller and Trumbore 1997
    const Eigen::Vector3d p0 = mesh.vertices.row(mesh.faces(f, 0));
    const Eigen::Vector3d e1 = Eigen::Vector3d(mesh.vertices.row(mesh.faces(f, 1))) - p0;
    const Eigen::Vector3d e2 = Eigen::Vector3d(mesh.vertices.row(mesh.faces(f, 2))) - p0;
    const Eigen::Vector3d p = direction.cross(e2);
    const double det = e1.dot(p);
    if (std::abs(det) < 1e-300) continue;
    const double inv = 1.0 / det;
    const Eigen::Vector3d s = origin - p0;
    const double u = s.dot(p) * inv;
    if (u < 0.0 || u > 1.0) continue;
    const Eigen::Vector3d q = s.cross(e1);
    const double v = direction.dot(q) * inv;
    if (v < 0.0 || u + v > 1.0) continue;
    const double t = e2.dot(q) * inv;
    if (t > 0.0 && t < best_t) {
      best_t = t;
      best = f;
    }
  }
  *t_hit = best_t;
  return best;
}

std::vector<std::vector<int>> FacesOfVertex(const Mesh& mesh) {
  std::vector<std::vector<int>> result(mesh.num_vertices());
  for (int f = 0; f < mesh.num_faces(); ++f)
    for (int k = 0; k < 3; ++k) result[mesh.faces(f, k)].push_back(f);
  return result;
}

}  // namespace

Correspondences AugmentCorrespondences(const Mesh& template_mesh, const Mesh& scan, const Correspondences& given,
                                       const AugmentOptions& options) {
  options.Check();
  ValidateCorrespondences(given, template_mesh.num_faces(), scan.num_faces(), "given correspondences");
  Correspondences result = given;
  std::set<int> used_scan;
  for (const CorrespondencePair& pair : given.pairs) used_scan.insert(pair.scan_triangle);
  const std::vector<std::vector<int>> template_adjacency = FacesOfVertex(template_mesh);
  const std::vector<std::vector<int>> scan_adjacency = FacesOfVertex(scan);
  for (const CorrespondencePair& seed : given.pairs) {
    PartFrame on_template, on_scan;
    if (!EstimatePart(template_mesh, template_adjacency, seed.template_triangle, options, &on_template)) continue;
    if (!EstimatePart(scan, scan_adjacency, seed.scan_triangle, options, &on_scan)) continue;
    if (on_scan.axis.dot(on_template.axis) < 0.0) on_scan.axis = -on_scan.axis;
    for (int k = 1; k < options.directions; ++k) {
      const double angle = 2.0 * M_PI * k / options.directions;
      const Eigen::Vector3d dir_t = Eigen::AngleAxisd(angle, on_template.axis) * on_template.start;
      const Eigen::Vector3d dir_s = Eigen::AngleAxisd(angle, on_scan.axis) * on_scan.start;
      double t_template = 0.0, t_scan = 0.0;
      const int hit_t = CastRay(template_mesh, on_template.centre, dir_t, &t_template);
      const int hit_s = CastRay(scan, on_scan.centre, dir_s, &t_scan);
      if (hit_t < 0 || hit_s < 0) continue;
      if (t_template > options.max_radius_factor * on_template.radius) continue;
      if (t_scan > options.max_radius_factor * on_scan.radius) continue;
      if (!used_scan.insert(hit_s).second) continue;
      CorrespondencePair pair = seed;
      pair.template_triangle = hit_t;
      pair.scan_triangle = hit_s;
      result.pairs.push_back(pair);
    }
  }
  return result;
}

}  // namespace confluent
