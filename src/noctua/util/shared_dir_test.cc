#include "noctua/util/shared_dir.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <cstdlib>
#include <filesystem>
#include <string>

#include "noctua/util/error.h"

namespace noctua {
namespace {

class FindSharedDirTest : public ::testing::Test {
 protected:
  void SetUp() override {
    std::filesystem::create_directories(dir_ / "from_environment" / "data");
    std::filesystem::create_directories(dir_ / "fallback" / "data");
    std::filesystem::create_directories(dir_ / "empty");
    if (const char* value = std::getenv("NOCTUA_SHARED_DIR")) saved_ = value;
  }
  void TearDown() override {
    if (saved_.empty()) {
      unsetenv("NOCTUA_SHARED_DIR");
    } else {
      setenv("NOCTUA_SHARED_DIR", saved_.c_str(), 1);
    }
    std::filesystem::remove_all(dir_);
  }
  std::filesystem::path dir_ = std::filesystem::temp_directory_path() /
                               ("noctua_shared_dir_test_" + std::to_string(getpid()));
  std::string saved_;
};

TEST_F(FindSharedDirTest, TheEnvironmentVariableWinsOverTheFallback) {
  setenv("NOCTUA_SHARED_DIR", (dir_ / "from_environment").c_str(), 1);
  EXPECT_EQ(FindSharedDir(dir_ / "fallback"), dir_ / "from_environment");
}

TEST_F(FindSharedDirTest, WithoutTheVariableTheFallbackIsUsed) {
  unsetenv("NOCTUA_SHARED_DIR");
  EXPECT_EQ(FindSharedDir(dir_ / "fallback"), dir_ / "fallback");
  setenv("NOCTUA_SHARED_DIR", "", 1);
  EXPECT_EQ(FindSharedDir(dir_ / "fallback"), dir_ / "fallback");
}

TEST_F(FindSharedDirTest, AFolderWithoutDataThrowsNamingIt) {
  unsetenv("NOCTUA_SHARED_DIR");
  try {
    FindSharedDir(dir_ / "empty");
    FAIL() << "no exception";
  } catch (const Error& error) {
    EXPECT_NE(std::string(error.what()).find((dir_ / "empty").string()), std::string::npos);
  }
}

}  // namespace
}  // namespace noctua
