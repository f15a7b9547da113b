// The DDS test-domain claim: distinct ids within a process, and an id another process holds is
// never handed out.
#include "tests/support/test_domain.h"

#include <cstdlib>
#include <filesystem>
#include <string>

#include <gtest/gtest.h>

namespace mpdrig::testing {
namespace {

TEST(TestDomain, ClaimsAreDistinctAndSkipIdsHeldElsewhere) {
  const int first = ClaimTestDomain();
  const int second = ClaimTestDomain();
  ASSERT_GT(first, 0);
  ASSERT_GT(second, 0);
  EXPECT_NE(first, second);

  // Another process holds the next free id for a few seconds; our next claim must skip it.
  const int held = second + 1;
  const std::string lock = std::filesystem::temp_directory_path().string() +
                           "/mpdrig-test-dds-domain-" + std::to_string(held) + ".lock";
  const std::string command = "flock -n '" + lock + "' sleep 3 & sleep 0.5";
  ASSERT_EQ(std::system(command.c_str()), 0);
  const int third = ClaimTestDomain();
  EXPECT_NE(third, held) << "an id held by another process was handed out";
  EXPECT_NE(third, first);
  EXPECT_NE(third, second);
}

}  // namespace
}  // namespace mpdrig::testing
