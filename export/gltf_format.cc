#include "export/gltf_format.h"

#include <cstdio>
#include <cstring>

#include "core/error.h"

namespace confluent::gltf {
namespace {

constexpr std::uint32_t kMagic = 0x46546C67;  // "glTF"
constexpr std::uint32_t kJsonChunk = 0x4E4F534A;
constexpr std::uint32_t kBinChunk = 0x004E4942;

void PutU32(std::vector<std::uint8_t>* out, std::uint32_t value) {
  for (int i = 0; i < 4; ++i) out->push_back(static_cast<std::uint8_t>(value >> (8 * i)));
}

std::uint32_t GetU32(const std::vector<std::uint8_t>& in, std::size_t offset) {
  std::uint32_t value = 0;
  for (int i = 0; i < 4; ++i) value |= static_cast<std::uint32_t>(in[offset + i]) << (8 * i);
  return value;
}

}  // namespace

std::string FrameName(int frame) {
  char name[32];
  std::snprintf(name, sizeof(name), "frame_%06d", frame);
  return name;
}

std::vector<std::uint8_t> PackGlb(const std::string& json_text, const std::vector<std::uint8_t>& bin) {
  std::string text = json_text;
  text.resize((text.size() + 3) & ~std::size_t{3}, ' ');
  const std::size_t bin_size = (bin.size() + 3) & ~std::size_t{3};
  std::vector<std::uint8_t> glb;
  glb.reserve(12 + 8 + text.size() + 8 + bin_size);
  PutU32(&glb, kMagic);
  PutU32(&glb, 2);
  PutU32(&glb, static_cast<std::uint32_t>(12 + 8 + text.size() + (bin.empty() ? 0 : 8 + bin_size)));
  PutU32(&glb, static_cast<std::uint32_t>(text.size()));
  PutU32(&glb, kJsonChunk);
  glb.insert(glb.end(), text.begin(), text.end());
  if (!bin.empty()) {
    PutU32(&glb, static_cast<std::uint32_t>(bin_size));
    PutU32(&glb, kBinChunk);
    glb.insert(glb.end(), bin.begin(), bin.end());
    glb.resize(glb.size() + bin_size - bin.size(), 0);
  }
  return glb;
}

void UnpackGlb(const std::vector<std::uint8_t>& glb, const std::string& name, std::string* json_text,
               std::vector<std::uint8_t>* bin) {
  if (glb.size() < 20 || GetU32(glb, 0) != kMagic) throw InputError(name, "is not a binary glTF (GLB) file");
  if (GetU32(glb, 4) != 2) throw InputError(name, "GLB version " + std::to_string(GetU32(glb, 4)) + " is not 2");
  if (GetU32(glb, 8) != glb.size()) throw InputError(name, "GLB length in the header does not match the file size");
  const std::size_t json_size = GetU32(glb, 12);
  if (GetU32(glb, 16) != kJsonChunk || 20 + json_size > glb.size()) throw InputError(name, "bad GLB JSON chunk");
  json_text->assign(reinterpret_cast<const char*>(glb.data()) + 20, json_size);
  bin->clear();
  const std::size_t next = 20 + json_size;
  if (next == glb.size()) return;
  if (next + 8 > glb.size()) throw InputError(name, "truncated GLB chunk header");
  const std::size_t bin_size = GetU32(glb, next);
  if (GetU32(glb, next + 4) != kBinChunk || next + 8 + bin_size > glb.size()) throw InputError(name, "bad GLB binary chunk");
  bin->assign(glb.begin() + next + 8, glb.begin() + next + 8 + bin_size);
}

}  // namespace confluent::gltf
