#pragma once
// Confluent Motion (de Aguiar, Zayer, Theobalt, Magnor and Seidel 2006, section 4): transfers the
// motion of a template mesh onto a high-resolution scan through sparse triangle correspondences,
// harmonic interpolation of rotation quaternions and a Poisson reconstruction.

#include <Eigen/Core>
#include <memory>
#include <string>
#include <vector>

#include "core/mesh.h"
#include "deform/correspondences.h"
#include "deform/laplacian.h"

namespace confluent {

// Options of ConfluentMotion.
struct ConfluentMotionOptions {
  CotanLaplacianOptions laplacian;      // weights of both systems (harmonic and Poisson)
  // Soft positional constraints on the corners of the scan's correspondence triangles, relative
  // to the mean diagonal of the Laplacian: each corner is drawn towards where its template
  // triangle carries it (the template triangle's current centroid plus its rotation applied to
  // the reference scan-template offset). They stop small rotation errors from accumulating
  // along limbs. 0 gives the report's formulation: the Poisson solve fixes the shape and only a
  // translation per component is fitted to the correspondences.
  double position_weight = 1.0;
  // A constraint quaternion with |w| below this is near a 180-degree rotation (report
  // section 4.3); 0.25 is a rotation of about 151 degrees.
  double singular_w = 0.25;
  // Near a singularity, use the previous frame (template pose and the scan's per-triangle
  // rotations) as an intermediate reference, so only the rotation since then is interpolated.
  bool intermediate_reference = true;
  // Report section 4.3, second solution: near a singularity, add constraints along the shortest
  // path over the scan from each near-180-degree pair to the nearest pair that is not, with
  // quaternions SLERPed along the path by arc length, so the twist spreads evenly instead of
  // collapsing where the blended quaternions cancel. The harmonic system is refactored when
  // the set of near-180-degree pairs changes. Takes precedence over intermediate_reference.
  bool slerp_paths = false;
  // Keep each constraint quaternion in the hemisphere of its value in the previous frame, so w
  // changes continuously (past 180 degrees it goes negative). Off: per frame, the hemisphere of
  // the neighbours only (rotations flip direction when they cross 180 degrees).
  bool temporal_signs = true;
  // When every pair has a segment label and the segments move rigidly, use precomputed
  // harmonic weight fields (one per segment) instead of a solve per frame.
  bool segment_fields = true;
  int max_segment_fields = 64;          // more distinct labels than this: no weight fields
  double segment_rigid_tolerance_rad = 1e-5;  // max angle between rotations within a segment
  // Threads one Deform() uses for the per-vertex and per-face loops and the triangular solves
  // (1 = serial; 2 or more = two, the second kept for the object's lifetime; small scans run
  // serially regardless). The result does not depend on it beyond round-off.
  int threads = 2;
  // Triangular solves with the factors rounded to single precision (arithmetic stays double):
  // about 1.25x faster frames at 50K triangles, with vertex errors of about 2e-7 m there (and
  // up to a few 1e-7 m on weakly constrained scans, so off by default: exact motions are then
  // reproduced to round-off). The Poisson factor stays double without positional constraints
  // (position_weight = 0), whose system is much worse conditioned.
  bool single_precision_solves = false;
  void Check() const;  // throws UsageError naming an invalid field and its value
};

// What the constructor found and did.
struct ConfluentMotionSetupSummary {
  int num_scan_vertices = 0;
  int num_scan_faces = 0;
  int num_components = 0;           // connected components of the scan
  int num_pairs = 0;
  int num_constrained_vertices = 0; // scan vertices with Dirichlet values
  int num_segment_fields = 0;       // 0 when the weight fields are not used
  double harmonic_factor_nonzeros = 0.0;
  double poisson_factor_nonzeros = 0.0;
  double factor_seconds = 0.0;      // both factorisations plus the weight fields
  std::vector<std::string> warnings;  // e.g. degenerate or non-manifold scan faces
};

// What one Deform() call did.
struct DeformSummary {
  int frame = 0;                        // 0-based count of Deform() calls
  double min_abs_w = 1.0;               // smallest |w| of the constraint rotations from the reference pose
  bool singular = false;                // some constraint's w (signs continuous over frames) < singular_w
  int reference_frame = -1;             // -1: the reference pose; else the intermediate reference frame
  bool used_segment_fields = false;
  int slerp_path_vertices = 0;          // scan vertices constrained along SLERP paths (0: none)
  double placement_rms_m = 0.0;         // rms residual of the correspondence-centroid fit
  std::vector<std::string> warnings;
};

// Animates one scan from a template mesh sequence. Construction factors the two sparse systems
// (harmonic interpolation with Dirichlet values at the correspondence triangles' vertices, and
// the cotangent Laplacian of the scan plus the soft positional constraints, or with one pinned
// vertex per component) once; each Deform() costs back-substitutions and assembly, or, with
// segment weight fields, one back-substitution. Frames should be given in order: sign consistency and
// the intermediate reference use the previous frame.
class ConfluentMotion {
 public:
  // `scan` and `template_reference` are in their (roughly aligned) reference poses, metres.
  // Throws InputError naming `correspondences_source` for invalid pairs (indices out of range,
  // duplicates, a zero-area template triangle) and naming `scan_source` for a scan without
  // faces or with a connected component that has no correspondence triangle.
  ConfluentMotion(const Mesh& scan, const Mesh& template_reference, const Correspondences& correspondences,
                  const ConfluentMotionOptions& options = {},
                  const std::string& scan_source = "scan",
                  const std::string& correspondences_source = "correspondences");
  ~ConfluentMotion();
  ConfluentMotion(ConfluentMotion&&) noexcept;
  ConfluentMotion& operator=(ConfluentMotion&&) noexcept;

  // The scan's vertices (n x 3, metres) in the pose of `template_vertices` (the template's
  // vertices in the current frame, same count and order as the reference). Never returns
  // non-finite values. Throws std::invalid_argument on a wrong row count or non-finite input.
  RowMatrixX3d Deform(const RowMatrixX3d& template_vertices, DeformSummary* summary = nullptr);

  // Forgets the previous frame (sign history and intermediate reference).
  void Reset();

  const ConfluentMotionSetupSummary& setup_summary() const;
  // Per-face rotation quaternions (w, x, y, z) of the last Deform(), from the scan's reference
  // pose, m x 4 (empty before the first frame).
  const Eigen::Matrix<double, Eigen::Dynamic, 4, Eigen::RowMajor>& face_rotations() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace confluent
