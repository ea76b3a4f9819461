#include "deform/point_cache.h"

#include <cstdint>
#include <cstring>
#include <filesystem>
#include <stdexcept>
#include <vector>

#include "core/error.h"

namespace confluent {

namespace {
static_assert(sizeof(float) == 4, "PC2 needs 32-bit floats");
constexpr char kMagic[12] = {'P', 'O', 'I', 'N', 'T', 'C', 'A', 'C', 'H', 'E', '2', '\0'};
constexpr long kSamplesOffset = 12 + 4 + 4 + 4 + 4;
}  // namespace

PointCacheWriter::PointCacheWriter(const std::string& path, int num_points, double start_frame, double sample_rate)
    : path_(path), temporary_path_(path + ".tmp"), num_points_(num_points) {
  std::error_code error;
  const std::filesystem::path parent = std::filesystem::path(path).parent_path();
  if (!parent.empty()) std::filesystem::create_directories(parent, error);
  file_ = std::fopen(temporary_path_.c_str(), "wb");
  if (file_ == nullptr) throw OutputError(path, "cannot open for writing");
  const std::int32_t version = 1, points = num_points, samples = 0;
  const float start = static_cast<float>(start_frame), rate = static_cast<float>(sample_rate);
  bool ok = std::fwrite(kMagic, 1, 12, file_) == 12;
  ok = ok && std::fwrite(&version, 4, 1, file_) == 1 && std::fwrite(&points, 4, 1, file_) == 1;
  ok = ok && std::fwrite(&start, 4, 1, file_) == 1 && std::fwrite(&rate, 4, 1, file_) == 1;
  ok = ok && std::fwrite(&samples, 4, 1, file_) == 1;
  if (!ok) throw OutputError(path, "write failed");
}

PointCacheWriter::~PointCacheWriter() {
  if (file_ != nullptr) {
    std::fclose(file_);
    std::remove(temporary_path_.c_str());
  }
}

void PointCacheWriter::Append(const RowMatrixX3d& points) {
  if (points.rows() != num_points_) throw std::invalid_argument("point cache frame has the wrong number of points");
  if (file_ == nullptr) throw OutputError(path_, "cache already finished");
  const Eigen::Matrix<float, Eigen::Dynamic, 3, Eigen::RowMajor> data = points.cast<float>();
  if (std::fwrite(data.data(), sizeof(float), data.size(), file_) != static_cast<std::size_t>(data.size()))
    throw OutputError(path_, "write failed (disk full?)");
  ++num_samples_;
}

void PointCacheWriter::Finish() {
  if (file_ == nullptr) throw OutputError(path_, "cache already finished");
  const std::int32_t samples = num_samples_;
  bool ok = std::fseek(file_, kSamplesOffset, SEEK_SET) == 0 && std::fwrite(&samples, 4, 1, file_) == 1;
  ok = (std::fclose(file_) == 0) && ok;
  file_ = nullptr;
  if (!ok || std::rename(temporary_path_.c_str(), path_.c_str()) != 0) {
    std::remove(temporary_path_.c_str());
    throw OutputError(path_, "cannot finish the point cache");
  }
}

std::vector<RowMatrixX3d> ReadPointCache(const std::string& path) {
  std::FILE* file = std::fopen(path.c_str(), "rb");
  if (file == nullptr) throw InputError(path, "cannot open");
  char magic[12];
  std::int32_t version = 0, points = 0, samples = 0;
  float start = 0, rate = 0;
  bool ok = std::fread(magic, 1, 12, file) == 12 && std::memcmp(magic, kMagic, 12) == 0;
  ok = ok && std::fread(&version, 4, 1, file) == 1 && std::fread(&points, 4, 1, file) == 1;
  ok = ok && std::fread(&start, 4, 1, file) == 1 && std::fread(&rate, 4, 1, file) == 1;
  ok = ok && std::fread(&samples, 4, 1, file) == 1 && points >= 0 && samples >= 0;
  std::vector<RowMatrixX3d> frames;
  Eigen::Matrix<float, Eigen::Dynamic, 3, Eigen::RowMajor> data(ok ? points : 0, 3);
  for (int s = 0; ok && s < samples; ++s) {
    ok = std::fread(data.data(), sizeof(float), data.size(), file) == static_cast<std::size_t>(data.size());
    if (ok) frames.push_back(data.cast<double>());
  }
  std::fclose(file);
  if (!ok) throw InputError(path, "not a valid PC2 point cache (bad header or truncated)");
  return frames;
}

}  // namespace confluent
