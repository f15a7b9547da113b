// Every JSON the `mpdrig` commands write keeps a string as it was: a log path with quotes,
// backslashes, control characters, non-ASCII UTF-8 and a byte that is not UTF-8 is read back
// (nlohmann-json's parser) from compare, traveltime, freqresp --from-log, fit, fit --resonances,
// diagnose --resonances and the diagnosis's JSON. Escaping was the bug class of the hand-written
// writers (one dropped control characters, one made them spaces). A 15 s log keeps it cheap: the
// commands' numbers are the other tests' business.
#include <sys/wait.h>
#include <unistd.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "tests/support/shell.h"
#include "tools/report/diagnosis_report.h"

namespace mpdrig {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;

// ", \, a newline, a tab, U+0001, ö and ∆ (2- and 3-byte UTF-8).
const std::string kNasty = "log \"q\" back\\slash\nline\ttab\x01 \xc3\xb6 \xe2\x88\x86";

std::string Quote(const std::string& text) {  // for sh: '...' holds anything but '
  return "'" + text + "'";
}

class JsonStringsTest : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    // One per process: ctest runs each test of this suite in a process of its own, maybe at once.
    dir_ = fs::temp_directory_path() / ("mpdrig_json_strings_test." + std::to_string(::getpid()));
    fs::remove_all(dir_);
    fs::create_directories(dir_ / kNasty);
    // 15 s of the lab's excitation (choke and pump steps give traveltime its fronts).
    made_ = Run("synth --seed 2 --duration 15 --out " + Quote(Log())) == 0;
    made_output_ = Output();
    std::ofstream(dir_ / kNasty / "list.csv") << "configuration,frequency_hz,uncertainty_hz\n"
                                              << "choke-closed,0.44,0.01\nchoke-open,0.25,0.01\n";
  }
  // A failed setup fails every test (an ASSERT in SetUpTestSuite would only skip them).
  void SetUp() override { ASSERT_TRUE(made_) << made_output_; }
  static void TearDownTestSuite() {
    if (!::testing::UnitTest::GetInstance()->failed_test_count()) fs::remove_all(dir_);
  }

  static std::string Log() { return kNasty + "/lab.csv"; }
  static std::string List() { return kNasty + "/list.csv"; }

  // `mpdrig ARGS` in the test's directory (paths relative to it); its exit code.
  static int Run(const std::string& args) {
    const std::string command = "cd " + Quote(dir_.string()) + " && " + Quote(MPDRIG_EXE) + " " +
                                args + " > output.txt 2>&1";
    const int status = std::system(command.c_str());
    return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  }
  static std::string Output() { return testing::ReadFile(dir_ / "output.txt"); }

  // The file a command wrote, parsed (a parse error fails the test with the text).
  static json Parsed(const std::string& name) {
    const std::string text = testing::ReadFile(dir_ / name);
    json parsed;
    EXPECT_NO_THROW(parsed = json::parse(text)) << name << ":\n" << text;
    return parsed;
  }

  static fs::path dir_;
  static bool made_;
  static std::string made_output_;
};

fs::path JsonStringsTest::dir_;
bool JsonStringsTest::made_ = false;
std::string JsonStringsTest::made_output_;

TEST_F(JsonStringsTest, ALogPathComesBackFromEveryCommandsJson) {
  ASSERT_EQ(Run("compare " + Quote(Log()) + " --cells 20 --json compare.json --quiet"), 0)
      << Output();
  EXPECT_EQ(Parsed("compare.json")["log"], Log());

  ASSERT_EQ(Run("freqresp --from-log " + Quote(Log()) + " --segment-s 6 --json freqresp.json"), 0)
      << Output();
  EXPECT_EQ(Parsed("freqresp.json")["log"], Log());

  ASSERT_EQ(Run("traveltime " + Quote(Log()) + " --json traveltime.json --quiet"), 0) << Output();
  EXPECT_EQ(Parsed("traveltime.json")["log"], Log());

  ASSERT_EQ(Run("fit " + Quote(Log()) +
                " --params wave_speed_mps --cells 20 --window-s 0:6 --json fit.json --quiet"),
            0)
      << Output();
  EXPECT_EQ(Parsed("fit.json")["log"], Log());

  ASSERT_EQ(Run("fit --resonances " + Quote(List()) + " --response analytic --json fitres.json"), 0)
      << Output();
  EXPECT_EQ(Parsed("fitres.json")["resonances"], List());

  ASSERT_EQ(Run("diagnose --resonances " + Quote(List()) +
                " --set wave_speed_mps=1173 --hold wave_speed_mps --response analytic "
                "--json diagres.json"),
            0)
      << Output();
  EXPECT_EQ(Parsed("diagres.json")["resonance_list"], List());
}

// A path is bytes, not always UTF-8: a stray byte becomes U+FFFD, and the JSON stays valid.
TEST_F(JsonStringsTest, APathThatIsNotUtf8StillGivesValidJson) {
  const std::string bad = kNasty + "/lab\xff.csv";
  fs::copy_file(dir_ / Log(), dir_ / bad, fs::copy_options::overwrite_existing);
  ASSERT_EQ(Run("traveltime " + Quote(bad) + " --json bad.json --quiet"), 0) << Output();
  EXPECT_EQ(Parsed("bad.json")["log"], kNasty + "/lab\xef\xbf\xbd.csv");
}

// diagnose on a log takes minutes; its JSON writer is tested here on a diagnosis made by hand.
TEST(DiagnosisJsonStrings, EveryTextFieldComesBackAsItWas) {
  Diagnosis d;
  d.selection_end = kNasty;
  d.equivalent = {kNasty};
  CandidateResult failed;
  failed.effect = kNasty;
  failed.failure = kNasty;
  d.failed.push_back(failed);
  const json parsed = json::parse(report::DiagnosisJson(d, kNasty));
  EXPECT_EQ(parsed["log"], kNasty);
  EXPECT_EQ(parsed["selection_end"], kNasty);
  EXPECT_EQ(parsed["equivalent"][0], kNasty);
  EXPECT_EQ(parsed["failed"][0]["effect"], kNasty);
  EXPECT_EQ(parsed["failed"][0]["failure"], kNasty);
  EXPECT_TRUE(parsed["verdict"].is_null());
}

}  // namespace
}  // namespace mpdrig
