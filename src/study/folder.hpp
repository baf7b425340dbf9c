// the study folder DIR, as a study's runs read and grow it:
//   DIR/base.toml                the run config as the study started: every run reads it, resumed runs too, so an
//                                edit of the config file (or a newer checkout) does not change a study half way
//   DIR/study.toml               the manifest: the study file's text, and per run its variant, seed, path, the stage
//                                it was computed from and the run it reused (empty: computed from scratch), its
//                                status, and for an adopted run the file it came from and that file's commit
//   DIR/<variant>/seed<k>.h5     the run files; beside each, seed<k>.summary.json (divcoll_post.robustness's
//                                summary, which stands for a run whose file is gone) and seed<k>.job (what the job
//                                scripts record of the job that runs it)
// Several jobs may rewrite the manifest at once (--run): each holds the folder's lock (io::WriterLock on
// DIR/study.toml) while it reads, merges and replaces it, and a run either side knows complete stays complete.
#pragma once

#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

#include "config/config.hpp"
#include "study/plan.hpp"
#include "study/study_file.hpp"

namespace divcoll::study {

// the folder's copy of the base config
inline constexpr const char* kBaseCopy = "base.toml";

// what the manifest keeps of a run besides its plan
struct RunState {
  std::string status = "planned";  // planned | complete
  double wall = 0;                 // seconds this study spent computing it
  std::string adopted_from;        // --adopt: the run file it was copied from
  std::string commit;              // --adopt: the commit the run file was made with
};

// a run as the manifest lists it
struct ManifestRun {
  std::string path, variant, from, reuses;
  std::uint64_t seed = 0;
  std::vector<std::string> overrides;
  RunState st;
};
struct Manifest {
  std::string name;       // the study's
  std::string base_copy;  // the base config's copy, relative to the folder
  std::vector<ManifestRun> runs;
};

// DIR/study.toml read; InputError "<file> is damaged: <reason>" if it does not parse
Manifest read_manifest(const std::string& dir);
// the manifest's text of a study's runs and their states
std::string manifest_text(const Study& s, const std::vector<PlannedRun>& runs, const std::vector<RunState>& st);
// replaces DIR/study.toml under the folder's lock, first merging the one there: a run another job completed
// meanwhile (its file or summary is there) is complete in `st` too, and an adoption it recorded is kept
void save_manifest(const std::string& dir, const Study& s, const std::vector<PlannedRun>& runs, std::vector<RunState>& st);

// divcoll_post.robustness's summary of a run file: DIR/<variant>/seed<k>.h5 -> DIR/<variant>/seed<k>.summary.json
std::filesystem::path summary_path(const std::filesystem::path& run);
// a run file that ended (its root has end_time): rank-local, read-only
bool run_file_complete(const std::filesystem::path& run);
// the first key whose value differs between two configs, as "key (a -> b)", leaving out the keys that say how a
// run is run or reported, not what it computes (as divcoll run --resume does); empty when they agree
std::string first_difference(const config::RunConfig& a, const config::RunConfig& b);

// the study file planned against the study folder, read only
struct Prepared {
  Study s;
  std::vector<PlannedRun> runs;
  std::vector<RunState> st;
};
// A folder with a manifest is continued only when `continuing` (--resume, --run, --submit, --adopt): every run the
// folder holds (its file, its summary, or complete in the manifest) must be in the study file with an unchanged
// config; runs may be added (seeds, variants). The runs read the folder's copy of the base config; `talk`: say so
// when the config file has changed since
Prepared prepare(const std::string& study_file, const std::string& dir, bool continuing, bool talk);
// makes the folder and its copy of the base config (once), which the runs of `s` then read
void create_folder(const std::string& dir, Study& s);

}  // namespace divcoll::study
