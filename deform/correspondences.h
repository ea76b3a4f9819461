#pragma once
// Template <-> scan triangle correspondences (docs/ARCHITECTURE.md section 3): file I/O,
// validation and the automatic augmentation of cylindrical parts (de Aguiar et al. 2006,
// section 4.2).

#include <string>
#include <vector>

#include "core/mesh.h"

namespace confluent {

// One marked triangle pair. Indices are 0-based face indices of the respective mesh file.
struct CorrespondencePair {
  int template_triangle = -1;
  int scan_triangle = -1;
  std::string segment;   // optional body-part label, e.g. "left_forearm"; empty if none
  double weight = 1.0;   // optional positive weight (harmonic constraints and placement fit)
};

// The contents of a correspondences.json file.
struct Correspondences {
  std::vector<CorrespondencePair> pairs;
  std::string template_path;  // optional "template" key: path of the template mesh, or empty
  std::string scan_path;      // optional "scan" key: path of the scan mesh, or empty
};

// Reads correspondences.json: {"pairs": [{"template_triangle": i, "scan_triangle": j,
// "segment": "...", "weight": w}, ...]} (segment, weight and extra keys optional).
// Throws InputError naming the file on a missing file, bad JSON, a missing or non-integer
// index, a negative index, or a weight that is not a finite positive number (naming the pair).
Correspondences ReadCorrespondences(const std::string& path);

// Writes `correspondences` as JSON, atomically. Throws OutputError on failure.
void WriteCorrespondences(const std::string& path, const Correspondences& correspondences);

// Checks the pairs against the meshes' face counts. Throws InputError("<source>", ...) naming
// the pair when an index is out of range, a pair is repeated, or one scan triangle is tied to
// two different template triangles; `source` is usually the file the pairs came from.
void ValidateCorrespondences(const Correspondences& correspondences, int num_template_faces,
                             int num_scan_faces, const std::string& source);

// Names from `segment_names` that no pair carries (e.g. the 16 template segments), in order.
std::vector<std::string> SegmentsWithoutPairs(const Correspondences& correspondences,
                                              const std::vector<std::string>& segment_names);

// Options for AugmentCorrespondences.
struct AugmentOptions {
  int directions = 8;                    // rays per given pair, evenly spaced around the part's axis
                                          // (the given direction included), so 7 new pairs each
  double neighbourhood_radius_m = 0.08;  // surface patch around a given triangle used to estimate
                                          // the part's axis (normal PCA) and cross-section centre
  double max_radius_factor = 3.0;        // a hit farther from the axis than this times the
                                          // estimated part radius is rejected
  void Check() const;  // throws UsageError naming an invalid field and its value
};

// Automatic augmentation for cylindrical parts (report section 4.2). For each given pair it
// estimates the part's axis and cross-section centre on both meshes (normals of the surface
// patch around the triangle, circle fit in the cross-sectional plane), casts `directions - 1`
// further rays from the centre in the cross-sectional plane, at the same angles around the
// (consistently oriented) axis on both meshes, and pairs the first triangles hit. The result
// holds the given pairs first, then the new ones (same segment and weight as their seed);
// scan triangles already used are skipped. Both meshes must be roughly aligned.
Correspondences AugmentCorrespondences(const Mesh& template_mesh, const Mesh& scan,
                                       const Correspondences& given, const AugmentOptions& options = {});

}  // namespace confluent
