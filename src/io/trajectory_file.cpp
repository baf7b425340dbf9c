// trajectory files (SPEC §9): Trajectory ↔ HDF5, with shapes checked both ways.
#include "io/trajectory_file.hpp"

#include <filesystem>
#include <limits>

#include "common/check.hpp"
#include "io/h5.hpp"

namespace divcoll::io {

namespace {

using h5::Dims;

// shape checks of an in-memory trajectory before writing
void check_shapes(const std::string& path, const Trajectory& t) {
  const std::string w = "cannot write " + path + ": ";
  DIVCOLL_THROW_UNLESS(t.steps >= 0 && t.n_masses >= 0,
                       w << "steps = " << t.steps << " and n_masses = " << t.n_masses << " must be >= 0");
  const size_t rows = static_cast<size_t>(t.steps) + 1, N = static_cast<size_t>(t.n_masses);
  DIVCOLL_THROW_UNLESS(t.x.size() == rows * N * 2,
                       w << "x has " << t.x.size() << " values, expected (T+1) x N x 2 = " << rows * N * 2);
  DIVCOLL_THROW_UNLESS(t.v.size() == rows * N * 2,
                       w << "v has " << t.v.size() << " values, expected (T+1) x N x 2 = " << rows * N * 2);
  DIVCOLL_THROW_UNLESS(t.touch.size() == rows * N,
                       w << "touch has " << t.touch.size() << " values, expected (T+1) x N = " << rows * N);
  DIVCOLL_THROW_UNLESS(is_trajectory_status(t.status),
                       w << "status \"" << t.status << "\" is not one of ok, nan, unstable");
  if (!t.has_grad) return;
  DIVCOLL_THROW_UNLESS(t.n_agents >= 0, w << "n_agents = " << t.n_agents << " must be >= 0");
  DIVCOLL_THROW_UNLESS(
      t.n_agents > 0 ? t.grad_agent_params.size() % t.n_agents == 0 : t.grad_agent_params.empty(),
      w << "grad_agent_params has " << t.grad_agent_params.size()
        << " values, not a multiple of n_agents = " << t.n_agents);
  DIVCOLL_THROW_UNLESS(t.grad_x0.size() == N * 2,
                       w << "grad_x0 has " << t.grad_x0.size() << " values, expected N x 2 = " << N * 2);
}

// the length of a rank-1 dataset
size_t length_of(const h5::Node& f, const std::string& path) {
  const Dims d = f.dims(path);
  DIVCOLL_THROW_UNLESS(d.size() == 1, f.where(path)
                                          << " has shape " << h5::dims_string(d) << ", expected rank 1");
  return static_cast<size_t>(d[0]);
}

}  // namespace

bool is_trajectory_status(const std::string& s) { return s == "ok" || s == "nan" || s == "unstable"; }

void write_trajectory(const std::string& path, const Trajectory& t, bool overwrite) {
  check_shapes(path, t);
  h5::File f = h5::File::create(path, overwrite);
  try {
    const hsize_t rows = h5::extent(static_cast<size_t>(t.steps) + 1), N = h5::extent(static_cast<size_t>(t.n_masses));
    f.write("x", t.x, Dims{rows, N, 2});
    f.write("v", t.v, Dims{rows, N, 2});
    f.write("touch", t.touch, Dims{rows, N});
    f.write_double("travel", t.travel);
    f.write_int("steps", t.steps);
    f.write_string("status", t.status);
    if (t.has_grad) {
      const size_t A = static_cast<size_t>(t.n_agents);
      const size_t Pa = A > 0 ? t.grad_agent_params.size() / A : 0;
      f.write("grad/agent_params", t.grad_agent_params, Dims{h5::extent(A), h5::extent(Pa)});
      if (!t.grad_connector_params.empty())
        f.write("grad/connector_params", t.grad_connector_params, Dims{h5::extent(t.grad_connector_params.size())});
      f.write("grad/x0", t.grad_x0, Dims{N, 2});
      f.write("grad/rest_length", t.grad_rest_length, Dims{h5::extent(t.grad_rest_length.size())});
    }
    f.close();
  } catch (...) {
    // leave no half-written file behind
    f.close_quietly();
    std::error_code ec;
    std::filesystem::remove(path, ec);
    throw;
  }
}

Trajectory read_trajectory(const std::string& path) {
  h5::File f = h5::File::open(path);
  Trajectory t;

  // positions fix T and N
  const Dims dx = f.dims("x");
  DIVCOLL_THROW_UNLESS(dx.size() == 3 && dx[0] >= 1 && dx[2] == 2,
                       f.where("x") << " has shape " << h5::dims_string(dx) << ", expected (T+1, N, 2)");
  DIVCOLL_THROW_UNLESS(dx[0] - 1 <= static_cast<hsize_t>(std::numeric_limits<int>::max()) &&
                           dx[1] <= static_cast<hsize_t>(std::numeric_limits<int>::max()),
                       f.where("x") << " has shape " << h5::dims_string(dx) << ", too large");
  t.steps = static_cast<int>(dx[0] - 1);
  t.n_masses = static_cast<int>(dx[1]);
  if (f.has_attribute("steps")) {
    const int64_t steps = f.read_int("steps");
    DIVCOLL_THROW_UNLESS(steps == t.steps, path << ": attribute 'steps' = " << steps
                                                << " disagrees with x, which has " << dx[0]
                                                << " rows (steps + 1)");
  }
  t.x = f.read<double>("x", dx);
  t.v = f.read<double>("v", dx);
  if (f.has("touch")) t.touch = f.read<uint8_t>("touch", Dims{dx[0], dx[1]});
  t.travel = f.read_double("travel");
  if (f.has_attribute("status")) {
    t.status = f.read_string("status");
    DIVCOLL_THROW_UNLESS(is_trajectory_status(t.status), path << ": attribute 'status' is \"" << t.status
                                                              << "\", not one of ok, nan, unstable");
  }

  // gradients
  t.has_grad = f.has("grad");
  if (t.has_grad) {
    const Dims da = f.dims("grad/agent_params");
    DIVCOLL_THROW_UNLESS(da.size() == 2, f.where("grad/agent_params") << " has shape " << h5::dims_string(da)
                                                                      << ", expected (A, P_a)");
    t.n_agents = static_cast<int>(da[0]);
    t.grad_agent_params = f.read<double>("grad/agent_params", da);
    if (f.has("grad/connector_params")) {
      const size_t pc = length_of(f, "grad/connector_params");
      t.grad_connector_params = f.read<double>("grad/connector_params", Dims{h5::extent(pc)});
    }
    t.grad_x0 = f.read<double>("grad/x0", Dims{dx[1], 2});
    const size_t S = length_of(f, "grad/rest_length");
    t.grad_rest_length = f.read<double>("grad/rest_length", Dims{h5::extent(S)});
  }
  return t;
}

}  // namespace divcoll::io
