// The topic table (service/dds/topics.h) is the one place a topic is named: these checks keep the
// documentation and every program's text in step with it, so that renaming a topic there and
// running the tests shows every place a reader would still see the old name.
#include "service/dds/topics.h"

#include <filesystem>
#include <fstream>
#include <map>
#include <regex>
#include <set>
#include <sstream>
#include <string>

#include <gtest/gtest.h>

namespace mpdrig::dds {
namespace {

namespace fs = std::filesystem;

std::string ReadFile(const fs::path& path) {
  std::ifstream in(path);
  std::stringstream text;
  text << in.rdbuf();
  return text.str();
}

std::map<std::string, const TopicSpec*> TopicsByName() {
  std::map<std::string, const TopicSpec*> by_name;
  for (const TopicSpec& topic : topics::kAll) by_name[topic.name] = &topic;
  return by_name;
}

TEST(Topics, NamesAreUniqueValidAndCarryTheirIdlType) {
  std::set<std::string> names;
  for (const TopicSpec& topic : topics::kAll) {
    EXPECT_TRUE(names.insert(topic.name).second) << topic.name << " twice";
    // Cyclone 0.10 accepts only these characters in a topic name.
    EXPECT_TRUE(std::regex_match(topic.name, std::regex("[A-Za-z0-9_/]+"))) << topic.name;
    ASSERT_NE(topic.type, nullptr) << topic.name;
    EXPECT_EQ(std::string(topic.type->m_typename).rfind("mpdrig::", 0), 0u)
        << topic.name << ": " << topic.type->m_typename;
  }
}

// Every table row of the docs that names a topic, `| `name` | `Type` | ...`, says the type the
// topic carries, and every topic is documented in a table or in the text.
TEST(Topics, TheDocumentedTablesMatchTheTopics) {
  const auto by_name = TopicsByName();
  const std::regex row(R"(^\| `(mpdrig_[a-z_]+)` \| `([A-Za-z]+)` \|)");
  std::string all_docs;
  int rows = 0;
  for (const auto& entry : fs::directory_iterator(fs::path(MPDRIG_SOURCE_DIR) / "docs")) {
    if (entry.path().extension() != ".md") continue;
    const std::string text = ReadFile(entry.path());
    all_docs += text;
    std::istringstream lines(text);
    std::string line;
    for (int number = 1; std::getline(lines, line); ++number) {
      std::smatch m;
      if (!std::regex_search(line, m, row)) continue;
      ++rows;
      const auto topic = by_name.find(m[1].str());
      ASSERT_NE(topic, by_name.end())
          << entry.path().filename() << ":" << number << ": no topic " << m[1] << " in topics.h";
      EXPECT_EQ(std::string(topic->second->type->m_typename), "mpdrig::" + m[2].str())
          << entry.path().filename() << ":" << number;
    }
  }
  EXPECT_GE(rows, 12);  // docs/service.md's rig topics and docs/live.md's shadow topics
  for (const TopicSpec& topic : topics::kAll) {
    EXPECT_NE(all_docs.find(std::string("`") + topic.name + "`"), std::string::npos)
        << topic.name << " is documented nowhere in docs/";
  }
}

// A name that looks like a topic in the programs' help texts, the code or the docs (it ends the
// way topic names end) must be one: after a rename, the old name left in a help text or a page
// fails here with its file and line.
TEST(Topics, EveryTopicLikeNameInTheSourcesIsATopic) {
  const auto by_name = TopicsByName();
  const std::regex topic_like(
      R"(\bmpdrig_[a-z_]*(sensors|status|command|request|estimate|profile)\b)");
  int seen = 0;
  for (const char* folder : {"service", "clients", "tools", "docs", "README.md"}) {
    const fs::path root = fs::path(MPDRIG_SOURCE_DIR) / folder;
    std::vector<fs::path> files;
    if (fs::is_regular_file(root)) files.push_back(root);
    if (fs::is_directory(root)) {
      for (const auto& entry : fs::recursive_directory_iterator(root)) {
        const std::string ext = entry.path().extension().string();
        if (entry.is_regular_file() && (ext == ".cc" || ext == ".h" || ext == ".md" ||
                                        ext == ".py" || ext == ".pyi" || ext == ".html")) {
          files.push_back(entry.path());
        }
      }
    }
    for (const fs::path& file : files) {
      std::istringstream lines(ReadFile(file));
      std::string line;
      for (int number = 1; std::getline(lines, line); ++number) {
        for (std::sregex_iterator it(line.begin(), line.end(), topic_like), end; it != end; ++it) {
          ++seen;
          EXPECT_TRUE(by_name.count(it->str()))
              << fs::relative(file, MPDRIG_SOURCE_DIR).string() << ":" << number << ": "
              << it->str() << " is not a topic of service/dds/topics.h";
        }
      }
    }
  }
  EXPECT_GT(seen, 20);  // the help texts and the docs name the topics
}

}  // namespace
}  // namespace mpdrig::dds
