// model/ is pure numerics (style.md, design.md): no DDS, no threads, no wall clock, no sockets, no
// environment variables, and no dependency on the layers above it (idl/, service/, tools/,
// clients/). Time is an argument. This test scans every source and build file under model/ and
// names each offending line.
#include <algorithm>
#include <filesystem>
#include <fstream>
#include <regex>
#include <sstream>
#include <string>
#include <vector>

#include <gtest/gtest.h>

namespace mpdrig {
namespace {

namespace fs = std::filesystem;

struct Rule {
  const char* what;
  std::regex pattern;
};

// Rules for C++ sources and .proto files. Matched against each line with its `//` comment
// removed, so a header may still say "no wall clock here".
const std::vector<Rule>& SourceRules() {
  static const std::vector<Rule> rules = {
      {"DDS header",
       std::regex(R"(^\s*#\s*include\s*[<"](dds|ddsc|ddscxx|org/eclipse/cyclonedds)/)")},
      {"DDS header", std::regex(R"(^\s*#\s*include\s*[<"]dds\.h[>"])")},
      {"generated DDS type (idl/)", std::regex(R"(^\s*#\s*include\s*"idl/)")},
      {"upper layer (service/, tools/ or clients/)",
       std::regex(R"(^\s*#\s*include\s*"(service|tools|clients)/)")},
      {"threads", std::regex(R"(^\s*#\s*include\s*<(thread|future|stop_token|pthread\.h)>)")},
      {"threads", std::regex(R"(std::(thread|jthread|async|this_thread)\b)")},
      {"wall clock", std::regex(R"(\b(system_clock|steady_clock|high_resolution_clock)\b)")},
      {"wall clock", std::regex(R"(\b(gettimeofday|clock_gettime|timespec_get)\s*\()")},
      // Configuration reaches the model as arguments (options structs); the command line reads
      // the environment and passes what it found.
      {"environment variable", std::regex(R"(\b(getenv|secure_getenv|setenv|putenv)\s*\()")},
      {"sockets",
       std::regex(
           R"(^\s*#\s*include\s*<(sys/socket\.h|netinet/[^>]*|arpa/inet\.h|netdb\.h|winsock2?\.h|asio\.hpp|boost/asio[^>]*)>)")},
  };
  return rules;
}

// Rules for CMake files: model/ must not link DDS or a threads library.
const std::vector<Rule>& CMakeRules() {
  static const std::vector<Rule> rules = {
      {"links DDS", std::regex(R"(\b(CycloneDDS|CycloneDDS-CXX|ddsc|ddscxx)\b)")},
      {"links threads", std::regex(R"(Threads::Threads|\bpthread\b)")},
      // The project's libraries model/ may link are its own two; any other is an upper layer.
      {"links an upper layer", std::regex(R"(\bmpdrig_(?!model\b|config_proto\b)\w+)")},
  };
  return rules;
}

bool IsCMake(const fs::path& path) {
  return path.filename() == "CMakeLists.txt" || path.extension() == ".cmake";
}

bool IsSource(const fs::path& path) {
  static const std::vector<std::string> extensions = {".h",   ".hh", ".hpp", ".cc",   ".cpp",
                                                      ".cxx", ".c",  ".inc", ".proto"};
  return std::find(extensions.begin(), extensions.end(), path.extension().string()) !=
         extensions.end();
}

// "name:line: what: text" for every offending line of `text`.
std::vector<std::string> FindViolations(const std::string& name, const std::string& text,
                                        bool cmake) {
  std::vector<std::string> violations;
  std::istringstream in(text);
  std::string line;
  int number = 0;
  while (std::getline(in, line)) {
    ++number;
    std::string code = line;
    const std::size_t comment = code.find(cmake ? "#" : "//");
    if (comment != std::string::npos) code.erase(comment);
    for (const Rule& rule : cmake ? CMakeRules() : SourceRules()) {
      if (std::regex_search(code, rule.pattern)) {
        violations.push_back(name + ":" + std::to_string(number) + ": " + rule.what + ": " + line);
      }
    }
  }
  return violations;
}

// The scanner itself: each rule fires on what it is for, and not on comments or look-alikes.
TEST(ModelPurity, ScannerCatchesEachForbiddenDependency) {
  const char* forbidden[] = {
      "#include <dds/dds.h>",
      "#include \"dds/ddsrt/time.h\"",
      "  #  include <ddsc/dds.h>",
      "#include <dds/dds.hpp>",
      "#include \"idl/rig_types.h\"",
      "#include \"service/rig/rig_service.h\"",
      "#include \"tools/cli/commands.h\"",
      "#include <thread>",
      "#include <future>",
      "std::thread worker([] {});",
      "std::this_thread::sleep_for(d);",
      "const auto now = std::chrono::steady_clock::now();",
      "auto t = std::chrono::system_clock::now(); // wall clock",
      "using Clock = std::chrono::high_resolution_clock;",
      "clock_gettime(CLOCK_MONOTONIC, &ts);",
      "const bool log = std::getenv(\"MPDRIG_CERES_LOG\") != nullptr;",
      "#include <sys/socket.h>",
      "#include <netinet/in.h>",
      "#include <boost/asio.hpp>",
  };
  for (const char* line : forbidden) {
    EXPECT_EQ(FindViolations("x.cc", line, false).size(), 1u) << line;
  }
  const char* allowed[] = {
      "// Time is an argument: no wall clock here, no steady_clock, no <thread>.",
      "#include <chrono>  // durations as arguments are fine",
      "#include \"model/sim/rig_simulator.h\"",
      "#include <cmath>",
      "double time_s = 0.0;",
      "int threads_per_block = 1;",
      "double steady_state_clock_pa = 0.0;",
      "bool solver_log = false;  // the command line sets it from MPDRIG_CERES_LOG (getenv)",
  };
  for (const char* line : allowed) {
    EXPECT_TRUE(FindViolations("x.cc", line, false).empty()) << line;
  }
  EXPECT_EQ(
      FindViolations("CMakeLists.txt", "target_link_libraries(m PUBLIC CycloneDDS::ddsc)", true)
          .size(),
      1u);
  EXPECT_EQ(
      FindViolations("CMakeLists.txt", "target_link_libraries(m Threads::Threads)", true).size(),
      1u);
  EXPECT_TRUE(
      FindViolations("CMakeLists.txt", "# model/ never links CycloneDDS or Threads", true).empty());
  for (const char* upper : {"mpdrig_dds", "mpdrig_rig_service", "mpdrig_report", "mpdrig_python",
                            "mpdrig_dashboard_feed", "mpdrig_idl"}) {
    const std::string line = std::string("target_link_libraries(m PRIVATE ") + upper + ")";
    EXPECT_EQ(FindViolations("CMakeLists.txt", line, true).size(), 1u) << line;
  }
  EXPECT_TRUE(FindViolations("CMakeLists.txt",
                             "target_link_libraries(mpdrig_model PUBLIC mpdrig_config_proto)", true)
                  .empty());
}

TEST(ModelPurity, ModelHasNoDdsThreadsWallClockOrSockets) {
  const fs::path model = fs::path(MPDRIG_SOURCE_DIR) / "model";
  ASSERT_TRUE(fs::is_directory(model)) << model;
  std::vector<std::string> violations;
  int scanned = 0;
  for (const fs::directory_entry& entry : fs::recursive_directory_iterator(model)) {
    if (!entry.is_regular_file()) continue;
    const fs::path& path = entry.path();
    const bool cmake = IsCMake(path);
    if (!cmake && !IsSource(path)) continue;
    std::ifstream file(path, std::ios::binary);
    ASSERT_TRUE(file) << path;
    std::ostringstream text;
    text << file.rdbuf();
    const std::string name = fs::relative(path, MPDRIG_SOURCE_DIR).string();
    for (std::string& v : FindViolations(name, text.str(), cmake)) violations.push_back(v);
    ++scanned;
  }
  EXPECT_GT(scanned, 10) << "model/ looks empty: is MPDRIG_SOURCE_DIR right?";
  std::string report;
  for (const std::string& v : violations) report += "  " + v + "\n";
  EXPECT_TRUE(violations.empty())
      << "model/ is pure numerics (style.md): time is an argument, transport lives in service/.\n"
      << report;
}

// model/'s folders form layers (model/CMakeLists.txt lists them lowest first, with what each
// holds): a file may include its own folder and folders listed before it. model/ compiles as one
// library, so a cycle between folders links fine and goes unseen until it makes the next change
// hard (a header of pipe/ that needs boundary/ that needs pipe/). The order is read from the
// foreach() of model/CMakeLists.txt, so the build and this test cannot disagree.
std::vector<std::string> ParseFolderOrder(const std::string& cmake_text) {
  const std::regex foreach_list(R"(foreach\s*\(\s*part\s+([^)]*)\))");
  std::smatch match;
  std::vector<std::string> order;
  if (!std::regex_search(cmake_text, match, foreach_list)) return order;
  std::istringstream words(match[1].str());
  for (std::string word; words >> word;) order.push_back(word);
  return order;
}

// "name:line: rule: text" for every include of `text` (the file model/<folder>/...) that names a
// model folder listed after <folder>, or one the order does not list.
std::vector<std::string> FindLayerViolations(const std::string& name, const std::string& text,
                                             const std::vector<std::string>& order) {
  std::vector<std::string> violations;
  const std::regex own_folder(R"(^model/([^/]+)/)");
  std::smatch own;
  if (!std::regex_search(name, own, own_folder)) return violations;
  const auto rank = [&order](const std::string& folder) {
    return std::find(order.begin(), order.end(), folder) - order.begin();
  };
  const auto own_rank = rank(own[1].str());
  const std::regex include(R"(^\s*#\s*include\s*"model/([^/"]+)/)");
  std::istringstream in(text);
  std::string line;
  int number = 0;
  while (std::getline(in, line)) {
    ++number;
    std::smatch target;
    if (!std::regex_search(line, target, include)) continue;
    const std::string folder = target[1].str();
    const auto target_rank = rank(folder);
    if (target_rank <= own_rank && target_rank < static_cast<long>(order.size())) continue;
    const std::string rule =
        target_rank == static_cast<long>(order.size())
            ? "model/" + folder + "/ is not in the folder order of model/CMakeLists.txt"
            : "model/" + own[1].str() + "/ may not include model/" + folder +
                  "/, which comes after it in the folder order of model/CMakeLists.txt";
    violations.push_back(name + ":" + std::to_string(number) + ": " + rule + ": " + line);
  }
  return violations;
}

TEST(ModelLayers, ScannerCatchesAnIncludeUpTheOrder) {
  const std::vector<std::string> order =
      ParseFolderOrder("foreach(part common core boundary\n    pipe)\n  add_subdirectory()");
  ASSERT_EQ(order, (std::vector<std::string>{"common", "core", "boundary", "pipe"}));
  // Down the order and within a folder: allowed.
  EXPECT_TRUE(FindLayerViolations("model/boundary/choke.h",
                                  "#include \"model/core/pipe_law.h\"\n"
                                  "#include \"model/boundary/piston.h\"\n"
                                  "#include <vector>\n// see model/pipe/pipe_solver.h\n",
                                  order)
                  .empty());
  // Up the order: named with file, line and rule.
  const std::vector<std::string> up =
      FindLayerViolations("model/boundary/choke.h",
                          "#include <vector>\n#include \"model/pipe/pipe_solver.h\"\n", order);
  ASSERT_EQ(up.size(), 1u);
  EXPECT_NE(up[0].find("model/boundary/choke.h:2: model/boundary/ may not include model/pipe/"),
            std::string::npos)
      << up[0];
  // An include of a folder the order does not know: refused, so a new folder has to take its
  // place in the order (EveryIncludeGoesDownTheFolderOrder also refuses the folder itself).
  EXPECT_EQ(FindLayerViolations("model/pipe/x.cc", "#include \"model/newthing/a.h\"", order).size(),
            1u);
}

TEST(ModelLayers, EveryIncludeGoesDownTheFolderOrder) {
  const fs::path model = fs::path(MPDRIG_SOURCE_DIR) / "model";
  std::ifstream cmake(model / "CMakeLists.txt");
  ASSERT_TRUE(cmake) << model / "CMakeLists.txt";
  std::ostringstream cmake_text;
  cmake_text << cmake.rdbuf();
  const std::vector<std::string> order = ParseFolderOrder(cmake_text.str());
  ASSERT_GT(order.size(), 5u) << "no foreach(part ...) folder list in model/CMakeLists.txt";

  std::string report;
  int scanned = 0;
  for (const fs::directory_entry& entry : fs::recursive_directory_iterator(model)) {
    if (entry.is_directory() && entry.path().parent_path() == model &&
        std::find(order.begin(), order.end(), entry.path().filename().string()) == order.end()) {
      report += "  model/" + entry.path().filename().string() +
                "/ is not in the folder order of model/CMakeLists.txt\n";
    }
    if (!entry.is_regular_file() || !IsSource(entry.path())) continue;
    std::ifstream file(entry.path(), std::ios::binary);
    ASSERT_TRUE(file) << entry.path();
    std::ostringstream text;
    text << file.rdbuf();
    const std::string name = fs::relative(entry.path(), MPDRIG_SOURCE_DIR).string();
    for (const std::string& v : FindLayerViolations(name, text.str(), order)) {
      report += "  " + v + "\n";
    }
    ++scanned;
  }
  EXPECT_GT(scanned, 10);
  EXPECT_TRUE(report.empty())
      << "model/ folders include only themselves and the folders before them (model/CMakeLists.txt"
         " lists the order and what each holds). Move shared vocabulary down, e.g. to "
         "model/core/:\n"
      << report;
}

// "file:line: text" for every line under `folder` that matches `include` (a source file) or
// `link` (a CMake file, its `#` comment removed).
std::string FindForbiddenLines(const fs::path& folder, const std::regex& include,
                               const std::regex& link, int* scanned) {
  std::string report;
  for (const fs::directory_entry& entry : fs::recursive_directory_iterator(folder)) {
    if (!entry.is_regular_file()) continue;
    const fs::path& path = entry.path();
    const bool cmake = IsCMake(path);
    if (!cmake && !IsSource(path)) continue;
    std::ifstream file(path, std::ios::binary);
    std::string line;
    int number = 0;
    while (std::getline(file, line)) {
      ++number;
      const std::string code = line.substr(0, line.find(cmake ? "#" : "//"));
      if (std::regex_search(cmake ? code : line, cmake ? link : include)) {
        report += "  " + fs::relative(path, MPDRIG_SOURCE_DIR).string() + ":" +
                  std::to_string(number) + ": " + line + "\n";
      }
    }
    ++*scanned;
  }
  return report;
}

// design.md: clients/ only speak the DDS topics. They may use the transport layer (service/dds)
// and the generated types, never the model, the service's rigs or the command line. The one
// header of model/ they may name is the project's error type (model/common/status.h: header-only,
// no model code), which the transport's API returns already; the client library returns it too.
TEST(ClientPurity, ClientsUseOnlyTheWireAndTheTransport) {
  const fs::path clients = fs::path(MPDRIG_SOURCE_DIR) / "clients";
  ASSERT_TRUE(fs::is_directory(clients)) << clients;
  const std::regex include(
      R"(^\s*#\s*include\s*"(model/(?!common/status\.h")|service/(rig|shadow)/|tools/))");
  const std::regex link(R"(\bmpdrig_(model|rig|report|shadow|config_proto)\w*)");
  int scanned = 0;
  const std::string report = FindForbiddenLines(clients, include, link, &scanned);
  EXPECT_GT(scanned, 1);
  EXPECT_TRUE(report.empty()) << "clients/ must not use the model or the service's internals:\n"
                              << report;
}

// service/ holds what serves (the rig service, the shadow, the transport); tools/ holds the
// command line that starts them and the offline commands (compare, fit, diagnose, the report).
// Dependencies point tools/ -> service/ -> model/, so nothing in service/ names tools/.
// The targets tools/ defines (the mpdrig program, the report's library, any added later), as
// an alternation of whole words.
std::string ToolsTargets() {
  const fs::path tools = fs::path(MPDRIG_SOURCE_DIR) / "tools";
  const std::regex defines(R"(add_(library|executable)\s*\(\s*(\w+))");
  std::string names;
  for (const fs::directory_entry& entry : fs::recursive_directory_iterator(tools)) {
    if (!entry.is_regular_file() || !IsCMake(entry.path())) continue;
    std::ifstream file(entry.path(), std::ios::binary);
    std::ostringstream text;
    text << file.rdbuf();
    const std::string cmake = text.str();
    for (std::sregex_iterator it(cmake.begin(), cmake.end(), defines), end; it != end; ++it) {
      names += (names.empty() ? "" : "|") + (*it)[2].str();
    }
  }
  return names;
}

TEST(ServicePurity, ServiceDoesNotUseTheCommandLine) {
  const fs::path service = fs::path(MPDRIG_SOURCE_DIR) / "service";
  ASSERT_TRUE(fs::is_directory(service)) << service;
  const std::string targets = ToolsTargets();
  ASSERT_NE(targets.find("mpdrig_report"), std::string::npos) << "tools/'s targets: " << targets;
  const std::regex include(R"(^\s*#\s*include\s*"tools/)");
  const std::regex link("\\b(" + targets + ")\\b");
  int scanned = 0;
  const std::string report = FindForbiddenLines(service, include, link, &scanned);
  EXPECT_GT(scanned, 10);
  EXPECT_TRUE(report.empty()) << "service/ must not use tools/ (the command line, the report):\n"
                              << report;
}

}  // namespace
}  // namespace mpdrig
