// --submit slurm|pbs: the hand-over of a study's runs to a cluster's scheduler (jobs/study-submit.sh)
#include "study/submit.hpp"

#include <unistd.h>

#include <cerrno>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>

#include "common/check.hpp"
#include "study/folder.hpp"
#include "study/plan.hpp"

namespace divcoll::study {
namespace {

namespace fs = std::filesystem;

// which runs are still to compute (a run file that ended counts as complete); refuses a run to compute whose base
// is kept only as its summary
std::vector<bool> pending_runs(const std::string& dir, Prepared& p) {
  const int N = static_cast<int>(p.runs.size());
  std::vector<bool> pending(N, false);
  for (int i = 0; i < N; ++i) {
    if (run_file_complete(fs::path(dir) / p.runs[i].path)) p.st[i].status = "complete";
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
  return pending;
}

// the runs to submit, one line each: number, path, the number of the submitted run it waits for (0: none), the
// stages it computes, the run it reuses; into DIR/jobs/runs.tsv, or a temporary file for a dry run. Returns its path
std::string write_run_list(const std::string& dir, const Prepared& p, const std::vector<bool>& pending, bool dry_run) {
  std::string list;
  if (dry_run) {
    char tmpl[] = "/tmp/divcoll-study-XXXXXX";
    const int fd = mkstemp(tmpl);
    DIVCOLL_THROW_UNLESS(fd >= 0, "cannot create a temporary file");
    ::close(fd);
    list = tmpl;
  } else {
    fs::create_directories(fs::path(dir) / "jobs");
    list = (fs::path(dir) / "jobs" / "runs.tsv").string();
  }
  std::ofstream out(list, std::ios::trunc);
  for (size_t i = 0; i < p.runs.size(); ++i) {
    if (!pending[i]) continue;
    const int b = p.runs[i].base_run;
    out << i + 1 << '\t' << p.runs[i].path << '\t' << (b >= 0 && pending[b] ? b + 1 : 0) << '\t'
        << stages_text(computed(p.runs[i])) << '\t' << (b >= 0 ? p.runs[b].path : std::string("-")) << '\n';
  }
  DIVCOLL_THROW_UNLESS(out.good(), "cannot write " << list);
  return list;
}

}  // namespace

int submit(const std::string& study_file, const std::string& out, const SubmitOptions& o) {
  DIVCOLL_THROW_UNLESS(o.scheduler == "slurm" || o.scheduler == "pbs", "--submit takes slurm or pbs, not " << o.scheduler);
  DIVCOLL_THROW_UNLESS(o.ranks_per_run >= 1, "--ranks-per-run must be at least 1");
  DIVCOLL_THROW_UNLESS(o.max_parallel >= 0, "--max-parallel must be at least 1 (0: no limit)");
  const char* env_root = std::getenv("DIVCOLL_ROOT");
  const std::string root = env_root && *env_root ? env_root : DIVCOLL_SOURCE_DIR;
  const std::string script = (fs::path(root) / "jobs" / "study-submit.sh").string();
  DIVCOLL_THROW_UNLESS(fs::is_regular_file(script), "no " << script << " (set DIVCOLL_ROOT to the repository)");
  Prepared p = prepare(study_file, out, true, true);
  const std::string dir = fs::absolute(out).lexically_normal().string();
  if (!o.dry_run) create_folder(dir, p.s);
  const std::vector<bool> pending = pending_runs(dir, p);
  if (!o.dry_run) save_manifest(dir, p.s, p.runs, p.st);
  const std::string list = write_run_list(dir, p, pending, o.dry_run);
  std::string self = fs::read_symlink("/proc/self/exe").string();
  std::vector<std::string> a = {"bash", script, o.scheduler, "--study", fs::absolute(study_file).lexically_normal().string(),
                                "--out", dir, "--runs", list, "--of", std::to_string(p.runs.size()), "--name", p.s.name,
                                "--bin", self, "--ranks-per-run", std::to_string(o.ranks_per_run),
                                "--max-parallel", std::to_string(o.max_parallel)};
  if (o.dry_run) a.push_back("--dry-run");
  a.push_back("--");
  a.insert(a.end(), o.scheduler_args.begin(), o.scheduler_args.end());
  std::vector<char*> argv;
  for (std::string& x : a) argv.push_back(x.data());
  argv.push_back(nullptr);
  std::fflush(stdout);
  execvp("bash", argv.data());
  throw InputError(msg() << "cannot run " << script << ": " << std::strerror(errno));
}

}  // namespace divcoll::study
