// The resonance list (resonance_list.h): the thesis's three peaks read back; every bad line
// rejected with file:line:column.
#include "model/analysis/resonance_list.h"

#include <gtest/gtest.h>

namespace mpdrig {
namespace {

std::string Error(std::string_view text) {
  auto parsed = ParseResonanceList(text, "r.csv");
  EXPECT_FALSE(parsed.ok()) << text;
  return parsed.ok() ? "" : parsed.status().message();
}

TEST(ResonanceList, ReadsTheThesisPeaks) {
  auto list =
      ReadResonanceList(std::string(MPDRIG_SOURCE_DIR) + "/docs/examples/thesis-resonances.csv");
  ASSERT_TRUE(list.ok()) << list.status().message();
  ASSERT_EQ(list->size(), 3u);
  EXPECT_EQ((*list)[0].configuration, Termination::kChokeClosed);
  EXPECT_DOUBLE_EQ((*list)[0].frequency_hz, 0.44);
  EXPECT_EQ((*list)[1].configuration, Termination::kChokeOpen);
  EXPECT_DOUBLE_EQ((*list)[1].frequency_hz, 0.25);
  EXPECT_EQ((*list)[2].configuration, Termination::kClosedAtPipeEnd);
  EXPECT_DOUBLE_EQ((*list)[2].frequency_hz, 0.49);
  EXPECT_DOUBLE_EQ((*list)[2].uncertainty_hz, 0.01);
  EXPECT_EQ((*list)[2].line, 4);
}

TEST(ResonanceList, CommentsBlankLinesAndCrlfAreFine) {
  auto list = ParseResonanceList(
      "# the rig, 2024\r\nconfiguration,frequency_hz,uncertainty_hz\r\n\r\nchoke-open, 0.25 "
      ",0.01\r\n",
      "r.csv");
  ASSERT_TRUE(list.ok()) << list.status().message();
  ASSERT_EQ(list->size(), 1u);
  EXPECT_EQ((*list)[0].line, 4);
}

TEST(ResonanceList, BadLinesNameFileLineAndColumn) {
  const std::string header = "configuration,frequency_hz,uncertainty_hz\n";
  EXPECT_EQ(Error("configuration,frequency\nchoke-open,0.25,0.01\n")
                .rfind("r.csv:1:1: expected the header", 0),
            0u);
  // An unknown configuration: column 1, the valid names listed.
  const std::string unknown = Error(header + "choke-open,0.25,0.01\nvalve,0.49,0.01\n");
  EXPECT_EQ(unknown.rfind("r.csv:3:1: unknown termination 'valve'", 0), 0u) << unknown;
  EXPECT_NE(unknown.find("closed-at-pipe-end"), std::string::npos);
  // Not a number, NaN, zero, negative: the field's column.
  EXPECT_EQ(Error(header + "choke-open,0.2x,0.01\n").rfind("r.csv:2:12: frequency_hz: '0.2x'", 0),
            0u);
  EXPECT_EQ(Error(header + "choke-open,nan,0.01\n").rfind("r.csv:2:12:", 0), 0u);
  EXPECT_EQ(
      Error(header + "choke-open,0.25,0\n").rfind("r.csv:2:17: uncertainty_hz must be > 0", 0), 0u);
  EXPECT_EQ(
      Error(header + "choke-open,-0.25,0.01\n").rfind("r.csv:2:12: frequency_hz must be > 0", 0),
      0u);
  EXPECT_EQ(Error(header + "choke-open,0.25,\n").rfind("r.csv:2:17: uncertainty_hz: ''", 0), 0u);
  // Too few and too many fields.
  EXPECT_EQ(Error(header + "choke-open,0.25\n").rfind("r.csv:2:16: expected 3 fields", 0), 0u);
  EXPECT_EQ(Error(header + "choke-open,0.25,0.01,x\n").rfind("r.csv:2:21: expected 3 fields", 0),
            0u);
  // A configuration twice.
  EXPECT_EQ(Error(header + "choke-open,0.25,0.01\nchoke-open,0.26,0.01\n")
                .rfind("r.csv:3:1: configuration 'choke-open' again (first on line 2)", 0),
            0u);
  // Nothing after the header, nothing at all.
  EXPECT_NE(Error(header).find("no resonance"), std::string::npos);
  EXPECT_NE(Error("").find("no header"), std::string::npos);
  auto missing = ReadResonanceList("/nonexistent/r.csv");
  ASSERT_FALSE(missing.ok());
  EXPECT_NE(missing.status().message().find("/nonexistent/r.csv"), std::string::npos);
}

}  // namespace
}  // namespace mpdrig
