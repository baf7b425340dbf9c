// divcoll report RUN.h5: runs postprocess/report.py with Debian's Python (/usr/bin/python3), which has
// h5py, numpy, matplotlib and scipy; the python3 first on PATH may be a bare interpreter without them.
#include <unistd.h>

#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <string>
#include <vector>

#include "cli/commands.hpp"
#include "common/check.hpp"

namespace divcoll::cli {

namespace fs = std::filesystem;

namespace {
// where report.py is: $DIVCOLL_POSTPROCESS, else next to the build folder of this binary, else the source
// folder this binary was configured from
fs::path find_report_script() {
  std::vector<fs::path> candidates;
  if (const char* env = std::getenv("DIVCOLL_POSTPROCESS")) candidates.emplace_back(fs::path(env) / "report.py");
  std::error_code ec;
  const fs::path self = fs::read_symlink("/proc/self/exe", ec);
  if (!ec)
    for (fs::path p = self.parent_path(); !p.empty() && p != p.root_path(); p = p.parent_path())
      candidates.push_back(p / "postprocess" / "report.py");
  candidates.emplace_back(fs::path(DIVCOLL_SOURCE_DIR) / "postprocess" / "report.py");
  for (const fs::path& c : candidates)
    if (fs::is_regular_file(c, ec)) return c;
  throw InputError(msg() << "cannot find postprocess/report.py (looked next to this binary and in "
                         << DIVCOLL_SOURCE_DIR << "); set DIVCOLL_POSTPROCESS to the postprocess folder");
}
}  // namespace

int report(const ReportArgs& a) {
  fs::path script = find_report_script();
  // a study folder (divcoll study --out DIR) gets the robustness page, by default in DIR/robustness
  const bool study = fs::is_directory(a.run);
  if (study) script = script.parent_path() / "robustness.py";
  const std::string out = study && a.out == ReportArgs{}.out ? (fs::path(a.run) / "robustness").string() : a.out;
  const char* python = "/usr/bin/python3";
  DIVCOLL_THROW_UNLESS(::access(python, X_OK) == 0,
                       python << " is missing: install Debian's python3-h5py python3-numpy python3-matplotlib "
                                 "python3-scipy (jobs/install-deps.sh does)");
  std::error_code ec;
  const fs::path self = fs::read_symlink("/proc/self/exe", ec);
  std::vector<std::string> args = {python, script.string(), a.run, "--out", out};
  if (!ec) args.insert(args.end(), {"--divcoll", self.string()});
  std::vector<char*> argv;
  for (auto& s : args) argv.push_back(s.data());
  argv.push_back(nullptr);
  std::fflush(stdout);
  ::execv(python, argv.data());
  throw InputError(msg() << "could not start " << python << " " << script.string());
}

}  // namespace divcoll::cli
