#include "evo/gd.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "collective/builders.hpp"
#include "common/check.hpp"
#include "common/dmath.hpp"
#include "evo/optim.hpp"
#include "morph/body.hpp"

namespace divcoll::evo {

GdOptions gd_options(const config::RunConfig::Agents& a) {
  return {a.epochs,         a.episode_steps, gd_rule_from(a.gd_rule), a.gd_step,        a.adam_lr,
          a.rest_moves,     a.rest_move_max, a.rest_length_min,        a.rest_length_max};
}

GdRule gd_rule_from(const std::string& name) {
  if (name == "paper") return GdRule::paper;
  if (name == "keep_best") return GdRule::keep_best;
  if (name == "adam") return GdRule::adam;
  throw InputError(msg() << "unknown gradient rule '" << name << "' (paper, keep_best or adam)");
}

const char* gd_rule_name(GdRule r) {
  switch (r) {
    case GdRule::paper: return "paper";
    case GdRule::keep_best: return "keep_best";
    case GdRule::adam: return "adam";
  }
  return "?";
}

bool move_rest_positions(morph::Agent& a, const std::vector<double>& delta, const GdOptions& opt) {
  const double lo = opt.rest_length_min * morph::kSpacing, hi = opt.rest_length_max * morph::kSpacing;
  double scale = 1.0;
  for (int attempt = 0; attempt < 5; ++attempt, scale *= 0.5) {
    morph::Agent b = a;
    for (size_t q = 0; q < b.rest_pos.size(); ++q) b.rest_pos[q] += scale * delta[q];
    // keep min x = 0 and the lowest mass at y = 0; rest lengths are measured after the shift, so they
    // are exactly the distances between the stored positions
    double mx = b.rest_pos[0], my = b.rest_pos[1];
    for (int q = 0; q < sim::kAgentMasses; ++q) mx = std::min(mx, b.rest_pos[2 * q]), my = std::min(my, b.rest_pos[2 * q + 1]);
    for (int q = 0; q < sim::kAgentMasses; ++q) b.rest_pos[2 * q] -= mx, b.rest_pos[2 * q + 1] -= my;
    morph::update_rest_lengths(b);
    bool ok = true;
    for (double L : b.rest_length) ok = ok && L >= lo && L <= hi;
    if (!ok) continue;
    a = std::move(b);
    return true;
  }
  return false;
}

std::vector<double> rest_gradient(const morph::Agent& a, const sim::RunResult& r) {
  // rest positions enter through x(0) and through the rest lengths. x(0) is the rest positions shifted
  // so that the lowest mass sits at y = 0: a mass that is lowest on its own lifts or lowers the whole
  // body when it moves, so its y gets −Σ_k ∂travel/∂x0_k,y as well. Where several masses share the
  // lowest height this is the upward one-sided derivative (the shift does not move). min x = 0 is the
  // same for x, but travel does not change under a horizontal translation, so that sum vanishes.
  std::vector<double> g = r.grad_x0;
  {
    int lowest = 0, ties = 0;
    for (int q = 1; q < sim::kAgentMasses; ++q)
      if (a.rest_pos[2 * q + 1] < a.rest_pos[2 * lowest + 1]) lowest = q;
    for (int q = 0; q < sim::kAgentMasses; ++q) ties += a.rest_pos[2 * q + 1] == a.rest_pos[2 * lowest + 1];
    if (ties == 1) {
      double lift = 0;
      for (int q = 0; q < sim::kAgentMasses; ++q) lift += r.grad_x0[2 * q + 1];
      g[2 * lowest + 1] -= lift;
    }
  }
  for (int q = 0; q < sim::kAgentSprings; ++q) {
    const int i = a.spring_i[q], j = a.spring_j[q];
    const double dx = a.rest_pos[2 * i] - a.rest_pos[2 * j], dy = a.rest_pos[2 * i + 1] - a.rest_pos[2 * j + 1];
    const double L = std::sqrt(dx * dx + dy * dy);
    const double gl = r.grad_rest_length[q];
    g[2 * i] += gl * dx / L;
    g[2 * i + 1] += gl * dy / L;
    g[2 * j] -= gl * dx / L;
    g[2 * j + 1] -= gl * dy / L;
  }
  return g;
}

namespace {

struct Eval {
  double travel = std::numeric_limits<double>::quiet_NaN();
  sim::Status status = sim::Status::ok;
  std::vector<double> g_params, g_rest;  // gradient of travel
};

Eval evaluate(const morph::Agent& a, const GdOptions& opt, const sim::RunPhysics& physics, sim::Simulator& sim,
              bool grad) {
  const sim::Scene s = collective::agent_scene(a, "flat", physics.contact);
  sim::RunOptions ro = physics.options();
  ro.steps = opt.steps;
  ro.grad = grad;
  sim::RunResult r = sim.run(s, ro);
  Eval e;
  e.status = r.status;
  if (r.status != sim::Status::ok) return e;
  e.travel = r.travel;
  if (!grad) return e;
  e.g_params = std::move(r.grad_agent_params);
  e.g_rest = rest_gradient(a, r);
  return e;
}

double norm(const std::vector<double>& v) {
  double s = 0;
  for (double x : v) s += x * x;
  return std::sqrt(s);
}

}  // namespace

bool step_agent(morph::Agent& a, const std::vector<double>& g_params, const std::vector<double>& g_rest,
                const GdOptions& opt, Adam& adam, int epoch) {
  for (const std::vector<double>* g : {&g_params, &g_rest})
    for (double x : *g)
      if (!std::isfinite(x)) return false;
  const size_t P = a.params.size();
  DIVCOLL_DEMAND(g_params.size() == P && g_rest.size() == a.rest_pos.size());
  // weights: a normalized ascent step, or Adam
  const double gn = norm(g_params);
  if (opt.rule == GdRule::adam) {
    std::vector<double> loss_grad(P);
    for (size_t q = 0; q < P; ++q) loss_grad[q] = -g_params[q];
    adam.step(a.params, std::move(loss_grad), opt.adam_lr, std::numeric_limits<double>::infinity(), epoch + 1);
  } else if (gn > 0) {
    for (size_t q = 0; q < P; ++q) a.params[q] += opt.step * g_params[q] / gn;
  }
  // rest positions: the mass with the largest gradient moves rest_move_max
  if (opt.rest_moves) {
    double gmax = 0;
    for (int q = 0; q < sim::kAgentMasses; ++q) gmax = std::max(gmax, dmath::hypot(g_rest[2 * q], g_rest[2 * q + 1]));
    if (gmax > 0) {
      std::vector<double> delta(g_rest.size());
      for (size_t q = 0; q < delta.size(); ++q) delta[q] = opt.rest_move_max * g_rest[q] / gmax;
      move_rest_positions(a, delta, opt);
    }
  }
  return true;
}

TrainResult train_agent(morph::Agent& a, const GdOptions& opt, const sim::RunPhysics& physics, sim::Simulator& sim) {
  TrainResult out;
  Adam adam;  // ascent on travel: descent on −travel
  morph::Agent best = a;
  double best_travel = -std::numeric_limits<double>::infinity();
  sim::Status last_status = sim::Status::ok;
  for (int epoch = 0; epoch <= opt.epochs; ++epoch) {
    const bool update = epoch < opt.epochs;
    const Eval e = evaluate(a, opt, physics, sim, update);
    out.curve_u.push_back(e.travel);
    last_status = e.status;
    if (e.status != sim::Status::ok) break;  // keep what we had before this step
    if (e.travel > best_travel) best_travel = e.travel, best = a;
    if (!update) break;
    // a gradient that is not finite stops training here, as an episode that was not ok does (before, a
    // normalized step by an infinite norm made the weights NaN, and NaN norms skipped steps without a word)
    if (!step_agent(a, e.g_params, e.g_rest, opt, adam, epoch)) {
      out.nonfinite_gradient_epoch = epoch;
      break;
    }
  }
  // the paper's rule keeps the last parameters; the others the best seen
  const bool last_ok = last_status == sim::Status::ok;
  if (opt.rule != GdRule::paper || !last_ok) {
    if (best_travel > -std::numeric_limits<double>::infinity()) {
      a = best;
      out.travel_u = best_travel;
    } else {
      out.travel_u = std::numeric_limits<double>::quiet_NaN();
      out.status = last_status;
    }
  } else {
    out.travel_u = out.curve_u.back();
  }
  out.fitness_bl = out.travel_u / body_length(a);
  return out;
}

}  // namespace divcoll::evo
