#include "cli/bench_farm.hpp"

#include <mpi.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <thread>
#include <vector>

#include "common/check.hpp"
#include "mpi/protocol.hpp"
#include "mpi/scheduler.hpp"

namespace divcoll::cli {
namespace {

double since(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

struct RoundStats {
  double wall = 0, fold = 0, busy = 0;  // busy: compute seconds summed over ranks
  mpi::FarmClock master;                     // rank 0's clock over the round
};

}  // namespace

int bench_farm_main(int argc, char** argv, const BenchFarmArgs& a) {
  DIVCOLL_THROW_UNLESS(a.item_ms >= 0 && a.result_bytes >= 0 && a.task_bytes >= 0 && a.items >= 0 && a.rounds >= 1,
                       "bench-farm: --item-ms, --result-bytes, --task-bytes, --items must be >= 0 and --rounds >= 1");
  DIVCOLL_THROW_UNLESS(a.fold == "none" || a.fold == "after" || a.fold == "during",
                       "bench-farm: --fold must be none, after or during, not " << a.fold);
  int provided = 0;
  MPI_Init_thread(&argc, &argv, MPI_THREAD_FUNNELED, &provided);
  int rank = 0, size = 1;
  MPI_Comm_rank(MPI_COMM_WORLD, &rank);
  MPI_Comm_size(MPI_COMM_WORLD, &size);
  const int doubles = a.result_bytes / 8;
  auto compute = [&](const std::string& task) {
    const auto t0 = std::chrono::steady_clock::now();
    const double v = static_cast<double>(task.size() % 7);
    std::string r = mpi::pack(std::vector<double>(doubles, v));
    const double left = a.item_ms * 1e-3 - since(t0);
    if (left > 0) std::this_thread::sleep_for(std::chrono::duration<double>(left));
    return r;
  };
  std::vector<double> sum(doubles, 0.0);
  auto fold_one = [&](const std::string& r) {
    const std::vector<double> g = mpi::unpack<std::vector<double>>(r);
    for (int q = 0; q < doubles; ++q) sum[q] += g[q];
  };
  mpi::FarmOptions opt;
  opt.block = a.block;
  opt.max_block = a.max_block;
  opt.depth = a.depth;
  opt.master_works = a.master_works;
  double fold_during = 0;
  if (a.fold == "during")
    opt.on_result = [&](int64_t, const std::string& r) {
      const auto t0 = std::chrono::steady_clock::now();
      fold_one(r);
      fold_during += since(t0);
    };
  const std::vector<std::string> items(rank == 0 ? a.items : 0, std::string(a.task_bytes, 'x'));

  std::vector<RoundStats> rounds;
  for (int round = 0; round <= a.rounds; ++round) {  // round 0 warms up
    MPI_Barrier(MPI_COMM_WORLD);
    const mpi::FarmClock before = mpi::farm_clock();
    fold_during = 0;
    const auto t0 = std::chrono::steady_clock::now();
    const mpi::FarmResult fr = mpi::farm(MPI_COMM_WORLD, items, compute, opt);
    double fold_after = 0;
    if (rank == 0 && a.fold == "after") {
      const auto t1 = std::chrono::steady_clock::now();
      for (const std::string& r : fr.results) fold_one(r);
      fold_after = since(t1);
    }
    RoundStats s;
    s.wall = since(t0);
    s.fold = fold_during + fold_after;
    const double busy = mpi::farm_clock().compute_s - before.compute_s;
    MPI_Reduce(&busy, &s.busy, 1, MPI_DOUBLE, MPI_SUM, 0, MPI_COMM_WORLD);
    const mpi::FarmClock& c = mpi::farm_clock();
    s.master = {c.compute_s - before.compute_s, c.farm_s - before.farm_s, c.items - before.items,
                c.serve_cpu_s - before.serve_cpu_s, c.task_s - before.task_s, c.result_s - before.result_s,
                c.task_msgs - before.task_msgs, c.result_msgs - before.result_msgs, c.results - before.results,
                c.task_bytes - before.task_bytes, c.result_bytes - before.result_bytes,
                c.compute_cpu_s - before.compute_cpu_s};
    if (round > 0) rounds.push_back(s);
  }
  if (rank == 0) {
    const bool works = a.master_works && size > 1 && rounds[0].master.items > 0;
    const int computing = size == 1 ? 1 : size - 1 + (works ? 1 : 0);
    double wall = 0, fold = 0, busy = 0, cpu = 0, task_s = 0, result_s = 0, tb = 0, rb = 0;
    long tm = 0, rm = 0, res = 0;
    for (const RoundStats& s : rounds) {
      wall += s.wall, fold += s.fold, busy += s.busy, cpu += s.master.serve_cpu_s;
      task_s += s.master.task_s, result_s += s.master.result_s, tb += s.master.task_bytes, rb += s.master.result_bytes;
      tm += s.master.task_msgs, rm += s.master.result_msgs, res += s.master.results;
    }
    const double R = static_cast<double>(rounds.size()), n = static_cast<double>(a.items) * R;
    const double item_s = n > 0 ? busy / n : 0.0;  // measured cost of one item (the sleep as slept)
    const double ideal = std::ceil(static_cast<double>(a.items) / computing) * item_s * R;
    auto us = [](double s, double k) { return k > 0 ? 1e6 * s / k : 0.0; };
    std::printf(
        "bench-farm: ranks %d (computing %d%s), %d items/round x %d rounds, item %.2f ms (measured %.3f ms), "
        "result %d B, block %s, depth %d, fold %s\n",
        size, computing, works ? ", the master too" : ", the master coordinates", a.items, a.rounds, a.item_ms,
        1e3 * item_s, a.result_bytes, a.block > 0 ? std::to_string(a.block).c_str() : ("guided<=" + std::to_string(a.max_block)).c_str(),
        a.depth, a.fold.c_str());
    std::printf("  round %.4f s (ideal %.4f s): efficiency %.1f%%, workers busy %.1f%%\n", wall / R, ideal / R,
                100 * ideal / wall, 100 * busy / (computing * wall));
    std::printf("  master: %.2f us CPU per item (serving thread); task %.2f us per message, %.2f us per item, "
                "%.0f B per message; result %.2f us per message, %.2f us per item, %.0f B per result; "
                "%.1f task and %.1f result messages per round; fold %.2f us per result (%s)\n",
                us(cpu, n), us(task_s, static_cast<double>(tm)), us(task_s, n), tm ? tb / tm : 0.0,
                us(result_s, static_cast<double>(rm)), us(result_s, static_cast<double>(res)),
                res ? rb / res : 0.0, tm / R, rm / R, us(fold, n), a.fold.c_str());
    std::printf("csv,%d,%d,%d,%.4f,%d,%d,%d,%s,%.5f,%.5f,%.4f,%.3f,%.3f,%.3f,%.3f,%.3f,%.1f,%.1f,%.1f,%.3f\n", size,
                computing, a.items, 1e3 * item_s, a.result_bytes, a.block, a.depth, a.fold.c_str(), wall / R,
                ideal / R, ideal / wall, us(cpu, n), us(task_s, static_cast<double>(tm)), us(task_s, n),
                us(result_s, static_cast<double>(rm)), us(result_s, static_cast<double>(res)),
                res ? rb / res : 0.0, tm / R, rm / R, us(fold, n));
    std::fflush(stdout);
  }
  MPI_Finalize();
  return 0;
}

}  // namespace divcoll::cli
