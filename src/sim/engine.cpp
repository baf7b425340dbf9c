#include "sim/engine.hpp"

#include <algorithm>
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
}  // namespace

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
    const size_t n_conn_acts = steps_kept * m.conn_layout.activation_count() * m.conn_cols;
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

  // the episode (engine.cpp): run = begin, forward_step per step (failed if one ends it), travel, and with grad
  // begin_adjoint, adjoint_step per step in reverse, end_adjoint
  struct Episode;
  RunResult run(const Scene& sc, const RunOptions& opt);
  Episode begin(const Scene& sc, const RunOptions& opt);
  bool forward_step(Episode& e, int t);
  RunResult failed(Episode& e);
  double travel(Episode& e);
  void begin_adjoint(Episode& e);
  void adjoint_step(Episode& e, int t);
  void flush_float_grads(Episode& e);
  RunResult end_adjoint(Episode& e);
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

// one episode in progress: the scene, the options and the shape, and where the forward and adjoint passes stand
struct Simulator::Impl::Episode {
  Episode(const Scene& scene, const RunOptions& options, Model& model)
      : sc(scene), opt(options), m(model), fl(options.float_networks), T(options.steps), n(model.substeps),
        N(model.N), S(model.S), N2(2 * static_cast<size_t>(model.N)), na(model.agent_layout.activation_count()),
        nc(model.conn_layout.activation_count() * model.conn_cols), cols(kConnectorSprings * model.C) {}
  const Scene& sc;
  const RunOptions& opt;
  Model& m;
  bool fl;               // networks in float
  int T, n, N, S;        // steps, substeps, masses, springs
  size_t N2;             // 2N
  int na, nc, cols;      // activations of an agent, of the connectors; connector springs
  int k = 0;             // substep state index: the tape's (grad), or a rolling index modulo 2
  RunResult res;
  // adjoint: x̄, v̄ of the current state and the previous one, the parameter-gradient sums
  double *xbar = nullptr, *vbar = nullptr, *xbar_prev = nullptr, *vbar_prev = nullptr;
  double *Lbar = nullptr, *ga = nullptr, *gc = nullptr;
};

namespace {
// the state k's positions, velocities and contact flags: on the tape with grad, else in a two-state ring
double* state_x(LineVector<double>& xs, const RunOptions& opt, size_t N2, int k) {
  return xs.data() + ((opt.grad ? k : k & 1) * N2);
}
uint8_t* state_tau(std::vector<uint8_t>& taus, const RunOptions& opt, int N, int k) {
  return taus.data() + (static_cast<size_t>(opt.grad ? k : k & 1) * N);
}
// the tape of one step is ≈ 8 KB for a pair and the backward pass reads it in descending order from several
// arrays at once, which the hardware prefetcher follows poorly: step t − 1's blocks are asked for while step t is
// being processed
// (pointers into the buffers are data() + offset, never &v[i]: a buffer a scene does not use (connectors,
// sensors) is empty, and indexing it is undefined)
void prefetch(const void* p, size_t bytes) {
  const char* c = static_cast<const char*>(p);
  for (size_t q = 0; q < bytes; q += 64) __builtin_prefetch(c + q);
}
}  // namespace

// the episode: a forward step per control step, then (with grad) an adjoint step per control step in reverse
RunResult Simulator::Impl::run(const Scene& sc, const RunOptions& opt) {
  Episode e = begin(sc, opt);
  for (int t = 0; t < e.T; ++t)
    if (!forward_step(e, t)) return failed(e);
  e.res.travel = travel(e);
  if (!opt.grad) return std::move(e.res);
  begin_adjoint(e);
  for (int t = e.T - 1; t >= 0; --t) adjoint_step(e, t);
  return end_adjoint(e);
}

