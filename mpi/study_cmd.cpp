#include "mpi/study_cmd.hpp"

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

#include "common/check.hpp"
#include "io/config.hpp"
#include "io/h5.hpp"
#include "mpi/agree.hpp"
#include "mpi/run_cmd.hpp"
#include "mpi/wait.hpp"

namespace divcoll::mpi {
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
  const toml::array* seeds = st->get("seeds")->as_array();
  DIVCOLL_THROW_UNLESS(seeds && !seeds->empty(), "study.seeds must be a non-empty list of integers >= 0");
  for (const toml::node& e : *seeds) {
    DIVCOLL_THROW_UNLESS(e.is_integer() && e.as_integer()->get() >= 0, "study.seeds must be a non-empty list of integers >= 0");
    const auto v = static_cast<std::uint64_t>(e.as_integer()->get());
    DIVCOLL_THROW_UNLESS(std::find(s.seeds.begin(), s.seeds.end(), v) == s.seeds.end(), "study.seeds lists " << v << " twice");
    s.seeds.push_back(v);
  }
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
      else if (key == "seeds") {
        const toml::array* a = val.as_array();
        DIVCOLL_THROW_UNLESS(a && !a->empty(), "variant.seeds must be a non-empty list of the study's seeds");
        for (const toml::node& e : *a) {
          DIVCOLL_THROW_UNLESS(e.is_integer() && e.as_integer()->get() >= 0,
                               "variant.seeds must be a non-empty list of the study's seeds");
          const auto sd = static_cast<std::uint64_t>(e.as_integer()->get());
          DIVCOLL_THROW_UNLESS(std::find(v.seeds.begin(), v.seeds.end(), sd) == v.seeds.end(),
                               "variant.seeds lists " << sd << " twice");
          v.seeds.push_back(sd);
        }
      } else throw InputError(msg() << "unknown key variant." << key << " in " << path << " (known: name, set, seeds, doc)");
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
          if (!incompatible_keys(runs[j].cfg, r.cfg, k + 1 < S ? names[k + 1] : std::string()).empty()) break;
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

// the manifest DIR/study.toml
toml::table manifest(const Study& s, const std::vector<PlannedRun>& runs, const std::vector<std::string>& status,
                     const std::vector<double>& wall) {
  toml::array seeds, vars, list;
  for (auto v : s.seeds) seeds.push_back(static_cast<int64_t>(v));
  for (const Variant& v : s.variants) {
    toml::array set;
    for (const auto& o : v.set) set.push_back(o);
    toml::table vt{{"name", v.name}, {"doc", v.doc}, {"set", set}};
    if (!v.seeds.empty()) {
      toml::array vs;
      for (auto sd : v.seeds) vs.push_back(static_cast<int64_t>(sd));
      vt.insert("seeds", vs);
    }
    vars.push_back(std::move(vt));
  }
  for (size_t i = 0; i < runs.size(); ++i) {
    const PlannedRun& r = runs[i];
    toml::array ovr;
    for (const auto& o : r.overrides) ovr.push_back(o);
    list.push_back(toml::table{{"variant", s.variants[r.variant].name},
                               {"seed", static_cast<int64_t>(r.seed)},
                               {"path", r.path},
                               {"from", r.from},
                               {"reuses", r.base_run >= 0 ? runs[r.base_run].path : std::string()},
                               {"overrides", ovr},
                               {"status", status[i]},
                               {"wall_s", wall[i]}});
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

std::string clock_text(double s) {
  char b[32];
  if (s < 0) return "unknown";
  if (s < 3600) std::snprintf(b, sizeof b, "%dm%02ds", static_cast<int>(s) / 60, static_cast<int>(s) % 60);
  else std::snprintf(b, sizeof b, "%dh%02dm", static_cast<int>(s) / 3600, static_cast<int>(s) % 3600 / 60);
  return b;
}

// the stages a run computes itself (indices), given what it reuses
std::vector<int> computed(const PlannedRun& r) {
  std::vector<int> out;
  const auto& names = io::stage_names();
  const int from = r.from.empty() ? 0 : static_cast<int>(std::find(names.begin(), names.end(), r.from) - names.begin());
  for (int i : enabled(r.cfg))
    if (i >= from) out.push_back(i);
  return out;
}

}  // namespace

int study_main(int argc, char** argv, const StudyArgs& args) {
  int provided = 0;  // FUNNELED: the task farm computes in a thread of its own (mpi/scheduler.hpp)
  MPI_Init_thread(&argc, &argv, MPI_THREAD_FUNNELED, &provided);
  int code = 0;
  {
    int rank = 0;
    MPI_Comm_rank(MPI_COMM_WORLD, &rank);
    const std::string dir = args.out;
    Study s;
    std::vector<PlannedRun> runs;
    std::vector<std::string> status;
    std::vector<double> wall;
    // everything that can be refused is refused here, on every rank alike, before any run starts
    try {
      s = parse_study(args.study);
      // a study being resumed reads the config it started with (its folder's copy)
      const fs::path copy = fs::path(dir) / kBaseCopy;
      if (!args.plan && args.resume && fs::exists(fs::path(dir) / "study.toml") && fs::is_regular_file(copy)) {
        if (rank == 0 && read_text(copy.string()) != read_text(s.base))
          std::printf("study: %s has changed since the study started; its runs go on with the copy it started "
                      "with, %s\n", s.base.c_str(), copy.string().c_str());
        s.base = copy.string();
      }
      runs = plan(s);
      status.assign(runs.size(), "planned");
      wall.assign(runs.size(), 0.0);
      if (args.plan) {
        if (rank == 0) {
          std::printf("study %s: %zu variant(s) x %zu seed(s) = %zu runs of %s (valid; nothing run)\n", s.name.c_str(),
                      s.variants.size(), s.seeds.size(), runs.size(), s.base.c_str());
          for (size_t i = 0; i < runs.size(); ++i) {
            std::string st;
            for (int k : computed(runs[i])) st += (st.empty() ? "" : ",") + io::stage_names()[k];
            std::printf("  %zu %s: computes %s%s\n", i + 1, runs[i].path.c_str(), st.c_str(),
                        runs[i].base_run >= 0 ? (", reuses " + runs[runs[i].base_run].path).c_str() : "");
          }
        }
        MPI_Finalize();
        return 0;
      }
      const fs::path man = fs::path(dir) / "study.toml";
      if (fs::exists(man)) {
        DIVCOLL_THROW_UNLESS(args.resume, man.string() << " exists: pass --resume to continue the study, or give another --out");
        toml::table old;
        try {
          old = toml::parse_file(man.string());
        } catch (const toml::parse_error& e) {
          throw InputError(msg() << man.string() << " is damaged: " << e.description());
        }
        DIVCOLL_THROW_UNLESS(old["study_file"].value_or(std::string()) == s.text,
                             args.study << " differs from the study file " << dir
                                        << " was started with: give another --out to run the changed study");
        if (const toml::array* list = old["run"].as_array())
          for (size_t i = 0; i < list->size() && i < runs.size(); ++i) {
            const toml::table* t = (*list)[i].as_table();
            if (!t) continue;
            status[i] = (*t)["status"].value_or(std::string("planned"));
            wall[i] = (*t)["wall_s"].value_or(0.0);
            // a run marked complete whose file is gone is run again, unless its summary is there (robustness.py
            // writes DIR/<variant>/seed<k>.summary.json beside each run file; a folder kept as its manifest and
            // summaries gathers seeds run elsewhere)
            if (status[i] == "complete" && !fs::exists(fs::path(dir) / runs[i].path) &&
                !fs::exists(summary_path(fs::path(dir) / runs[i].path)))
              status[i] = "planned";
          }
      } else {
        for (const PlannedRun& r : runs)
          DIVCOLL_THROW_UNLESS(!fs::exists(fs::path(dir) / r.path),
                               (fs::path(dir) / r.path).string() << " exists but " << man.string()
                                                                 << " does not: this folder holds another study");
      }
      std::error_code ec;
      if (rank == 0) fs::create_directories(dir, ec);
      barrier_sleeping(MPI_COMM_WORLD);
      DIVCOLL_THROW_UNLESS(fs::is_directory(dir), "cannot create the study folder " << dir);
      agree_rank0(MPI_COMM_WORLD, [&] {  // a failure on rank 0 stops every rank here
        if (!fs::exists(copy)) {
          const std::string text = read_text(s.base);
          std::ofstream out(copy, std::ios::binary);
          out << text;
          DIVCOLL_THROW_UNLESS(out.good(), "cannot write " << copy.string());
        }
        write_manifest(dir, manifest(s, runs, status, wall));
      });
      s.base = copy.string();
    } catch (const InputError& e) {
      if (rank == 0) std::fprintf(stderr, "divcoll: error: %s\n", e.what());
      MPI_Finalize();
      return 2;
    }

    const int N = static_cast<int>(runs.size());
    if (rank == 0) {
      int reuse = 0;
      for (const PlannedRun& r : runs) reuse += r.base_run >= 0;
      std::printf("study %s: %zu variant(s) x %zu seed(s) = %d runs of %s into %s (%d reuse earlier stages)\n",
                  s.name.c_str(), s.variants.size(), s.seeds.size(), N, s.base.c_str(), dir.c_str(), reuse);
      std::fflush(stdout);
    }
    // seconds per computed stage, measured on this study's finished runs (for the ETA)
    std::map<int, std::vector<double>> stage_s;
    const auto t0 = std::chrono::steady_clock::now();
    const auto& names = io::stage_names();
    for (int i = 0; i < N && code == 0; ++i) {
      const PlannedRun& r = runs[i];
      const std::string vname = s.variants[r.variant].name;
      const std::string path = (fs::path(dir) / r.path).string();
      std::string stages_text;
      for (int st : computed(r)) stages_text += (stages_text.empty() ? "" : ",") + names[st];
      if (rank == 0) {
        // ETA: every remaining run's computed stages at the mean time this study measured for them
        double eta = 0;
        bool known = true;
        for (int j = i; j < N; ++j) {
          if (status[j] == "complete") continue;
          for (int st : computed(runs[j])) {
            if (stage_s[st].empty()) { known = false; break; }
            double m = 0;
            for (double x : stage_s[st]) m += x;
            eta += m / stage_s[st].size();
          }
        }
        const double el = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
        if (status[i] == "complete")
          std::printf("study: run %d/%d %s seed %llu: complete in %s\n", i + 1, N, vname.c_str(),
                      static_cast<unsigned long long>(r.seed), path.c_str());
        else
          std::printf("study: run %d/%d %s seed %llu stages %s%s | elapsed %s, ETA %s\n", i + 1, N, vname.c_str(),
                      static_cast<unsigned long long>(r.seed), stages_text.c_str(),
                      r.base_run >= 0 ? (" (earlier stages from " + runs[r.base_run].path + ")").c_str() : "",
                      clock_text(el).c_str(), clock_text(known ? eta : -1).c_str());
        std::fflush(stdout);
      }
      if (status[i] == "complete") continue;
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
        int base_ok = 1;
        if (rank == 0) base_ok = fs::exists(fs::path(dir) / runs[r.base_run].path);
        MPI_Bcast(&base_ok, 1, MPI_INT, 0, MPI_COMM_WORLD);
        if (!base_ok) {
          if (rank == 0)
            std::fprintf(stderr,
                         "divcoll: error: %s reuses the stages before %s of %s, whose run file is not in %s (only its "
                         "summary is): put the run file back, or remove the summary to compute that run again\n",
                         r.path.c_str(), r.from.c_str(), runs[r.base_run].path.c_str(), dir.c_str());
          code = 2;
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
      status[i] = "complete";
      wall[i] = std::chrono::duration<double>(std::chrono::steady_clock::now() - t1).count();
      if (rank == 0) {
        try {
          io::h5::File f = io::h5::File::open(path);
          for (int st : computed(r))
            if (f.has(names[st]) && f.group(names[st]).has_attribute("wall_s"))
              stage_s[st].push_back(f.group(names[st]).read_double("wall_s"));
        } catch (const std::exception&) {
          // timings only feed the ETA
        }
        write_manifest(dir, manifest(s, runs, status, wall));
      }
    }
    if (rank == 0 && code == 0)
      std::printf("study %s: done, %d runs in %s; `divcoll report %s` writes the robustness page\n", s.name.c_str(), N,
                  dir.c_str(), dir.c_str());
  }
  MPI_Finalize();
  return code;
}

}  // namespace divcoll::mpi
