#include "stages/schedule.hpp"

#include <algorithm>
#include <chrono>
#include <iterator>
#include <stdexcept>
#include <utility>

namespace divcoll::stages {
namespace {

double since(std::chrono::steady_clock::time_point t) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t).count();
}

}  // namespace

ScheduleOptions driver_schedule(int done, int ranks, int checkpoint_every) {
  ScheduleOptions o;
  o.from = done;
  o.commit_every = checkpoint_every;
  o.together_items = kTogetherItemsPerRank * static_cast<size_t>(std::max(1, ranks));
  o.together_rounds = 0;
  return o;
}

Schedule::Schedule(Plan& plan, ScheduleOptions options)
    : plan_(plan), info_(plan.info()), o_(std::move(options)) {
  if (info_.passes < 1) throw std::logic_error(info_.label + ": passes < 1");
  if (info_.independent_rounds && info_.passes != 1)
    throw std::logic_error(info_.label + ": independent rounds with passes");
  rounds_ = plan.rounds();
  stop_ = o_.until < 0 ? rounds_ : std::min(o_.until, rounds_);
  end_ = o_.until < 0 && plan.closing_round() ? rounds_ + 1 : stop_;
  every_ = info_.commit_every > 0 ? info_.commit_every : o_.commit_every;
  if (every_ < 1) throw std::logic_error(info_.label + ": a commit every " + std::to_string(every_) + " rounds");
  round_ = o_.from;
}

// one step of `call`: its input asked for and taken, its items and costs appended
void Schedule::add_step(FarmCall& call, int step, bool& costed) {
  auto t = std::chrono::steady_clock::now();
  std::string in = plan_.round_input(step);
  if (info_.independent_rounds && step < rounds_ && !in.empty())
    throw std::logic_error(info_.label + ": a plan with independent rounds has a round input");
  plan_.take_input(step, in);
  input_s_ += since(t);
  t = std::chrono::steady_clock::now();
  std::vector<std::string> items = plan_.items(step);
  const std::vector<double> costs = plan_.item_costs(step);
  if (!costs.empty() && costs.size() != items.size())
    throw std::logic_error(info_.label + ": item_costs gives " + std::to_string(costs.size()) + " costs for " +
                           std::to_string(items.size()) + " items");
  costed = costed && !costs.empty();
  call.costs.insert(call.costs.end(), costs.begin(), costs.end());
  std::move(items.begin(), items.end(), std::back_inserter(call.items));
  call.first.push_back(static_cast<int64_t>(call.items.size()));
  call.steps.push_back(step);
  call.inputs.push_back(std::move(in));
  items_s_ += since(t);
}

FarmCall Schedule::next() {
  if (done()) throw std::logic_error(info_.label + ": no farm call left");
  FarmCall call;
  call.round = round_;
  call.closing = round_ >= rounds_;
  call.first = {0};
  bool costed = true;
  if (info_.independent_rounds && !call.closing) {
    // rounds round_ .. round_ + m - 1 in one farm, each still its own step
    int m = 0;
    do {
      add_step(call, round_ + m, costed);
      ++m;
    } while (round_ + m < stop_ && (o_.together_rounds <= 0 || m < o_.together_rounds) &&
             (o_.together_items == 0 || call.items.size() < o_.together_items) &&
             !(o_.ends_farm && o_.ends_farm(round_ + m)));
    call.rounds = m;
  } else {
    add_step(call, round_ * info_.passes + pass_, costed);
    call.ends_rounds = pass_ + 1 == info_.passes;
  }
  if (!costed) call.costs.clear();
  // a commit after the last round of this call if a commit point (every `every_` rounds, the last round run) lies
  // among its rounds: the state is the state after all of them
  const int after = call.round + call.rounds;
  call.commit = call.ends_rounds && !call.closing && (after / every_ > call.round / every_ || after == stop_);
  advance(call);
  return call;
}

void Schedule::follow(const FarmHead& head) {
  if (done() || head.round != round_) throw std::logic_error(info_.label + ": a farm call out of turn");
  for (size_t k = 0; k < head.steps.size(); ++k) plan_.take_input(head.steps[k], head.inputs[k]);
  advance(head);
}

void Schedule::advance(const FarmHead& head) {
  if (head.ends_rounds) {
    round_ = head.round + head.rounds;
    pass_ = 0;
  } else {
    ++pass_;
  }
}

void Schedule::reduce(const FarmCall& call, int64_t item, const std::string& result) {
  // the last step whose items start at or before `item` (a step without items is passed over)
  const auto after = std::upper_bound(call.first.begin(), call.first.end(), item);
  const size_t at = static_cast<size_t>(after - call.first.begin()) - 1;
  plan_.reduce(call.steps[at], item - call.first[at], result);
}

Records Schedule::end(const FarmCall& call) {
  Records out;
  for (int step : call.steps)
    for (Record& r : plan_.end_round(step)) out.push_back(std::move(r));
  return out;
}

}  // namespace divcoll::stages
