#pragma once

#include <cstdint>
#include <filesystem>
#include <string>
#include <string_view>

#include "noctua/geometry/camera.h"
#include "noctua/slam/map.h"
#include "noctua/slam/slam_options.h"

namespace noctua::slam {

// What a saved map is only valid with: the features it was made from (the feature method and
// the pyramid their octaves refer to), the camera its keypoints were seen with, the virtual
// baseline of its right coordinates and, once there is one, the place-recognition vocabulary.
struct MapIdentity {
  std::string method;  // feature method name (pipeline::CreateMethod)
  geometry::Intrinsics intrinsics;
  geometry::Distortion distortion;
  double scale_factor = 1.2;
  int num_levels = 8;
  double bf = 40.0;
  std::string vocabulary;  // identity of the vocabulary; "" while the SLAM uses none

  // Throws noctua::Error naming `file` and the first field in which `other` (the map's identity)
  // differs from this one (the run's).
  void CheckSameAs(const MapIdentity& other, const std::filesystem::path& file) const;
};

MapIdentity MakeMapIdentity(const std::string& method, const geometry::PinholeCamera& camera,
                            const SlamOptions& options);

// The binary format (docs/slam.md, "Saving and reusing a map"): a 24-byte header (magic bytes,
// format version, payload length, CRC-32 of the payload) and a payload of tagged, length-prefixed
// sections, every number little-endian and fixed-width. A new version is written whenever the
// layout changes; readers refuse any other version.
inline constexpr char kMapMagic[8] = {'N', 'O', 'C', 'T', 'M', 'A', 'P', '\0'};
inline constexpr std::uint32_t kMapFormatVersion = 2;
inline constexpr std::size_t kMapHeaderBytes = 24;
inline constexpr std::size_t kMapChecksumOffset = 20;

// CRC-32 (IEEE 802.3, as zlib and PNG compute it).
std::uint32_t Crc32(std::string_view bytes);

// The good keyframes and map points with their features, observations and covisibility,
// renumbered in id order; culled ones and the trackers' scratch are left out. The same map gives
// the same bytes.
std::string SerializeMap(const Map& map, const MapIdentity& identity);
// Writes SerializeMap atomically; throws noctua::Error naming the file when it cannot.
void SaveMap(const Map& map, const MapIdentity& identity, const std::filesystem::path& path);

// Reads a map back. Throws noctua::Error naming `name` (the file) for bytes that are not a map
// of this format version, truncated or damaged bytes, or a map whose identity differs from
// `expected` (the run's): never a map that would mislead or crash the tracker.
Map ParseMap(std::string_view bytes, const MapIdentity& expected, const std::string& name);
// ParseMap of a file's bytes; a missing or unreadable file is refused the same way.
Map LoadMap(const std::filesystem::path& path, const MapIdentity& expected);

}  // namespace noctua::slam
