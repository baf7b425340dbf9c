// the driver (mpi/driver.hpp): what waits between copies is merged per dataset, a plan's every row, its state
// and its counter are in the run file when drive() returns, independent rounds farmed together are each
// reduced and recorded as their own, and the driver calls a plan as the serial farm does; at 1 to 4 ranks
#include <gtest/gtest.h>
#include <mpi.h>

#include <filesystem>
#include <functional>
#include <map>
#include <string>
#include <variant>
#include <vector>

#include "config/config.hpp"
#include "io/h5.hpp"
#include "mpi/driver.hpp"
#include "mpi/protocol.hpp"
#include "stages/schedule.hpp"
#include "stages/serial.hpp"
#include "stages/toy_plan.hpp"

namespace divcoll {
namespace {

int rank_of() {
  int r = 0;
  MPI_Comm_rank(MPI_COMM_WORLD, &r);
  return r;
}

// drives `plan` (output.checkpoint_every = `every`, `checkpoint` at each commit) into a new file `name` in a new
// temporary folder, on every rank; returns its path once every rank has closed it (the test removes the folder)
std::string drive_into(const std::string& name, mpi::Plan& plan, int every, const std::function<void()>& checkpoint) {
  std::string path = (std::filesystem::temp_directory_path() / "divcoll_drive_XXXXXX").string();
  if (rank_of() == 0) path = std::string(mkdtemp(path.data())) + "/" + name;
  path = mpi::broadcast(MPI_COMM_WORLD, path);
  {
    io::h5::Handle fapl(H5Pcreate(H5P_FILE_ACCESS), H5Pclose);
    H5Pset_fapl_mpio(fapl.id(), MPI_COMM_WORLD, MPI_INFO_NULL);
    io::h5::File f = io::h5::File::create(path, true, fapl.id());
    config::RunConfig cfg = config::default_config();
    cfg.run.progress_every_s = 0;
    cfg.output.checkpoint_every = every;
    mpi::drive(MPI_COMM_WORLD, cfg, f, plan, checkpoint);
    f.close();
  }
  MPI_Barrier(MPI_COMM_WORLD);
  return path;
}

TEST(RecordQueue, MergesRowsPerDatasetAndTheLastValueOfARowWins) {
  mpi::RecordQueue q;
  q.add({{"a", {4, 2}, {0}, std::vector<double>{1, 2}}, {"b", {3}, {1}, std::vector<int32_t>{7}}});
  q.add({{"a", {4, 2}, {2, 0}, std::vector<double>{5, 6, 3, 4}}});
  EXPECT_EQ(q.bytes(), 2 * sizeof(double) + sizeof(int32_t) + 4 * sizeof(double));
  const mpi::Records r = q.take();
  ASSERT_EQ(r.size(), 2u);
  EXPECT_EQ(r[0].path, "a");
  EXPECT_EQ(r[0].rows, (std::vector<int64_t>{0, 2}));
  EXPECT_EQ(std::get<std::vector<double>>(r[0].values), (std::vector<double>{3, 4, 5, 6}));
  EXPECT_EQ(r[1].path, "b");
  EXPECT_EQ(std::get<std::vector<int32_t>>(r[1].values), (std::vector<int32_t>{7}));
  EXPECT_EQ(q.bytes(), 0u);
  EXPECT_TRUE(q.take().empty());
}

// R rounds of 3 items (item i of round r computes 10 r + i); each round records row r of "toy/sums" (its
// results' sum) and rewrites row 0 of "toy/last" (the round's index); the state is the running total
class ToyPlan final : public mpi::Plan {
 public:
  explicit ToyPlan(int rounds) : R_(rounds) {}
  Info info() const override { return {"toy", "toy", "rounds_done", "round", "items"}; }
  int rounds() const override { return R_; }
  std::vector<std::string> state_paths() const override { return {"toy/total"}; }
  void start(int, const mpi::StoredState&) override { total_ = 0; }
  mpi::Records state() const override { return {{"toy/total", {1}, {0}, std::vector<double>{total_}}}; }
  std::vector<std::string> items(int r) override {
    sum_ = 0;
    return {mpi::pack(10 * r), mpi::pack(10 * r + 1), mpi::pack(10 * r + 2)};
  }
  std::string compute(const std::string& b) override { return b; }
  void reduce(int, int64_t, const std::string& b) override { sum_ += mpi::unpack<int>(b); }
  mpi::Records end_round(int r) override {
    total_ += sum_;
    return {{"toy/sums", {static_cast<uint64_t>(R_), 1}, {r}, std::vector<double>{static_cast<double>(sum_)}},
            {"toy/last", {1}, {0}, std::vector<int64_t>{r}}};
  }

