#include "stages/serial.hpp"

#include <algorithm>
#include <cmath>
#include <functional>
#include <limits>
#include <numeric>
#include <random>
#include <stdexcept>

namespace divcoll::stages {
namespace {

void add(Records& to, Records from) {
  for (Record& r : from) to.push_back(std::move(r));
}

// the order to compute `n` items in
std::vector<size_t> compute_order(size_t n, const std::vector<double>& costs, const SerialOptions& o) {
  std::vector<size_t> order(n);
  std::iota(order.begin(), order.end(), size_t{0});
  switch (o.order) {
    case SerialOptions::Order::items: break;
    case SerialOptions::Order::dearest_first:
      if (!costs.empty())
        std::stable_sort(order.begin(), order.end(), [&](size_t a, size_t b) { return costs[a] > costs[b]; });
      break;
    case SerialOptions::Order::reversed: std::reverse(order.begin(), order.end()); break;
    case SerialOptions::Order::shuffled: {
      std::mt19937_64 g(o.shuffle_seed);
      std::shuffle(order.begin(), order.end(), g);
      break;
    }
  }
  return order;
}

}  // namespace

Records SerialRun::written() const {
  Records out = setup;
  out.insert(out.end(), rounds.begin(), rounds.end());
  out.insert(out.end(), state.begin(), state.end());
  out.insert(out.end(), finish.begin(), finish.end());
  return out;
}

SerialRun run_serial(Plan& plan, const SerialOptions& o, Plan* worker) {
  SerialRun run;
  const Plan::Info info = plan.info();
  const int R = plan.rounds(), passes = info.passes;
  if (passes < 1) throw std::logic_error(info.label + ": passes < 1");
  if (info.independent_rounds && passes != 1) throw std::logic_error(info.label + ": independent rounds with passes");
  run.attributes = plan.attributes();
  run.setup = plan.setup();
  plan.start(o.from, o.stored);
  const int stop = o.until < 0 ? R : std::min(o.until, R);
  const int end = o.until < 0 && plan.closing_round() ? R + 1 : stop;
  Plan& computing = worker ? *worker : plan;

  // one farm of `steps` (their items already made, `first[k]` where step k's start): compute, then reduce in
  // item order
  auto farm = [&](const std::vector<int>& steps, const std::vector<std::string>& items, const std::vector<int64_t>& first,
                  const std::vector<double>& costs) {
    std::vector<std::string> results(items.size());
    for (size_t i : compute_order(items.size(), costs, o)) results[i] = computing.compute(items[i]);
    run.items += static_cast<int64_t>(items.size());
    size_t at = 0;
    for (size_t i = 0; i < items.size(); ++i) {
      while (static_cast<int64_t>(i) >= first[at + 1]) ++at;
      plan.reduce(steps[at], static_cast<int64_t>(i) - first[at], results[i]);
    }
    for (int step : steps) {
      add(run.rounds, plan.end_round(step));
      for (std::string& w : plan.take_warnings()) run.warnings.push_back(std::move(w));
    }
  };
  auto costs_of = [&](int step, size_t count, std::vector<double>& costs, bool& costed) {
    std::vector<double> c = plan.item_costs(step);
    if (!c.empty() && c.size() != count)
      throw std::logic_error(info.label + ": item_costs gives " + std::to_string(c.size()) + " costs for " +
                             std::to_string(count) + " items");
    costed = costed && !c.empty();
    costs.insert(costs.end(), c.begin(), c.end());
  };

  int r = o.from;
  auto take_state = [&] {
    run.state = plan.state();
    run.state_attributes = plan.state_attributes();
  };
  if (r >= stop) take_state();
  while (r < end) {
    std::vector<std::string> items;
    std::vector<double> costs;
    bool costed = true;
    if (info.independent_rounds && r < R) {
      std::vector<int> steps;
      std::vector<int64_t> first = {0};
      for (int k = 0; k < std::max(1, o.rounds_per_farm) && r + k < stop; ++k) {
        const std::string in = plan.round_input(r + k);
        if (!in.empty()) throw std::logic_error(info.label + ": a plan with independent rounds has a round input");
        plan.take_input(r + k, in);
        if (worker) worker->take_input(r + k, in);
        std::vector<std::string> more = plan.items(r + k);
        costs_of(r + k, more.size(), costs, costed);
        std::move(more.begin(), more.end(), std::back_inserter(items));
        first.push_back(static_cast<int64_t>(items.size()));
        steps.push_back(r + k);
      }
      farm(steps, items, first, costed ? costs : std::vector<double>{});
      for (int step : steps) run.summaries.push_back(plan.summary(step));
      r += static_cast<int>(steps.size());
    } else {
      for (int pass = 0; pass < passes; ++pass) {
        const int step = r * passes + pass;
        const std::string in = plan.round_input(step);
        plan.take_input(step, in);
        if (worker) worker->take_input(step, in);
        items = plan.items(step);
        costs.clear(), costed = true;
        costs_of(step, items.size(), costs, costed);
        farm({step}, items, {0, static_cast<int64_t>(items.size())}, costed ? costs : std::vector<double>{});
      }
      if (r < R) run.summaries.push_back(plan.summary(r));
      ++r;
    }
    if (r == stop) take_state();
  }
  run.done = std::min(r, R);
  if (o.until < 0) {
    run.finish = plan.finish();
    run.finish_summary = plan.finish_summary();
  }
  return run;
}

std::map<std::string, Dataset> datasets(const std::vector<Records>& sessions) {
  std::map<std::string, Dataset> out;
  for (const Records& records : sessions)
    for (const Record& r : records) {
      Dataset& d = out[r.path];
      const uint64_t size = std::accumulate(r.dims.begin(), r.dims.end(), uint64_t{1}, std::multiplies<>());
      if (d.dims.empty()) {
        d.dims = r.dims;
        d.type = r.values.index();
        d.values.assign(size, std::numeric_limits<double>::quiet_NaN());
      }
      if (d.dims != r.dims || d.type != r.values.index())
        throw std::logic_error(r.path + ": written with other dims or another type");
      const uint64_t width = r.dims.empty() ? 1 : size / r.dims[0];
      std::visit(
          [&](const auto& v) {
            if (v.size() != r.rows.size() * width)
              throw std::logic_error(r.path + ": " + std::to_string(v.size()) + " values for " +
                                     std::to_string(r.rows.size()) + " rows of " + std::to_string(width));
            for (size_t k = 0; k < r.rows.size(); ++k) {
              if (r.rows[k] < 0 || static_cast<uint64_t>(r.rows[k]) >= (r.dims.empty() ? 1 : r.dims[0]))
                throw std::logic_error(r.path + ": row " + std::to_string(r.rows[k]) + " out of range");
              for (uint64_t q = 0; q < width; ++q)
                d.values[r.rows[k] * width + q] = static_cast<double>(v[k * width + q]);
            }
          },
          r.values);
    }
  return out;
}

std::map<std::string, Dataset> datasets(const Records& records) { return datasets(std::vector<Records>{records}); }

StoredState committed_state(const Plan& plan, const std::vector<const SerialRun*>& sessions) {
  std::vector<Records> written;
  for (const SerialRun* s : sessions) written.push_back(s->written());
  const std::map<std::string, Dataset> all = datasets(written);
  StoredState stored;
  for (const std::string& p : plan.state_paths()) {
    const auto it = all.find(p);
    if (it == all.end()) throw std::logic_error("committed_state: " + p + " was never written");
    stored[p] = it->second.values;
  }
  for (const auto& [name, value] : plan.state_attributes()) {
    (void)value;
    for (const SerialRun* s : sessions)
      for (const auto& [n, v] : s->state_attributes)
        if (n == name) stored[name] = {static_cast<double>(v)};
  }
  return stored;
}

}  // namespace divcoll::stages
