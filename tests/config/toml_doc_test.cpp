// config's TOML reader for the formats beside the run config (config/toml_doc.hpp): a text read as plain values
// (tables in the library's order, with lines), written back as the library writes it, and a text that does not
// parse refused with its origin and line
#include "config/toml_doc.hpp"

#include <gtest/gtest.h>

#include <string>

namespace divcoll::config {
namespace {

using Kind = TomlValue::Kind;

TEST(TomlDoc, ReadsEveryKindOfValue) {
  const TomlValue t = parse_toml("b = 2\na = 'x'\n[t]\nf = 1.5\nok = true\nlist = [1, 2]\nwhen = 1979-05-27\n"
                                 "[[rows]]\nn = 1\n[[rows]]\nn = 2\n",
                                 "test.toml");
  ASSERT_TRUE(t.is(Kind::table));
  ASSERT_EQ(t.keys.size(), 4u);
  EXPECT_EQ(t.keys[0].first, "a");  // the library's order: by key
  EXPECT_EQ(t.string_or("a", "?"), "x");
  EXPECT_EQ(t.integer_or("b", 0), 2);
  EXPECT_EQ(t.find("b")->line, 1);
  const TomlValue* sub = t.find("t");
  ASSERT_NE(sub, nullptr);
  EXPECT_EQ(sub->number_or("f", 0), 1.5);
  EXPECT_TRUE(sub->find("ok")->boolean);
  EXPECT_EQ(sub->find("list")->items.size(), 2u);
  EXPECT_TRUE(sub->find("when")->is(Kind::other));
  EXPECT_EQ(t.find("rows")->items.at(1).integer_or("n", 0), 2);
  // missing or of another kind: the default
  EXPECT_EQ(t.string_or("b", "d"), "d");
  EXPECT_EQ(t.number_or("b", 0), 2.0);
  EXPECT_EQ(t.integer_or("nothing", 7), 7);
  EXPECT_EQ(t.find("nothing"), nullptr);
  EXPECT_EQ(t.find("a")->find("x"), nullptr);
}

TEST(TomlDoc, WritesWhatItReadsBack) {
  TomlValue t;
  t.set("name", TomlValue::of("n"));
  t.set("seed", TomlValue::of(std::int64_t{3}));
  t.set("wall_s", TomlValue::of(0.0));
  t.set("list", TomlValue::list(std::vector<std::string>{"a", "b"}));
  TomlValue row;
  row.set("status", TomlValue::of("complete"));
  t.set("run", TomlValue::list(std::vector<TomlValue>{row, row}));
  t.set("seed", TomlValue::of(std::int64_t{4}));  // replaces
  const std::string text = toml_text(t);
  EXPECT_NE(text.find("status = 'complete'"), std::string::npos) << text;
  EXPECT_NE(text.find("[[run]]"), std::string::npos) << text;
  EXPECT_NE(text.find("wall_s = 0.0"), std::string::npos) << text;
  const TomlValue back = parse_toml(text, "written");
  EXPECT_EQ(back.integer_or("seed", 0), 4);
  EXPECT_EQ(back.find("list")->items.at(1).string, "b");
  EXPECT_EQ(back.find("run")->items.size(), 2u);
  EXPECT_EQ(toml_text(back), text);
}

TEST(TomlDoc, RefusesATextThatDoesNotParseWithItsOriginAndLine) {
  try {
    parse_toml("a = 1\nb = [1,\n", "some/file.toml");
    FAIL() << "accepted";
  } catch (const TomlSyntaxError& e) {
    const std::string m = e.what();
    EXPECT_EQ(m, "some/file.toml: " + e.reason + " at line " + std::to_string(e.line));
    EXPECT_GE(e.line, 2);
    EXPECT_FALSE(e.reason.empty());
  }
}

}  // namespace
}  // namespace divcoll::config
