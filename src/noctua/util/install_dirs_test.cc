#include "noctua/util/install_dirs.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <cstdlib>
#include <filesystem>
#include <string>

#include "noctua/util/error.h"

namespace noctua {
namespace {

class FindConfigDirTest : public ::testing::Test {
 protected:
  void SetUp() override {
    std::filesystem::create_directories(dir_ / "installed");
    std::filesystem::create_directories(dir_ / "source");
    if (const char* value = std::getenv("NOCTUA_CONFIG_DIR")) saved_ = value;
    unsetenv("NOCTUA_CONFIG_DIR");
  }
  void TearDown() override {
    if (!saved_.empty()) setenv("NOCTUA_CONFIG_DIR", saved_.c_str(), 1);
    std::filesystem::remove_all(dir_);
  }
  std::filesystem::path dir_ = std::filesystem::temp_directory_path() /
                               ("noctua_config_dir_test_" + std::to_string(getpid()));
  std::string saved_;
};

TEST_F(FindConfigDirTest, TheFirstExistingCandidateWins) {
  EXPECT_EQ(FindConfigDir({dir_ / "missing", dir_ / "installed", dir_ / "source"}),
            dir_ / "installed");
}

TEST_F(FindConfigDirTest, TheEnvironmentVariableWinsOverTheCandidates) {
  setenv("NOCTUA_CONFIG_DIR", (dir_ / "source").c_str(), 1);
  EXPECT_EQ(FindConfigDir({dir_ / "installed"}), dir_ / "source");
}

TEST_F(FindConfigDirTest, NoFolderNamesEveryPlaceLookedAt) {
  try {
    FindConfigDir({dir_ / "a", dir_ / "b"});
    FAIL() << "no error";
  } catch (const Error& error) {
    EXPECT_NE(std::string(error.what()).find((dir_ / "b").string()), std::string::npos);
  }
}

TEST(ExecutableDirTest, IsTheTestsOwnFolder) {
  EXPECT_TRUE(std::filesystem::exists(ExecutableDir() / "util_test"));
}

}  // namespace
}  // namespace noctua
