#include "sim/engine.hpp"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <limits>

#include "common/aligned.hpp"
#include "common/check.hpp"
#include "sim/model.hpp"
#include "sim/stages.hpp"

namespace divcoll::sim {
namespace {
// float_networks: steps whose parameter gradients are summed in float before they join the double sums
constexpr int kFloatGradSteps = 16;
// RunOptions::float_networks's default (set_default_float_networks)
std::atomic<bool> g_default_float_networks{false};
}  // namespace
void set_default_float_networks(bool on) { g_default_float_networks = on; }
bool default_float_networks() { return g_default_float_networks; }

const char* status_name(Status s) {
  switch (s) {
    case Status::ok: return "ok";
    case Status::nan: return "nan";
    case Status::unstable: return "unstable";
  }
  return "?";
}

// buffers sized once per (shape, steps, options) and reused: nothing is allocated inside the step loop
struct Simulator::Impl {
  Model model;

  // tape (grad) or rolling state (no grad). Substep states k = 0 .. T·n
  LineVector<double> xs, vs;           // (states × N × 2)
  std::vector<uint8_t> taus;           // (states × N)
  LineVector<double> vps;              // (T·n × N × 2) v' per substep (grad only)
  std::vector<ContactRecord> recs;     // (T·n × N) (grad only)
  LineVector<double> os;               // (T × S) o'_t after control (grad) or (S) rolling
  LineVector<double> agent_acts;       // (T × A × agent acts) (grad) or one step
  LineVector<double> conn_acts;        // (T × conn acts × 5C) (grad) or one step
  LineVector<float> agent_acts_f, conn_acts_f, scratch_f;  // the same with RunOptions::float_networks
  LineVector<float> g_agent_f, g_conn_f;  // float_networks: parameter gradients of the last few steps, in float
  // the parameter gradients, summed here (on whole cache lines, as the kernels want them) and copied out
  LineVector<double> g_agent, g_conn;

  // scratch (every buffer here starts on a cache line: common/aligned.hpp says why)
  LineVector<double> F, Fb, vpb, xb, vb, xb2, vb2, ob, Lb, scratch;

  template <class V>
  static void fit(V& v, size_t n) {
    if (v.size() < n) v.resize(n);
  }

  void size_for(const Model& m, const RunOptions& opt) {
    const size_t N2 = 2 * static_cast<size_t>(m.N);
    const size_t steps_kept = opt.grad ? opt.steps : 1;
    const size_t sub_kept = opt.grad ? static_cast<size_t>(opt.steps) * m.substeps : 1;
    const size_t states = opt.grad ? sub_kept + 1 : 2;
    fit(xs, states * N2);
    fit(vs, states * N2);
    fit(taus, states * m.N);
    if (opt.grad) {
      fit(vps, sub_kept * N2);
      fit(recs, sub_kept * m.N);
    } else {
      fit(vps, N2);
    }
    fit(os, (steps_kept + 1) * m.S);
    const size_t n_agent_acts = steps_kept * m.A * m.agent_layout.activation_count();
    const size_t n_conn_acts = steps_kept * m.conn_layout.activation_count() * kConnectorSprings * m.C;
    if (opt.float_networks) {
      fit(agent_acts_f, n_agent_acts);
      fit(conn_acts_f, n_conn_acts);
      fit(scratch_f, control_scratch_count(m));
    } else {
      fit(agent_acts, n_agent_acts);
      fit(conn_acts, n_conn_acts);
    }
    for (auto* b : {&F, &Fb, &vpb, &xb, &vb, &xb2, &vb2}) fit(*b, N2);
    fit(ob, m.S);
    fit(Lb, m.S);
    fit(scratch, control_scratch_count(m));
  }

