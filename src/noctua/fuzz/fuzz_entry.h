#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

namespace noctua::fuzz {

// Entry points shared by the libFuzzer targets (fuzz/, built with -DNOCTUA_FUZZ=ON and clang)
// and the corpus replay test of the normal build. Each feeds arbitrary bytes to one reader and
// returns true when the input was accepted, false when it was refused with noctua::Error. Any
// other outcome (a crash, a sanitizer report, another exception escaping) is a bug.

// A TUM trajectory file (ReadTumTrajectory), then its TUM text read back.
bool TrajectoryEntry(const std::uint8_t* data, std::size_t size);
// An association list and a "timestamp file" list (ReadAssociationList, ReadTimedFileList),
// then the colour/depth pairing of the latter with itself.
bool AssociationEntry(const std::uint8_t* data, std::size_t size);
// A settings file: camera (ReadCameraConfig), extractor (LoadExtractorOptions) and SLAM
// (LoadSlamSetup) settings.
bool SettingsEntry(const std::uint8_t* data, std::size_t size);
// The extractor on a small image: byte 0 picks the width (1-64), byte 1 the height (1-64),
// byte 2 the channel count (1, 3 or 4) and the method; the rest are the pixels (repeated).
bool ExtractorEntry(const std::uint8_t* data, std::size_t size);

// The targets by name ("trajectory", "association", "settings", "extractor").
using EntryFunction = bool (*)(const std::uint8_t*, std::size_t);
EntryFunction EntryByName(const std::string& name);
std::vector<std::string> TargetNames();

}  // namespace noctua::fuzz
