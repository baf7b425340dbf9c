// random numbers that are bit-identical on every platform and standard library (SPEC §10).
//
// The generator is std::mt19937_64, whose output sequence the C++ standard fixes. The std
// distributions (uniform_real_distribution, normal_distribution, ...) are implementation-defined, so
// nothing in divcoll uses them: every draw goes through the helpers below, which only use raw 64-bit
// outputs of the generator (normal() also needs log, sqrt and cos of the C library, so it is
// bit-identical wherever libm is). Every generator is seeded by seed_for(run seed, stage, item index).
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <numbers>
#include <random>
#include <vector>

#include "common/dmath.hpp"

namespace divcoll {

using Rng = std::mt19937_64;

// splitmix64 finaliser (Steele, Lea & Flood 2014): a bijective 64-bit mixer
inline uint64_t splitmix64(uint64_t x) {
  x += 0x9e3779b97f4a7c15ull;
  x = (x ^ (x >> 30)) * 0xbf58476d1ce4e5b9ull;
  x = (x ^ (x >> 27)) * 0x94d049bb133111ebull;
  return x ^ (x >> 31);
}

// the seed of the generator of one item of one stage of one run; each argument goes through its own
// mixing round, so (a, b, c) and (b, a, c) give unrelated seeds
inline uint64_t seed_for(uint64_t run_seed, uint64_t stage, uint64_t item) {
  uint64_t h = splitmix64(run_seed);
  h = splitmix64(h ^ stage);
  return splitmix64(h ^ item);
}

// a generator seeded by seed_for(run_seed, stage, item)
inline Rng make_rng(uint64_t run_seed, uint64_t stage, uint64_t item) {
  return Rng(seed_for(run_seed, stage, item));
}

// uniform double in [0, 1): the top 53 bits of one draw
inline double uniform01(Rng& rng) { return static_cast<double>(rng() >> 11) * 0x1.0p-53; }

// uniform integer in [0, n), n >= 1, unbiased by rejection (one draw almost always)
inline uint64_t uniform_int(Rng& rng, uint64_t n) {
  // reject the lowest (2^64 mod n) values so that the rest split evenly into n classes
  const uint64_t threshold = (0 - n) % n;
  for (;;) {
    const uint64_t r = rng();
    if (r >= threshold) return r % n;
  }
}

// standard normal N(0, 1) by Box–Muller from two uniform draws; the second variate is discarded so
// the generator carries no hidden state (each call consumes exactly two draws)
inline double normal(Rng& rng) {
  // u1 in (0, 1] so that log(u1) is finite
  const double u1 = static_cast<double>((rng() >> 11) + 1) * 0x1.0p-53;
  const double u2 = uniform01(rng);
  return std::sqrt(-2.0 * dmath::log(u1)) * dmath::cos(2.0 * std::numbers::pi * u2);
}

// N(mean, sd²)
inline double normal(Rng& rng, double mean, double sd) { return mean + sd * normal(rng); }

// k of the indices 0..n−1, distinct and in increasing order, by a partial Fisher–Yates shuffle (all of
// them when k ≥ n)
inline std::vector<int64_t> sorted_sample(Rng& rng, int64_t n, int64_t k) {
  std::vector<int64_t> idx(static_cast<size_t>(n));
  for (int64_t i = 0; i < n; ++i) idx[i] = i;
  const int64_t m = std::min(k, n);
  for (int64_t i = 0; i < m; ++i) std::swap(idx[i], idx[i + uniform_int(rng, n - i)]);
  idx.resize(static_cast<size_t>(m));
  std::sort(idx.begin(), idx.end());
  return idx;
}

}  // namespace divcoll