// checks the scene and options, compiles the model, sizes the buffers and writes state 0: x = x0, v = 0, o = 0, τ = 0
Simulator::Impl::Episode Simulator::Impl::begin(const Scene& sc, const RunOptions& opt) {
  // non-finite controller weights are not refused here: they end the episode with status nan
  validate(sc, ValidateOptions{.finite_params = false});
  DIVCOLL_THROW_UNLESS(opt.steps >= 1, "steps must be at least 1 (got " << opt.steps << ")");
  DIVCOLL_THROW_UNLESS(opt.hidden_every >= 1, "hidden_every must be at least 1 (got " << opt.hidden_every << ")");
  DIVCOLL_THROW_UNLESS(!opt.record_hidden || !joint_connector_params(sc.connector_params.size()),
                       "record_hidden keeps a hidden state per connector spring (SPEC §8.2), but the scene's joint "
                       "connector network has one per connector");

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

  Episode e(sc, opt, m);
  const int T = e.T, N = e.N, S = e.S;
  const size_t N2 = e.N2;
  RunResult& res = e.res;
  res.substeps = e.n;
  if (opt.record) {
    res.x.assign((T + 1) * N2, std::numeric_limits<double>::quiet_NaN());
    res.v.assign((T + 1) * N2, std::numeric_limits<double>::quiet_NaN());
    res.touch.assign(static_cast<size_t>(T + 1) * N, 0);
  }
  if (opt.record_tether) res.tether.assign(sc.connector_spring_index.size() * kTetherColumns, 0.0);
  if (opt.record_hidden && m.C > 0) res.hidden.reserve(static_cast<size_t>((T + opt.hidden_every - 1) / opt.hidden_every) * e.cols * 32);
  if (opt.record_inputs && m.C > 0)
    res.inputs.reserve(static_cast<size_t>((T + opt.hidden_every - 1) / opt.hidden_every) * e.cols * kConnectorInputs);

  std::copy(sc.x0.begin(), sc.x0.end(), xs.begin());
  std::fill(vs.begin(), vs.begin() + N2, 0.0);
  std::fill(taus.begin(), taus.begin() + N, 0);
  std::fill(os.begin(), os.begin() + S, 0.0);
  if (opt.record) std::copy(sc.x0.begin(), sc.x0.end(), res.x.begin()), std::fill(res.v.begin(), res.v.begin() + N2, 0.0);
  return e;
}

