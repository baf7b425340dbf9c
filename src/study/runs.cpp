// the runs of a study, one after another in one session: every process runs this loop; the leader reads the
// folder, writes the manifest and prints
#include "study/runs.hpp"

#include <chrono>
#include <cstdio>
#include <filesystem>

#include "common/check.hpp"
#include "study/eta.hpp"
#include "study/folder.hpp"
#include "study/plan.hpp"

namespace divcoll::study {
namespace {

namespace fs = std::filesystem;

void print_plan(const Prepared& p) {
  std::printf("study %s: %zu variant(s) x %zu seed(s) = %zu runs of %s (valid; nothing run)\n", p.s.name.c_str(),
              p.s.variants.size(), p.s.seeds.size(), p.runs.size(), p.s.base.c_str());
  for (size_t i = 0; i < p.runs.size(); ++i)
    std::printf("  %zu %s: computes %s%s\n", i + 1, p.runs[i].path.c_str(), stages_text(computed(p.runs[i])).c_str(),
                p.runs[i].base_run >= 0 ? (", reuses " + p.runs[p.runs[i].base_run].path).c_str() : "");
}

class StudyRuns {
 public:
  StudyRuns(const std::string& dir, Prepared& p, int only, Session& session)
      : dir_(dir), p_(p), only_(only), session_(session), t0_(std::chrono::steady_clock::now()) {}
  int run();

 private:
  void say_start() const;
  // the line before run i: its stages and what it reuses, elapsed time and the ETA of every remaining run's
  // computed stages at the mean time this study measured for them
  void say_run(int i) const;
  // 0 when the run that run i reuses is complete; else its refusal, said, and the exit status
  int check_base(int i);
  // computes run i (it is not complete); its exit status, 0 once it is complete in the manifest
  int run_one(int i);

  const std::string dir_;
  Prepared& p_;
  const int only_;  // --run: the one run to compute, -1: every one
  Session& session_;
  StageTimes times_;  // seconds per computed stage, measured on this study's finished runs (for the ETA)
  const std::chrono::steady_clock::time_point t0_;
};

void StudyRuns::say_start() const {
  int reuse = 0;
  for (const PlannedRun& r : p_.runs) reuse += r.base_run >= 0;
  std::printf("study %s: %zu variant(s) x %zu seed(s) = %zu runs of %s into %s (%d reuse earlier stages)%s\n",
              p_.s.name.c_str(), p_.s.variants.size(), p_.s.seeds.size(), p_.runs.size(), p_.s.base.c_str(),
              dir_.c_str(), reuse, only_ >= 0 ? (": run " + std::to_string(only_ + 1) + " only").c_str() : "");
  std::fflush(stdout);
}

void StudyRuns::say_run(int i) const {
  const int N = static_cast<int>(p_.runs.size());
  const PlannedRun& r = p_.runs[i];
  const std::string vname = p_.s.variants[r.variant].name;
  const std::string path = (fs::path(dir_) / r.path).string();
  double eta = 0;
  bool known = true;
  for (int j = i; j < N; ++j) {
    if (p_.st[j].status == "complete" || (only_ >= 0 && j != only_)) continue;
    for (int k : computed(p_.runs[j])) {
      const double m = times_.mean(k);
      if (m < 0) {
        known = false;
        break;
      }
      eta += m;
    }
  }
  const double el = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0_).count();
  if (p_.st[i].status == "complete")
    std::printf("study: run %d/%d %s seed %llu: complete in %s\n", i + 1, N, vname.c_str(),
                static_cast<unsigned long long>(r.seed), path.c_str());
  else
    std::printf("study: run %d/%d %s seed %llu stages %s%s | elapsed %s, ETA %s\n", i + 1, N, vname.c_str(),
                static_cast<unsigned long long>(r.seed), stages_text(computed(r)).c_str(),
                r.base_run >= 0 ? (" (earlier stages from " + p_.runs[r.base_run].path + ")").c_str() : "",
                clock_text(el).c_str(), clock_text(known ? eta : -1).c_str());
  std::fflush(stdout);
}

int StudyRuns::check_base(int i) {
  const PlannedRun& r = p_.runs[i];
  const PlannedRun& base = p_.runs[r.base_run];
  // 0: the base's run file is complete; 1: only its summary is kept; 2: it is not complete (yet)
  int state = 0;
  if (session_.leader()) {
    const fs::path bp = fs::path(dir_) / base.path;
    state = run_file_complete(bp) ? 0 : !fs::exists(bp) && fs::exists(summary_path(bp)) ? 1 : 2;
  }
  state = session_.share(state);
  if (state == 0) return 0;
  if (session_.leader() && state == 1)
    std::fprintf(stderr,
                 "divcoll: error: %s reuses the stages before %s of %s, whose run file is not in %s (only its "
                 "summary is): put the run file back, or remove the summary to compute that run again\n",
                 r.path.c_str(), r.from.c_str(), base.path.c_str(), dir_.c_str());
  else if (session_.leader())
    std::fprintf(stderr,
                 "divcoll: error: run %d (%s) reuses the stages before %s of run %s, which is not complete "
                 "yet: that run must end first (divcoll study %s --status)\n",
                 i + 1, r.path.c_str(), r.from.c_str(), base.path.c_str(), dir_.c_str());
  return state == 1 ? 2 : kBaseNotComplete;
}

int StudyRuns::run_one(int i) {
  const PlannedRun& r = p_.runs[i];
  RunRequest req;
  req.config = p_.s.base;
  req.overrides = r.overrides;
  req.out = (fs::path(dir_) / r.path).string();
  // a run file that exists was started (or derived) before a kill: it is continued
  const int exists = session_.share(session_.leader() ? fs::exists(req.out) : 0);
  if (r.base_run >= 0 && !exists) {
    if (const int refused = check_base(i)) return refused;
    req.from = r.from;
    req.base = (fs::path(dir_) / p_.runs[r.base_run].path).string();
  } else {
    req.resume = true;
  }
  const auto t1 = std::chrono::steady_clock::now();
  int code = session_.run(req);
  if (code != 0) return code;
  p_.st[i].status = "complete";
  p_.st[i].wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - t1).count();
  if (session_.leader()) {
    times_.add(req.out, computed(r));
    try {
      save_manifest(dir_, p_.s, p_.runs, p_.st);
    } catch (const std::exception& e) {
      std::fprintf(stderr, "divcoll: error: %s\n", e.what());
      code = 1;
    }
  }
  return session_.share(code);
}

