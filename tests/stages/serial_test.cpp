// the serial farm (stages/serial.hpp) on a toy plan: the driver's order of calls, reduction in item order
// whatever the compute order, independent rounds farmed together, state and resume, the datasets of records
#include "stages/serial.hpp"

#include <gtest/gtest.h>

#include <stdexcept>
#include <string>
#include <vector>

#include "stages/payload.hpp"
#include "stages/stage_testing.hpp"

namespace divcoll::stages {
namespace {

// round r: items k = 0..n-1 computing (r + 1) * 10 + k; the reduction is an order-sensitive hash of the results;
// the state is the running hash and the number of items reduced
class ToyPlan final : public Plan {
 public:
  ToyPlan(int rounds, bool independent, int n = 5) : R_(rounds), independent_(independent), n_(n) {}
  Info info() const override {
    Info i{"toy", "toy", "rounds_done", "round", "items", 0};
    i.independent_rounds = independent_;
    return i;
  }
  int rounds() const override { return R_; }
  Records setup() override { return {{"toy/setup", {1}, {0}, std::vector<int64_t>{42}}}; }
  std::vector<std::string> state_paths() const override { return {"toy/state"}; }
  std::vector<std::pair<std::string, int64_t>> state_attributes() const override { return {{"reduced", reduced_}}; }
  void start(int done, const StoredState& s) override {
    hash_ = done > 0 ? s.at("toy/state")[0] : 0;
    reduced_ = done > 0 ? static_cast<int64_t>(s.at("reduced")[0]) : 0;
    calls.push_back("start " + std::to_string(done));
  }
  Records state() const override { return {{"toy/state", {1}, {0}, std::vector<double>{hash_}}}; }
  void take_input(int step, const std::string&) override { calls.push_back("input " + std::to_string(step)); }
  std::vector<std::string> items(int step) override {
    calls.push_back("items " + std::to_string(step));
    std::vector<std::string> out;
    for (int k = 0; k < n_; ++k) out.push_back(pack(int32_t{(step + 1) * 10 + k}));
    round_hash_[step] = 0;
    return out;
  }
  std::vector<double> item_costs(int) const override { return costs; }
  std::string compute(const std::string& item) override {
    computed.push_back(unpack<int32_t>(item));
    return item;
  }
  void reduce(int step, int64_t i, const std::string& result) override {
    const int32_t v = unpack<int32_t>(result);
    EXPECT_EQ(v, (step + 1) * 10 + i);  // every result reaches its own step and index
    round_hash_[step] = round_hash_[step] * 31 + v;
    ++reduced_;
  }
  Records end_round(int step) override {
    calls.push_back("end " + std::to_string(step));
    hash_ = hash_ * 7 + round_hash_.at(step);
    return {{"toy/rounds", {static_cast<uint64_t>(R_)}, {step}, std::vector<double>{round_hash_.at(step)}}};
  }
  Records finish() override { return {{"toy/final", {1}, {0}, std::vector<double>{hash_}}}; }

  std::vector<std::string> calls;
  std::vector<int32_t> computed;
  std::vector<double> costs;

