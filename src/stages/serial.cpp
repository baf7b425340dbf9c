#include "stages/serial.hpp"

#include <algorithm>
#include <cmath>
#include <functional>
#include <limits>
#include <numeric>
#include <optional>
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

// the schedule of a serial run with `o`
ScheduleOptions schedule_options(const SerialOptions& o) {
  ScheduleOptions s = o.ranks > 0 ? driver_schedule(o.from, o.ranks, o.checkpoint_every) : ScheduleOptions{};
  s.from = o.from;
  s.until = o.until;
  s.commit_every = o.checkpoint_every;
  if (o.ranks <= 0) s.together_rounds = std::max(1, o.rounds_per_farm);
  return s;
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
  run.attributes = plan.attributes();
  run.setup = plan.setup();
  plan.start(o.from, o.stored);
  Schedule schedule(plan, schedule_options(o));
  std::optional<Schedule> follower;
  if (worker) follower.emplace(*worker, schedule_options(o));
  Plan& computing = worker ? *worker : plan;
  auto take_state = [&] {
    run.state = plan.state();
    run.state_attributes = plan.state_attributes();
  };
  if (o.from >= schedule.stop()) take_state();
  while (!schedule.done()) {
    FarmCall call = schedule.next();
    if (follower) follower->follow(call);
    if (o.on_farm) o.on_farm(call);
    // compute in the order asked for, then reduce in item order
    std::vector<std::string> results(call.items.size());
    for (size_t i : compute_order(call.items.size(), call.costs, o)) results[i] = computing.compute(call.items[i]);
    run.items += static_cast<int64_t>(call.items.size());
    for (size_t i = 0; i < results.size(); ++i) schedule.reduce(call, static_cast<int64_t>(i), results[i]);
    add(run.rounds, schedule.end(call));
    for (std::string& w : plan.take_warnings()) run.warnings.push_back(std::move(w));
    if (!call.ends_rounds || call.closing) continue;
    for (int k = 0; k < call.rounds; ++k) run.summaries.push_back(plan.summary(call.round + k));
    if (call.commit && call.round + call.rounds == schedule.stop()) take_state();  // the last commit's state
  }
  run.done = schedule.rounds_done();
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
