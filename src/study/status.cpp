// DIR --status: every run of a study folder and what it is doing, from the manifest, the run files and their
// checkpoints, the runs' writer locks and the job scripts' records (DIR/<variant>/seed<k>.job)
#include "study/status.hpp"

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <filesystem>
#include <fstream>
#include <map>
#include <set>

#include "common/check.hpp"
#include "config/config.hpp"
#include "io/file_lock.hpp"
#include "io/h5.hpp"
#include "study/eta.hpp"
#include "study/folder.hpp"
#include "study/plan.hpp"

namespace divcoll::study {
namespace {

namespace fs = std::filesystem;

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

std::vector<std::string> last_lines(const std::string& path, size_t n) {
  std::ifstream in(path);
  std::vector<std::string> all;
  std::string line;
  while (std::getline(in, line)) all.push_back(line);
  if (all.size() > n) all.erase(all.begin(), all.end() - static_cast<long>(n));
  return all;
}

// one run of the manifest as the folder shows it
struct RunView {
  const ManifestRun* m = nullptr;
  fs::path file;
  config::RunConfig cfg;
  bool have_cfg = false;  // its config still reads
  bool done = false;      // its run file ended, or it is complete and kept as its summary
  std::map<std::string, std::string> job;
  int base = -1;          // the run it reuses
};

class StatusReport {
 public:
  explicit StatusReport(const std::string& dir);
  int print();

 private:
  // the stages of run i still to compute: those not complete in its file (or its checkpoint); `at` gets the first
  std::vector<int> remaining(int i, std::string* at) const;
  std::string done_line(const RunView& v) const;
  std::string open_line(int i);

