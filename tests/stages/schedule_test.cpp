// a plan's schedule (stages/schedule.hpp) on a toy plan: passes, independent rounds farmed together, commit
// points, the closing round, a resume, the other processes following the master; and the driver's calls and the
// serial farm's are the same for every shape of plan (each stage's plans: tests/stages/<name>_test.cpp)
#include "stages/schedule.hpp"

#include <gtest/gtest.h>

#include <map>
#include <stdexcept>
#include <string>
#include <vector>

#include "stages/payload.hpp"
#include "stages/stage_testing.hpp"
#include "stages/toy_plan.hpp"

namespace divcoll::stages {
namespace {

using Toy = test::ShapedPlan;

// every call of `plan`'s schedule with `o`, each computed and ended
std::vector<FarmCall> walk(Plan& plan, const ScheduleOptions& o) {
  plan.start(o.from, {{"toy/sum", {0}}});
  Schedule schedule(plan, o);
  std::vector<FarmCall> calls;
  while (!schedule.done()) {
    calls.push_back(schedule.next());
    const FarmCall& call = calls.back();
    for (size_t i = 0; i < call.items.size(); ++i)
      schedule.reduce(call, static_cast<int64_t>(i), plan.compute(call.items[i]));
    schedule.end(call);
  }
  return calls;
}

std::vector<std::vector<int>> steps_of(const std::vector<FarmCall>& calls) {
  std::vector<std::vector<int>> out;
  for (const FarmCall& c : calls) out.push_back(c.steps);
  return out;
}

std::vector<int> commits_of(const std::vector<FarmCall>& calls) {  // rounds done at each commit
  std::vector<int> out;
  for (const FarmCall& c : calls)
    if (c.commit) out.push_back(c.round + c.rounds);
  return out;
}

TEST(Schedule, APlanOfPassesMakesACallPerPassAndItsRoundEndsWithTheLastPass) {
  Toy plan({.rounds = 3, .passes = 2});
  ScheduleOptions o;
  o.commit_every = 2;
  const std::vector<FarmCall> calls = walk(plan, o);
  EXPECT_EQ(steps_of(calls), (std::vector<std::vector<int>>{{0}, {1}, {2}, {3}, {4}, {5}}));
  for (size_t k = 0; k < calls.size(); ++k) {
    EXPECT_EQ(calls[k].round, static_cast<int>(k / 2));
    EXPECT_EQ(calls[k].ends_rounds, k % 2 == 1);
    EXPECT_EQ(calls[k].inputs, std::vector<std::string>{"in " + std::to_string(k)});
    EXPECT_EQ(calls[k].first, (std::vector<int64_t>{0, 3}));
  }
  EXPECT_EQ(commits_of(calls), (std::vector<int>{2, 3}));  // every 2 rounds, and the last
  // the plan's own commit_every wins
  Toy own({.rounds = 5, .commit_every = 3});
  EXPECT_EQ(commits_of(walk(own, o)), (std::vector<int>{3, 5}));
}

TEST(Schedule, IndependentRoundsJoinAFarmUntilItHoldsEnoughItems) {
  Toy plan({.rounds = 10, .independent = true, .items = {5}});
  ScheduleOptions o;
  o.together_items = 12;
  o.together_rounds = 0;
  const std::vector<FarmCall> calls = walk(plan, o);
  EXPECT_EQ(steps_of(calls), (std::vector<std::vector<int>>{{0, 1, 2}, {3, 4, 5}, {6, 7, 8}, {9}}));
  EXPECT_EQ(calls[0].first, (std::vector<int64_t>{0, 5, 10, 15}));
  EXPECT_EQ(calls[1].round, 3);
  EXPECT_EQ(calls[1].rounds, 3);
  EXPECT_EQ(commits_of(calls), (std::vector<int>{3, 6, 9, 10}));  // after each farm holding a commit point
  // every round's items before the first round's results and end
  const std::vector<std::string> head(plan.log.begin(), plan.log.begin() + 8);
  EXPECT_EQ(head, (std::vector<std::string>{"input 0 ", "items 0", "input 1 ", "items 1", "input 2 ", "items 2",
                                            "reduce 0 0", "reduce 0 1"}));
  // the driver's: kTogetherItemsPerRank items per rank, a commit where a commit point lies among the farm's rounds
  Toy driven({.rounds = 10, .independent = true, .items = {5}});
  const std::vector<FarmCall> d = walk(driven, driver_schedule(0, 1, 4));
  EXPECT_EQ(steps_of(d), (std::vector<std::vector<int>>{{0, 1, 2, 3, 4, 5, 6}, {7, 8, 9}}));
  EXPECT_EQ(commits_of(d), (std::vector<int>{7, 10}));
  // at most `together_rounds` rounds, and a farm ends where `ends_farm` says
  Toy capped({.rounds = 5, .independent = true});
  o.together_items = 0;
  o.together_rounds = 2;
  o.ends_farm = [](int done) { return done == 3; };
  EXPECT_EQ(steps_of(walk(capped, o)), (std::vector<std::vector<int>>{{0, 1}, {2}, {3, 4}}));
}

TEST(Schedule, AStepWithoutItemsIsPassedOverAndCostsComeOnlyWhenEveryStepGivesThem) {
  ScheduleOptions o;
  o.together_rounds = 3;
  Toy costed({.rounds = 3, .independent = true, .costed = true, .items = {2, 1, 3}});
  const std::vector<FarmCall> c = walk(costed, o);
  ASSERT_EQ(c.size(), 1u);
  EXPECT_EQ(c[0].costs, (std::vector<double>{1, 2, 1, 1, 2, 3}));
  // step 1 has no items (and so no costs): its results are passed over, and the call has no costs
  Toy plan({.rounds = 3, .independent = true, .costed = true, .items = {2, 0, 3}});
  const std::vector<FarmCall> calls = walk(plan, o);
  ASSERT_EQ(calls.size(), 1u);
  EXPECT_EQ(calls[0].first, (std::vector<int64_t>{0, 2, 2, 5}));
  EXPECT_TRUE(calls[0].costs.empty());
  const std::vector<std::string> want = {"input 0 ",   "items 0",    "input 1 ",   "items 1",    "input 2 ",
                                         "items 2",    "reduce 0 0", "reduce 0 1", "reduce 2 0", "reduce 2 1",
                                         "reduce 2 2", "end 0",      "end 1",      "end 2"};
  EXPECT_EQ(plan.log, want);
}

TEST(Schedule, TheClosingRoundComesLastUncountedAndWithoutACommit) {
  Toy plan({.rounds = 2, .passes = 2, .closing = true});
  plan.start(0, {});
  Schedule schedule(plan, ScheduleOptions{});
  std::vector<bool> closing_next;
  std::vector<FarmCall> calls;
  while (!schedule.done()) {
    closing_next.push_back(schedule.closing_next());
    calls.push_back(schedule.next());
    schedule.end(calls.back());  // results need not reach the plan here
  }
  EXPECT_EQ(closing_next, (std::vector<bool>{false, false, false, false, true, false}));
  EXPECT_EQ(steps_of(calls), (std::vector<std::vector<int>>{{0}, {1}, {2}, {3}, {4}, {5}}));
  EXPECT_TRUE(calls[4].closing && calls[5].closing && !calls[5].commit && calls[5].ends_rounds);
  EXPECT_EQ(calls[5].round, 2);
  EXPECT_EQ(commits_of(calls), (std::vector<int>{1, 2}));
  EXPECT_EQ(schedule.rounds_done(), 2);
  // stopped early (until): no closing round, and a commit where it stops
  Toy early({.rounds = 4, .closing = true});
  ScheduleOptions o;
  o.until = 3;
  o.commit_every = 2;
  const std::vector<FarmCall> e = walk(early, o);
  EXPECT_EQ(steps_of(e), (std::vector<std::vector<int>>{{0}, {1}, {2}}));
  EXPECT_EQ(commits_of(e), (std::vector<int>{2, 3}));
}

TEST(Schedule, AResumeStartsAfterTheRoundsDoneAndKeepsTheCommitPoints) {
  Toy plan({.rounds = 6, .closing = true});
  ScheduleOptions o;
  o.from = 3;
  o.commit_every = 2;
  const std::vector<FarmCall> calls = walk(plan, o);
  EXPECT_EQ(steps_of(calls), (std::vector<std::vector<int>>{{3}, {4}, {5}, {6}}));
  EXPECT_EQ(commits_of(calls), (std::vector<int>{4, 6}));
  // every round done: only the closing round, redone
  Toy finished({.rounds = 6, .closing = true});
  o.from = 6;
  const std::vector<FarmCall> f = walk(finished, o);
  ASSERT_EQ(f.size(), 1u);
  EXPECT_TRUE(f[0].closing);
}

TEST(Schedule, AnotherProcessFollowsTheMastersCallsAndTakesTheSameInputs) {
  Toy master({.rounds = 3, .passes = 2}), worker({.rounds = 3, .passes = 2});
  master.start(0, {});
  Schedule m(master, ScheduleOptions{}), w(worker, ScheduleOptions{});
  while (!m.done()) {
    const FarmCall call = m.next();
    EXPECT_FALSE(w.done());
    EXPECT_EQ(w.closing_next(), false);
    w.follow(call);
  }
  EXPECT_TRUE(w.done());
  // the same inputs: the master's log holds them and its items (its results were never reduced here)
  std::vector<std::string> inputs;
  for (const std::string& line : master.log)
    if (line.rfind("input", 0) == 0) inputs.push_back(line);
  EXPECT_EQ(worker.log, inputs);
  EXPECT_THROW(w.follow(FarmHead{}), std::logic_error);
}

TEST(Schedule, RefusesARoundInputOfIndependentRoundsAndPassesWithIndependentRounds) {
  class Inputs final : public Plan {
   public:
    Info info() const override {
      Info i{"inputs", "inputs"};
      i.independent_rounds = true;
      return i;
    }
    int rounds() const override { return 2; }
    void start(int, const StoredState&) override {}
    std::string round_input(int) override { return "weights"; }
    std::vector<std::string> items(int) override { return {"a"}; }
    std::string compute(const std::string& b) override { return b; }
    void reduce(int, int64_t, const std::string&) override {}
    Records end_round(int) override { return {}; }
  } inputs;
  Schedule s(inputs, ScheduleOptions{});
  EXPECT_THROW(s.next(), std::logic_error);
  Toy both({.passes = 2, .independent = true});
  EXPECT_THROW(Schedule(both, ScheduleOptions{}).done(), std::logic_error);
}

TEST(Schedule, TheDriverAndTheSerialFarmMakeTheSameCallsOfEveryShapeOfPlan) {
  const std::vector<Toy::Shape> shapes = {
      {.rounds = 5},
      {.rounds = 4, .passes = 3, .costed = true},
      {.rounds = 3, .passes = 2, .closing = true, .items = {2, 0, 4}},
      {.rounds = 9, .commit_every = 4, .closing = true},
      {.rounds = 40, .independent = true, .items = {5, 1, 0, 7}},
      {.rounds = 70, .independent = true, .costed = true, .items = {1}},
      {.rounds = 6, .independent = true, .closing = true, .items = {20}},
  };
  for (size_t k = 0; k < shapes.size(); ++k) {
    SCOPED_TRACE("shape " + std::to_string(k));
    auto make = [&] { return std::make_unique<Toy>(shapes[k]); };
    test::expect_driver_and_serial_calls_agree(make, {1, 2, 3});
    test::expect_resumed_calls_agree(make, 2);
  }
}

}  // namespace
}  // namespace divcoll::stages
