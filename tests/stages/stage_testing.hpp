// helpers of the stage tests: a tiny config, random agents, and runs of a plan through the serial farm
// (stages/serial.hpp) compared dataset by dataset
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
#include "stages/serial.hpp"
#include "testing.hpp"

namespace divcoll::stages::test {

using Datasets = std::map<std::string, Dataset>;

// configs/tiny.toml with `overrides`
inline io::RunConfig tiny(const std::vector<std::string>& overrides = {}) {
  return io::load_config(testing::source_dir() + "/configs/tiny.toml", overrides);
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

}  // namespace divcoll::stages::test