  std::string dir_;
  Manifest manifest_;
  std::vector<RunView> runs_;
  StageTimes times_;                 // seconds per stage, from the complete runs
  std::vector<double> eta_, finish_;  // own remaining seconds; when it ends if all goes at once
  bool eta_known_ = true;
  int n_done_ = 0, n_running_ = 0, n_waiting_ = 0, n_failed_ = 0, n_queued_ = 0;
};

StatusReport::StatusReport(const std::string& dir) : dir_(dir), manifest_(read_manifest(dir)) {
  const std::string base = (fs::path(dir) / manifest_.base_copy).string();
  const int N = static_cast<int>(manifest_.runs.size());
  runs_.resize(N);
  eta_.assign(N, 0.0), finish_.assign(N, 0.0);
  for (int i = 0; i < N; ++i) {
    RunView& v = runs_[i];
    v.m = &manifest_.runs[i];
    v.file = fs::path(dir) / v.m->path;
    try {
      v.cfg = config::load_config(base, v.m->overrides);
      v.have_cfg = true;
    } catch (const std::exception&) {
    }
    v.job = job_file(v.file);
    v.done = run_file_complete(v.file) || (v.m->st.status == "complete" && fs::exists(summary_path(v.file)));
    if (run_file_complete(v.file) && v.have_cfg) times_.add(v.file.string(), computed(v.cfg, v.m->from));
    for (int j = 0; j < N; ++j)
      if (!v.m->reuses.empty() && manifest_.runs[j].path == v.m->reuses) v.base = j;
  }
}

std::vector<int> StatusReport::remaining(int i, std::string* at) const {
  const auto& names = config::stage_names();
  const RunView& v = runs_[i];
  std::vector<int> out;
  std::set<std::string> complete_stages;
  for (const fs::path& src : {fs::path(v.file.string() + ".ckpt"), v.file}) {
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
  if (!v.have_cfg) return out;
  for (int st : computed(v.cfg, v.m->from))
    if (!complete_stages.count(names[st])) {
      if (at && at->empty()) *at = names[st];
      out.push_back(st);
    }
  return out;
}

std::string StatusReport::done_line(const RunView& v) const {
  std::string line = "done";
  if (!v.m->st.adopted_from.empty()) line += " (adopted from " + v.m->st.adopted_from + ", commit " + v.m->st.commit + ")";
  else if (!fs::exists(v.file)) line += " (kept as its summary)";
  return line;
}

// a run not done: running, failed, waiting on its base, starting, queued or not started; counted
std::string StatusReport::open_line(int i) {
  const RunView& v = runs_[i];
  std::string at;
  double e = 0;
  for (int st : remaining(i, &at)) {
    const double m = times_.mean(st);
    if (m < 0) eta_known_ = false;
    e += std::max(m, 0.0);
  }
  eta_[i] = e;
  const std::string eta_text = eta_known_ ? ", ETA " + clock_text(e) : std::string(", ETA unknown (no run of its stages has ended)");
  const auto& job = v.job;
  const std::string jobtext = job.count("job") ? " (job " + job.at("job") + ")" : std::string();
  const std::string state = job.count("state") ? job.at("state") : std::string();
  const std::string stage = at.empty() ? std::string("?") : at;
  std::string holder;
  if (io::WriterLock::held_by_someone(v.file.string(), &holder)) {
    ++n_running_;
    return "running" + jobtext + " at stage " + stage + eta_text + " [" + holder + "]";
  }
  if (state == "failed") {
    ++n_failed_;
    std::string line = "failed" + jobtext + (job.count("rc") ? ", status " + job.at("rc") : std::string());
    if (job.count("log")) {
      line += ", last lines of " + job.at("log") + ":";
      for (const std::string& l : last_lines(job.at("log"), 5)) line += "\n      | " + l;
    }
    return line;
  }
  if (v.base >= 0 && !runs_[v.base].done) {
    ++n_waiting_;
    return "waiting on " + v.m->reuses + jobtext;
  }
  if (state == "running" || state == "requeued") {
    ++n_running_;
    return (state == "requeued" ? "requeued at the time limit" : "starting") + jobtext + ", next stage " + stage + eta_text;
  }
  ++n_queued_;
  if (!state.empty() && state != "complete")
    return state + jobtext + (fs::exists(v.file) ? ", stopped at stage " + at : std::string()) + eta_text;
  return std::string(fs::exists(v.file) ? "stopped at stage " + at + " (not running)" : "not started") + eta_text;
}

int StatusReport::print() {
  const int N = static_cast<int>(runs_.size());
  std::printf("study %s in %s: %d runs\n", manifest_.name.c_str(), dir_.c_str(), N);
  for (int i = 0; i < N; ++i) {
    std::string line;
    if (runs_[i].done) ++n_done_, line = done_line(runs_[i]);
    else line = open_line(i);
    const int b = runs_[i].base;
    finish_[i] = eta_[i] + (b >= 0 && b < i ? finish_[b] : 0.0);
    std::printf("  %d %s: %s\n", i + 1, runs_[i].m->path.c_str(), line.c_str());
  }
  double serial = 0, parallel = 0;
  for (int i = 0; i < N; ++i) serial += eta_[i], parallel = std::max(parallel, finish_[i]);
  std::printf("%d done, %d running, %d to run, %d waiting on their base, %d failed", n_done_, n_running_, n_queued_,
              n_waiting_, n_failed_);
  if (n_done_ == N) std::printf("; the study is complete\n");
  else if (!eta_known_) std::printf("; overall ETA unknown until a run of every stage has ended\n");
  else std::printf("; overall ETA %s with every ready run at once (%s one after another)\n", clock_text(parallel).c_str(),
                   clock_text(serial).c_str());
  return n_failed_ > 0 ? 1 : 0;
}

}  // namespace

int status(const std::string& dir) {
  DIVCOLL_THROW_UNLESS(fs::is_regular_file(fs::path(dir) / "study.toml"), dir << " is not a study folder (no study.toml)");
  setenv("HDF5_USE_FILE_LOCKING", "FALSE", 0);  // run files being written are read too
  return StatusReport(dir).print();
}

}  // namespace divcoll::study
