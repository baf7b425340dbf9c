// pagmo2's CMA-ES as ask/tell (the black-box control of connector training, evo/connector_opt.hpp).
//
// Why a file of its own: Debian's libpagmo is built for generic x86-64, where Eigen aligns its heap blocks to
// 16 bytes; divcoll is built with -march=native, where Eigen (pacmap.cpp) aligns them to 64 bytes with its own
// allocator. A cmaes object whose matrices the library allocated and divcoll's code freed (or the reverse)
// crashes. This file is compiled for generic x86-64 with Eigen renamed (CMakeLists.txt), so its Eigen code is
// the library's and never merges with pacmap's; nothing of pagmo or Eigen crosses this header.
#pragma once

#include <cstdint>
#include <memory>
#include <vector>

namespace divcoll::evo {

class Cmaes {
 public:
  // `init`: the initial mean; `sigma`: the initial standard deviation per coordinate; `lambda` ≥ 5 candidates
  Cmaes(const std::vector<double>& init, int lambda, double sigma, unsigned seed);
  ~Cmaes();
  // the candidates of the next generation (the same on every call until tell)
  std::vector<std::vector<double>> ask();
  // their fitness (to minimise), in the order of ask
  void tell(const std::vector<double>& fitness);

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace divcoll::evo
