// the study file (TOML), read through src/config's TOML reader and checked before any config is built:
//   [study]
//   name  = "claims"               run-file folder names and the report title (default: the file's stem)
//   base  = "../paper.toml"        the run config every run starts from (relative to the study file)
//   seeds = [1, 2, 3]              run.seed of each replicate run
//   scale = ["deploy.pairs=100"]   section.key=value overrides applied to every run (before the variant's)
//   doc   = "..."                  optional: what the study asks
//   [[variant]]                    one table per variant, in the order they run and are reported
//   name = "baseline"              [A-Za-z0-9_-]+, unique; its runs are DIR/<name>/seed<k>.h5
//   set  = []                      section.key=value overrides of this variant
//   doc  = "..."                   optional: the reading of the paper it stands for
//   seeds = [1, 2]                 optional: run this variant at these study seeds only (default: every one)
//   added = "2026-12-06"           optional: the date a variant joined the study after its first runs (kept in
//                                  the manifest; a pre-registered selection reports such a variant, never picks it)
#pragma once

#include <cstdint>
#include <string>
#include <vector>

namespace divcoll::study {

struct Variant {
  std::string name, doc;
  std::vector<std::string> set;
  std::vector<std::uint64_t> seeds;  // the study seeds this variant runs at (empty: every one)
  std::string added;                 // YYYY-MM-DD: joined the study after its first run ("": from the start)
};

struct Study {
  std::string name, doc, base, text;  // base: absolute path of the run config; text: the study file
  std::string base_given;             // study.base as resolved from the study file (base may be the folder's copy)
  std::vector<std::uint64_t> seeds;
  std::vector<std::string> scale;
  std::vector<Variant> variants;
};

// a text file's content; InputError "cannot read the study file PATH" if it cannot be read
std::string read_text(const std::string& path);

// the study file at `path`, parsed and checked (not yet the configs); InputError naming the file and the key
Study parse_study(const std::string& path);
// the same of a study file's `text` (`path` names it and places study.base)
Study parse_study_text(const std::string& text, const std::string& path);

}  // namespace divcoll::study
