// the study file (src/study/study_file.hpp) read through config's TOML reader: what it gives, and every refusal
// with the message that names the file and the key
#include "study/study_file.hpp"

#include <gtest/gtest.h>

#include <string>

#include "common/check.hpp"
#include "testing.hpp"

namespace divcoll::study {
namespace {

const std::string kPath = "/nowhere/studies/claims.toml";

// a study file over configs/tiny.toml with `study_extra` in [study] and `variants` after it
std::string text(const std::string& study_extra = "", const std::string& variants = "[[variant]]\nname = \"a\"\n") {
  return "[study]\nbase = \"" + testing::source_dir() + "/configs/tiny.toml\"\nseeds = [1, 2]\n" + study_extra + "\n" +
         variants;
}

// the message of the refusal of `t`
std::string refusal(const std::string& t) {
  try {
    parse_study_text(t, kPath);
  } catch (const InputError& e) {
    return e.what();
  }
  return "(accepted)";
}

TEST(StudyFile, ReadsEveryKey) {
  const Study s = parse_study_text(text("name = \"n\"\ndoc = \"d\"\nscale = [\"deploy.pairs=2\"]",
                                        "[[variant]]\nname = \"a\"\ndoc = \"x\"\nset = [\"agents.epochs=2\"]\n"
                                        "[[variant]]\nname = \"b-2\"\nseeds = [2]\nadded = \"2026-12-06\"\n"),
                                   kPath);
  EXPECT_EQ(s.name, "n");
  EXPECT_EQ(s.doc, "d");
  EXPECT_EQ(s.base, testing::source_dir() + "/configs/tiny.toml");
  EXPECT_EQ(s.base_given, s.base);
  EXPECT_EQ(s.seeds, (std::vector<std::uint64_t>{1, 2}));
  EXPECT_EQ(s.scale, std::vector<std::string>{"deploy.pairs=2"});
  ASSERT_EQ(s.variants.size(), 2u);
  EXPECT_EQ(s.variants[0].name, "a");
  EXPECT_EQ(s.variants[0].doc, "x");
  EXPECT_EQ(s.variants[0].set, std::vector<std::string>{"agents.epochs=2"});
  EXPECT_TRUE(s.variants[0].seeds.empty());
  EXPECT_EQ(s.variants[1].seeds, std::vector<std::uint64_t>{2});
  EXPECT_EQ(s.variants[0].added, "");
  EXPECT_EQ(s.variants[1].added, "2026-12-06");
}

TEST(StudyFile, NameDefaultsToTheFileStemAndBaseIsRelativeToTheFile) {
  const std::string dir = testing::source_dir() + "/configs/studies";
  const Study s = parse_study_text("[study]\nbase = \"../tiny.toml\"\nseeds = [3]\n[[variant]]\nname = \"a\"\n",
                                   dir + "/mine.toml");
  EXPECT_EQ(s.name, "mine");
  EXPECT_EQ(s.base, testing::source_dir() + "/configs/tiny.toml");
}

TEST(StudyFile, TheCommittedStudiesRead) {
  for (const char* f : {"tiny", "claims", "verdicts"})
    EXPECT_NO_THROW(parse_study(testing::source_dir() + "/configs/studies/" + f + ".toml")) << f;
}

TEST(StudyFile, RefusesATextThatIsNoToml) {
  const std::string m = refusal("[study]\nseeds = [1,\n");
  EXPECT_EQ(m.rfind(kPath + ": ", 0), 0u) << m;
  EXPECT_NE(m.find(" at line "), std::string::npos) << m;
}

TEST(StudyFile, RefusesUnknownTablesAndKeys) {
  EXPECT_EQ(refusal(text() + "[studies]\n"),
            "unknown table [studies] in " + kPath + " (a study file has [study] and [[variant]])");
  EXPECT_EQ(refusal(text("repeats = 3")),
            "unknown key study.repeats in " + kPath + " (known: name, base, seeds, scale, doc)");
  EXPECT_EQ(refusal(text("", "[[variant]]\nname = \"a\"\nsets = []\n")),
            "unknown key variant.sets in " + kPath + " (known: name, set, seeds, doc, added)");
}

TEST(StudyFile, RefusesMissingParts) {
  EXPECT_EQ(refusal("[[variant]]\nname = \"a\"\n"), kPath + " has no [study] table");
  EXPECT_EQ(refusal("[study]\nseeds = [1]\n[[variant]]\nname = \"a\"\n"),
            "study.base (the run config) is missing in " + kPath);
  EXPECT_EQ(refusal("[study]\nbase = \"x.toml\"\n[[variant]]\nname = \"a\"\n"),
            "study.seeds (the list of run seeds) is missing in " + kPath);
  EXPECT_EQ(refusal(text("", "")), kPath + " has no [[variant]] table (give at least one)");
  EXPECT_EQ(refusal(text("", "[variant]\nname = \"a\"\n")), kPath + " has no [[variant]] table (give at least one)");
  EXPECT_EQ(refusal("[study]\nbase = \"none.toml\"\nseeds = [1]\n[[variant]]\nname = \"a\"\n"),
            "study.base: no config file /nowhere/studies/none.toml");
}

TEST(StudyFile, RefusesBadValues) {
  EXPECT_EQ(refusal(text("name = 3")), "study.name must be a string");
  EXPECT_EQ(refusal(text("scale = \"deploy.pairs=2\"")), "study.scale must be a list of strings");
  EXPECT_EQ(refusal(text("", "[[variant]]\nname = \"a\"\nset = [1]\n")), "variant.set must be a list of strings");
  const std::string base = "[study]\nbase = \"" + testing::source_dir() + "/configs/tiny.toml\"\n";
  const std::string v = "[[variant]]\nname = \"a\"\n";
  EXPECT_EQ(refusal(base + "seeds = []\n" + v), "study.seeds must be a non-empty list of integers >= 0");
  EXPECT_EQ(refusal(base + "seeds = [-1]\n" + v), "study.seeds must be a non-empty list of integers >= 0");
  EXPECT_EQ(refusal(base + "seeds = [1, 1]\n" + v), "study.seeds lists 1 twice");
}

TEST(StudyFile, RefusesBadVariants) {
  EXPECT_EQ(refusal(text("", "[[variant]]\nname = \"a b\"\n")),
            "variant name 'a b' must be letters, digits, _ or - (it names a folder)");
  EXPECT_EQ(refusal(text("", "[[variant]]\nname = \"a\"\n[[variant]]\nname = \"a\"\n")), "variant a is listed twice");
  EXPECT_EQ(refusal(text("", "[[variant]]\nname = \"a\"\nseeds = [3]\n")),
            "variant a: seed 3 is not one of study.seeds");
  EXPECT_EQ(refusal(text("", "[[variant]]\nname = \"a\"\nseeds = []\n")),
            "variant.seeds must be a non-empty list of the study's seeds");
  EXPECT_EQ(refusal("variant = [1]\n" + text("", "")), "every variant must be a [[variant]] table");
  EXPECT_EQ(refusal(text("", "[[variant]]\nname = \"a\"\nadded = \"6 Dec\"\n")),
            "variant a: added = '6 Dec' is not a date YYYY-MM-DD");
}

}  // namespace
}  // namespace divcoll::study
