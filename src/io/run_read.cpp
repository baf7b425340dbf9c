#include "io/run_read.hpp"

#include <sstream>

#include "common/check.hpp"
#include "io/run_file.hpp"
#include "sim/scene.hpp"

namespace divcoll::io {

using h5::Dims;
namespace {
constexpr int M11 = sim::kAgentMasses, S21 = sim::kAgentSprings;
}

std::string join(const std::vector<std::string>& v) {
  std::string s;
  for (const auto& x : v) s += (s.empty() ? "" : ",") + x;
  return s;
}

std::vector<std::string> split(const std::string& s) {
  std::vector<std::string> out;
  std::stringstream ss(s);
  for (std::string x; std::getline(ss, x, ',');) out.push_back(x);
  return out;
}

std::vector<evo::Individual> read_pool(const h5::Node& file, const std::string& g, std::vector<uint8_t>* survived) {
  Dims d;
  const auto id = file.read<int64_t>(g + "/id", &d);
  const size_t M = d[0];
  const auto parent = file.read<int64_t>(g + "/parent");
  const auto cells = file.read<int64_t>(g + "/cells");
  const auto springs = file.read<int64_t>(g + "/springs");
  const auto rest_pos = file.read<double>(g + "/rest_pos");
  const auto si = file.read<int32_t>(g + "/spring_i");
  const auto sj = file.read<int32_t>(g + "/spring_j");
  const auto rl = file.read<double>(g + "/rest_length");
  const auto amp = file.read<double>(g + "/amplitude");
  Dims pd;
  const auto params = file.read<double>(g + "/params", &pd);
  const auto fit = file.read<double>(g + "/fitness");
  const auto trav = file.read<double>(g + "/travel_u");
  const auto status = file.read<uint8_t>(g + "/status");
  const auto desc = file.read<double>(g + "/descriptor");
  Dims cd;
  const auto curve = file.read<double>(g + "/curve_u", &cd);
  if (survived) *survived = file.read<uint8_t>(g + "/survived");
  std::vector<evo::Individual> out(M);
  const size_t P = pd[1], C = cd[1];
  for (size_t i = 0; i < M; ++i) {
    evo::Individual& x = out[i];
    x.id = id[i];
    x.parent = parent[i];
    x.agent.cells = static_cast<uint32_t>(cells[i]);
    x.agent.springs = static_cast<uint32_t>(springs[i]);
    x.agent.rest_pos.assign(rest_pos.begin() + i * 2 * M11, rest_pos.begin() + (i + 1) * 2 * M11);
    x.agent.spring_i.assign(si.begin() + i * S21, si.begin() + (i + 1) * S21);
    x.agent.spring_j.assign(sj.begin() + i * S21, sj.begin() + (i + 1) * S21);
    x.agent.rest_length.assign(rl.begin() + i * S21, rl.begin() + (i + 1) * S21);
    x.agent.amplitude.assign(amp.begin() + i * S21, amp.begin() + (i + 1) * S21);
    x.agent.params.assign(params.begin() + i * P, params.begin() + (i + 1) * P);
    x.train.fitness_bl = fit[i];
    x.train.travel_u = trav[i];
    x.train.status = static_cast<sim::Status>(status[i]);
    x.train.curve_u.assign(curve.begin() + i * C, curve.begin() + (i + 1) * C);
    for (int q = 0; q < morph::kDescriptorSize; ++q) x.descriptor[q] = desc[i * morph::kDescriptorSize + q];
  }
  return out;
}

std::vector<evo::Individual> read_final_population(const h5::Node& file, const std::string& group) {
  DIVCOLL_THROW_UNLESS(file.has(group + "/final"),
                       file.file() << " has no " << group << "/final: its agents stage has not finished");
  return read_pool(file, group + "/final", nullptr);
}

std::vector<std::vector<double>> split_weights(const std::vector<double>& flat, size_t rows) {
  const size_t Pc = static_cast<size_t>(sim::connector_param_count()), Pj = sim::connector_param_count(true);
  DIVCOLL_THROW_UNLESS(rows > 0 && (flat.size() == rows * Pc || flat.size() == rows * Pj),
                       "connector weights: " << flat.size() << " values are not " << rows << " rows of " << Pc
                                             << " (or " << Pj << ", the joint network)");
  const size_t n = flat.size() / rows;
  std::vector<std::vector<double>> out;
  for (size_t r = 0; r < rows; ++r) out.emplace_back(flat.begin() + r * n, flat.begin() + (r + 1) * n);
  return out;
}

std::vector<double> join_weights(const std::vector<std::vector<double>>& rows) {
  std::vector<double> flat;
  for (const auto& p : rows) flat.insert(flat.end(), p.begin(), p.end());
  return flat;
}

namespace {

// the rows of `<group>/params` (replicate × connector_weight) as the file lays them out; `replicates` >= 0:
// refused unless there are that many
h5::Dims weights_dims(const h5::Node& file, const std::string& group, int replicates) {
  const std::string p = group + "/params";
  DIVCOLL_THROW_UNLESS(file.has(p), file.file() << " has no " << p << ": run the stage that trains them first");
  const run_file::Layout l = run_file::layout(file, p, "replicate,connector_weight");
  if (replicates >= 0 && l.dims[0] != static_cast<hsize_t>(replicates))
    throw InputError(file.where(p) + " has the shape " + h5::dims_string(l.dims) + " (replicate, connector_weight), expected " +
                     h5::dims_string({static_cast<hsize_t>(replicates), l.dims[1]}) + ": " + std::to_string(replicates) +
                     " replicates, as the config says");
  return l.dims;
}

}  // namespace

std::vector<std::vector<double>> read_weights(const h5::Node& file, const std::string& group, int replicates) {
  const h5::Dims d = weights_dims(file, group, replicates);
  return split_weights(file.read<double>(group + "/params", d), d[0]);
}

std::vector<double> read_weights_row(const h5::Node& file, const std::string& group, int row) {
  const h5::Dims d = weights_dims(file, group, -1);
  DIVCOLL_THROW_UNLESS(row >= 0 && row < static_cast<int>(d[0]),
                       "--replicate = " << row << " is out of range [0, " << d[0] - 1 << "]");
  return split_weights(file.read<double>(group + "/params", d), d[0])[row];
}

std::string anchors_path(const std::string& population_group) {
  const std::string tail = "agents";
  DIVCOLL_THROW_UNLESS(population_group.size() >= tail.size() &&
                           population_group.compare(population_group.size() - tail.size(), tail.size(), tail) == 0,
                       "not a population group: " << population_group);
  return population_group.substr(0, population_group.size() - tail.size()) + "connectors/anchors";
}

std::vector<int32_t> anchors_rows(const std::vector<morph::Agent>& agents) {
  std::vector<int32_t> an;
  for (const auto& a : agents) {
    const auto& x = a.anchors;
    an.insert(an.end(), {x.back_foot, x.front_foot, x.back_upper, x.front_upper});
  }
  return an;
}

void check_layout(const h5::Node& file, const std::string& path, std::string_view axes, const h5::Dims& dims,
                  const std::string& why) {
  DIVCOLL_THROW_UNLESS(file.has(path), file.file() << " has no " << path);
  const run_file::Layout l = run_file::layout(file, path, axes);
  if (l.dims != dims)
    throw InputError(file.where(path) + " has the shape " + h5::dims_string(l.dims) + " (" + std::string(axes) +
                     "), expected " + h5::dims_string(dims) + ": " + why);
}

void read_anchors(const h5::Node& file, const std::string& path, std::vector<morph::Agent>& agents) {
  const std::vector<int32_t> an =
      read_checked<int32_t>(file, path, "agent,anchor", Dims{static_cast<hsize_t>(agents.size()), 4},
                            std::to_string(agents.size()) + " agents in the population, 4 anchors each");
  for (size_t i = 0; i < agents.size(); ++i)
    agents[i].anchors = {an[4 * i], an[4 * i + 1], an[4 * i + 2], an[4 * i + 3]};
}

}  // namespace divcoll::io
