#include "noctua/util/version.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <string>

namespace noctua {
namespace {

TEST(Version, LibraryAndHeadersAgreeOnMajorMinorPatch) {
  EXPECT_EQ(Version(), NOCTUA_VERSION_STRING);
  EXPECT_EQ(Version(), std::to_string(NOCTUA_VERSION_MAJOR) + "." +
                           std::to_string(NOCTUA_VERSION_MINOR) + "." +
                           std::to_string(NOCTUA_VERSION_PATCH));
  EXPECT_THAT(Version(), ::testing::MatchesRegex("[0-9]+\\.[0-9]+\\.[0-9]+"));
}

}  // namespace
}  // namespace noctua