 private:
  const int R_;
  const bool independent_;
  const int n_;
  double hash_ = 0;
  int64_t reduced_ = 0;
  std::map<int, double> round_hash_;
};

TEST(SerialFarm, CallsAPlanInTheDriversOrderAndRecordsEveryRound) {
  ToyPlan plan(3, false);
  const SerialRun run = run_serial(plan);
  const std::vector<std::string> want = {"start 0", "input 0", "items 0", "end 0", "input 1", "items 1", "end 1",
                                         "input 2", "items 2", "end 2"};
  EXPECT_EQ(plan.calls, want);
  EXPECT_EQ(run.done, 3);
  EXPECT_EQ(run.items, 15);
  EXPECT_EQ(run.summaries.size(), 3u);
  ASSERT_EQ(run.rounds.size(), 3u);
  ASSERT_EQ(run.finish.size(), 1u);
  const test::Datasets d = test::written(run);
  EXPECT_EQ(test::at(d, "toy/rounds").dims, std::vector<uint64_t>{3});
  EXPECT_EQ(test::at(d, "toy/setup").values, std::vector<double>{42});
  EXPECT_EQ(test::at(d, "toy/final").values, test::at(d, "toy/state").values);
}

TEST(SerialFarm, ReducesInItemOrderWhateverTheComputeOrder) {
  ToyPlan plain(2, false);
  const test::Datasets want = test::written(run_serial(plain));
  for (auto order : {SerialOptions::Order::reversed, SerialOptions::Order::shuffled, SerialOptions::Order::dearest_first}) {
    ToyPlan plan(2, false);
    plan.costs = {1, 5, 2, 4, 3};
    SerialOptions o;
    o.order = order;
    o.shuffle_seed = 3;
    const SerialRun run = run_serial(plan, o);
    test::expect_same(test::written(run), want);
    if (order == SerialOptions::Order::reversed) {
      EXPECT_EQ(plan.computed.front(), 14);
    }
    if (order == SerialOptions::Order::dearest_first) {
      EXPECT_EQ(plan.computed.front(), 11);  // cost 5
    }
  }
}

TEST(SerialFarm, IndependentRoundsFarmedTogetherAreEachReducedAndRecordedAsTheirOwn) {
  ToyPlan one(4, true);
  const test::Datasets want = test::written(run_serial(one));
  ToyPlan together(4, true);
  SerialOptions o;
  o.rounds_per_farm = 3;
  o.order = SerialOptions::Order::reversed;
  const SerialRun run = run_serial(together, o);
  test::expect_same(test::written(run), want);
  // rounds 0-2 in one farm: every round's items before the first round's end
  const std::vector<std::string> want_calls = {"start 0", "input 0", "items 0", "input 1", "items 1", "input 2",
                                               "items 2", "end 0",   "end 1",   "end 2",   "input 3", "items 3",
                                               "end 3"};
  EXPECT_EQ(together.calls, want_calls);
}

TEST(SerialFarm, AResumeFromTheCommittedStateContinuesAsAnUninterruptedRun) {
  ToyPlan plain(4, false);
  const test::Datasets want = test::written(run_serial(plain));
  for (int cut = 1; cut < 4; ++cut)
    test::expect_same(test::resumed([] { return std::make_unique<ToyPlan>(4, false); }, cut), want);
  // the committed state holds the state paths and the state attributes
  ToyPlan first(4, false);
  SerialOptions o;
  o.until = 2;
  const SerialRun a = run_serial(first, o);
  ToyPlan second(4, false);
  const StoredState s = committed_state(second, {&a});
  EXPECT_EQ(s.at("reduced"), std::vector<double>{10});
  EXPECT_EQ(s.count("toy/state"), 1u);
}

TEST(SerialFarm, RefusesCostsThatDoNotMatchTheItems) {
  ToyPlan plan(1, false);
  plan.costs = {1, 2};
  EXPECT_THROW(run_serial(plan), std::logic_error);
}

TEST(SerialFarm, DatasetsPlaceRowsAndTheLastWriteOfARowWins) {
  const Records r = {{"a", {3, 2}, {2, 0}, std::vector<double>{5, 6, 1, 2}},
                     {"a", {3, 2}, {2}, std::vector<double>{7, 8}},
                     {"b", {2}, {1}, std::vector<uint8_t>{9}}};
  const test::Datasets d = datasets(r);
  const std::vector<double>& a = test::at(d, "a").values;
  EXPECT_EQ(a[0], 1);
  EXPECT_EQ(a[1], 2);
  EXPECT_TRUE(std::isnan(a[2]) && std::isnan(a[3]));
  EXPECT_EQ(a[4], 7);
  EXPECT_EQ(a[5], 8);
  EXPECT_EQ(test::at(d, "b").type, 3u);
  EXPECT_THROW(datasets(Records{{"c", {2}, {2}, std::vector<double>{1}}}), std::logic_error);
  EXPECT_THROW(datasets(Records{{"c", {2}, {0}, std::vector<double>{1}}, {"c", {3}, {0}, std::vector<double>{1}}}),
               std::logic_error);
}

}  // namespace
}  // namespace divcoll::stages