 private:
  int R_;
  int sum_ = 0;
  double total_ = 0;
};

TEST(Drive, EveryRowStateAndCounterAreWrittenByTheEndWhenNoCommitCopies) {
  const int R = 5;
  int commits = 0;
  ToyPlan plan(R);
  // commits after rounds 2, 4 and 5 (the last); no Checkpointer: nothing copies
  const std::string path = drive_into("toy.h5", plan, 2, [&] { ++commits; });
  EXPECT_EQ(commits, 3);
  if (rank_of() == 0) {
    io::h5::File f = io::h5::File::open(path);
    const std::vector<double> sums = f.read<double>("toy/sums", io::h5::Dims{R, 1});
    double total = 0;
    for (int r = 0; r < R; ++r) {
      EXPECT_EQ(sums[r], 30.0 * r + 3) << "round " << r;
      total += sums[r];
    }
    EXPECT_EQ(f.read<int64_t>("toy/last", io::h5::Dims{1})[0], R - 1);
    EXPECT_EQ(f.read<double>("toy/total", io::h5::Dims{1})[0], total);
    EXPECT_EQ(f.group("toy").read_int("rounds_done"), R);
    std::filesystem::remove_all(std::filesystem::path(path).parent_path());
  }
}

// 3 counted rounds adding 1, 2, 3 to the state, and a closing round that adds 1000 to it: the state committed with
// the last round (written at the end, since nothing copies) must be the state before the closing round
class ClosingPlan final : public mpi::Plan {
 public:
  Info info() const override { return {"closing", "closing", "rounds_done", "round", "items"}; }
  int rounds() const override { return 3; }
  bool closing_round() const override { return true; }
  std::vector<std::string> state_paths() const override { return {"closing/total"}; }
  void start(int, const mpi::StoredState&) override { total_ = 0; }
  mpi::Records state() const override { return {{"closing/total", {1}, {0}, std::vector<double>{total_}}}; }
  std::vector<std::string> items(int r) override { return {mpi::pack(r)}; }
  std::string compute(const std::string& b) override { return b; }
  void reduce(int, int64_t, const std::string&) override {}
  mpi::Records end_round(int r) override {
    total_ += r < 3 ? r + 1 : 1000;
    return {{"closing/rounds", {4}, {r}, std::vector<double>{total_}}};
  }

 private:
  double total_ = 0;
};

TEST(Drive, TheClosingRoundDoesNotChangeTheCommittedState) {
  ClosingPlan plan;
  const std::string path = drive_into("closing.h5", plan, 1, [] {});  // no copies: every commit waits for the end
  if (rank_of() == 0) {
    io::h5::File f = io::h5::File::open(path);
    EXPECT_EQ(f.read<double>("closing/total", io::h5::Dims{1})[0], 6.0);
    EXPECT_EQ(f.read<double>("closing/rounds", io::h5::Dims{4}), (std::vector<double>{1, 3, 6, 1006}));
    EXPECT_EQ(f.group("closing").read_int("rounds_done"), 3);
    std::filesystem::remove_all(std::filesystem::path(path).parent_path());
  }
}

// R independent rounds of one item each (item of round r computes 100 + r); the driver farms several together,
// yet each result must reach its own round, in order, and each round record its own row
class IndependentPlan final : public mpi::Plan {
 public:
  explicit IndependentPlan(int rounds) : R_(rounds) {}
  Info info() const override {
    Info i{"independent", "ind", "rounds_done", "round", "items"};
    i.independent_rounds = true;
    return i;
  }
  int rounds() const override { return R_; }
  void start(int, const mpi::StoredState&) override {}
  std::vector<std::string> items(int r) override { return {mpi::pack(100 + r)}; }
  std::string compute(const std::string& b) override { return b; }
  void reduce(int r, int64_t i, const std::string& b) override {
    EXPECT_EQ(i, 0);
    EXPECT_EQ(mpi::unpack<int>(b), 100 + r);
    value_[r] = mpi::unpack<int>(b);
    reduced.push_back(r);
  }
  mpi::Records end_round(int r) override {
    ended.push_back(r);
    return {{"ind/values", {static_cast<uint64_t>(R_)}, {r}, std::vector<int64_t>{value_.at(r)}}};
  }
  std::vector<int> reduced, ended;