int StudyRuns::run() {
  const int N = static_cast<int>(p_.runs.size());
  if (session_.leader()) say_start();
  int code = 0;
  for (int i = 0; i < N && code == 0; ++i) {
    if (only_ >= 0 && i != only_) continue;
    if (session_.leader()) say_run(i);
    if (p_.st[i].status != "complete") code = run_one(i);
  }
  if (session_.leader() && code == 0 && only_ < 0)
    std::printf("study %s: done, %d runs in %s; `divcoll report %s` writes the robustness page\n", p_.s.name.c_str(), N,
                dir_.c_str(), dir_.c_str());
  if (session_.leader() && code == 0 && only_ >= 0)
    std::printf("study %s: run %d (%s) complete\n", p_.s.name.c_str(), only_ + 1, p_.runs[only_].path.c_str());
  return code;
}

}  // namespace

int run_study(const StudyRequest& req, Session& session) {
  Prepared p;
  int only = -1;
  // everything that can be refused is refused here, on every process alike, before any run starts
  try {
    if (req.plan) {
      p.s = parse_study(req.study);
      p.runs = plan(p.s);
      if (session.leader()) print_plan(p);
      return 0;
    }
    DIVCOLL_THROW_UNLESS(req.run.empty() || req.resume,
                         "--run K computes one run of a study folder that exists: pass --resume too");
    p = prepare(req.study, req.out, req.resume, session.leader());
    if (!req.run.empty()) only = find_run(p.runs, req.run);
    session.wait_all();
    session.on_leader([&] {  // a failure on the leader stops every process here
      create_folder(req.out, p.s);
      save_manifest(req.out, p.s, p.runs, p.st);
    });
    p.s.base = (fs::path(req.out) / kBaseCopy).string();
  } catch (const InputError& e) {
    if (session.leader()) std::fprintf(stderr, "divcoll: error: %s\n", e.what());
    return 2;
  }
  return StudyRuns(req.out, p, only, session).run();
}

}  // namespace divcoll::study
