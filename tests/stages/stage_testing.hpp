// helpers of the stage tests: a tiny config, random agents, runs of a plan through the serial farm
// (stages/serial.hpp) compared dataset by dataset, and a plan's farm calls as the driver makes them
#pragma once

#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <map>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

#include "collective/builders.hpp"
#include "common/rng.hpp"
#include "config/config.hpp"
#include "stages/schedule.hpp"
#include "stages/serial.hpp"
#include "testing.hpp"

namespace divcoll::stages::test {

using Datasets = std::map<std::string, Dataset>;

// configs/tiny.toml with `overrides`
inline config::RunConfig tiny(const std::vector<std::string>& overrides = {}) {
  return config::load_config(testing::source_dir() + "/configs/tiny.toml", overrides);
}

// n random agents with their anchors (computed, as load_population does before the connectors stage stores them)
inline std::vector<morph::Agent> random_population(int n, uint64_t seed = 7) {
  std::vector<morph::Agent> out;
  for (int i = 0; i < n; ++i) {
    Rng rng = make_rng(seed, 99, static_cast<uint64_t>(i));
    out.push_back(collective::random_agent(rng));
    out.back().anchors = collective::compute_anchors(out.back(), sim::RunPhysics{});
  }
  return out;
}

inline bool same_bits(double a, double b) { return (std::isnan(a) && std::isnan(b)) || a == b; }

inline const Dataset& at(const Datasets& d, const std::string& path) {
  const auto it = d.find(path);
  if (it == d.end()) throw std::runtime_error("no dataset " + path);
  return it->second;
}

// the same datasets, with the same dims, types and bits
inline void expect_same(const Datasets& a, const Datasets& b) {
  ASSERT_EQ(a.size(), b.size());
  for (const auto& [path, d] : a) {
    const auto it = b.find(path);
    ASSERT_NE(it, b.end()) << path;
    EXPECT_EQ(d.dims, it->second.dims) << path;
    EXPECT_EQ(d.type, it->second.type) << path;
    ASSERT_EQ(d.values.size(), it->second.values.size()) << path;
    size_t differ = 0;
    for (size_t i = 0; i < d.values.size(); ++i) differ += !same_bits(d.values[i], it->second.values[i]);
    EXPECT_EQ(differ, 0u) << path << ": values differ";
  }
}

inline Datasets written(const SerialRun& run) { return datasets(run.written()); }

// a run stopped after `cut` rounds and resumed by a new plan (make()) from the state committed then: the
// datasets of both sessions together
template <class Make>
Datasets resumed(const Make& make, int cut, SerialOptions o = {}) {
  const auto first = make();
  o.until = cut;
  const SerialRun a = run_serial(*first, o);
  EXPECT_EQ(a.done, cut);
  EXPECT_TRUE(a.finish.empty());
  const auto second = make();
  SerialOptions rest = o;
  rest.until = -1;
  rest.from = cut;
  rest.stored = committed_state(*second, {&a});
  const SerialRun b = run_serial(*second, rest);
  return datasets(std::vector<Records>{a.written(), b.written()});
}

// the farm calls the MPI driver (mpi/driver.cpp) makes of `plan` on `ranks` ranks, a commit every `every` rounds,
// from `from` rounds done with the state `stored`: the plan started as the driver starts it, its schedule
// (driver_schedule) walked by a recording farm that computes every item and hands the results back in item order
inline std::vector<FarmCall> driver_calls(Plan& plan, int ranks, int every, int from = 0,
                                          const StoredState& stored = {}) {
  plan.attributes();
  plan.setup();
  plan.start(from, stored);
  Schedule schedule(plan, driver_schedule(from, ranks, every));
  std::vector<FarmCall> calls;
  while (!schedule.done()) {
    FarmCall call = schedule.next();
    calls.push_back(call);
    for (size_t i = 0; i < call.items.size(); ++i)
      schedule.reduce(call, static_cast<int64_t>(i), plan.compute(call.items[i]));
    schedule.end(call);
  }
  plan.finish();
  return calls;
}

// the same farm calls, call by call: steps, inputs, items, where each step's items start, costs, rounds, commits.
// Of the costs only their count: a plan may estimate costs from measured times (the agents plan: the seconds an
// agent's parent took to train), which differ from run to run and change only who computes what
inline void expect_same_calls(const std::vector<FarmCall>& a, const std::vector<FarmCall>& b) {
  ASSERT_EQ(a.size(), b.size()) << "farm calls";
  for (size_t k = 0; k < a.size(); ++k) {
    EXPECT_EQ(a[k].steps, b[k].steps) << "call " << k;
    EXPECT_TRUE(a[k].inputs == b[k].inputs) << "call " << k << ": inputs differ";
    EXPECT_EQ(a[k].items.size(), b[k].items.size()) << "call " << k;
    EXPECT_TRUE(a[k].items == b[k].items) << "call " << k << ": items differ";
    EXPECT_EQ(a[k].first, b[k].first) << "call " << k;
    EXPECT_EQ(a[k].costs.size(), b[k].costs.size()) << "call " << k;
    EXPECT_EQ(a[k].round, b[k].round) << "call " << k;
    EXPECT_EQ(a[k].rounds, b[k].rounds) << "call " << k;
    EXPECT_EQ(a[k].ends_rounds, b[k].ends_rounds) << "call " << k;
    EXPECT_EQ(a[k].commit, b[k].commit) << "call " << k;
    EXPECT_EQ(a[k].closing, b[k].closing) << "call " << k;
  }
}

// the driver and the serial farm make the same farm calls of the plans make() builds, at each of `ranks` (the
// serial farm set to farm as the driver does on that many ranks), a commit every 2 rounds
template <class Make>
void expect_driver_and_serial_calls_agree(const Make& make, const std::vector<int>& ranks = {1, 2}) {
  for (int n : ranks) {
    SCOPED_TRACE(std::to_string(n) + " ranks");
    SerialOptions o;
    o.ranks = n;
    o.checkpoint_every = 2;
    std::vector<FarmCall> serial;
    o.on_farm = [&](const FarmCall& call) { serial.push_back(call); };
    run_serial(*make(), o);
    ASSERT_FALSE(serial.empty());
    expect_same_calls(driver_calls(*make(), n, 2), serial);
  }
}

// ... and resumed after `cut` rounds: the run stopped there by the serial farm, then the plan make_after(that
// run) builds (the plan a runner builds on --resume) resumed by both from the state committed then, at one rank
template <class Make, class MakeAfter>
void expect_resumed_calls_agree(const Make& make, int cut, const MakeAfter& make_after) {
  SCOPED_TRACE("resumed after " + std::to_string(cut) + " rounds");
  SerialOptions o;
  o.ranks = 1;
  o.until = cut;
  const SerialRun first = run_serial(*make(), o);
  const auto second = make_after(first);
  o.until = -1;
  o.from = cut;
  o.stored = committed_state(*second, {&first});
  std::vector<FarmCall> serial;
  o.on_farm = [&](const FarmCall& call) { serial.push_back(call); };
  run_serial(*second, o);
  ASSERT_FALSE(serial.empty());
  expect_same_calls(driver_calls(*make_after(first), 1, 1, cut, o.stored), serial);
}
template <class Make>
void expect_resumed_calls_agree(const Make& make, int cut) {
  expect_resumed_calls_agree(make, cut, [&](const SerialRun&) { return make(); });
}

}  // namespace divcoll::stages::test
