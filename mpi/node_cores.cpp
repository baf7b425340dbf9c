#include "mpi/node_cores.hpp"

#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <fstream>
#include <sstream>
#include <vector>

namespace divcoll::mpi {
namespace {

// the first line of a file ("" when it cannot be read)
std::string first_line(const std::string& path) {
  std::ifstream in(path);
  std::string line;
  if (in) std::getline(in, line);
  return line;
}

// a file's first line read from the first of `dirs` that has it
std::string first_line_in(const std::vector<std::string>& dirs, const std::string& name) {
  for (const std::string& d : dirs)
    if (std::string s = first_line(d + "/" + name); !s.empty()) return s;
  return "";
}

// the places a controller's files may be: the process's own cgroup under the mount, then each of its ancestors up to
// the mount's root (a quota set on a parent limits its children too; a container with a cgroup namespace sees its own
// cgroup as the root, while /proc/self/cgroup may name the host's)
std::vector<std::string> cgroup_dirs(const std::string& mount, std::string path) {
  std::vector<std::string> dirs;
  while (!path.empty() && path != "/") {
    dirs.push_back(mount + path);
    path.erase(path.find_last_of('/'));
  }
  dirs.push_back(mount);
  return dirs;
}

}  // namespace

int cpu_list_count(const std::string& list) {
  int count = 0;
  std::stringstream ss(list);
  std::string part;
  while (std::getline(ss, part, ',')) {
    part.erase(std::remove_if(part.begin(), part.end(), [](char c) { return c == ' ' || c == '\n'; }), part.end());
    if (part.empty()) continue;
    const size_t dash = part.find('-');
    char* end = nullptr;
    const long a = std::strtol(part.c_str(), &end, 10);
    if (end == part.c_str()) return -1;
    long b = a;
    if (dash != std::string::npos) {
      const char* second = part.c_str() + dash + 1;
      b = std::strtol(second, &end, 10);
      if (end == second) return -1;
    }
    if (*end != '\0' || a < 0 || b < a) return -1;
    count += static_cast<int>(b - a + 1);
  }
  return count > 0 ? count : -1;
}

int cpu_quota_cores(const std::string& cpu_max) {
  std::istringstream in(cpu_max);
  std::string quota;
  double period = 0;
  if (!(in >> quota >> period) || quota == "max" || period <= 0) return 0;
  char* end = nullptr;
  const double q = std::strtod(quota.c_str(), &end);
  if (end == quota.c_str() || q <= 0) return 0;
  return static_cast<int>(std::ceil(q / period - 1e-9));
}

std::string cgroup_path(const std::string& proc_self_cgroup, const std::string& controller) {
  std::istringstream in(proc_self_cgroup);
  std::string line;
  while (std::getline(in, line)) {
    const size_t c1 = line.find(':');
    const size_t c2 = c1 == std::string::npos ? c1 : line.find(':', c1 + 1);
    if (c2 == std::string::npos) continue;
    const std::string controllers = line.substr(c1 + 1, c2 - c1 - 1);
    const std::string path = line.substr(c2 + 1);
    if (controller.empty()) {
      if (line.compare(0, c1, "0") == 0 && controllers.empty()) return path;
      continue;
    }
    std::stringstream names(controllers);
    for (std::string name; std::getline(names, name, ',');)
      if (name == controller) return path;
  }
  return "";
}

int node_cores() {
  long online = sysconf(_SC_NPROCESSORS_ONLN);
  int cores = online > 0 ? static_cast<int>(online) : 1;
  const auto limit = [&cores](int n) {
    if (n > 0) cores = std::min(cores, n);
  };

  std::ifstream in("/proc/self/cgroup");
  std::stringstream text;
  text << in.rdbuf();
  const std::string cg = text.str();
  // cgroup v2: one hierarchy. The cpuset's effective CPUs already honour its ancestors'; a quota is each level's own
  const std::vector<std::string> v2 = cgroup_dirs("/sys/fs/cgroup", cgroup_path(cg, ""));
  limit(cpu_list_count(first_line_in(v2, "cpuset.cpus.effective")));
  for (const std::string& d : v2) limit(cpu_quota_cores(first_line(d + "/cpu.max")));
  // cgroup v1: a hierarchy per controller
  const std::vector<std::string> v1set = cgroup_dirs("/sys/fs/cgroup/cpuset", cgroup_path(cg, "cpuset"));
  limit(cpu_list_count(first_line_in(v1set, "cpuset.effective_cpus")));
  limit(cpu_list_count(first_line_in(v1set, "cpuset.cpus")));
  for (const std::string mount : {"/sys/fs/cgroup/cpu", "/sys/fs/cgroup/cpu,cpuacct"})
    for (const std::string& d : cgroup_dirs(mount, cgroup_path(cg, "cpu"))) {
      const std::string quota = first_line(d + "/cpu.cfs_quota_us");
      const std::string period = first_line(d + "/cpu.cfs_period_us");
      if (!quota.empty() && !period.empty() && quota[0] != '-') limit(cpu_quota_cores(quota + " " + period));
    }
  // Slurm: the CPUs of this node in the job's allocation
  if (const char* s = std::getenv("SLURM_CPUS_ON_NODE")) limit(std::atoi(s));
  return cores;
}

}  // namespace divcoll::mpi
