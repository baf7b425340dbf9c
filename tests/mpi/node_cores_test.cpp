// mpi/node_cores: the cores a node gives the job, read from what limits it (cpusets, CPU quotas, Slurm)
#include "mpi/node_cores.hpp"

#include <gtest/gtest.h>
#include <unistd.h>

#include <cstdlib>

namespace divcoll::mpi {
namespace {

TEST(NodeCores, CountsALinuxCpuList) {
  EXPECT_EQ(cpu_list_count("0"), 1);
  EXPECT_EQ(cpu_list_count("0-3"), 4);
  EXPECT_EQ(cpu_list_count("0-3,8,10-11\n"), 7);
  EXPECT_EQ(cpu_list_count(""), -1);
  EXPECT_EQ(cpu_list_count("x"), -1);
  EXPECT_EQ(cpu_list_count("3-1"), -1);
  EXPECT_EQ(cpu_list_count("0-2a"), -1);
}

TEST(NodeCores, ReadsACpuQuotaRoundedUp) {
  EXPECT_EQ(cpu_quota_cores("200000 100000"), 2);
  EXPECT_EQ(cpu_quota_cores("150000 100000"), 2);
  EXPECT_EQ(cpu_quota_cores("50000 100000"), 1);
  EXPECT_EQ(cpu_quota_cores("max 100000"), 0);
  EXPECT_EQ(cpu_quota_cores(""), 0);
  EXPECT_EQ(cpu_quota_cores("100000 0"), 0);
}

TEST(NodeCores, FindsAControllersCgroup) {
  const std::string v1 = "9:name=systemd:/\n4:cpu,cpuacct:/job/7\n3:cpuset:/slurm/uid_0/job_7\n0::/\n";
  EXPECT_EQ(cgroup_path(v1, "cpu"), "/job/7");
  EXPECT_EQ(cgroup_path(v1, "cpuacct"), "/job/7");
  EXPECT_EQ(cgroup_path(v1, "cpuset"), "/slurm/uid_0/job_7");
  EXPECT_EQ(cgroup_path(v1, "memory"), "");
  EXPECT_EQ(cgroup_path(v1, ""), "/");
  EXPECT_EQ(cgroup_path("0::/user.slice/session-3.scope\n", ""), "/user.slice/session-3.scope");
  EXPECT_EQ(cgroup_path("0::/user.slice\n", "cpu"), "");
}

TEST(NodeCores, NeverMoreThanTheMachineHasAndHonoursSlurm) {
  const int online = static_cast<int>(sysconf(_SC_NPROCESSORS_ONLN));
  const char* had = std::getenv("SLURM_CPUS_ON_NODE");
  const std::string saved = had ? had : "";
  unsetenv("SLURM_CPUS_ON_NODE");
  const int n = node_cores();
  EXPECT_GE(n, 1);
  EXPECT_LE(n, online);
  setenv("SLURM_CPUS_ON_NODE", "1", 1);
  EXPECT_EQ(node_cores(), 1);
  setenv("SLURM_CPUS_ON_NODE", "100000", 1);  // more than the machine: the machine limits
  EXPECT_EQ(node_cores(), n);
  if (had) setenv("SLURM_CPUS_ON_NODE", saved.c_str(), 1);
  else unsetenv("SLURM_CPUS_ON_NODE");
}

}  // namespace
}  // namespace divcoll::mpi
