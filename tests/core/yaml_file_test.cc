// LoadYamlFile (src/core/yaml_file.cc): every YAML file's one entry: read as any system
// writes it, parsed, a key set twice refused with both lines, errors with file and line.
#include "kincal/yaml_file.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

#include "temp_path.h"
#include "windows_text.h"

namespace kincal {
namespace {

std::string Write(const std::string& text) {
  const std::string path = testing::TempPath("yaml_file_test.yaml");
  std::ofstream(path, std::ios::binary) << text;
  return path;
}

std::string ErrorOf(const std::string& text) {
  const std::string path = Write(text);
  const StatusOr<YAML::Node> n = LoadYamlFile(path, "test file");
  return n.ok() ? "no error" : n.status().message().substr(path.size());
}

TEST(YamlFile, ReadsWhatOtherSystemsWrite) {
  const std::string text = "# a comment\nduration_s: 7  # seconds\nlow: [1, 2]\n";
  for (const auto& [system, other] : testing::OtherSystemsText(text)) {
    const StatusOr<YAML::Node> n = LoadYamlFile(Write(other), "test file");
    ASSERT_TRUE(n.ok()) << system << ": " << n.status().message();
    EXPECT_EQ(n.value()["duration_s"].as<double>(), 7.0) << system;
    EXPECT_EQ(n.value()["low"].size(), 2u) << system;
  }
  const StatusOr<YAML::Node> empty = LoadYamlFile(Write(""), "test file");
  ASSERT_TRUE(empty.ok());
  EXPECT_TRUE(empty.value().IsNull());
}

// Issue 34's sweep: `duration_s: 7` added at the end of a scenario that already had
// `duration_s: 120` ran for 120 s (yaml-cpp keeps both keys and answers with the first).
TEST(YamlFile, AKeySetTwiceIsNamedWithBothLines) {
  EXPECT_EQ(ErrorOf("duration_s: 120\nseed: 1\nduration_s: 7\n"),
            ":3: key 'duration_s' is set twice (first on line 1); YAML keys are unique: keep the "
            "one you mean");
  EXPECT_TRUE(ErrorOf("controls:\n  low: [1]\n  high: [2]\n  low: [3]\n")
                  .starts_with(":4: key 'controls.low' is set twice (first on line 2)"));
  EXPECT_TRUE(ErrorOf("markers:\n  - {x: 1, x: 2}\n")
                  .starts_with(":2: key 'markers.x' is set twice (first on line 2)"));
  // The same key in different maps is no repeat.
  EXPECT_EQ(ErrorOf("a: {k: 1}\nb: {k: 2}\nc: [{k: 1}, {k: 2}]\n"), "no error");
}

TEST(YamlFile, ParseErrorsAndMissingFilesAreNamed) {
  EXPECT_TRUE(ErrorOf("a: [1, 2\nb: 3\n").starts_with(":2: ")) << ErrorOf("a: [1, 2\nb: 3\n");
  const std::string missing = testing::TempPath("yaml_file_test_missing.yaml");
  std::filesystem::remove(missing);
  EXPECT_EQ(LoadYamlFile(missing, "scenario").status().message(),
            missing + ": cannot open scenario: No such file or directory");
}

}  // namespace
}  // namespace kincal
