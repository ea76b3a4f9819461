#pragma once
// The GLB container and the glTF names shared by export/gltf_writer.cc and export/gltf_reader.cc.

#include <cstdint>
#include <string>
#include <vector>

namespace confluent::gltf {

// glTF componentType and bufferView target codes.
constexpr int kByte = 5120;
constexpr int kUnsignedByte = 5121;
constexpr int kShort = 5122;
constexpr int kUnsignedShort = 5123;
constexpr int kUnsignedInt = 5125;
constexpr int kFloat = 5126;
constexpr int kArrayBuffer = 34962;
constexpr int kElementArrayBuffer = 34963;

constexpr const char* kMeshopt = "EXT_meshopt_compression";
constexpr const char* kQuantization = "KHR_mesh_quantization";
constexpr const char* kUnlit = "KHR_materials_unlit";

// The root node: a -90 degree rotation about x from confluent's world (Z up) to glTF's (Y up).
constexpr const char* kRootName = "confluent_z_up";

// "frame_000012": the name of frame k's node and mesh.
std::string FrameName(int frame);

// A GLB file: 12-byte header, the JSON chunk (space-padded) and the binary chunk (zero-padded).
std::vector<std::uint8_t> PackGlb(const std::string& json_text, const std::vector<std::uint8_t>& bin);

// Splits GLB bytes into the JSON text and the binary chunk (empty when absent). Throws
// InputError(name) when the header, a chunk length or the chunk order is wrong.
void UnpackGlb(const std::vector<std::uint8_t>& glb, const std::string& name, std::string* json_text,
               std::vector<std::uint8_t>* bin);

}  // namespace confluent::gltf
