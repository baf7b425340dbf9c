// --adopt RUN.h5: a run file made elsewhere taken into the study folder as the run of its (variant, seed)
#include "study/adopt.hpp"

#include <cstdio>
#include <filesystem>

#include "common/check.hpp"
#include "config/config.hpp"
#include "io/h5.hpp"
#include "study/folder.hpp"

namespace divcoll::study {
namespace {

namespace fs = std::filesystem;

// a complete run file's stored config and the commit it was made with
struct Stored {
  config::RunConfig cfg;
  std::string commit;
};

Stored stored_run(const std::string& run_file) {
  Stored out;
  io::h5::File f = io::h5::File::open(run_file);
  DIVCOLL_THROW_UNLESS(f.has_attribute("format") && f.read_string("format") == "divcoll-run" &&
                           f.has_attribute("config"),
                       run_file << " is not a divcoll run file (no format and config attributes)");
  out.cfg = config::parse_config(f.read_string("config"), run_file + " (stored config)");
  DIVCOLL_THROW_UNLESS(f.has_attribute("end_time"),
                       run_file << " is not complete (no end_time): finish it first (divcoll run --resume)");
  if (f.has_attribute("git_commit")) out.commit = f.read_string("git_commit");
  return out;
}

// which run of the study the file stands for: --variant, else its folder's name, else the run of its seed whose
// config it has; `diff` gets the first key where the file differs from it (empty: none)
int target_run(const Prepared& p, const std::string& run_file, const std::string& variant_given,
               const config::RunConfig& cfg, std::string& diff) {
  std::vector<int> same_seed;
  for (size_t i = 0; i < p.runs.size(); ++i)
    if (p.runs[i].seed == cfg.run.seed) same_seed.push_back(static_cast<int>(i));
  DIVCOLL_THROW_UNLESS(!same_seed.empty(), run_file << " has run.seed = " << cfg.run.seed
                                                    << ", which no run of the study has");
  std::string variant = variant_given;
  if (variant.empty()) {
    const std::string folder = fs::absolute(run_file).parent_path().filename().string();
    for (int i : same_seed)
      if (p.s.variants[p.runs[i].variant].name == folder) variant = folder;
  }
  int target = -1;
  if (!variant.empty()) {
    for (int i : same_seed)
      if (p.s.variants[p.runs[i].variant].name == variant) target = i;
    DIVCOLL_THROW_UNLESS(target >= 0, "the study has no run of variant " << variant << " at seed " << cfg.run.seed);
    diff = first_difference(p.runs[target].cfg, cfg);
    return target;
  }
  for (int i : same_seed)
    if (first_difference(p.runs[i].cfg, cfg).empty()) target = i;
  if (target < 0) {
    target = same_seed.front();
    diff = first_difference(p.runs[target].cfg, cfg);
  }
  return target;
}

}  // namespace

int adopt(const std::string& study_file, const std::string& dir, const std::string& run_file, const std::string& variant) {
  Prepared p = prepare(study_file, dir, true, true);
  const Stored stored = stored_run(run_file);
  std::string diff;
  const int target = target_run(p, run_file, variant, stored.cfg, diff);
  const PlannedRun& r = p.runs[target];
  const std::string vname = p.s.variants[r.variant].name;
  DIVCOLL_THROW_UNLESS(diff.empty(), run_file << " is not the study's run " << r.path << " (variant " << vname
                                              << ", seed " << r.seed << "): its config differs first at "
                                              << diff << " (study -> file)");
  const fs::path dest = fs::path(dir) / r.path;
  DIVCOLL_THROW_UNLESS(!fs::exists(dest), dest.string() << " exists: the study already has this run");
  DIVCOLL_THROW_UNLESS(p.st[target].status != "complete",
                       "the study already has run " << r.path << " (complete, kept as its summary)");
  create_folder(dir, p.s);
  fs::create_directories(dest.parent_path());
  const fs::path tmp = dest.string() + ".adopt";
  fs::copy_file(run_file, tmp, fs::copy_options::overwrite_existing);
  fs::rename(tmp, dest);
  p.st[target].status = "complete";
  p.st[target].adopted_from = fs::absolute(run_file).lexically_normal().string();
  p.st[target].commit = stored.commit;
  save_manifest(dir, p.s, p.runs, p.st);
  std::printf("study: adopted %s as %s (variant %s, seed %llu, made with commit %s)\n", run_file.c_str(),
              dest.string().c_str(), vname.c_str(), static_cast<unsigned long long>(r.seed),
              stored.commit.empty() ? "unknown" : stored.commit.c_str());
  return 0;
}

}  // namespace divcoll::study
