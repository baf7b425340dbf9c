// divcoll report RUN.h5 and divcoll movie RUN.h5: run divcoll_post.report and divcoll_post.movie under a
// Python that has numpy, h5py and matplotlib: $DIVCOLL_PYTHON, else the first python3 on PATH that imports
// them, else /usr/bin/python3 (Debian's, which jobs/install-deps.sh equips); the one used is printed.
#include <fcntl.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <sstream>
#include <string>
#include <vector>

#include "cli/commands.hpp"
#include "common/check.hpp"

namespace divcoll::cli {

namespace fs = std::filesystem;

namespace {
bool executable(const fs::path& p) {
  std::error_code ec;
  return fs::is_regular_file(p, ec) && ::access(p.c_str(), X_OK) == 0;
}

// runs argv (with stdin, stdout and stderr to /dev/null when quiet) and waits; its exit status, or -1 when it
// could not start
int spawn(const std::vector<std::string>& args, bool quiet) {
  std::fflush(stdout);
  std::fflush(stderr);
  const pid_t pid = ::fork();
  if (pid < 0) return -1;
  if (pid == 0) {
    const int null = quiet ? ::open("/dev/null", O_RDWR) : -1;
    if (null >= 0) {
      ::dup2(null, 0);
      ::dup2(null, 1);
      ::dup2(null, 2);
    }
    std::vector<char*> argv;
    for (const auto& s : args) argv.push_back(const_cast<char*>(s.c_str()));
    argv.push_back(nullptr);
    ::execv(argv[0], argv.data());
    ::_exit(127);
  }
  int status = 0;
  if (::waitpid(pid, &status, 0) < 0) return -1;
  return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

bool has_modules(const fs::path& python) {
  return spawn({python.string(), "-c", "import numpy, h5py, matplotlib"}, /*quiet=*/true) == 0;
}
}  // namespace

PythonChoice find_python() {
  if (const char* env = std::getenv("DIVCOLL_PYTHON"); env && *env) {
    DIVCOLL_THROW_UNLESS(executable(env), "DIVCOLL_PYTHON=" << env << " is not an executable file");
    return {env, "from DIVCOLL_PYTHON"};
  }
  std::vector<std::string> tried;
  if (const char* path = std::getenv("PATH")) {
    std::stringstream ss(path);
    std::string dir;
    while (std::getline(ss, dir, ':')) {
      const fs::path p = fs::path(dir.empty() ? "." : dir) / "python3";
      if (!executable(p)) continue;
      if (has_modules(p)) return {p.string(), "the first python3 on PATH that has numpy, h5py and matplotlib"};
      tried.push_back(p.string());
    }
  }
  const std::string deb = "/usr/bin/python3";
  DIVCOLL_THROW_UNLESS(executable(deb), "no Python found: set DIVCOLL_PYTHON, or install Debian's python3-h5py "
                                        "python3-numpy python3-matplotlib python3-scipy (jobs/install-deps.sh does)");
  std::string why = "Debian's; no python3 on PATH";
  if (!tried.empty()) {
    why += " has numpy, h5py and matplotlib (tried";
    for (const auto& t : tried) why += " " + t;
    why += ")";
  }
  return {deb, why};
}

// the folder that holds the divcoll_post package (postprocess/ of the checkout): $DIVCOLL_POSTPROCESS, else a
// postprocess/ next to the build folder of this binary or above it, else the source folder this binary was
// configured from
std::string find_postprocess_dir() {
  std::vector<fs::path> candidates;
  if (const char* env = std::getenv("DIVCOLL_POSTPROCESS")) candidates.emplace_back(env);
  std::error_code ec;
  const fs::path self = fs::read_symlink("/proc/self/exe", ec);
  if (!ec)
    for (fs::path p = self.parent_path(); !p.empty() && p != p.root_path(); p = p.parent_path())
      candidates.push_back(p / "postprocess");
  candidates.emplace_back(fs::path(DIVCOLL_SOURCE_DIR) / "postprocess");
  for (const fs::path& c : candidates)
    if (fs::is_regular_file(c / "divcoll_post" / "__init__.py", ec)) return c.string();
  throw InputError(msg() << "cannot find postprocess/divcoll_post (looked next to this binary and in "
                         << DIVCOLL_SOURCE_DIR << "); set DIVCOLL_POSTPROCESS to the postprocess folder");
}

// `python -m module args --divcoll <this binary>`, with the postprocess folder first on PYTHONPATH (set in this
// process, so that the Python it starts inherits it)
std::vector<std::string> python_command(const std::string& module, const std::vector<std::string>& args,
                                        bool announce) {
  const PythonChoice py = find_python();
  if (announce) std::printf("divcoll: Python %s (%s)\n", py.path.c_str(), py.why.c_str());
  std::string path = find_postprocess_dir();
  if (const char* old = std::getenv("PYTHONPATH"); old && *old) path += std::string(":") + old;
  ::setenv("PYTHONPATH", path.c_str(), /*overwrite=*/1);
  std::vector<std::string> cmd = {py.path, "-m", module};
  cmd.insert(cmd.end(), args.begin(), args.end());
  std::error_code ec;
  const fs::path self = fs::read_symlink("/proc/self/exe", ec);
  if (!ec) cmd.insert(cmd.end(), {"--divcoll", self.string()});
  return cmd;
}

int exec_python(const std::string& module, const std::vector<std::string>& args) {
  std::vector<std::string> cmd = python_command(module, args, true);
  std::vector<char*> argv;
  for (auto& s : cmd) argv.push_back(s.data());
  argv.push_back(nullptr);
  std::fflush(stdout);
  ::execv(argv[0], argv.data());
  throw InputError(msg() << "could not start " << cmd[0] << " -m " << cmd[2]);
}

int run_python(const std::string& module, const std::vector<std::string>& args) {
  return spawn(python_command(module, args, true), /*quiet=*/false);
}

int report(const ReportArgs& a) {
  // a study folder (divcoll study --out DIR) gets the robustness page, by default in DIR/robustness
  if (fs::is_directory(a.run)) {
    const std::string out = a.out == ReportArgs{}.out ? (fs::path(a.run) / "robustness").string() : a.out;
    std::vector<std::string> args = {a.run, "--out", out};
    if (!a.keep.empty()) args.insert(args.end(), {"--keep", a.keep});
    return exec_python("divcoll_post.robustness", args);
  }
  if (!a.keep.empty())
    throw InputError(msg() << "report --keep " << a.keep << ": --keep copies a study folder, and " << a.run
                           << " is a run file");
  std::vector<std::string> args = {a.run, "--out", a.out};
  if (a.movie) args.push_back("--movie");
  return exec_python("divcoll_post.report", args);
}

int movie(const MovieArgs& a) {
  std::vector<std::string> args = {a.run, "--out", a.out};
  if (a.quick) args.push_back("--quick");
  return exec_python("divcoll_post.movie", args);
}

}  // namespace divcoll::cli
