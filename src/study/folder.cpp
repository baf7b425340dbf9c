#include "study/folder.hpp"

#include <chrono>
#include <cstdio>
#include <fstream>
#include <set>
#include <thread>

#include "common/check.hpp"
#include "config/toml_doc.hpp"
#include "io/file_lock.hpp"
#include "io/h5.hpp"

namespace divcoll::study {
namespace {

namespace fs = std::filesystem;
using config::TomlValue;
using Kind = config::TomlValue::Kind;

TomlValue seed_values(const std::vector<std::uint64_t>& seeds) {
  std::vector<TomlValue> a;
  for (auto x : seeds) a.push_back(TomlValue::of(static_cast<std::int64_t>(x)));
  return TomlValue::list(std::move(a));
}

TomlValue run_table(const Study& s, const std::vector<PlannedRun>& runs, size_t i, const RunState& st) {
  const PlannedRun& r = runs[i];
  TomlValue t;
  t.set("variant", TomlValue::of(s.variants[r.variant].name));
  t.set("seed", TomlValue::of(static_cast<std::int64_t>(r.seed)));
  t.set("path", TomlValue::of(r.path));
  t.set("from", TomlValue::of(r.from));
  t.set("reuses", TomlValue::of(r.base_run >= 0 ? runs[r.base_run].path : std::string()));
  t.set("overrides", TomlValue::list(r.overrides));
  t.set("status", TomlValue::of(st.status));
  t.set("wall_s", TomlValue::of(st.wall));
  if (!st.adopted_from.empty()) t.set("adopted_from", TomlValue::of(st.adopted_from));
  if (!st.commit.empty()) t.set("git_commit", TomlValue::of(st.commit));
  return t;
}

ManifestRun manifest_run(const TomlValue& r) {
  ManifestRun o;
  if (const TomlValue* a = r.find("overrides"); a && a->is(Kind::array))
    for (const TomlValue& e : a->items)
      if (e.is(Kind::string)) o.overrides.push_back(e.string);
  o.st.status = r.string_or("status", "planned");
  o.st.wall = r.number_or("wall_s", 0.0);
  o.st.adopted_from = r.string_or("adopted_from", "");
  o.st.commit = r.string_or("git_commit", "");
  o.variant = r.string_or("variant", "");
  o.from = r.string_or("from", "");
  o.reuses = r.string_or("reuses", "");
  o.seed = static_cast<std::uint64_t>(r.integer_or("seed", 0));
  o.path = r.string_or("path", "");
  return o;
}

// the manifest is rewritten by every job of a study that runs its runs at once (--run): each holds the folder's
// lock while it reads, merges and replaces it
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

void write_manifest(const std::string& dir, const std::string& text) {
  const fs::path p = fs::path(dir) / "study.toml", tmp = fs::path(dir) / "study.toml.new";
  {
    std::ofstream out(tmp, std::ios::binary | std::ios::trunc);
    DIVCOLL_THROW_UNLESS(out, "cannot write " << tmp.string());
    out << "# divcoll study manifest: written by `divcoll study`, read by `divcoll report DIR`\n" << text << "\n";
    DIVCOLL_THROW_UNLESS(out.good(), "cannot write " << tmp.string());
  }
  fs::rename(tmp, p);
}

// keys that say how a run is run or reported, not what it computes (as `divcoll run --resume` allows)
const std::set<std::string>& free_keys() {
  static const std::set<std::string> k = {"run.progress_every_s", "run.stop_grace_s", "run.memory_limit_gb", "output.dir",
                                          "output.checkpoint_every", "output.checkpoint_interval_s"};
  return k;
}

// a run the manifest lists that the folder holds must keep its config in the study file
void check_held_run(const std::string& study_file, const std::string& dir, const Prepared& p, const ManifestRun& o,
                    int j) {
  config::RunConfig before;
  try {
    before = config::load_config(p.s.base, o.overrides);
  } catch (const InputError& e) {
    throw InputError(msg() << "run " << o.path << " of " << dir << " no longer reads: " << e.what());
  }
  const std::string diff = first_difference(before, p.runs[j].cfg);
  DIVCOLL_THROW_UNLESS(diff.empty(), study_file << " changes the config of run " << o.path << ", which " << dir
                                                << " holds: " << diff << ". Only runs may be added to a "
                                                << "study that has started; give another --out to run the "
                                                << "changed study");
}

// the manifest's runs into the plan's states, each checked against the study file
void take_manifest(const std::string& study_file, const std::string& dir, Prepared& p) {
  for (const ManifestRun& o : read_manifest(dir).runs) {
    const fs::path file = fs::path(dir) / o.path;
    const bool held = o.st.status == "complete" || fs::exists(file) || fs::exists(summary_path(file));
    int j = -1;
    for (size_t i = 0; i < p.runs.size(); ++i)
      if (p.runs[i].path == o.path) j = static_cast<int>(i);
    if (j < 0) {
      DIVCOLL_THROW_UNLESS(!held, study_file << " has no run " << o.path << " (variant " << o.variant << ", seed "
                                             << o.seed << "), which " << dir << " holds: a study folder only grows; "
                                             << "give another --out to run the changed study");
      continue;
    }
    if (held) check_held_run(study_file, dir, p, o, j);
    p.st[j] = o.st;
    // a run marked complete whose file is gone is run again, unless its summary is there (robustness.py
    // writes DIR/<variant>/seed<k>.summary.json beside each run file; a folder kept as its manifest and
    // summaries gathers seeds run elsewhere)
    if (p.st[j].status == "complete" && !fs::exists(file) && !fs::exists(summary_path(file))) p.st[j].status = "planned";
  }
}

}  // namespace

Manifest read_manifest(const std::string& dir) {
  const fs::path man = fs::path(dir) / "study.toml";
  std::ifstream in(man, std::ios::binary);
  DIVCOLL_THROW_UNLESS(in, "cannot read " << man.string());
  const std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  TomlValue t;
  try {
    t = config::parse_toml(text, man.string());
  } catch (const config::TomlSyntaxError& e) {
    throw InputError(msg() << man.string() << " is damaged: " << e.reason);
  }
  Manifest m;
  m.name = t.string_or("name", "?");
  m.base_copy = t.string_or("base_copy", kBaseCopy);
  if (const TomlValue* list = t.find("run"); list && list->is(Kind::array))
    for (const TomlValue& r : list->items)
      if (r.is(Kind::table)) m.runs.push_back(manifest_run(r));
  return m;
}

std::string manifest_text(const Study& s, const std::vector<PlannedRun>& runs, const std::vector<RunState>& st) {
  std::vector<TomlValue> vars, list;
  for (const Variant& v : s.variants) {
    TomlValue vt;
    vt.set("name", TomlValue::of(v.name));
    vt.set("doc", TomlValue::of(v.doc));
    vt.set("set", TomlValue::list(v.set));
    if (!v.seeds.empty()) vt.set("seeds", seed_values(v.seeds));
    if (!v.added.empty()) vt.set("added", TomlValue::of(v.added));
    vars.push_back(std::move(vt));
  }
  for (size_t i = 0; i < runs.size(); ++i) list.push_back(run_table(s, runs, i, st[i]));
  TomlValue t;
  t.set("format", TomlValue::of("divcoll-study"));
  t.set("name", TomlValue::of(s.name));
  t.set("doc", TomlValue::of(s.doc));
  t.set("base", TomlValue::of(s.base_given));
  t.set("base_copy", TomlValue::of(kBaseCopy));
  t.set("seeds", seed_values(s.seeds));
  t.set("scale", TomlValue::list(s.scale));
  t.set("variant", TomlValue::list(std::move(vars)));
  t.set("run", TomlValue::list(std::move(list)));
  t.set("study_file", TomlValue::of(s.text));
  return config::toml_text(t);
}

void save_manifest(const std::string& dir, const Study& s, const std::vector<PlannedRun>& runs,
                   std::vector<RunState>& st) {
  io::WriterLock lock = lock_manifest(dir);
  if (fs::exists(fs::path(dir) / "study.toml")) {
    for (const ManifestRun& o : read_manifest(dir).runs)
      for (size_t i = 0; i < runs.size(); ++i)
        if (runs[i].path == o.path) {
          // another job's run that ended meanwhile (a run marked complete whose file and summary are gone is not)
          const fs::path f = fs::path(dir) / o.path;
          if (o.st.status == "complete" && st[i].status != "complete" &&
              (fs::exists(f) || fs::exists(summary_path(f))))
            st[i] = o.st;
          if (st[i].adopted_from.empty()) st[i].adopted_from = o.st.adopted_from, st[i].commit = o.st.commit;
        }
  }
  write_manifest(dir, manifest_text(s, runs, st));
}

fs::path summary_path(const fs::path& run) {
  fs::path p = run;
  return p.replace_extension(".summary.json");
}

bool run_file_complete(const fs::path& run) {
  if (!fs::is_regular_file(run)) return false;
  try {
    io::h5::File f = io::h5::File::open(run.string());
    return f.has_attribute("end_time");
  } catch (const std::exception&) {
    return false;
  }
}

std::string first_difference(const config::RunConfig& a, const config::RunConfig& b) {
  const auto fa = config::flat(a), fb = config::flat(b);
  for (size_t i = 0; i < fa.size() && i < fb.size(); ++i)
    if (fa[i].second != fb[i].second && !free_keys().count(fa[i].first))
      return fa[i].first + " (" + fa[i].second + " -> " + fb[i].second + ")";
  return {};
}

Prepared prepare(const std::string& study_file, const std::string& dir, bool continuing, bool talk) {
  Prepared p;
  Study& s = p.s;
  s = parse_study(study_file);
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
    take_manifest(study_file, dir, p);
  } else {
    for (const PlannedRun& r : p.runs)
      DIVCOLL_THROW_UNLESS(!fs::exists(fs::path(dir) / r.path),
                           (fs::path(dir) / r.path).string() << " exists but " << man.string()
                                                             << " does not: this folder holds another study");
  }
  return p;
}

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

}  // namespace divcoll::study
