// How many cores this node gives the job. The task farm asks it to choose between looking again and sleeping
// (mpi/scheduler.cpp): a rank may spin briefly only when every rank on the node has a core of its own. A
// container or a batch system limits a job's cores without changing what the machine reports (a cpuset, a
// CPU-time quota, a Slurm allocation), so the count is the fewest of: the CPUs online; the CPUs of the
// process's cpuset cgroup; its CPU-time quota in cores, rounded up (cgroup v2 cpu.max, v1 cpu.cfs_quota_us over
// cpu.cfs_period_us); Slurm's SLURM_CPUS_ON_NODE. What cannot be read limits nothing.
#pragma once

#include <string>

namespace divcoll::mpi {

// the cores this node gives the job (at least 1)
int node_cores();

// the parts, for the tests
// CPUs in a Linux CPU list ("0-3,8,10-11" -> 7); -1 when the text is not one
int cpu_list_count(const std::string& list);
// cores of a cgroup v2 cpu.max ("200000 100000" -> 2, "150000 100000" -> 2, "max 100000" -> 0: no quota; 0 too
// when the text is not one)
int cpu_quota_cores(const std::string& cpu_max);
// the cgroup of a controller in the text of /proc/self/cgroup: "" for the v2 hierarchy ("0::/a/b" -> "/a/b"),
// else a v1 controller ("4:cpu,cpuacct:/a" -> "/a" for "cpu"); "" when absent
std::string cgroup_path(const std::string& proc_self_cgroup, const std::string& controller);

}  // namespace divcoll::mpi
