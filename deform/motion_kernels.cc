// The vectorised per-frame kernels of Confluent Motion: field mixing (target clones for
// x86-64-v3) and face assembly (AVX2 with FMA when the CPU has it, else one slot at a time).

#include "deform/motion_kernels.h"

#if defined(__x86_64__)
#include <immintrin.h>
#endif
#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>

namespace confluent::deform_internal {

// A buffer of at least `size` doubles starting at a 32-byte boundary, inside `storage`.
double* Aligned32(std::vector<double>* storage, std::size_t size) {
  if (storage->size() < size + 4) storage->assign(size + 4, 0.0);
  const std::uintptr_t address = reinterpret_cast<std::uintptr_t>(storage->data());
  return storage->data() + ((32 - address % 32) % 32) / sizeof(double);
}

// Four doubles for GCC's vector extensions, at any 8-byte boundary.
typedef double Vec4u __attribute__((vector_size(32), aligned(8)));

// Rows [begin, end) of vertex_q (4 per row) = fields (num_fields per row) x field_q (num_fields x 4,
// row-major).
__attribute__((target_clones("arch=x86-64-v3", "default"))) void MixFields(const double* fields, int num_fields,
                                                                             const double* field_q, int begin,
                                                                             int end, double* vertex_q) {
  const Vec4u* q = reinterpret_cast<const Vec4u*>(field_q);
  for (int v = begin; v < end; ++v) {
    const double* w = fields + static_cast<std::size_t>(v) * num_fields;
    // Four partial sums keep the multiply-adds independent.
    Vec4u sum0 = q[0] * 0.0, sum1 = sum0, sum2 = sum0, sum3 = sum0;
    int g = 0;
    for (; g + 3 < num_fields; g += 4) {
      sum0 += w[g] * q[g];
      sum1 += w[g + 1] * q[g + 1];
      sum2 += w[g + 2] * q[g + 2];
      sum3 += w[g + 3] * q[g + 3];
    }
    for (; g < num_fields; ++g) sum0 += w[g] * q[g];
    *reinterpret_cast<Vec4u*>(vertex_q + 4 * static_cast<std::size_t>(v)) = (sum0 + sum1) + (sum2 + sum3);
  }
}


namespace {

// One slot of AssembleFaces; returns 1 when the interpolated quaternion vanished, else 0.
inline int AssembleSlot(const FaceAssembly& in, int slot, double* face_q, double* rhs) {
  const int* corner = in.corners + 3 * static_cast<std::size_t>(slot);
  const std::size_t f = in.face[slot];
  const double* a = in.vertex_q + 4 * static_cast<std::size_t>(corner[0]);
  const double* b = in.vertex_q + 4 * static_cast<std::size_t>(corner[1]);
  const double* c = in.vertex_q + 4 * static_cast<std::size_t>(corner[2]);
  double q[4];
  for (int k = 0; k < 4; ++k) q[k] = a[k] + b[k] + c[k];
  const double squared = q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3];
  int vanishing = 0;
  if (squared > 1e-18 && squared <= std::numeric_limits<double>::max()) {
    const double inverse = 1.0 / std::sqrt(squared);
    for (int k = 0; k < 4; ++k) q[k] *= inverse;
    if (in.intermediate != nullptr) {
      const double* r = in.intermediate + 4 * f;
      const Eigen::Quaterniond composed =
          (Eigen::Quaterniond(q[0], q[1], q[2], q[3]) * Eigen::Quaterniond(r[0], r[1], r[2], r[3])).normalized();
      q[0] = composed.w(), q[1] = composed.x(), q[2] = composed.y(), q[3] = composed.z();
    }
  } else {
    vanishing = 1;
    const double identity[4] = {1.0, 0.0, 0.0, 0.0};
    const double* keep = in.previous != nullptr ? in.previous + 4 * f : identity;
    for (int k = 0; k < 4; ++k) q[k] = keep[k];
  }
  for (int k = 0; k < 4; ++k) face_q[4 * f + k] = q[k];
  // u_j = R g_j with R the rotation matrix of the unit quaternion (w, x, y, z).
  const double tx = 2 * q[1], ty = 2 * q[2], tz = 2 * q[3];
  const double twx = tx * q[0], twy = ty * q[0], twz = tz * q[0];
  const double txx = tx * q[1], txy = ty * q[1], txz = tz * q[1];
  const double tyy = ty * q[2], tyz = tz * q[2], tzz = tz * q[3];
  const double r[3][3] = {{1 - (tyy + tzz), txy - twz, txz + twy},
                          {txy + twz, 1 - (txx + tzz), tyz - twx},
                          {txz - twy, tyz + twx, 1 - (txx + tyy)}};
  const double* g = in.flux_edges + 6 * static_cast<std::size_t>(slot / kFaceBlock) * kFaceBlock + slot % kFaceBlock;
  double* y0 = rhs + 4 * static_cast<std::size_t>(corner[0]);
  double* y1 = rhs + 4 * static_cast<std::size_t>(corner[1]);
  double* y2 = rhs + 4 * static_cast<std::size_t>(corner[2]);
  for (int k = 0; k < 3; ++k) {
    const double u0 = r[k][0] * g[0] + r[k][1] * g[kFaceBlock] + r[k][2] * g[2 * kFaceBlock];
    const double u1 = r[k][0] * g[3 * kFaceBlock] + r[k][1] * g[4 * kFaceBlock] + r[k][2] * g[5 * kFaceBlock];
    y0[k] += u0;
    y1[k] += u1;
    y2[k] -= u0 + u1;
  }
  return vanishing;
}

// AssembleFaces, one slot at a time.
int AssembleFacesGeneric(const FaceAssembly& in, int block_begin, int block_end, double* face_q, double* rhs) {
  int vanishing = 0;
  const int end = std::min(in.num_faces, block_end * kFaceBlock);
  for (int slot = block_begin * kFaceBlock; slot < end; ++slot) vanishing += AssembleSlot(in, slot, face_q, rhs);
  return vanishing;
}

#if defined(__x86_64__)
// Rows i of the 4 x 4 block (a, b, c, d) become the columns (and back).
__attribute__((target("avx2,fma"))) inline void Transpose4(__m256d* a, __m256d* b, __m256d* c, __m256d* d) {
  const __m256d t0 = _mm256_unpacklo_pd(*a, *b), t1 = _mm256_unpackhi_pd(*a, *b);
  const __m256d t2 = _mm256_unpacklo_pd(*c, *d), t3 = _mm256_unpackhi_pd(*c, *d);
  *a = _mm256_permute2f128_pd(t0, t2, 0x20);
  *b = _mm256_permute2f128_pd(t1, t3, 0x20);
  *c = _mm256_permute2f128_pd(t0, t2, 0x31);
  *d = _mm256_permute2f128_pd(t1, t3, 0x31);
}

// AssembleFaces with AVX2, four slots per step (across faces); slots with a vanishing
// quaternion, an intermediate reference or in a partial block go through AssembleSlot.
__attribute__((target("avx2,fma"))) int AssembleFacesAvx2(const FaceAssembly& in, int block_begin, int block_end,
                                                          double* face_q, double* rhs) {
  int vanishing = 0;
  const __m256d one = _mm256_set1_pd(1.0), tiny = _mm256_set1_pd(1e-18),
                largest = _mm256_set1_pd(std::numeric_limits<double>::max()), zero = _mm256_setzero_pd();
  for (int block = block_begin; block < block_end; ++block) {
    const int first = block * kFaceBlock;
    if (first + kFaceBlock > in.num_faces || in.intermediate != nullptr) {
      vanishing += AssembleFacesGeneric(in, block, block + 1, face_q, rhs);
      continue;
    }
    for (int half = 0; half < kFaceBlock; half += 4) {
      const int base = first + half;
      const int* corner = in.corners + 3 * static_cast<std::size_t>(base);
      __m256d q[4];
      for (int l = 0; l < 4; ++l)
        q[l] = _mm256_add_pd(_mm256_add_pd(_mm256_loadu_pd(in.vertex_q + 4 * static_cast<std::size_t>(corner[3 * l])),
                                           _mm256_loadu_pd(in.vertex_q + 4 * static_cast<std::size_t>(corner[3 * l + 1]))),
                             _mm256_loadu_pd(in.vertex_q + 4 * static_cast<std::size_t>(corner[3 * l + 2])));
      Transpose4(&q[0], &q[1], &q[2], &q[3]);  // now w, x, y, z of the four slots
      __m256d squared = _mm256_mul_pd(q[0], q[0]);
      for (int k = 1; k < 4; ++k) squared = _mm256_fmadd_pd(q[k], q[k], squared);
      const __m256d valid =
          _mm256_and_pd(_mm256_cmp_pd(squared, tiny, _CMP_GT_OQ), _mm256_cmp_pd(squared, largest, _CMP_LE_OQ));
      if (_mm256_movemask_pd(valid) != 0xF) {
        for (int l = 0; l < 4; ++l) vanishing += AssembleSlot(in, base + l, face_q, rhs);
        continue;
      }
      const __m256d inverse = _mm256_div_pd(one, _mm256_sqrt_pd(squared));
      const __m256d w = _mm256_mul_pd(q[0], inverse), x = _mm256_mul_pd(q[1], inverse),
                    y = _mm256_mul_pd(q[2], inverse), z = _mm256_mul_pd(q[3], inverse);
      __m256d rows[4] = {w, x, y, z};
      Transpose4(&rows[0], &rows[1], &rows[2], &rows[3]);
      for (int l = 0; l < 4; ++l) _mm256_storeu_pd(face_q + 4 * static_cast<std::size_t>(in.face[base + l]), rows[l]);
      const __m256d tx = _mm256_add_pd(x, x), ty = _mm256_add_pd(y, y), tz = _mm256_add_pd(z, z);
      const __m256d twx = _mm256_mul_pd(tx, w), twy = _mm256_mul_pd(ty, w), twz = _mm256_mul_pd(tz, w);
      const __m256d txx = _mm256_mul_pd(tx, x), txy = _mm256_mul_pd(ty, x), txz = _mm256_mul_pd(tz, x);
      const __m256d tyy = _mm256_mul_pd(ty, y), tyz = _mm256_mul_pd(tz, y), tzz = _mm256_mul_pd(tz, z);
      const __m256d r[3][3] = {
          {_mm256_sub_pd(one, _mm256_add_pd(tyy, tzz)), _mm256_sub_pd(txy, twz), _mm256_add_pd(txz, twy)},
          {_mm256_add_pd(txy, twz), _mm256_sub_pd(one, _mm256_add_pd(txx, tzz)), _mm256_sub_pd(tyz, twx)},
          {_mm256_sub_pd(txz, twy), _mm256_add_pd(tyz, twx), _mm256_sub_pd(one, _mm256_add_pd(txx, tyy))}};
      const double* g = in.flux_edges + 6 * static_cast<std::size_t>(block) * kFaceBlock + half;
      __m256d u[3][4];  // per corner: x, y, z, 0 of the four slots
      for (int j = 0; j < 2; ++j) {
        const __m256d gx = _mm256_loadu_pd(g + (3 * j) * kFaceBlock), gy = _mm256_loadu_pd(g + (3 * j + 1) * kFaceBlock),
                      gz = _mm256_loadu_pd(g + (3 * j + 2) * kFaceBlock);
        for (int k = 0; k < 3; ++k)
          u[j][k] = _mm256_fmadd_pd(r[k][0], gx, _mm256_fmadd_pd(r[k][1], gy, _mm256_mul_pd(r[k][2], gz)));
        u[j][3] = zero;
      }
      for (int k = 0; k < 3; ++k) u[2][k] = _mm256_sub_pd(zero, _mm256_add_pd(u[0][k], u[1][k]));
      u[2][3] = zero;
      for (int j = 0; j < 3; ++j) Transpose4(&u[j][0], &u[j][1], &u[j][2], &u[j][3]);  // now per slot
      for (int l = 0; l < 4; ++l)
        for (int j = 0; j < 3; ++j) {
          double* out = rhs + 4 * static_cast<std::size_t>(corner[3 * l + j]);
          _mm256_store_pd(out, _mm256_add_pd(_mm256_load_pd(out), u[j][l]));
        }
    }
  }
  return vanishing;
}
#endif

}  // namespace

// Step 5 of Deform() for the slots of blocks [block_begin, block_end); rhs is 32-byte aligned.
// Returns the number of faces whose interpolated quaternion vanished.
int AssembleFaces(const FaceAssembly& in, int block_begin, int block_end, double* face_q, double* rhs) {
#if defined(__x86_64__)
  if (__builtin_cpu_supports("avx2") && __builtin_cpu_supports("fma"))
    return AssembleFacesAvx2(in, block_begin, block_end, face_q, rhs);
#endif
  return AssembleFacesGeneric(in, block_begin, block_end, face_q, rhs);
}

}  // namespace confluent::deform_internal
