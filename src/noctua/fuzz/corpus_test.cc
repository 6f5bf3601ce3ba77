// Replays every file of fuzz/corpus/<target>/ and fuzz/crashes/<target>/ through the same entry
// function the libFuzzer target calls: inputs that once crashed stay fixed, and the sanitizer
// build checks the whole corpus on every CI run.
#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <iterator>

#include "noctua/fuzz/fuzz_entry.h"

namespace noctua::fuzz {
namespace {

namespace fs = std::filesystem;

std::vector<fs::path> FilesUnder(const fs::path& dir) {
  std::vector<fs::path> files;
  if (!fs::is_directory(dir)) return files;
  for (const auto& entry : fs::directory_iterator(dir)) {
    if (entry.is_regular_file() && entry.path().filename() != "README.md") {
      files.push_back(entry.path());
    }
  }
  std::sort(files.begin(), files.end());
  return files;
}

class CorpusTest : public ::testing::TestWithParam<std::string> {};

TEST_P(CorpusTest, EveryCorpusAndCrashFileIsAcceptedOrRefusedCleanly) {
  const EntryFunction entry = EntryByName(GetParam());
  const fs::path root = fs::path(NOCTUA_SOURCE_DIR) / "fuzz";
  std::vector<fs::path> files = FilesUnder(root / "corpus" / GetParam());
  ASSERT_GE(files.size(), 3u) << "the corpus of " << GetParam() << " is missing";
  for (const fs::path& crash : FilesUnder(root / "crashes" / GetParam())) files.push_back(crash);
  int accepted = 0;
  for (const fs::path& file : files) {
    std::ifstream in(file, std::ios::binary);
    const std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    bool ok = false;
    EXPECT_NO_THROW(ok = entry(reinterpret_cast<const std::uint8_t*>(bytes.data()), bytes.size()))
        << file;
    accepted += ok ? 1 : 0;
  }
  // The seeds are valid files: a reader that refused everything would pass otherwise.
  EXPECT_GT(accepted, 0) << GetParam();
}

INSTANTIATE_TEST_SUITE_P(Targets, CorpusTest, ::testing::ValuesIn(TargetNames()));

}  // namespace
}  // namespace noctua::fuzz
