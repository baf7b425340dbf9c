#include "study/study_file.hpp"

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <regex>
#include <set>
#include <sstream>

#include "common/check.hpp"
#include "config/toml_doc.hpp"

namespace divcoll::study {
namespace {

namespace fs = std::filesystem;
using config::TomlValue;
using Kind = config::TomlValue::Kind;

std::vector<std::string> strings(const TomlValue& n, const std::string& what) {
  DIVCOLL_THROW_UNLESS(n.is(Kind::array), what << " must be a list of strings");
  std::vector<std::string> out;
  for (const TomlValue& e : n.items) {
    DIVCOLL_THROW_UNLESS(e.is(Kind::string), what << " must be a list of strings");
    out.push_back(e.string);
  }
  return out;
}

std::string text_of(const TomlValue& n, const std::string& what) {
  DIVCOLL_THROW_UNLESS(n.is(Kind::string), what << " must be a string");
  return n.string;
}

// a non-empty list of distinct seeds (integers >= 0); `must` ends the message for any other value
std::vector<std::uint64_t> seed_list(const TomlValue& n, const std::string& what, const std::string& must) {
  DIVCOLL_THROW_UNLESS(n.is(Kind::array) && !n.items.empty(), what << " must be " << must);
  std::vector<std::uint64_t> out;
  for (const TomlValue& e : n.items) {
    DIVCOLL_THROW_UNLESS(e.is(Kind::integer) && e.integer >= 0, what << " must be " << must);
    const auto v = static_cast<std::uint64_t>(e.integer);
    DIVCOLL_THROW_UNLESS(std::find(out.begin(), out.end(), v) == out.end(), what << " lists " << v << " twice");
    out.push_back(v);
  }
  return out;
}

// the [study] table's keys into `s`
void read_study_table(const TomlValue& st, const std::string& path, Study& s) {
  const std::set<std::string> study_keys = {"name", "base", "seeds", "scale", "doc"};
  for (const auto& [k, v] : st.keys)
    DIVCOLL_THROW_UNLESS(study_keys.count(k),
                         "unknown key study." << k << " in " << path << " (known: name, base, seeds, scale, doc)");
  DIVCOLL_THROW_UNLESS(st.find("base"), "study.base (the run config) is missing in " << path);
  DIVCOLL_THROW_UNLESS(st.find("seeds"), "study.seeds (the list of run seeds) is missing in " << path);
  s.name = st.find("name") ? text_of(*st.find("name"), "study.name") : fs::path(path).stem().string();
  s.doc = st.find("doc") ? text_of(*st.find("doc"), "study.doc") : "";
  const std::string base = text_of(*st.find("base"), "study.base");
  s.base = fs::absolute(fs::path(path).parent_path() / base).lexically_normal().string();
  DIVCOLL_THROW_UNLESS(fs::is_regular_file(s.base), "study.base: no config file " << s.base);
  s.base_given = s.base;
  if (st.find("scale")) s.scale = strings(*st.find("scale"), "study.scale");
  s.seeds = seed_list(*st.find("seeds"), "study.seeds", "a non-empty list of integers >= 0");
}

// one [[variant]] table, checked against the variants before it and the study's seeds
Variant read_variant(const TomlValue& n, const std::string& path, const Study& s) {
  static const std::regex ok_name("[A-Za-z0-9_-]+");
  DIVCOLL_THROW_UNLESS(n.is(Kind::table), "every variant must be a [[variant]] table");
  Variant v;
  for (const auto& [key, val] : n.keys) {
    if (key == "name") v.name = text_of(val, "variant.name");
    else if (key == "doc") v.doc = text_of(val, "variant.doc");
    else if (key == "set") v.set = strings(val, "variant.set");
    else if (key == "seeds") v.seeds = seed_list(val, "variant.seeds", "a non-empty list of the study's seeds");
    else if (key == "added") v.added = text_of(val, "variant.added");
    else throw InputError(msg() << "unknown key variant." << key << " in " << path
                                << " (known: name, set, seeds, doc, added)");
  }
  static const std::regex iso_date("[0-9]{4}-(0[1-9]|1[0-2])-(0[1-9]|[12][0-9]|3[01])");
  DIVCOLL_THROW_UNLESS(v.added.empty() || std::regex_match(v.added, iso_date),
                       "variant " << v.name << ": added = '" << v.added << "' is not a date YYYY-MM-DD");
  DIVCOLL_THROW_UNLESS(std::regex_match(v.name, ok_name),
                       "variant name '" << v.name << "' must be letters, digits, _ or - (it names a folder)");
  for (const Variant& o : s.variants) DIVCOLL_THROW_UNLESS(o.name != v.name, "variant " << v.name << " is listed twice");
  for (std::uint64_t sd : v.seeds)
    DIVCOLL_THROW_UNLESS(std::find(s.seeds.begin(), s.seeds.end(), sd) != s.seeds.end(),
                         "variant " << v.name << ": seed " << sd << " is not one of study.seeds");
  return v;
}

}  // namespace

std::string read_text(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  DIVCOLL_THROW_UNLESS(in, "cannot read the study file " << path);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

Study parse_study(const std::string& path) { return parse_study_text(read_text(path), path); }

Study parse_study_text(const std::string& text, const std::string& path) {
  Study s;
  s.text = text;
  const TomlValue root = config::parse_toml(s.text, path);
  for (const auto& [key, v] : root.keys)
    DIVCOLL_THROW_UNLESS(key == "study" || key == "variant",
                         "unknown table [" << key << "] in " << path << " (a study file has [study] and [[variant]])");
  const TomlValue* st = root.find("study");
  DIVCOLL_THROW_UNLESS(st && st->is(Kind::table), path << " has no [study] table");
  read_study_table(*st, path, s);
  const TomlValue* vars = root.find("variant");
  DIVCOLL_THROW_UNLESS(vars && vars->is(Kind::array) && !vars->items.empty(),
                       path << " has no [[variant]] table (give at least one)");
  for (const TomlValue& n : vars->items) s.variants.push_back(read_variant(n, path, s));
  return s;
}

}  // namespace divcoll::study
