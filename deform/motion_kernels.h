#pragma once
// The vectorised per-frame kernels of Confluent Motion (deform/confluent_motion.h): mixing the
// segment fields into vertex quaternions, and assembling the face rotations and their flux.
// Internal to deform/.

#include <cstddef>
#include <vector>

namespace confluent::deform_internal {

// A buffer of at least `size` doubles starting at a 32-byte boundary, inside `storage`.
double* Aligned32(std::vector<double>* storage, std::size_t size);

// Rows [begin, end) of vertex_q (4 per row) = fields (num_fields per row) x field_q (num_fields x 4,
// row-major).
void MixFields(const double* fields, int num_fields, const double* field_q, int begin, int end, double* vertex_q);

// Step 5 of Deform() for faces in blocks of kFaceBlock slots: per face, the rotation (normalised
// sum of the corner quaternions) into face_q, and its flux into rhs (4 doubles per row, the last
// unused).
constexpr int kFaceBlock = 8;
struct FaceAssembly {
  int num_faces = 0;
  const int* face = nullptr;           // per slot (the order faces are visited in), the face
  const int* corners = nullptr;        // 3 per slot: rows of vertex_q and rhs
  // Per block of kFaceBlock slots: g0 x, y, z and g1 x, y, z (kFaceBlock each); corner 0 gets
  // R g0, corner 1 R g1 and corner 2 -R (g0 + g1). Padded with zeros.
  const double* flux_edges = nullptr;
  const double* vertex_q = nullptr;    // 4 per row
  const double* previous = nullptr;    // 4 per face: previous rotations, or null
  const double* intermediate = nullptr;  // 4 per face: the intermediate reference's, or null
};

// Step 5 of Deform() for the slots of blocks [block_begin, block_end); rhs is 32-byte aligned.
// Returns the number of faces whose interpolated quaternion vanished.
int AssembleFaces(const FaceAssembly& in, int block_begin, int block_end, double* face_q, double* rhs);

}  // namespace confluent::deform_internal