  RunResult run(const Scene& sc, const RunOptions& opt);
};

Simulator::Simulator() : impl_(std::make_unique<Impl>()) {}
Simulator::~Simulator() = default;

size_t Simulator::workspace_bytes() const {
  const Impl& I = *impl_;
  size_t b = 0;
  for (const auto* v : {&I.xs, &I.vs, &I.vps, &I.os, &I.agent_acts, &I.conn_acts, &I.F, &I.Fb, &I.vpb, &I.xb,
                        &I.vb, &I.xb2, &I.vb2, &I.ob, &I.Lb, &I.scratch})
    b += v->capacity() * sizeof(double);
  for (const auto* v : {&I.agent_acts_f, &I.conn_acts_f, &I.scratch_f, &I.g_agent_f, &I.g_conn_f})
    b += v->capacity() * sizeof(float);
  b += I.taus.capacity() + I.recs.capacity() * sizeof(ContactRecord);
  return b;
}

namespace {
bool finite_gradients(const RunResult& r) {
  for (const auto* v : {&r.grad_agent_params, &r.grad_connector_params, &r.grad_x0, &r.grad_rest_length})
    for (double x : *v)
      if (!std::isfinite(x)) return false;
  return true;
}
}  // namespace

// float_networks: float's range ends at 3.4e38, and the adjoint of a long episode can pass it where double's
// does not (3 of 20 strong connectors of a paper-scale run had overflowing gradients): such an episode is
// redone with the networks in double, so a caller gets a finite gradient whenever double would give one
RunResult Simulator::run(const Scene& scene, const RunOptions& opt) {
  RunResult r = impl_->run(scene, opt);
  if (opt.float_networks && opt.grad && r.status == Status::ok && !finite_gradients(r)) {
    RunOptions in_double = opt;
    in_double.float_networks = false;
    r = impl_->run(scene, in_double);
    r.redone_in_double = true;
  }
  return r;
}

std::vector<RunResult> Simulator::run_batch(const std::vector<Scene>& scenes, const RunOptions& opt) {
  std::vector<RunResult> out;
  out.reserve(scenes.size());
  for (size_t b = 0; b < scenes.size(); ++b) {
    const Scene& s = scenes[b];
    const Scene& f = scenes.front();
    DIVCOLL_THROW_UNLESS(s.n_masses() == f.n_masses() && s.n_springs() == f.n_springs() &&
                             s.n_agents() == f.n_agents() && s.n_connectors() == f.n_connectors(),
                         "batch scene " << b << " has shape (N, S, A, C) = (" << s.n_masses() << ", "
                                        << s.n_springs() << ", " << s.n_agents() << ", " << s.n_connectors()
                                        << "), unlike scene 0's (" << f.n_masses() << ", " << f.n_springs()
                                        << ", " << f.n_agents() << ", " << f.n_connectors() << ")");
  }
  for (const Scene& s : scenes) out.push_back(run(s, opt));
  return out;
}

RunResult simulate(const Scene& scene, const RunOptions& opt) {
  Simulator sim;
  return sim.run(scene, opt);
}

namespace {
// the contact events of one substep's records, counted while they are in cache
void count_contacts(const ContactRecord* rec, int N, RunResult::ContactCounts& c) {
  for (int i = 0; i < N; ++i) {
    const ContactRecord& r = rec[i];
    c.floor += r.kind == 1;
    c.wall += r.kind == 2;
    c.sliding += r.friction_active;
    c.toi += r.toi_active;
    c.belt += r.kind == 1 && (r.b[0] != 0 || r.b[1] != 0);
  }
}
}  // namespace

RunResult Simulator::Impl::run(const Scene& sc, const RunOptions& opt) {
  // non-finite controller weights are not refused here: they end the episode with status nan
  validate(sc, ValidateOptions{.finite_params = false});
  DIVCOLL_THROW_UNLESS(opt.steps >= 1, "steps must be at least 1 (got " << opt.steps << ")");
  DIVCOLL_THROW_UNLESS(opt.hidden_every >= 1, "hidden_every must be at least 1 (got " << opt.hidden_every << ")");

  // substeps: from the stability rule, or as the scene file demands if that is enough
  const int needed = substeps_needed(sc);
  int n_sub = sc.constants.substeps;
  if (n_sub == 0) n_sub = needed;
  DIVCOLL_THROW_UNLESS(n_sub >= needed,
                       "the scene is unstable at dt = " << sc.constants.dt << " s: dt*sqrt(sum k/m) = "
                           << stability_number(sc, sc.constants.dt) << " at the worst mass needs at least "
                           << needed << " substeps, but the scene sets substeps = " << n_sub
                           << " (set it to 0 to choose automatically)");
  Model& m = model;
  m.compile(sc, n_sub);
  if (m.A > 0) m.prepare_sines(opt.steps);
  if (opt.float_networks) m.pack_float();
  size_for(m, opt);
  const bool fl = opt.float_networks;

  const int T = opt.steps, n = m.substeps, N = m.N, S = m.S;
  const size_t N2 = 2 * static_cast<size_t>(N);
  const int na = m.agent_layout.activation_count();
  const int nc = m.conn_layout.activation_count() * kConnectorSprings * m.C;
  const int cols = kConnectorSprings * m.C;

  RunResult res;
  res.substeps = n;
  if (opt.record) {
    res.x.assign((T + 1) * N2, std::numeric_limits<double>::quiet_NaN());
    res.v.assign((T + 1) * N2, std::numeric_limits<double>::quiet_NaN());
    res.touch.assign(static_cast<size_t>(T + 1) * N, 0);
  }
  if (opt.record_hidden && m.C > 0) res.hidden.reserve(static_cast<size_t>((T + opt.hidden_every - 1) / opt.hidden_every) * cols * 32);
  if (opt.record_inputs && m.C > 0)
    res.inputs.reserve(static_cast<size_t>((T + opt.hidden_every - 1) / opt.hidden_every) * cols * kConnectorInputs);

  // state 0: x = x0, v = 0, o = 0, τ = 0
  std::copy(sc.x0.begin(), sc.x0.end(), xs.begin());
  std::fill(vs.begin(), vs.begin() + N2, 0.0);
  std::fill(taus.begin(), taus.begin() + N, 0);
  std::fill(os.begin(), os.begin() + S, 0.0);
  if (opt.record) std::copy(sc.x0.begin(), sc.x0.end(), res.x.begin()), std::fill(res.v.begin(), res.v.begin() + N2, 0.0);

  // ---- forward -------------------------------------------------------------------------------------
  int k = 0;  // substep state index (grad) — rolling index modulo 2 otherwise
  auto sx = [&](int kk) { return &xs[(opt.grad ? kk : kk & 1) * N2]; };
  auto sv = [&](int kk) { return &vs[(opt.grad ? kk : kk & 1) * N2]; };
  auto st = [&](int kk) { return &taus[static_cast<size_t>(opt.grad ? kk : kk & 1) * N]; };
  for (int t = 0; t < T; ++t) {
    // control: o'_t from state t (o kept per step on the tape)
    double* o = &os[(opt.grad ? t + 1 : 0) * static_cast<size_t>(S)];
    if (opt.grad) std::copy(os.begin() + t * S, os.begin() + (t + 1) * S, o);
    const size_t ta = (opt.grad ? t : 0) * static_cast<size_t>(m.A) * na, tc = (opt.grad ? t : 0) * static_cast<size_t>(nc);
    auto control = [&](auto cb) {
      control_forward(m, t, sx(k), sv(k), st(k), o, cb);
      if (opt.record_hidden && m.C > 0 && t % opt.hidden_every == 0) {
        const auto* h2 = cb.conn_acts + static_cast<size_t>(m.conn_layout.activation_offset(2)) * cols;
        res.hidden.insert(res.hidden.end(), h2, h2 + static_cast<size_t>(32) * cols);
      }
      if (opt.record_inputs && m.C > 0 && t % opt.hidden_every == 0) {
        const auto* in = cb.conn_acts + static_cast<size_t>(m.conn_layout.activation_offset(0)) * cols;
        res.inputs.insert(res.inputs.end(), in, in + static_cast<size_t>(kConnectorInputs) * cols);
      }
    };
    if (fl) control(ControlBuffers<float>{agent_acts_f.data() + ta, conn_acts_f.data() + tc});
    else control(ControlBuffers<double>{agent_acts.data() + ta, conn_acts.data() + tc});
    // physics substeps
    for (int s = 0; s < n; ++s, ++k) {
      double* vp = opt.grad ? &vps[static_cast<size_t>(k) * N2] : vps.data();
      springs_forward(m, sx(k), sv(k), o, F.data());
      velocity_forward(m, t, sx(k), sv(k), F.data(), vp);
      contact_forward(m, sx(k), vp, sx(k + 1), sv(k + 1), st(k + 1),
                      opt.grad ? &recs[static_cast<size_t>(k) * N] : nullptr);
      if (opt.grad) count_contacts(&recs[static_cast<size_t>(k) * N], N, res.contacts);
    }
    // numerical trouble ends the episode, with where it happened
    const double* x1 = sx(k);
    const double* v1 = sv(k);
    for (int i = 0; i < N; ++i) {
      const bool finite = std::isfinite(x1[2 * i]) && std::isfinite(x1[2 * i + 1]) && std::isfinite(v1[2 * i]) &&
                          std::isfinite(v1[2 * i + 1]);
      const bool tame = std::abs(v1[2 * i]) <= opt.speed_limit && std::abs(v1[2 * i + 1]) <= opt.speed_limit;
      if (!finite || !tame) {
        res.status = finite ? Status::unstable : Status::nan;
        res.bad_step = t + 1;
        res.bad_mass = i;
        res.message = msg() << (finite ? "runaway velocity" : "non-finite state") << " at step " << t + 1
                            << ", mass " << i << " (x = " << x1[2 * i] << ", " << x1[2 * i + 1]
                            << "; v = " << v1[2 * i] << ", " << v1[2 * i + 1] << ")";
        break;
      }
    }
    if (opt.record) {
      std::copy(x1, x1 + N2, res.x.begin() + (t + 1) * N2);
      std::copy(v1, v1 + N2, res.v.begin() + (t + 1) * N2);
      std::copy(st(k), st(k) + N, res.touch.begin() + static_cast<size_t>(t + 1) * N);
    }
    if (res.status != Status::ok) break;
  }

  if (res.status != Status::ok) {
    res.travel = std::numeric_limits<double>::quiet_NaN();
    res.contacts = {};  // as before: counted for finished episodes only
    if (opt.grad) {
      if (opt.agent_param_grad) res.grad_agent_params.assign(static_cast<size_t>(m.A) * m.agent_params, 0.0);
      res.grad_connector_params.assign(m.C > 0 ? m.conn_params : 0, 0.0);
      res.grad_x0.assign(N2, 0.0);
      res.grad_rest_length.assign(S, 0.0);
    }
    return res;
  }

  // travel = mean x at T − mean x at 0
  const double* xT = sx(k);
  double sT = 0, s0 = 0;
  for (int i = 0; i < N; ++i) {
    sT += xT[2 * i];
    s0 += sc.x0[2 * i];
  }
  res.travel = sT / N - s0 / N;
  if (!opt.grad) return res;

  // ---- backward ------------------------------------------------------------------------------------
  g_agent.assign(opt.agent_param_grad ? static_cast<size_t>(m.A) * m.agent_params : 0, 0.0);
  g_conn.assign(m.C > 0 ? m.conn_params : 0, 0.0);
  res.grad_rest_length.assign(S, 0.0);
  double* Lbar = res.grad_rest_length.data();
  double* ga = opt.agent_param_grad ? g_agent.data() : nullptr;
  double* gc = m.C > 0 ? g_conn.data() : nullptr;
  // seed: ∂travel/∂x_T = (1/N, 0)
  double* xbar = xb.data();
  double* vbar = vb.data();
  double* xbar_prev = xb2.data();
  double* vbar_prev = vb2.data();
  for (int i = 0; i < N; ++i) {
    xbar[2 * i] = 1.0 / N;
    xbar[2 * i + 1] = 0;
  }
  std::fill(vbar, vbar + N2, 0.0);
  std::fill(ob.begin(), ob.begin() + S, 0.0);
  // float_networks: the parameter gradients are summed in float over at most kFloatGradSteps steps, then added
  // into the double sums (float's rounding of a sum of 16 terms, not of 1000; zeroing and adding every step
  // cost as much as an agent's network)
  if (fl) {
    g_agent_f.assign(opt.agent_param_grad ? static_cast<size_t>(m.A) * m.agent_params : 0, 0.0f);
    g_conn_f.assign(m.C > 0 ? m.conn_params : 0, 0.0f);
  }
  auto flush_float_grads = [&] {
    auto add = [](LineVector<float>& f, double* into) {
      for (size_t q = 0; q < f.size(); ++q) into[q] += f[q], f[q] = 0.0f;
    };
    if (!g_agent_f.empty()) add(g_agent_f, ga);
    if (!g_conn_f.empty()) add(g_conn_f, gc);
  };
  // the tape of one step is ≈ 8 KB for a pair and the backward pass reads it in descending order from
  // several arrays at once, which the hardware prefetcher follows poorly: step t − 1's blocks are asked for
  // while step t is being processed
  auto prefetch = [](const void* p, size_t bytes) {
    const char* c = static_cast<const char*>(p);
    for (size_t q = 0; q < bytes; q += 64) __builtin_prefetch(c + q);
  };
  for (int t = T - 1; t >= 0; --t) {
    if (t > 0) {
      const size_t k0 = static_cast<size_t>(t - 1) * n;
      if (fl) {
        prefetch(&agent_acts_f[static_cast<size_t>(t - 1) * m.A * na], sizeof(float) * m.A * na);
        prefetch(&conn_acts_f[static_cast<size_t>(t - 1) * nc], sizeof(float) * nc);
      } else {
        prefetch(&agent_acts[static_cast<size_t>(t - 1) * m.A * na], sizeof(double) * m.A * na);
        prefetch(&conn_acts[static_cast<size_t>(t - 1) * nc], sizeof(double) * nc);
      }
      prefetch(&recs[k0 * N], sizeof(ContactRecord) * n * N);
      prefetch(&xs[k0 * N2], sizeof(double) * n * N2);
      prefetch(&vs[k0 * N2], sizeof(double) * n * N2);
      prefetch(&vps[k0 * N2], sizeof(double) * n * N2);
      prefetch(&os[static_cast<size_t>(t) * S], sizeof(double) * S);
    }
    const double* o = &os[(t + 1) * static_cast<size_t>(S)];
    for (int s = n - 1; s >= 0; --s) {
      --k;
      const double* vp = &vps[static_cast<size_t>(k) * N2];
      // contact: x̄_{k+1}, v̄_{k+1} → v̄', x̄_k (partial)
      std::fill(xbar_prev, xbar_prev + N2, 0.0);
      std::fill(vbar_prev, vbar_prev + N2, 0.0);
      contact_adjoint(m, vp, sv(k + 1), &recs[static_cast<size_t>(k) * N], xbar, vbar, vpb.data(), xbar_prev);
      velocity_adjoint(m, vpb.data(), vbar_prev, Fb.data());
      springs_adjoint(m, sx(k), sv(k), o, Fb.data(), xbar_prev, vbar_prev, ob.data(), Lbar);
      std::swap(xbar, xbar_prev);
      std::swap(vbar, vbar_prev);
    }
    const size_t ta = static_cast<size_t>(t) * m.A * na, tc = static_cast<size_t>(t) * nc;
    if (fl) {
      control_adjoint(m, t, sx(k), sv(k), ControlBuffers<float>{agent_acts_f.data() + ta, conn_acts_f.data() + tc},
                      ob.data(), xbar, vbar, Lbar, opt.agent_param_grad ? g_agent_f.data() : nullptr,
                      m.C > 0 ? g_conn_f.data() : nullptr, scratch_f.data());
      if (t % kFloatGradSteps == 0) flush_float_grads();
    } else {
      control_adjoint(m, t, sx(k), sv(k), ControlBuffers<double>{agent_acts.data() + ta, conn_acts.data() + tc},
                      ob.data(), xbar, vbar, Lbar, ga, gc, scratch.data());
    }
    // truncated backpropagation: state t starts a window and ends the previous one, whose seed restarts here
    if (opt.grad_window > 0 && t > 0 && t % opt.grad_window == 0) {
      for (int i = 0; i < N; ++i) xbar[2 * i] = 1.0 / N, xbar[2 * i + 1] = 0;
      std::fill(vbar, vbar + N2, 0.0);
      std::fill(ob.begin(), ob.begin() + S, 0.0);
    }
  }
  if (fl) flush_float_grads();
  if (opt.agent_param_grad) res.grad_agent_params.assign(g_agent.begin(), g_agent.end());
  res.grad_connector_params.assign(g_conn.begin(), g_conn.end());
  // x0 is both the initial state and travel's baseline
  res.grad_x0.assign(xbar, xbar + N2);
  for (int i = 0; i < N; ++i) res.grad_x0[2 * i] -= 1.0 / N;
  return res;
}

}  // namespace divcoll::sim