// control step t: the networks (o'_t from state t), the physics substeps, the finiteness check, the recording.
// False when numerical trouble ended the episode (res says where)
bool Simulator::Impl::forward_step(Episode& e, int t) {
  const RunOptions& opt = e.opt;
  Model& m = e.m;
  const int n = e.n, N = e.N, S = e.S;
  const size_t N2 = e.N2;
  RunResult& res = e.res;
  int& k = e.k;
  auto sx = [&](int kk) { return state_x(xs, opt, N2, kk); };
  auto sv = [&](int kk) { return state_x(vs, opt, N2, kk); };
  auto st = [&](int kk) { return state_tau(taus, opt, N, kk); };
  // control: o'_t from state t (o kept per step on the tape)
  double* o = os.data() + ((opt.grad ? t + 1 : 0) * static_cast<size_t>(S));
  if (opt.grad) std::copy(os.begin() + t * S, os.begin() + (t + 1) * S, o);
  const size_t ta = (opt.grad ? t : 0) * static_cast<size_t>(m.A) * e.na, tc = (opt.grad ? t : 0) * static_cast<size_t>(e.nc);
  auto control = [&](auto cb) {
    control_forward(m, t, sx(k), sv(k), st(k), o, cb);
    if (opt.record_hidden && m.C > 0 && t % opt.hidden_every == 0) {
      const auto* h2 = cb.conn_acts + static_cast<size_t>(m.conn_layout.activation_offset(2)) * e.cols;
      res.hidden.insert(res.hidden.end(), h2, h2 + static_cast<size_t>(32) * e.cols);
    }
    if (opt.record_inputs && m.C > 0 && t % opt.hidden_every == 0) {
      const auto* in = cb.conn_acts + static_cast<size_t>(m.conn_layout.activation_offset(0)) * e.cols;
      res.inputs.insert(res.inputs.end(), in, in + static_cast<size_t>(kConnectorInputs) * e.cols);
    }
  };
  if (e.fl) control(ControlBuffers<float>{agent_acts_f.data() + ta, conn_acts_f.data() + tc});
  else control(ControlBuffers<double>{agent_acts.data() + ta, conn_acts.data() + tc});
  // physics substeps
  for (int s = 0; s < n; ++s, ++k) {
    double* vp = opt.grad ? vps.data() + (static_cast<size_t>(k) * N2) : vps.data();
    springs_forward(m, sx(k), sv(k), o, F.data());
    velocity_forward(m, t, sx(k), sv(k), F.data(), vp);
    contact_forward(m, sx(k), vp, sx(k + 1), sv(k + 1), st(k + 1),
                    opt.grad ? recs.data() + (static_cast<size_t>(k) * N) : nullptr);
    if (opt.record_tether) tether_accumulate(m, sx(k), sv(k), sx(k + 1), res.tether.data());
    if (opt.grad) count_contacts(recs.data() + (static_cast<size_t>(k) * N), N, res.contacts);
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
  return res.status == Status::ok;
}

// an episode that ended early: travel NaN, no contact counts, zero gradients of the asked-for shapes
RunResult Simulator::Impl::failed(Episode& e) {
  RunResult& res = e.res;
  res.travel = std::numeric_limits<double>::quiet_NaN();
  res.contacts = {};  // as before: counted for finished episodes only
  if (e.opt.grad) {
    if (e.opt.agent_param_grad) res.grad_agent_params.assign(static_cast<size_t>(e.m.A) * e.m.agent_params, 0.0);
    res.grad_connector_params.assign(e.m.C > 0 ? e.m.conn_params : 0, 0.0);
    res.grad_x0.assign(e.N2, 0.0);
    res.grad_rest_length.assign(e.S, 0.0);
  }
  return std::move(res);
}

// travel = mean x at T − mean x at 0
double Simulator::Impl::travel(Episode& e) {
  const double* xT = state_x(xs, e.opt, e.N2, e.k);
  double sT = 0, s0 = 0;
  for (int i = 0; i < e.N; ++i) {
    sT += xT[2 * i];
    s0 += e.sc.x0[2 * i];
  }
  return sT / e.N - s0 / e.N;
}

// the adjoint's seed ∂travel/∂x_T = (1/N, 0) and zeroed sums
void Simulator::Impl::begin_adjoint(Episode& e) {
  const RunOptions& opt = e.opt;
  Model& m = e.m;
  const int N = e.N, S = e.S;
  g_agent.assign(opt.agent_param_grad ? static_cast<size_t>(m.A) * m.agent_params : 0, 0.0);
  g_conn.assign(m.C > 0 ? m.conn_params : 0, 0.0);
  e.res.grad_rest_length.assign(S, 0.0);
  e.Lbar = e.res.grad_rest_length.data();
  e.ga = opt.agent_param_grad ? g_agent.data() : nullptr;
  e.gc = m.C > 0 ? g_conn.data() : nullptr;
  e.xbar = xb.data();
  e.vbar = vb.data();
  e.xbar_prev = xb2.data();
  e.vbar_prev = vb2.data();
  for (int i = 0; i < N; ++i) {
    e.xbar[2 * i] = 1.0 / N;
    e.xbar[2 * i + 1] = 0;
  }
  std::fill(e.vbar, e.vbar + e.N2, 0.0);
  std::fill(ob.begin(), ob.begin() + S, 0.0);
  // float_networks: the parameter gradients are summed in float over at most kFloatGradSteps steps, then added
  // into the double sums (float's rounding of a sum of 16 terms, not of 1000; zeroing and adding every step
  // cost as much as an agent's network)
  if (e.fl) {
    g_agent_f.assign(opt.agent_param_grad ? static_cast<size_t>(m.A) * m.agent_params : 0, 0.0f);
    g_conn_f.assign(m.C > 0 ? m.conn_params : 0, 0.0f);
  }
}

void Simulator::Impl::flush_float_grads(Episode& e) {
  auto add = [](LineVector<float>& f, double* into) {
    for (size_t q = 0; q < f.size(); ++q) into[q] += f[q], f[q] = 0.0f;
  };
  if (!g_agent_f.empty()) add(g_agent_f, e.ga);
  if (!g_conn_f.empty()) add(g_conn_f, e.gc);
}

// the adjoint of control step t: the substeps' contact, velocity and spring adjoints in reverse, then the
// networks'; at a window boundary of truncated backpropagation the seed restarts
void Simulator::Impl::adjoint_step(Episode& e, int t) {
  const RunOptions& opt = e.opt;
  Model& m = e.m;
  const int n = e.n, N = e.N, S = e.S;
  const size_t N2 = e.N2;
  const int na = e.na, nc = e.nc;
  int& k = e.k;
  auto sx = [&](int kk) { return state_x(xs, opt, N2, kk); };
  auto sv = [&](int kk) { return state_x(vs, opt, N2, kk); };
  if (t > 0) {
    const size_t k0 = static_cast<size_t>(t - 1) * n;
    if (e.fl) {
      prefetch(agent_acts_f.data() + (static_cast<size_t>(t - 1) * m.A * na), sizeof(float) * m.A * na);
      prefetch(conn_acts_f.data() + (static_cast<size_t>(t - 1) * nc), sizeof(float) * nc);
    } else {
      prefetch(agent_acts.data() + (static_cast<size_t>(t - 1) * m.A * na), sizeof(double) * m.A * na);
      prefetch(conn_acts.data() + (static_cast<size_t>(t - 1) * nc), sizeof(double) * nc);
    }
    prefetch(recs.data() + (k0 * N), sizeof(ContactRecord) * n * N);
    prefetch(xs.data() + (k0 * N2), sizeof(double) * n * N2);
    prefetch(vs.data() + (k0 * N2), sizeof(double) * n * N2);
    prefetch(vps.data() + (k0 * N2), sizeof(double) * n * N2);
    prefetch(os.data() + (static_cast<size_t>(t) * S), sizeof(double) * S);
  }
  const double* o = os.data() + ((t + 1) * static_cast<size_t>(S));
  for (int s = n - 1; s >= 0; --s) {
    --k;
    const double* vp = vps.data() + (static_cast<size_t>(k) * N2);
    // contact: x̄_{k+1}, v̄_{k+1} → v̄', x̄_k (partial)
    std::fill(e.xbar_prev, e.xbar_prev + N2, 0.0);
    std::fill(e.vbar_prev, e.vbar_prev + N2, 0.0);
    contact_adjoint(m, vp, sv(k + 1), recs.data() + (static_cast<size_t>(k) * N), e.xbar, e.vbar, vpb.data(), e.xbar_prev);
    velocity_adjoint(m, vpb.data(), e.vbar_prev, Fb.data());
    springs_adjoint(m, sx(k), sv(k), o, Fb.data(), e.xbar_prev, e.vbar_prev, ob.data(), e.Lbar);
    std::swap(e.xbar, e.xbar_prev);
    std::swap(e.vbar, e.vbar_prev);
  }
  const size_t ta = static_cast<size_t>(t) * m.A * na, tc = static_cast<size_t>(t) * nc;
  if (e.fl) {
    control_adjoint(m, t, sx(k), sv(k), ControlBuffers<float>{agent_acts_f.data() + ta, conn_acts_f.data() + tc},
                    ob.data(), e.xbar, e.vbar, e.Lbar, opt.agent_param_grad ? g_agent_f.data() : nullptr,
                    m.C > 0 ? g_conn_f.data() : nullptr, scratch_f.data());
    if (t % kFloatGradSteps == 0) flush_float_grads(e);
  } else {
    control_adjoint(m, t, sx(k), sv(k), ControlBuffers<double>{agent_acts.data() + ta, conn_acts.data() + tc},
                    ob.data(), e.xbar, e.vbar, e.Lbar, e.ga, e.gc, scratch.data());
  }
  // truncated backpropagation: state t starts a window and ends the previous one, whose seed restarts here
  if (opt.grad_window > 0 && t > 0 && t % opt.grad_window == 0) {
    for (int i = 0; i < N; ++i) e.xbar[2 * i] = 1.0 / N, e.xbar[2 * i + 1] = 0;
    std::fill(e.vbar, e.vbar + N2, 0.0);
    std::fill(ob.begin(), ob.begin() + S, 0.0);
  }
}

// the gradients out: the parameter sums, and x0's (the initial state and travel's baseline)
RunResult Simulator::Impl::end_adjoint(Episode& e) {
  if (e.fl) flush_float_grads(e);
  RunResult& res = e.res;
  if (e.opt.agent_param_grad) res.grad_agent_params.assign(g_agent.begin(), g_agent.end());
  res.grad_connector_params.assign(g_conn.begin(), g_conn.end());
  res.grad_x0.assign(e.xbar, e.xbar + e.N2);
  for (int i = 0; i < e.N; ++i) res.grad_x0[2 * i] -= 1.0 / e.N;
  return std::move(res);
}

}  // namespace divcoll::sim
