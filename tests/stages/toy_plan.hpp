// a toy plan of any shape (rounds, passes, independent rounds, a closing round, items per step, costs) that logs
// the calls made of it: the schedule's tests (tests/stages/schedule_test.cpp) and the driver's
// (tests/mpi/driver_test.cpp)
#pragma once

#include <gtest/gtest.h>

#include <cstdint>
#include <string>
#include <utility>
#include <vector>

#include "stages/payload.hpp"
#include "stages/plan.hpp"

namespace divcoll::stages::test {

// `rounds` rounds of `passes` passes; step s has items[s % items.size()] items computing 1000 s + k; round inputs
// "in s" unless independent; costs k + 1 when `costed`. It logs take_input, items, reduce and end_round
class ShapedPlan final : public Plan {
 public:
  struct Shape {
    int rounds = 4, passes = 1, commit_every = 0;
    bool independent = false, closing = false, costed = false;
    std::vector<int> items = {3};
  };
  explicit ShapedPlan(Shape s) : s_(std::move(s)) {}
  Info info() const override {
    Info i{"toy", "toy", "rounds_done", "round", "items", s_.commit_every};
    i.passes = s_.passes;
    i.independent_rounds = s_.independent;
    return i;
  }
  int rounds() const override { return s_.rounds; }
  bool closing_round() const override { return s_.closing; }
  std::vector<std::string> state_paths() const override { return {"toy/sum"}; }
  void start(int done, const StoredState& st) override { sum_ = done > 0 ? st.at("toy/sum")[0] : 0; }
  Records state() const override { return {{"toy/sum", {1}, {0}, std::vector<double>{sum_}}}; }
  std::string round_input(int step) override { return s_.independent ? std::string() : "in " + std::to_string(step); }
  void take_input(int step, const std::string& in) override {
    log.push_back("input " + std::to_string(step) + " " + in);
  }
  std::vector<std::string> items(int step) override {
    log.push_back("items " + std::to_string(step));
    std::vector<std::string> out;
    for (int k = 0; k < count(step); ++k) out.push_back(pack(int32_t{1000 * step + k}));
    return out;
  }
  std::vector<double> item_costs(int step) const override {
    std::vector<double> c;
    if (s_.costed)
      for (int k = 0; k < count(step); ++k) c.push_back(k + 1);
    return c;
  }
  std::string compute(const std::string& item) override { return item; }
  void reduce(int step, int64_t i, const std::string& result) override {
    const int32_t v = unpack<int32_t>(result);
    EXPECT_EQ(v, 1000 * step + i);  // every result reaches its own step and index
    sum_ += v;
    log.push_back("reduce " + std::to_string(step) + " " + std::to_string(i));
  }
  Records end_round(int step) override {
    log.push_back("end " + std::to_string(step));
    return {{"toy/steps", {static_cast<uint64_t>((s_.rounds + 1) * s_.passes)}, {step}, std::vector<double>{sum_}}};
  }

  std::vector<std::string> log;

 private:
  int count(int step) const { return s_.items[static_cast<size_t>(step) % s_.items.size()]; }
  Shape s_;
  double sum_ = 0;
};

}  // namespace divcoll::stages::test
