#include "evo/es_cmaes.hpp"

#include <pagmo/algorithms/cmaes.hpp>
#include <pagmo/population.hpp>
#include <pagmo/problem.hpp>
#include <pagmo/types.hpp>

#include "common/check.hpp"

namespace divcoll::evo {
namespace {

// the fitness pagmo asks for: recorded (ask: any value returned), then looked up in the same order (tell).
// cmaes draws a generation's candidates before it evaluates any of them, so an evolve on a copy of the
// algorithm names exactly the candidates the real evolve evaluates.
struct Cache {
  bool recording = true;
  std::vector<std::vector<double>> asked;
  std::vector<double> fitness;
  size_t next = 0;
};
struct Problem {
  std::shared_ptr<Cache> cache;
  unsigned n = 1;
  pagmo::vector_double fitness(const pagmo::vector_double& x) const {
    Cache& c = *cache;
    if (c.recording) {
      c.asked.push_back(x);
      return {0.0};
    }
    DIVCOLL_DEMAND(c.next < c.fitness.size() && x == c.asked[c.next]);
    return {c.fitness[c.next++]};
  }
  // the box only sets cmaes's initial scale (width 1, so sigma is the sd per coordinate); it is not enforced
  std::pair<pagmo::vector_double, pagmo::vector_double> get_bounds() const {
    return {pagmo::vector_double(n, -0.5), pagmo::vector_double(n, 0.5)};
  }
};

}  // namespace

struct Cmaes::Impl {
  std::shared_ptr<Cache> cache = std::make_shared<Cache>();
  pagmo::algorithm algo;
  pagmo::population pop;
  int lambda = 0;
  bool asked = false;
};

Cmaes::Cmaes(const std::vector<double>& init, int lambda, double sigma, unsigned seed) : impl_(std::make_unique<Impl>()) {
  DIVCOLL_DEMAND(lambda >= 5);
  impl_->lambda = lambda;
  // one generation per evolve; memory: the distribution carries over; ftol = xtol = 0: never stop early
  impl_->algo = pagmo::algorithm(pagmo::cmaes(1, -1, -1, -1, -1, sigma, 0.0, 0.0, true, false, seed));
  impl_->pop = pagmo::population(pagmo::problem(Problem{impl_->cache, static_cast<unsigned>(init.size())}));
  for (int i = 0; i < lambda; ++i) impl_->pop.push_back(init, {0.0});
}
Cmaes::~Cmaes() = default;

std::vector<std::vector<double>> Cmaes::ask() {
  Cache& c = *impl_->cache;
  if (!impl_->asked) {
    c.recording = true;
    c.asked.clear();
    pagmo::algorithm copy = impl_->algo;
    copy.evolve(impl_->pop);
    DIVCOLL_DEMAND(static_cast<int>(c.asked.size()) == impl_->lambda);
    impl_->asked = true;
  }
  return c.asked;
}

void Cmaes::tell(const std::vector<double>& fitness) {
  if (!impl_->asked) ask();
  Cache& c = *impl_->cache;
  DIVCOLL_DEMAND(static_cast<int>(fitness.size()) == impl_->lambda);
  c.recording = false;
  c.fitness = fitness;
  c.next = 0;
  impl_->pop = impl_->algo.evolve(impl_->pop);
  DIVCOLL_DEMAND(static_cast<int>(c.next) == impl_->lambda);
  impl_->asked = false;
}

}  // namespace divcoll::evo
