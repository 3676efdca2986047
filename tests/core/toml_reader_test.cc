#include "core/toml/toml_reader.h"

#include <gtest/gtest.h>

#include <string>
#include <vector>

namespace canalid::core {
namespace {

TEST(TomlReader, SyntaxErrorNamesFileLineAndColumn) {
  try {
    TomlReader reader("a = 1\nb = = 2\n", "given.toml");
    FAIL() << "expected TomlError";
  } catch (const TomlError& e) {
    ASSERT_EQ(e.issues().size(), 1u);
    EXPECT_EQ(e.issues()[0].file, "given.toml");
    EXPECT_EQ(e.issues()[0].line, 2);
    EXPECT_EQ(std::string(e.what()).rfind("given.toml:2:", 0), 0u) << e.what();
  }
}

TEST(TomlReader, AFileThatCannotBeReadIsOneIssueAtItsStart) {
  try {
    TomlReader::FromFile("/nonexistent/x.toml");
    FAIL() << "expected TomlError";
  } catch (const TomlError& e) {
    EXPECT_EQ(std::string(e.what()), "/nonexistent/x.toml:1:1: cannot read the file");
  }
}

TEST(TomlReader, IssuesComeInFileOrderWithTheirPaths) {
  TomlReader reader("[t]\nx = 1\ny = \"s\"\nz = 3\n", "f.toml");
  const toml::table& t = *reader.root().get("t")->as_table();
  reader.Problem(t.get("y")->source(), "t.y", "second");
  reader.Problem(t.get("x")->source(), "", "'t.x' first");
  reader.Problem(toml::source_region{}, "", "at the start");
  const std::vector<TomlIssue> issues = reader.Issues();
  ASSERT_EQ(issues.size(), 3u);
  EXPECT_EQ(issues[0].ToString(), "f.toml:1:1: at the start");
  EXPECT_EQ(issues[1].ToString(), "f.toml:2:5: 't.x' first");
  EXPECT_EQ(issues[2].ToString(), "f.toml:3:5: t.y: second");
  const auto unknown = TomlReader::UnknownKeys(t, {"x", "y"});
  ASSERT_EQ(unknown.size(), 1u);
  EXPECT_EQ(unknown[0].first, "z");
  EXPECT_EQ(unknown[0].second.begin.line, 4u);
}

TEST(TomlReader, LocateFallsBackToTheNearestMarkedPath) {
  TomlReader reader("[[reach]]\nname = \"a\"\n", "f.toml");
  const auto& reach = *reader.root().get("reach")->as_array()->get(0)->as_table();
  reader.Mark("reach[0]", reach.source());
  EXPECT_EQ(reader.Locate("reach[0].level.max").begin.line, reach.source().begin.line);
  EXPECT_EQ(reader.Locate("other.key").begin.line, 0u);  // unmarked: the file's start
}

TEST(TomlReader, NamesAndPaths) {
  EXPECT_EQ(TomlKeyPath("", "a"), "a");
  EXPECT_EQ(TomlKeyPath("t[0]", "a"), "t[0].a");
  EXPECT_EQ(JoinNames({"a", "b"}), "a, b");
  EXPECT_EQ(JoinNames({"a", "b"}, "\""), "\"a\", \"b\"");
  TomlReader reader("i = 1\nf = 1.5\n", "f.toml");
  EXPECT_STREQ(TomlTypeName(*reader.root().get("i")), "an integer");
  EXPECT_STREQ(TomlTypeName(*reader.root().get("f")), "a float");
}

}  // namespace
}  // namespace canalid::core
