#include "mpi/pipeline.hpp"

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <string>
#include <vector>

#include "mpi/driver.hpp"
#include "mpi/scheduler.hpp"

namespace divcoll::mpi {
namespace {

// a finished stage's timings, as attributes of its group (every rank writes) and, on rank 0, as text: its wall time,
// how busy each rank was (seconds computing items) and the CPU seconds of its computing and serving threads,
// gathered on every rank, and rank 0's time outside the farm
void record_stage_times(MPI_Comm comm, io::h5::File& file, const std::string& name, double wall,
                        const FarmClock& before, const DriverClock& dbefore) {
  int rank = 0, size = 1;
  MPI_Comm_rank(comm, &rank);
  MPI_Comm_size(comm, &size);
  const FarmClock& fc = farm_clock();
  double mine[3] = {fc.compute_s - before.compute_s, fc.compute_cpu_s - before.compute_cpu_s,
                    fc.serve_cpu_s - before.serve_cpu_s};
  std::vector<double> all(3 * static_cast<size_t>(size));
  MPI_Allgather(mine, 3, MPI_DOUBLE, all.data(), 3, MPI_DOUBLE, comm);
  auto per_rank = [&](int k) {  // "r0,r1,..." of column k
    std::string text;
    for (int r = 0; r < size; ++r) {
      char tmp[32];
      std::snprintf(tmp, sizeof tmp, "%s%.3f", r == 0 ? "" : ",", all[3 * static_cast<size_t>(r) + k]);
      text += tmp;
    }
    return text;
  };
  double busy_sum = 0, busy_max = 0, cpu_sum = 0, serve_sum = 0;
  for (int r = 0; r < size; ++r) {
    const double* c = &all[3 * static_cast<size_t>(r)];
    busy_sum += c[0], busy_max = std::max(busy_max, c[0]), cpu_sum += c[1], serve_sum += c[2];
  }
  io::h5::Node g = file.group(name);
  g.write_double("wall_s_last_session", wall);
  g.write_double("wall_s", (g.has_attribute("wall_s") ? g.read_double("wall_s") : 0.0) + wall);
  // timings are attributes: `divcoll compare` (and the determinism tests) compare datasets only
  g.write_string("busy_s_per_rank_last_session", per_rank(0));
  // CPU seconds of each rank's computing thread inside compute() (below busy: it was descheduled) and of
  // its serving thread inside the farm (0 at one rank)
  g.write_string("compute_cpu_s_per_rank_last_session", per_rank(1));
  g.write_string("serve_cpu_s_per_rank_last_session", per_rank(2));
  // rank 0's time outside the farm, while the workers wait for it (the serial part of the stage)
  const DriverClock& dc = driver_clock();
  double serial[4] = {dc.input_s - dbefore.input_s, dc.items_s - dbefore.items_s,
                      dc.writes_s - dbefore.writes_s, dc.commits_s - dbefore.commits_s};
  MPI_Bcast(serial, 4, MPI_DOUBLE, 0, comm);  // every rank writes rank 0's figures
  char serial_text[160];
  std::snprintf(serial_text, sizeof serial_text, "input=%.3f,items=%.3f,writes=%.3f,commits=%.3f", serial[0],
                serial[1], serial[2], serial[3]);
  g.write_string("master_serial_s_last_session", serial_text);
  if (rank == 0) {  // run_with_status has marked the stage complete
    std::printf("stage %s: done in %.1f s; ranks busy %.0f%% of it (master %.0f%%), load imbalance max/mean %.2f\n",
                name.c_str(), wall, 100 * busy_sum / (size * wall), 100 * all[0] / wall,
                busy_sum > 0 ? busy_max / (busy_sum / size) : 1.0);
    std::printf("stage %s: master outside the farm %.1f s over %ld rounds (input %.2f, items %.2f, writes %.2f, "
                "commits %.2f s)\n",
                name.c_str(), serial[0] + serial[1] + serial[2] + serial[3], dc.rounds - dbefore.rounds,
                serial[0], serial[1], serial[2], serial[3]);
    if (size > 1 && busy_sum > 0 && wall > 0)
      std::printf("stage %s: computing threads on a core %.1f%% of their busy time; serving threads %.2f%% of a "
                  "core each\n",
                  name.c_str(), 100 * cpu_sum / busy_sum, 100 * serve_sum / (size * wall));
  }
}

}  // namespace

void run_stages(MPI_Comm comm, const config::RunConfig& cfg, io::h5::File& file, Checkpointer& checkpoints, bool agents_only) {
  int rank = 0;
  MPI_Comm_rank(comm, &rank);
  // the stages call ckpt at each commit; it copies the run file to its checkpoint when
  // output.checkpoint_interval_s has passed or a stop was asked for, and the end of a stage copies always
  auto ckpt = [&] { checkpoints.commit(); };
  for (const Stage& stage : kStages) {
    const std::string name(stage.info.name);
    if (agents_only ? name != "agents" : !config::stage_enabled(cfg, name)) continue;
    if (complete(file, name)) {
      if (rank == 0) std::printf("stage %s: complete in the run file\n", name.c_str());
      continue;
    }
    const auto t1 = std::chrono::steady_clock::now();
    const FarmClock before = farm_clock();
    const DriverClock dbefore = driver_clock();
    // a finished stage is never redone on --resume: its end is a forced checkpoint
    run_with_status(file, name, [&] { checkpoints.force(); }, [&] { stage.run(comm, cfg, file, ckpt); });
    const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - t1).count();
    record_stage_times(comm, file, name, wall, before, dbefore);
  }
}


}  // namespace divcoll::mpi
