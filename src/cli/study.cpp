#include "cli/study.hpp"

#include <mpi.h>
#include <toml++/toml.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>
#include <regex>
#include <set>
#include <sstream>
#include <vector>
#include <thread>
#include <cerrno>
#include <cstdlib>
#include <cstring>

#include <fcntl.h>
#include <unistd.h>

#include "common/check.hpp"
#include "config/config.hpp"
#include "io/file_lock.hpp"
#include "io/h5.hpp"
#include "mpi/agree.hpp"
#include "cli/run.hpp"
#include "mpi/wait.hpp"

namespace divcoll::cli {
namespace {

namespace fs = std::filesystem;

struct Variant {
  std::string name, doc;
  std::vector<std::string> set;
  std::vector<std::uint64_t> seeds;  // the study seeds this variant runs at (empty: every one)
};

struct Study {
  std::string name, doc, base, text;  // base: absolute path of the run config; text: the study file
  std::string base_given;             // study.base as resolved from the study file (base may be the folder's copy)
  std::vector<std::uint64_t> seeds;
  std::vector<std::string> scale;
  std::vector<Variant> variants;
};

// one run of the study and how it is made
struct PlannedRun {
  int variant = 0;
  std::uint64_t seed = 0;
  std::vector<std::string> overrides;  // scale, then the variant's, then run.seed
  io::RunConfig cfg;
  std::string path;                    // relative to the study folder
  int base_run = -1;                   // index of the run whose earlier stages it reuses (-1: none)
  std::string from;                    // the first stage it computes when it reuses
};

std::string read_text(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  DIVCOLL_THROW_UNLESS(in, "cannot read the study file " << path);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

std::vector<std::string> strings(const toml::node& n, const std::string& what) {
  const toml::array* a = n.as_array();
  DIVCOLL_THROW_UNLESS(a, what << " must be a list of strings");
  std::vector<std::string> out;
  for (const toml::node& e : *a) {
    DIVCOLL_THROW_UNLESS(e.is_string(), what << " must be a list of strings");
    out.push_back(e.as_string()->get());
  }
  return out;
}

std::string text_of(const toml::node& n, const std::string& what) {
  DIVCOLL_THROW_UNLESS(n.is_string(), what << " must be a string");
  return n.as_string()->get();
}

// a non-empty list of distinct seeds (integers >= 0); `must` ends the message for any other value
std::vector<std::uint64_t> seed_list(const toml::node& n, const std::string& what, const std::string& must) {
  const toml::array* a = n.as_array();
  DIVCOLL_THROW_UNLESS(a && !a->empty(), what << " must be " << must);
  std::vector<std::uint64_t> out;
  for (const toml::node& e : *a) {
    DIVCOLL_THROW_UNLESS(e.is_integer() && e.as_integer()->get() >= 0, what << " must be " << must);
    const auto v = static_cast<std::uint64_t>(e.as_integer()->get());
    DIVCOLL_THROW_UNLESS(std::find(out.begin(), out.end(), v) == out.end(), what << " lists " << v << " twice");
    out.push_back(v);
  }
  return out;
}

// parses and checks the study file (not yet the configs)
Study parse_study(const std::string& path) {
  Study s;
  s.text = read_text(path);
  toml::table root;
  try {
    root = toml::parse(s.text, path);
  } catch (const toml::parse_error& e) {
    throw InputError(msg() << path << ": " << e.description() << " at line " << e.source().begin.line);
  }
  for (auto&& [k, v] : root) {
    const std::string key(k.str());
    DIVCOLL_THROW_UNLESS(key == "study" || key == "variant",
                         "unknown table [" << key << "] in " << path << " (a study file has [study] and [[variant]])");
  }
  const toml::table* st = root["study"].as_table();
  DIVCOLL_THROW_UNLESS(st, path << " has no [study] table");
  const std::set<std::string> study_keys = {"name", "base", "seeds", "scale", "doc"};
  for (auto&& [k, v] : *st)
    DIVCOLL_THROW_UNLESS(study_keys.count(std::string(k.str())),
                         "unknown key study." << k.str() << " in " << path << " (known: name, base, seeds, scale, doc)");
  DIVCOLL_THROW_UNLESS(st->contains("base"), "study.base (the run config) is missing in " << path);
  DIVCOLL_THROW_UNLESS(st->contains("seeds"), "study.seeds (the list of run seeds) is missing in " << path);
  s.name = st->contains("name") ? text_of(*st->get("name"), "study.name") : fs::path(path).stem().string();
  s.doc = st->contains("doc") ? text_of(*st->get("doc"), "study.doc") : "";
  const std::string base = text_of(*st->get("base"), "study.base");
  s.base = fs::absolute(fs::path(path).parent_path() / base).lexically_normal().string();
  DIVCOLL_THROW_UNLESS(fs::is_regular_file(s.base), "study.base: no config file " << s.base);
  s.base_given = s.base;
  if (st->contains("scale")) s.scale = strings(*st->get("scale"), "study.scale");
  s.seeds = seed_list(*st->get("seeds"), "study.seeds", "a non-empty list of integers >= 0");
  const toml::array* vars = root["variant"].as_array();
  DIVCOLL_THROW_UNLESS(vars && !vars->empty(), path << " has no [[variant]] table (give at least one)");
  const std::regex ok_name("[A-Za-z0-9_-]+");
  for (const toml::node& n : *vars) {
    const toml::table* t = n.as_table();
    DIVCOLL_THROW_UNLESS(t, "every variant must be a [[variant]] table");
    Variant v;
    for (auto&& [k, val] : *t) {
      const std::string key(k.str());
      if (key == "name") v.name = text_of(val, "variant.name");
      else if (key == "doc") v.doc = text_of(val, "variant.doc");
      else if (key == "set") v.set = strings(val, "variant.set");
      else if (key == "seeds") v.seeds = seed_list(val, "variant.seeds", "a non-empty list of the study's seeds");
      else throw InputError(msg() << "unknown key variant." << key << " in " << path << " (known: name, set, seeds, doc)");
    }
    DIVCOLL_THROW_UNLESS(std::regex_match(v.name, ok_name),
                         "variant name '" << v.name << "' must be letters, digits, _ or - (it names a folder)");
    for (const Variant& o : s.variants) DIVCOLL_THROW_UNLESS(o.name != v.name, "variant " << v.name << " is listed twice");
    for (std::uint64_t sd : v.seeds)
      DIVCOLL_THROW_UNLESS(std::find(s.seeds.begin(), s.seeds.end(), sd) != s.seeds.end(),
                           "variant " << v.name << ": seed " << sd << " is not one of study.seeds");
    s.variants.push_back(std::move(v));
  }
  return s;
}

// the stages `cfg` runs, as indices into io::stage_names()
std::vector<int> enabled(const io::RunConfig& cfg) {
  std::vector<int> out;
  const auto& names = io::stage_names();
  for (int i = 0; i < static_cast<int>(names.size()); ++i)
    if (io::stage_enabled(cfg, names[i])) out.push_back(i);
  return out;
}

// every run with its config (validated) and what it reuses
std::vector<PlannedRun> plan(const Study& s) {
  const auto& names = io::stage_names();
  const int S = static_cast<int>(names.size());
  std::vector<PlannedRun> runs;
  for (std::uint64_t seed : s.seeds)
    for (int v = 0; v < static_cast<int>(s.variants.size()); ++v) {
      const std::vector<std::uint64_t>& only = s.variants[v].seeds;
      if (!only.empty() && std::find(only.begin(), only.end(), seed) == only.end()) continue;
      PlannedRun r;
      r.variant = v;
      r.seed = seed;
      r.overrides = s.scale;
      r.overrides.insert(r.overrides.end(), s.variants[v].set.begin(), s.variants[v].set.end());
      r.overrides.push_back("run.seed=" + std::to_string(seed));
      try {
        r.cfg = io::load_config(s.base, r.overrides);
      } catch (const InputError& e) {
        throw InputError(msg() << "variant " << s.variants[v].name << " (seed " << seed << "): " << e.what());
      }
      r.path = s.variants[v].name + "/seed" + std::to_string(seed) + ".h5";
      const std::vector<int> mine = enabled(r.cfg);
      // the longest run of leading stages an earlier run of this seed computed with the same keys
      int best_k = 0;
      for (int j = 0; j < static_cast<int>(runs.size()); ++j) {
        if (runs[j].seed != seed) continue;
        const std::vector<int> theirs = enabled(runs[j].cfg);
        int k = 0;
        while (k < S) {
          const bool need = std::find(mine.begin(), mine.end(), k) != mine.end();
          const bool have = std::find(theirs.begin(), theirs.end(), k) != theirs.end();
          if (need && !have) break;
          if (!io::incompatible_keys(runs[j].cfg, r.cfg, k + 1 < S ? names[k + 1] : std::string()).empty()) break;
          ++k;
        }
        if (k > best_k) best_k = k, r.base_run = j;
      }
      // the first stage this run computes: after the reused ones, at most its last stage (which is then
      // recomputed on a copy, so that every run has a stage of its own), never agents (--from cannot)
      if (r.base_run >= 0 && !mine.empty()) {
        const int from = std::min(best_k, mine.back());
        if (from >= 1) r.from = names[from];
        else r.base_run = -1;
      } else {
        r.base_run = -1;
      }
      runs.push_back(std::move(r));
    }
  return runs;
}

// the run config as the study started with it, copied into the study folder: every run, resumed ones too,
// reads this copy, so a study is not changed half way by an edit of the config file (or a newer checkout)
constexpr const char* kBaseCopy = "base.toml";

// what the manifest keeps of a run besides its plan
struct RunState {
  std::string status = "planned";  // planned | complete
  double wall = 0;                 // seconds this study spent computing it
  std::string adopted_from;        // --adopt: the run file it was copied from
  std::string commit;              // --adopt: the commit the run file was made with
};

// the manifest DIR/study.toml
toml::table manifest(const Study& s, const std::vector<PlannedRun>& runs, const std::vector<RunState>& st) {
  auto ints = [](const std::vector<std::uint64_t>& xs) {
    toml::array a;
    for (auto x : xs) a.push_back(static_cast<int64_t>(x));
    return a;
  };
  toml::array seeds = ints(s.seeds), vars, list;
  for (const Variant& v : s.variants) {
    toml::array set;
    for (const auto& o : v.set) set.push_back(o);
    toml::table vt{{"name", v.name}, {"doc", v.doc}, {"set", set}};
    if (!v.seeds.empty()) vt.insert("seeds", ints(v.seeds));
    vars.push_back(std::move(vt));
  }
  for (size_t i = 0; i < runs.size(); ++i) {
    const PlannedRun& r = runs[i];
    toml::array ovr;
    for (const auto& o : r.overrides) ovr.push_back(o);
    toml::table t{{"variant", s.variants[r.variant].name},
                  {"seed", static_cast<int64_t>(r.seed)},
                  {"path", r.path},
                  {"from", r.from},
                  {"reuses", r.base_run >= 0 ? runs[r.base_run].path : std::string()},
                  {"overrides", ovr},
                  {"status", st[i].status},
                  {"wall_s", st[i].wall}};
    if (!st[i].adopted_from.empty()) t.insert("adopted_from", st[i].adopted_from);
    if (!st[i].commit.empty()) t.insert("git_commit", st[i].commit);
    list.push_back(std::move(t));
  }
  toml::array scale;
  for (const auto& o : s.scale) scale.push_back(o);
  return toml::table{{"format", "divcoll-study"},
                     {"name", s.name},
                     {"doc", s.doc},
                     {"base", s.base_given},
                     {"base_copy", std::string(kBaseCopy)},
                     {"seeds", seeds},
                     {"scale", scale},
                     {"variant", vars},
                     {"run", list},
                     {"study_file", s.text}};
}

void write_manifest(const std::string& dir, const toml::table& t) {
  const fs::path p = fs::path(dir) / "study.toml", tmp = fs::path(dir) / "study.toml.new";
  {
    std::ofstream out(tmp, std::ios::binary | std::ios::trunc);
    DIVCOLL_THROW_UNLESS(out, "cannot write " << tmp.string());
    out << "# divcoll study manifest: written by `divcoll study`, read by `divcoll report DIR`\n" << t << "\n";
    DIVCOLL_THROW_UNLESS(out.good(), "cannot write " << tmp.string());
  }
  fs::rename(tmp, p);
}

// robustness.py's summary of a run file: DIR/<variant>/seed<k>.h5 -> DIR/<variant>/seed<k>.summary.json
std::filesystem::path summary_path(const std::filesystem::path& run) {
  std::filesystem::path p = run;
  return p.replace_extension(".summary.json");
}

// a run of an existing manifest: its overrides and state, by path
struct OldRun {
  std::vector<std::string> overrides;
  RunState st;
  std::string variant, from, reuses;
  std::uint64_t seed = 0;
};

toml::table read_manifest(const fs::path& man) {
  try {
    return toml::parse_file(man.string());
  } catch (const toml::parse_error& e) {
    throw InputError(msg() << man.string() << " is damaged: " << e.description());
  }
}

std::vector<std::pair<std::string, OldRun>> manifest_runs(const toml::table& t) {
  std::vector<std::pair<std::string, OldRun>> out;
  if (const toml::array* list = t["run"].as_array())
    for (const toml::node& n : *list) {
      const toml::table* r = n.as_table();
      if (!r) continue;
      OldRun o;
      if (const toml::array* a = (*r)["overrides"].as_array())
        for (const toml::node& e : *a)
          if (e.is_string()) o.overrides.push_back(e.as_string()->get());
      o.st.status = (*r)["status"].value_or(std::string("planned"));
      o.st.wall = (*r)["wall_s"].value_or(0.0);
      o.st.adopted_from = (*r)["adopted_from"].value_or(std::string());
      o.st.commit = (*r)["git_commit"].value_or(std::string());
      o.variant = (*r)["variant"].value_or(std::string());
      o.from = (*r)["from"].value_or(std::string());
      o.reuses = (*r)["reuses"].value_or(std::string());
      o.seed = static_cast<std::uint64_t>((*r)["seed"].value_or(int64_t{0}));
      out.emplace_back((*r)["path"].value_or(std::string()), std::move(o));
    }
  return out;
}

// keys that say how a run is run or reported, not what it computes (as `divcoll run --resume` allows)
const std::set<std::string>& free_keys() {
  static const std::set<std::string> k = {"run.progress_every_s", "run.stop_grace_s", "run.memory_limit_gb", "output.dir",
                                          "output.checkpoint_every", "output.checkpoint_interval_s"};
  return k;
}

// the first key whose value differs between two configs, as "key (a -> b)"; empty when they agree
std::string first_difference(const io::RunConfig& a, const io::RunConfig& b) {
  const auto fa = io::flat(a), fb = io::flat(b);
  for (size_t i = 0; i < fa.size() && i < fb.size(); ++i)
    if (fa[i].second != fb[i].second && !free_keys().count(fa[i].first))
      return fa[i].first + " (" + fa[i].second + " -> " + fb[i].second + ")";
  return {};
}

// a run file that ended (its root has end_time): rank-local, read-only
bool run_file_complete(const fs::path& p) {
  if (!fs::is_regular_file(p)) return false;
  try {
    io::h5::File f = io::h5::File::open(p.string());
    return f.has_attribute("end_time");
  } catch (const std::exception&) {
    return false;
  }
}

// the manifest is rewritten by every job of a study that runs its runs at once (--run): each holds the
// folder's lock (io/file_lock.hpp on DIR/study.toml) while it reads, merges and replaces it; a run that
// either side knows complete stays complete
io::WriterLock lock_manifest(const std::string& dir) {
  const std::string target = (fs::path(dir) / "study.toml").string();
  const auto until = std::chrono::steady_clock::now() + std::chrono::seconds(300);
  for (;;) {
    try {
      return io::WriterLock::acquire(target, 1);
    } catch (const InputError& e) {
      if (std::chrono::steady_clock::now() > until)
        throw InputError(msg() << "the study manifest stays locked: " << e.what());
      std::this_thread::sleep_for(std::chrono::milliseconds(100));
    }
  }
}

void save_manifest(const std::string& dir, const Study& s, const std::vector<PlannedRun>& runs,
                   std::vector<RunState>& st) {
  io::WriterLock lock = lock_manifest(dir);
  const fs::path man = fs::path(dir) / "study.toml";
  if (fs::exists(man)) {
    for (auto& [path, o] : manifest_runs(read_manifest(man)))
      for (size_t i = 0; i < runs.size(); ++i)
        if (runs[i].path == path) {
          // another job's run that ended meanwhile (a run marked complete whose file and summary are gone is not)
          const fs::path f = fs::path(dir) / path;
          if (o.st.status == "complete" && st[i].status != "complete" &&
              (fs::exists(f) || fs::exists(summary_path(f))))
            st[i] = o.st;
          if (st[i].adopted_from.empty()) st[i].adopted_from = o.st.adopted_from, st[i].commit = o.st.commit;
        }
  }
  write_manifest(dir, manifest(s, runs, st));
}

std::string clock_text(double s) {
  char b[32];
  if (s < 0) return "unknown";
  if (s < 3600) std::snprintf(b, sizeof b, "%dm%02ds", static_cast<int>(s) / 60, static_cast<int>(s) % 60);
  else std::snprintf(b, sizeof b, "%dh%02dm", static_cast<int>(s) / 3600, static_cast<int>(s) % 3600 / 60);
  return b;
}

// the stages a run computes itself (indices), given what it reuses
std::vector<int> computed(const io::RunConfig& cfg, const std::string& from) {
  std::vector<int> out;
  const auto& names = io::stage_names();
  const int f = from.empty() ? 0 : static_cast<int>(std::find(names.begin(), names.end(), from) - names.begin());
  for (int i : enabled(cfg))
    if (i >= f) out.push_back(i);
  return out;
}
std::vector<int> computed(const PlannedRun& r) { return computed(r.cfg, r.from); }

std::string stages_text(const std::vector<int>& st) {
  std::string t;
  for (int k : st) t += (t.empty() ? "" : ",") + io::stage_names()[k];
  return t;
}

// the study file planned against the study folder, read only. A folder with a manifest is continued only with
// `continuing` (--resume, --run, --submit, --adopt): every run the folder holds (its file, its summary, or
// complete in the manifest) must be in the study file with an unchanged config; runs may be added (seeds,
// variants). The runs read the folder's copy of the base config.
struct Prepared {
  Study s;
  std::vector<PlannedRun> runs;
  std::vector<RunState> st;
};

Prepared prepare(const StudyArgs& args, bool continuing, bool talk) {
  Prepared p;
  Study& s = p.s;
  const std::string& dir = args.out;
  s = parse_study(args.study);
  const fs::path man = fs::path(dir) / "study.toml", copy = fs::path(dir) / kBaseCopy;
  if (fs::exists(man)) {
    DIVCOLL_THROW_UNLESS(continuing, man.string() << " exists: pass --resume to continue the study, or give another --out");
    if (fs::is_regular_file(copy)) {
      if (talk && read_text(copy.string()) != read_text(s.base))
        std::printf("study: %s has changed since the study started; its runs go on with the copy it started "
                    "with, %s\n", s.base.c_str(), copy.string().c_str());
      s.base = copy.string();
    }
  }
  p.runs = plan(s);
  p.st.assign(p.runs.size(), RunState{});
  if (fs::exists(man)) {
    for (auto& [path, o] : manifest_runs(read_manifest(man))) {
      const fs::path file = fs::path(dir) / path;
      const bool held = o.st.status == "complete" || fs::exists(file) || fs::exists(summary_path(file));
      int j = -1;
      for (size_t i = 0; i < p.runs.size(); ++i)
        if (p.runs[i].path == path) j = static_cast<int>(i);
      if (j < 0) {
        DIVCOLL_THROW_UNLESS(!held, args.study << " has no run " << path << " (variant " << o.variant << ", seed "
                                               << o.seed << "), which " << dir << " holds: a study folder only grows; "
                                               << "give another --out to run the changed study");
        continue;
      }
      if (held) {
        io::RunConfig before;
        try {
          before = io::load_config(s.base, o.overrides);
        } catch (const InputError& e) {
          throw InputError(msg() << "run " << path << " of " << dir << " no longer reads: " << e.what());
        }
        const std::string diff = first_difference(before, p.runs[j].cfg);
        DIVCOLL_THROW_UNLESS(diff.empty(), args.study << " changes the config of run " << path << ", which " << dir
                                                      << " holds: " << diff << ". Only runs may be added to a "
                                                      << "study that has started; give another --out to run the "
                                                      << "changed study");
      }
      p.st[j] = o.st;
      // a run marked complete whose file is gone is run again, unless its summary is there (robustness.py
      // writes DIR/<variant>/seed<k>.summary.json beside each run file; a folder kept as its manifest and
      // summaries gathers seeds run elsewhere)
      if (p.st[j].status == "complete" && !fs::exists(file) && !fs::exists(summary_path(file)))
        p.st[j].status = "planned";
    }
  } else {
    for (const PlannedRun& r : p.runs)
      DIVCOLL_THROW_UNLESS(!fs::exists(fs::path(dir) / r.path),
                           (fs::path(dir) / r.path).string() << " exists but " << man.string()
                                                             << " does not: this folder holds another study");
  }
  return p;
}

// the study folder and its copy of the base config (rank 0, or a process without MPI)
void create_folder(const std::string& dir, Study& s) {
  std::error_code ec;
  fs::create_directories(dir, ec);
  DIVCOLL_THROW_UNLESS(fs::is_directory(dir), "cannot create the study folder " << dir);
  const fs::path copy = fs::path(dir) / kBaseCopy;
  if (!fs::exists(copy)) {
    const std::string text = read_text(s.base);
    std::ofstream out(copy, std::ios::binary);
    out << text;
    DIVCOLL_THROW_UNLESS(out.good(), "cannot write " << copy.string());
  }
  s.base = copy.string();
}

// the run --run names: its 1-based index in the plan, or its path (baseline/seed3.h5, or baseline/seed3)
int find_run(const std::vector<PlannedRun>& runs, const std::string& which) {
  if (!which.empty() && std::all_of(which.begin(), which.end(), [](char c) { return c >= '0' && c <= '9'; })) {
    const long k = std::stol(which);
    DIVCOLL_THROW_UNLESS(k >= 1 && k <= static_cast<long>(runs.size()),
                         "--run " << which << ": the study has runs 1 to " << runs.size());
    return static_cast<int>(k - 1);
  }
  for (size_t i = 0; i < runs.size(); ++i)
    if (runs[i].path == which || runs[i].path == which + ".h5") return static_cast<int>(i);
  throw InputError(msg() << "--run " << which << ": no such run in the study (give its number or its path, e.g. "
                         << runs.front().path << ")");
}

// ---- --adopt RUN.h5 ----------------------------------------------------------------------------------------
int adopt_main(const StudyArgs& args) {
  Prepared p = prepare(args, true, true);
  const std::string& dir = args.out;
  io::RunConfig cfg;
  std::string commit;
  {
    std::string why;
    io::h5::File f = io::h5::File::open(args.adopt);
    DIVCOLL_THROW_UNLESS(f.has_attribute("format") && f.read_string("format") == "divcoll-run" &&
                             f.has_attribute("config"),
                         args.adopt << " is not a divcoll run file (no format and config attributes)");
    cfg = io::parse_config(f.read_string("config"), args.adopt + " (stored config)");
    DIVCOLL_THROW_UNLESS(f.has_attribute("end_time"),
                         args.adopt << " is not complete (no end_time): finish it first (divcoll run --resume)");
    if (f.has_attribute("git_commit")) commit = f.read_string("git_commit");
  }
  // which run of the study it stands for: --variant, else its folder's name, else the run of its seed whose
  // config it has
  std::vector<int> same_seed;
  for (size_t i = 0; i < p.runs.size(); ++i)
    if (p.runs[i].seed == cfg.run.seed) same_seed.push_back(static_cast<int>(i));
  DIVCOLL_THROW_UNLESS(!same_seed.empty(), args.adopt << " has run.seed = " << cfg.run.seed
                                                      << ", which no run of the study has");
  std::string variant = args.variant;
  if (variant.empty()) {
    const std::string folder = fs::absolute(args.adopt).parent_path().filename().string();
    for (int i : same_seed)
      if (p.s.variants[p.runs[i].variant].name == folder) variant = folder;
  }
  int target = -1;
  std::string diff;
  if (!variant.empty()) {
    for (int i : same_seed)
      if (p.s.variants[p.runs[i].variant].name == variant) target = i;
    DIVCOLL_THROW_UNLESS(target >= 0, "the study has no run of variant " << variant << " at seed " << cfg.run.seed);
    diff = first_difference(p.runs[target].cfg, cfg);
  } else {
    for (int i : same_seed)
      if (first_difference(p.runs[i].cfg, cfg).empty()) target = i;
    if (target < 0) {
      target = same_seed.front();
      diff = first_difference(p.runs[target].cfg, cfg);
    }
  }
  const PlannedRun& r = p.runs[target];
  const std::string vname = p.s.variants[r.variant].name;
  DIVCOLL_THROW_UNLESS(diff.empty(), args.adopt << " is not the study's run " << r.path << " (variant " << vname
                                                << ", seed " << r.seed << "): its config differs first at "
                                                << diff << " (study -> file)");
  const fs::path dest = fs::path(dir) / r.path;
  DIVCOLL_THROW_UNLESS(!fs::exists(dest), dest.string() << " exists: the study already has this run");
  DIVCOLL_THROW_UNLESS(p.st[target].status != "complete",
                       "the study already has run " << r.path << " (complete, kept as its summary)");
  create_folder(dir, p.s);
  fs::create_directories(dest.parent_path());
  const fs::path tmp = dest.string() + ".adopt";
  fs::copy_file(args.adopt, tmp, fs::copy_options::overwrite_existing);
  fs::rename(tmp, dest);
  p.st[target].status = "complete";
  p.st[target].adopted_from = fs::absolute(args.adopt).lexically_normal().string();
  p.st[target].commit = commit;
  save_manifest(dir, p.s, p.runs, p.st);
  std::printf("study: adopted %s as %s (variant %s, seed %llu, made with commit %s)\n", args.adopt.c_str(),
              dest.string().c_str(), vname.c_str(), static_cast<unsigned long long>(r.seed),
              commit.empty() ? "unknown" : commit.c_str());
  return 0;
}

// ---- --status ----------------------------------------------------------------------------------------------
// DIR/<variant>/seed<k>.job: what the job scripts record of the job that runs a run (key=value lines:
// scheduler, job, state = queued | running | requeued | complete | failed, log, rc)
std::map<std::string, std::string> job_file(const fs::path& run) {
  std::map<std::string, std::string> out;
  fs::path p = run;
  std::ifstream in(p.replace_extension(".job"));
  std::string line;
  while (std::getline(in, line)) {
    const auto eq = line.find('=');
    if (eq != std::string::npos) out[line.substr(0, eq)] = line.substr(eq + 1);
  }
  return out;
}

// whether a live process holds the run's writer lock (RUN.h5.lock, byte 0); the holder's text
bool lock_held(const fs::path& run, std::string* holder) {
  const std::string lp = io::WriterLock::lock_path(run.string());
  const int fd = ::open(lp.c_str(), O_RDONLY);
  if (fd < 0) return false;
  struct flock fl {};
  fl.l_type = F_WRLCK;
  fl.l_whence = SEEK_SET;
  fl.l_start = 0;
  fl.l_len = 1;
  const bool held = fcntl(fd, F_GETLK, &fl) == 0 && fl.l_type != F_UNLCK;
  char b[256] = {0};
  const ssize_t n = ::read(fd, b, sizeof b - 1);
  ::close(fd);
  if (holder) *holder = n > 0 ? std::string(b, static_cast<size_t>(n)) : std::string();
  if (holder && !holder->empty() && holder->back() == '\n') holder->pop_back();
  return held;
}

std::vector<std::string> last_lines(const std::string& path, size_t n) {
  std::ifstream in(path);
  std::vector<std::string> all;
  std::string line;
  while (std::getline(in, line)) all.push_back(line);
  if (all.size() > n) all.erase(all.begin(), all.end() - static_cast<long>(n));
  return all;
}

int status_main(const StudyArgs& args) {
  const std::string dir = args.study;
  const fs::path man = fs::path(dir) / "study.toml";
  DIVCOLL_THROW_UNLESS(fs::is_regular_file(man), dir << " is not a study folder (no study.toml)");
  setenv("HDF5_USE_FILE_LOCKING", "FALSE", 0);  // run files being written are read too
  const toml::table t = read_manifest(man);
  const auto old = manifest_runs(t);
  const std::string base = (fs::path(dir) / t["base_copy"].value_or(std::string(kBaseCopy))).string();
  const auto& names = io::stage_names();
  const int N = static_cast<int>(old.size());
  std::vector<io::RunConfig> cfgs(N);
  std::vector<bool> have_cfg(N, false), done(N, false);
  std::vector<std::map<std::string, std::string>> jobs(N);
  std::map<int, std::vector<double>> stage_s;  // seconds per stage, from the complete runs
  for (int i = 0; i < N; ++i) {
    const fs::path f = fs::path(dir) / old[i].first;
    try {
      cfgs[i] = io::load_config(base, old[i].second.overrides);
      have_cfg[i] = true;
    } catch (const std::exception&) {
    }
    jobs[i] = job_file(f);
    done[i] = run_file_complete(f) || (old[i].second.st.status == "complete" && fs::exists(summary_path(f)));
    if (run_file_complete(f) && have_cfg[i]) {
      try {
        io::h5::File h = io::h5::File::open(f.string());
        for (int st : computed(cfgs[i], old[i].second.from))
          if (h.has(names[st]) && h.group(names[st]).has_attribute("wall_s"))
            stage_s[st].push_back(h.group(names[st]).read_double("wall_s"));
      } catch (const std::exception&) {
      }
    }
  }
  auto mean = [&](int st) {
    if (stage_s[st].empty()) return -1.0;
    double m = 0;
    for (double x : stage_s[st]) m += x;
    return m / static_cast<double>(stage_s[st].size());
  };
  // the stages of run i still to compute: those not complete in its file (or its checkpoint)
  auto remaining = [&](int i, std::string* at) {
    std::vector<int> out;
    const fs::path f = fs::path(dir) / old[i].first;
    std::set<std::string> complete_stages;
    for (const fs::path& src : {fs::path(f.string() + ".ckpt"), f}) {
      if (!fs::is_regular_file(src)) continue;
      try {
        io::h5::File h = io::h5::File::open(src.string());
        for (const std::string& n : names)
          if (h.has(n) && h.group(n).has_attribute("status") && h.group(n).read_string("status") == "complete")
            complete_stages.insert(n);
        break;
      } catch (const std::exception&) {
      }
    }
    if (!have_cfg[i]) return out;
    for (int st : computed(cfgs[i], old[i].second.from))
      if (!complete_stages.count(names[st])) {
        if (at && at->empty()) *at = names[st];
        out.push_back(st);
      }
    return out;
  };
  std::vector<double> eta(N, 0.0), finish(N, 0.0);  // own remaining seconds; when it ends if all goes at once
  bool eta_known = true;
  int n_done = 0, n_running = 0, n_waiting = 0, n_failed = 0, n_queued = 0;
  std::printf("study %s in %s: %d runs\n", t["name"].value_or(std::string("?")).c_str(), dir.c_str(), N);
  for (int i = 0; i < N; ++i) {
    const auto& [path, o] = old[i];
    const fs::path f = fs::path(dir) / path;
    int b = -1;
    for (int j = 0; j < N; ++j)
      if (!o.reuses.empty() && old[j].first == o.reuses) b = j;
    std::string line;
    const auto& job = jobs[i];
    const std::string jobtext = job.count("job") ? " (job " + job.at("job") + ")" : std::string();
    std::string holder;
    if (done[i]) {
      ++n_done;
      line = "done";
      if (!o.st.adopted_from.empty()) line += " (adopted from " + o.st.adopted_from + ", commit " + o.st.commit + ")";
      else if (!fs::exists(f)) line += " (kept as its summary)";
    } else {
      std::string at;
      double e = 0;
      for (int st : remaining(i, &at)) {
        const double m = mean(st);
        if (m < 0) eta_known = false;
        e += std::max(m, 0.0);
      }
      eta[i] = e;
      const std::string eta_text = eta_known ? ", ETA " + clock_text(e) : std::string(", ETA unknown (no run of its stages has ended)");
      const std::string state = job.count("state") ? job.at("state") : std::string();
      if (lock_held(f, &holder)) {
        ++n_running;
        line = "running" + jobtext + " at stage " + (at.empty() ? std::string("?") : at) + eta_text + " [" + holder + "]";
      } else if (state == "failed") {
        ++n_failed;
        line = "failed" + jobtext + (job.count("rc") ? ", status " + job.at("rc") : std::string());
        if (job.count("log")) {
          line += ", last lines of " + job.at("log") + ":";
          for (const std::string& l : last_lines(job.at("log"), 5)) line += "\n      | " + l;
        }
      } else if (b >= 0 && !done[b]) {
        ++n_waiting;
        line = "waiting on " + o.reuses + jobtext;
      } else if (state == "running" || state == "requeued") {
        ++n_running;
        line = (state == "requeued" ? "requeued at the time limit" : "starting") + jobtext + ", next stage " +
               (at.empty() ? std::string("?") : at) + eta_text;
      } else if (!state.empty() && state != "complete") {
        ++n_queued;
        line = state + jobtext + (fs::exists(f) ? ", stopped at stage " + at : std::string()) + eta_text;
      } else {
        ++n_queued;
        line = std::string(fs::exists(f) ? "stopped at stage " + at + " (not running)" : "not started") + eta_text;
      }
    }
    finish[i] = eta[i] + (b >= 0 && b < i ? finish[b] : 0.0);
    std::printf("  %d %s: %s\n", i + 1, path.c_str(), line.c_str());
  }
  double serial = 0, parallel = 0;
  for (int i = 0; i < N; ++i) serial += eta[i], parallel = std::max(parallel, finish[i]);
  std::printf("%d done, %d running, %d to run, %d waiting on their base, %d failed", n_done, n_running, n_queued,
              n_waiting, n_failed);
  if (n_done == N) std::printf("; the study is complete\n");
  else if (!eta_known) std::printf("; overall ETA unknown until a run of every stage has ended\n");
  else std::printf("; overall ETA %s with every ready run at once (%s one after another)\n", clock_text(parallel).c_str(),
                   clock_text(serial).c_str());
  return n_failed > 0 ? 1 : 0;
}

// ---- --submit ----------------------------------------------------------------------------------------------
int submit_main(const StudyArgs& args) {
  DIVCOLL_THROW_UNLESS(args.submit == "slurm" || args.submit == "pbs", "--submit takes slurm or pbs, not " << args.submit);
  DIVCOLL_THROW_UNLESS(args.ranks_per_run >= 1, "--ranks-per-run must be at least 1");
  DIVCOLL_THROW_UNLESS(args.max_parallel >= 0, "--max-parallel must be at least 1 (0: no limit)");
  const char* env_root = std::getenv("DIVCOLL_ROOT");
  const std::string root = env_root && *env_root ? env_root : DIVCOLL_SOURCE_DIR;
  const std::string script = (fs::path(root) / "jobs" / "study-submit.sh").string();
  DIVCOLL_THROW_UNLESS(fs::is_regular_file(script), "no " << script << " (set DIVCOLL_ROOT to the repository)");
  Prepared p = prepare(args, true, true);
  const std::string dir = fs::absolute(args.out).lexically_normal().string();
  if (!args.dry_run) create_folder(dir, p.s);
  const int N = static_cast<int>(p.runs.size());
  std::vector<bool> pending(N, false);
  for (int i = 0; i < N; ++i) {
    const fs::path f = fs::path(dir) / p.runs[i].path;
    if (run_file_complete(f)) p.st[i].status = "complete";
    pending[i] = p.st[i].status != "complete";
  }
  for (int i = 0; i < N; ++i) {
    const int b = p.runs[i].base_run;
    if (!pending[i] || b < 0 || pending[b] || fs::exists(fs::path(dir) / p.runs[i].path)) continue;
    DIVCOLL_THROW_UNLESS(fs::exists(fs::path(dir) / p.runs[b].path),
                         p.runs[i].path << " reuses the stages before " << p.runs[i].from << " of " << p.runs[b].path
                                        << ", whose run file is not in " << dir << " (only its summary is): put the "
                                        << "run file back, or remove the summary to compute that run again");
  }
  if (!args.dry_run) save_manifest(dir, p.s, p.runs, p.st);
  // the runs to submit, one line each: number, path, the number of the submitted run it waits for (0: none),
  // the stages it computes, the run it reuses
  std::string list;
  if (args.dry_run) {
    char tmpl[] = "/tmp/divcoll-study-XXXXXX";
    const int fd = mkstemp(tmpl);
    DIVCOLL_THROW_UNLESS(fd >= 0, "cannot create a temporary file");
    ::close(fd);
    list = tmpl;
  } else {
    fs::create_directories(fs::path(dir) / "jobs");
    list = (fs::path(dir) / "jobs" / "runs.tsv").string();
  }
  {
    std::ofstream out(list, std::ios::trunc);
    for (int i = 0; i < N; ++i) {
      if (!pending[i]) continue;
      const int b = p.runs[i].base_run;
      out << i + 1 << '\t' << p.runs[i].path << '\t' << (b >= 0 && pending[b] ? b + 1 : 0) << '\t'
          << stages_text(computed(p.runs[i])) << '\t' << (b >= 0 ? p.runs[b].path : std::string("-")) << '\n';
    }
    DIVCOLL_THROW_UNLESS(out.good(), "cannot write " << list);
  }
  std::string self = fs::read_symlink("/proc/self/exe").string();
  std::vector<std::string> a = {"bash", script, args.submit, "--study", fs::absolute(args.study).lexically_normal().string(),
                                "--out", dir, "--runs", list, "--of", std::to_string(N), "--name", p.s.name,
                                "--bin", self, "--ranks-per-run", std::to_string(args.ranks_per_run),
                                "--max-parallel", std::to_string(args.max_parallel)};
  if (args.dry_run) a.push_back("--dry-run");
  a.push_back("--");
  a.insert(a.end(), args.scheduler_args.begin(), args.scheduler_args.end());
  std::vector<char*> argv;
  for (std::string& x : a) argv.push_back(x.data());
  argv.push_back(nullptr);
  std::fflush(stdout);
  execvp("bash", argv.data());
  throw InputError(msg() << "cannot run " << script << ": " << std::strerror(errno));
}

}  // namespace

int study_main(int argc, char** argv, const StudyArgs& args) {
  // the commands that run nothing themselves need no MPI (--submit hands over to the scheduler's script)
  const int used = !args.adopt.empty() + args.status + !args.submit.empty() + !args.run.empty() + args.plan;
  try {
    DIVCOLL_THROW_UNLESS(used <= 1, "--plan, --status, --adopt, --submit and --run go one at a time");
    DIVCOLL_THROW_UNLESS(args.status || !args.out.empty(), "--out DIR (the study folder) is required");
    DIVCOLL_THROW_UNLESS(args.submit.empty() || !args.resume, "--submit continues a study folder by itself: drop --resume");
    DIVCOLL_THROW_UNLESS(!args.submit.empty() || (args.scheduler_args.empty() && !args.dry_run && args.max_parallel == 0 &&
                                                  args.ranks_per_run == 1),
                         "--ranks-per-run, --max-parallel, --dry-run and scheduler options go with --submit");
    DIVCOLL_THROW_UNLESS(args.variant.empty() || !args.adopt.empty(), "--variant goes with --adopt");
    if (args.status) {
      DIVCOLL_THROW_UNLESS(fs::is_directory(args.study), "--status takes the study folder: divcoll study DIR --status");
      return status_main(args);
    }
    DIVCOLL_THROW_UNLESS(fs::is_regular_file(args.study), "no study file " << args.study);
    if (!args.adopt.empty()) return adopt_main(args);
    if (!args.submit.empty()) return submit_main(args);
  } catch (const InputError& e) {
    std::fprintf(stderr, "divcoll: error: %s\n", e.what());
    return 2;
  }

  int provided = 0;  // FUNNELED: the task farm computes in a thread of its own (mpi/scheduler.hpp)
  MPI_Init_thread(&argc, &argv, MPI_THREAD_FUNNELED, &provided);
  int code = 0;
  {
    int rank = 0;
    MPI_Comm_rank(MPI_COMM_WORLD, &rank);
    const std::string dir = args.out;
    Prepared p;
    int only = -1;  // --run: the one run to compute
    // everything that can be refused is refused here, on every rank alike, before any run starts
    try {
      if (args.plan) {
        p.s = parse_study(args.study);
        p.runs = plan(p.s);
        if (rank == 0) {
          std::printf("study %s: %zu variant(s) x %zu seed(s) = %zu runs of %s (valid; nothing run)\n", p.s.name.c_str(),
                      p.s.variants.size(), p.s.seeds.size(), p.runs.size(), p.s.base.c_str());
          for (size_t i = 0; i < p.runs.size(); ++i)
            std::printf("  %zu %s: computes %s%s\n", i + 1, p.runs[i].path.c_str(), stages_text(computed(p.runs[i])).c_str(),
                        p.runs[i].base_run >= 0 ? (", reuses " + p.runs[p.runs[i].base_run].path).c_str() : "");
        }
        MPI_Finalize();
        return 0;
      }
      DIVCOLL_THROW_UNLESS(args.run.empty() || args.resume,
                           "--run K computes one run of a study folder that exists: pass --resume too");
      p = prepare(args, args.resume, rank == 0);
      if (!args.run.empty()) only = find_run(p.runs, args.run);
      mpi::barrier_sleeping(MPI_COMM_WORLD);
      mpi::agree_rank0(MPI_COMM_WORLD, [&] {  // a failure on rank 0 stops every rank here
        create_folder(dir, p.s);
        save_manifest(dir, p.s, p.runs, p.st);
      });
      p.s.base = (fs::path(dir) / kBaseCopy).string();
    } catch (const InputError& e) {
      if (rank == 0) std::fprintf(stderr, "divcoll: error: %s\n", e.what());
      MPI_Finalize();
      return 2;
    }
    Study& s = p.s;
    std::vector<PlannedRun>& runs = p.runs;
    std::vector<RunState>& st = p.st;

    const int N = static_cast<int>(runs.size());
    if (rank == 0) {
      int reuse = 0;
      for (const PlannedRun& r : runs) reuse += r.base_run >= 0;
      std::printf("study %s: %zu variant(s) x %zu seed(s) = %d runs of %s into %s (%d reuse earlier stages)%s\n",
                  s.name.c_str(), s.variants.size(), s.seeds.size(), N, s.base.c_str(), dir.c_str(), reuse,
                  only >= 0 ? (": run " + std::to_string(only + 1) + " only").c_str() : "");
      std::fflush(stdout);
    }
    // seconds per computed stage, measured on this study's finished runs (for the ETA)
    std::map<int, std::vector<double>> stage_s;
    const auto t0 = std::chrono::steady_clock::now();
    const auto& names = io::stage_names();
    for (int i = 0; i < N && code == 0; ++i) {
      if (only >= 0 && i != only) continue;
      const PlannedRun& r = runs[i];
      const std::string vname = s.variants[r.variant].name;
      const std::string path = (fs::path(dir) / r.path).string();
      if (rank == 0) {
        // ETA: every remaining run's computed stages at the mean time this study measured for them
        double eta = 0;
        bool known = true;
        for (int j = i; j < N; ++j) {
          if (st[j].status == "complete" || (only >= 0 && j != only)) continue;
          for (int k : computed(runs[j])) {
            if (stage_s[k].empty()) { known = false; break; }
            double m = 0;
            for (double x : stage_s[k]) m += x;
            eta += m / stage_s[k].size();
          }
        }
        const double el = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
        if (st[i].status == "complete")
          std::printf("study: run %d/%d %s seed %llu: complete in %s\n", i + 1, N, vname.c_str(),
                      static_cast<unsigned long long>(r.seed), path.c_str());
        else
          std::printf("study: run %d/%d %s seed %llu stages %s%s | elapsed %s, ETA %s\n", i + 1, N, vname.c_str(),
                      static_cast<unsigned long long>(r.seed), stages_text(computed(r)).c_str(),
                      r.base_run >= 0 ? (" (earlier stages from " + runs[r.base_run].path + ")").c_str() : "",
                      clock_text(el).c_str(), clock_text(known ? eta : -1).c_str());
        std::fflush(stdout);
      }
      if (st[i].status == "complete") continue;
      RunArgs ra;
      ra.config = s.base;
      ra.overrides = r.overrides;
      ra.out = path;
      // a run file that exists was started (or derived) before a kill: it is continued
      bool exists = false;
      if (rank == 0) exists = fs::exists(path);
      int ex = exists;
      MPI_Bcast(&ex, 1, MPI_INT, 0, MPI_COMM_WORLD);
      if (r.base_run >= 0 && !ex) {
        // 0: the base's run file is complete; 1: only its summary is kept; 2: it is not complete (yet)
        int base_state = 0;
        if (rank == 0) {
          const fs::path bp = fs::path(dir) / runs[r.base_run].path;
          base_state = run_file_complete(bp) ? 0 : !fs::exists(bp) && fs::exists(summary_path(bp)) ? 1 : 2;
        }
        MPI_Bcast(&base_state, 1, MPI_INT, 0, MPI_COMM_WORLD);
        if (base_state != 0) {
          if (rank == 0 && base_state == 1)
            std::fprintf(stderr,
                         "divcoll: error: %s reuses the stages before %s of %s, whose run file is not in %s (only its "
                         "summary is): put the run file back, or remove the summary to compute that run again\n",
                         r.path.c_str(), r.from.c_str(), runs[r.base_run].path.c_str(), dir.c_str());
          else if (rank == 0)
            std::fprintf(stderr,
                         "divcoll: error: run %d (%s) reuses the stages before %s of run %s, which is not complete "
                         "yet: that run must end first (divcoll study %s --status)\n",
                         i + 1, r.path.c_str(), r.from.c_str(), runs[r.base_run].path.c_str(), dir.c_str());
          code = base_state == 1 ? 2 : kBaseNotComplete;
          break;
        }
        ra.from = r.from;
        ra.base = (fs::path(dir) / runs[r.base_run].path).string();
      } else {
        ra.resume = true;
      }
      const auto t1 = std::chrono::steady_clock::now();
      code = run_session(ra);
      if (code != 0) break;
      st[i].status = "complete";
      st[i].wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - t1).count();
      if (rank == 0) {
        try {
          io::h5::File f = io::h5::File::open(path);
          for (int k : computed(r))
            if (f.has(names[k]) && f.group(names[k]).has_attribute("wall_s"))
              stage_s[k].push_back(f.group(names[k]).read_double("wall_s"));
        } catch (const std::exception&) {
          // timings only feed the ETA
        }
        try {
          save_manifest(dir, s, runs, st);
        } catch (const std::exception& e) {
          std::fprintf(stderr, "divcoll: error: %s\n", e.what());
          code = 1;
        }
      }
      MPI_Bcast(&code, 1, MPI_INT, 0, MPI_COMM_WORLD);
    }
    if (rank == 0 && code == 0 && only < 0)
      std::printf("study %s: done, %d runs in %s; `divcoll report %s` writes the robustness page\n", s.name.c_str(), N,
                  dir.c_str(), dir.c_str());
    if (rank == 0 && code == 0 && only >= 0)
      std::printf("study %s: run %d (%s) complete\n", s.name.c_str(), only + 1, runs[only].path.c_str());
  }
  MPI_Finalize();
  return code;
}

}  // namespace divcoll::cli