 private:
  int R_;
  std::map<int, int64_t> value_;
};

TEST(Drive, IndependentRoundsFarmedTogetherAreEachReducedAndRecordedAsTheirOwn) {
  const int R = 3 * static_cast<int>(stages::kTogetherItemsPerRank) + 5;  // one item per round: farms of several
  int commits = 0;
  IndependentPlan plan(R);
  const std::string path = drive_into("ind.h5", plan, 1, [&] { ++commits; });
  int size = 1;
  MPI_Comm_size(MPI_COMM_WORLD, &size);
  const int per_farm = static_cast<int>(stages::kTogetherItemsPerRank) * size;
  EXPECT_EQ(commits, (R + per_farm - 1) / per_farm) << "one commit per farm of kTogetherItemsPerRank rounds per rank";
  if (rank_of() == 0) {
    std::vector<int> in_order(R);
    for (int r = 0; r < R; ++r) in_order[r] = r;
    EXPECT_EQ(plan.reduced, in_order);
    EXPECT_EQ(plan.ended, in_order);
    io::h5::File f = io::h5::File::open(path);
    const std::vector<int64_t> v = f.read<int64_t>("ind/values", io::h5::Dims{R});
    for (int r = 0; r < R; ++r) EXPECT_EQ(v[r], 100 + r);
    EXPECT_EQ(f.group("ind").read_int("rounds_done"), R);
    std::filesystem::remove_all(std::filesystem::path(path).parent_path());
  }
}


// the driver calls a plan as its schedule says, as the serial farm set to farm as the driver does on this many
// ranks calls it: the master's plan takes the same inputs, makes the same items, reduces the same results and
// ends the same steps in the same order, and a checkpoint comes at each commit the schedule names
TEST(Drive, CallsAPlanAsTheSerialFarmDoesAtThisRankCount) {
  int size = 1;
  MPI_Comm_size(MPI_COMM_WORLD, &size);
  using Shape = stages::test::ShapedPlan::Shape;
  const std::vector<std::pair<Shape, int>> cases = {  // a plan's shape, output.checkpoint_every
      {{.rounds = 5}, 2},
      {{.rounds = 4, .passes = 3, .costed = true}, 1},
      {{.rounds = 3, .passes = 2, .closing = true, .items = {2, 0, 4}}, 2},
      {{.rounds = 9, .commit_every = 4, .closing = true}, 1},
      {{.rounds = 40, .independent = true, .items = {5, 1, 0, 7}}, 3},
      {{.rounds = 70, .independent = true, .costed = true, .items = {1}}, 1},
  };
  for (size_t k = 0; k < cases.size(); ++k) {
    SCOPED_TRACE("case " + std::to_string(k));
    const auto& [shape, every] = cases[k];
    stages::test::ShapedPlan driven(shape);
    int checkpoints = 0;
    const std::string path = drive_into("shaped.h5", driven, every, [&] { ++checkpoints; });
    if (rank_of() != 0) continue;
    std::filesystem::remove_all(std::filesystem::path(path).parent_path());
    stages::test::ShapedPlan serial(shape);
    stages::SerialOptions o;
    o.ranks = size;
    o.checkpoint_every = every;
    int commits = 0;
    o.on_farm = [&](const stages::FarmCall& call) { commits += call.commit; };
    stages::run_serial(serial, o);
    EXPECT_EQ(driven.log, serial.log);
    EXPECT_EQ(checkpoints, commits);
  }
}

}  // namespace
}  // namespace divcoll
