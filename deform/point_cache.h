#pragma once
// PC2 point caches (the format of Blender's Mesh Cache modifier and 3ds Max's Point Cache):
// a header, then float32 x y z per vertex per frame.

#include <cstdio>
#include <string>
#include <vector>

#include "core/mesh.h"

namespace confluent {

// Streams frames into a .pc2 file: header "POINTCACHE2\0", int32 version 1, int32 number of
// points, float32 start frame, float32 sample rate (frames per sample), int32 number of
// samples; then per frame n x 3 float32 positions, little-endian. The file is written to a
// temporary name and renamed by Finish(), so an interrupted run leaves no partial cache.
class PointCacheWriter {
 public:
  // Opens `path` for writing a cache of `num_points` points. Throws OutputError on failure.
  PointCacheWriter(const std::string& path, int num_points, double start_frame = 0.0, double sample_rate = 1.0);
  ~PointCacheWriter();  // removes the temporary file unless Finish() ran
  PointCacheWriter(const PointCacheWriter&) = delete;
  PointCacheWriter& operator=(const PointCacheWriter&) = delete;

  // Appends one frame (num_points x 3, metres). Throws OutputError on a write failure and
  // std::invalid_argument on a wrong row count.
  void Append(const RowMatrixX3d& points);
  // Writes the sample count and renames the file into place. Throws OutputError.
  void Finish();
  int num_samples() const { return num_samples_; }

 private:
  std::string path_, temporary_path_;
  std::FILE* file_ = nullptr;
  int num_points_ = 0;
  int num_samples_ = 0;
};

// Reads a .pc2 file into frames (for tests and tools). Throws InputError naming the file.
std::vector<RowMatrixX3d> ReadPointCache(const std::string& path);

}  // namespace confluent
