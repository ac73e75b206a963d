// Internal to core/encode: the numbers of the glTF 2.0 binary container and
// of the glTF enums glb.cpp writes and glb_decode.cpp reads.
#pragma once

#include <cstdint>

namespace tinsmith::encode::glb_format {

inline constexpr std::uint32_t kMagic = 0x46546C67;  // "glTF", little-endian
inline constexpr std::uint32_t kVersion = 2;
inline constexpr std::uint32_t kChunkJson = 0x4E4F534A;  // "JSON"
inline constexpr std::uint32_t kChunkBin = 0x004E4942;   // "BIN\0"
inline constexpr std::uint32_t kHeaderBytes = 12;
inline constexpr std::uint32_t kChunkHeaderBytes = 8;

inline constexpr int kUnsignedByte = 5121;
inline constexpr int kUnsignedShort = 5123;
inline constexpr int kUnsignedInt = 5125;
inline constexpr int kFloat = 5126;

inline constexpr int kArrayBuffer = 34962;
inline constexpr int kElementArrayBuffer = 34963;

inline constexpr int kTriangles = 4;

inline constexpr const char* kDracoExtension = "KHR_draco_mesh_compression";

}  // namespace tinsmith::encode::glb_format
