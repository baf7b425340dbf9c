// scene files (SPEC §9): sim::Scene ↔ HDF5, with every dataset's presence and shape checked on read.
#include "io/scene_file.hpp"

#include <filesystem>
#include <limits>

#include "common/check.hpp"
#include "config/environments.hpp"
#include "io/h5.hpp"

namespace divcoll::io {

namespace {

using h5::Dims;

// the first terrain x_start as written (it stands for -inf)
constexpr double kMinusInfinity = -1e9;

// the double-valued scene constants and environment attributes, by name
struct DoubleKey {
  const char* name;
  double sim::Constants::*field;
};
const DoubleKey kConstants[] = {
    {"dt", &sim::Constants::dt},
    {"omega", &sim::Constants::omega},
    {"agent_alpha", &sim::Constants::agent_alpha},
    {"agent_kappa", &sim::Constants::agent_kappa},
    {"conn_alpha", &sim::Constants::conn_alpha},
    {"conn_kappa_x", &sim::Constants::conn_kappa_x},
    {"conn_kappa_v", &sim::Constants::conn_kappa_v},
    {"eps_len", &sim::Constants::eps_len},
};

// an integer attribute that must fit an int
int read_int32(const h5::Node& n, const std::string& attr) {
  const int64_t v = n.read_int(attr);
  DIVCOLL_THROW_UNLESS(v >= std::numeric_limits<int>::min() && v <= std::numeric_limits<int>::max(),
                       n.where() << ": attribute '" << attr << "' = " << v << " is out of range");
  return static_cast<int>(v);
}

// the first dim of a rank-2 dataset whose second dim is fixed, e.g. A of agents/mass_index (A × 11)
size_t rows_of(const h5::Node& root, const std::string& path, hsize_t cols, const char* rows_name) {
  const Dims d = root.dims(path);
  DIVCOLL_THROW_UNLESS(d.size() == 2 && d[1] == cols, root.where(path) << " has shape " << h5::dims_string(d)
                                                                       << ", expected (" << rows_name << ", "
                                                                       << cols << ")");
  return static_cast<size_t>(d[0]);
}

// the length of a rank-1 dataset
size_t length_of(const h5::Node& root, const std::string& path, const char* len_name) {
  const Dims d = root.dims(path);
  DIVCOLL_THROW_UNLESS(d.size() == 1, root.where(path) << " has shape " << h5::dims_string(d)
                                                       << ", expected (" << len_name << ",)");
  return static_cast<size_t>(d[0]);
}

}  // namespace

sim::Scene read_scene(const std::string& path) {
  h5::File f = h5::File::open(path);
  sim::Scene s;

  // identity
  DIVCOLL_THROW_UNLESS(
      f.has_attribute("format"),
      path << ": attribute 'format' is missing; this is not a divcoll scene file (expected format = \""
           << kSceneFormat << "\")");
  const std::string format = f.read_string("format");
  DIVCOLL_THROW_UNLESS(format == kSceneFormat, path << ": attribute 'format' is \"" << format
                                                    << "\", expected \"" << kSceneFormat << "\"");
  const int64_t version = f.read_int("version");
  DIVCOLL_THROW_UNLESS(version == kSceneVersion, path << ": scene file version " << version
                                                      << " is not supported (this program reads version "
                                                      << kSceneVersion << ")");

  // constants
  for (const DoubleKey& k : kConstants) s.constants.*(k.field) = f.read_double(k.name);
  s.constants.n_sines = read_int32(f, "n_sines");
  s.constants.substeps = f.has_attribute("substeps") ? read_int32(f, "substeps") : 0;

  // masses and springs
  const size_t N = length_of(f, "masses/m", "N");
  s.mass = f.read<double>("masses/m", Dims{h5::extent(N)});
  s.x0 = f.read<double>("masses/x0", Dims{h5::extent(N), 2});
  const size_t S = length_of(f, "springs/i", "S");
  s.spring_i = f.read<int32_t>("springs/i", Dims{h5::extent(S)});
  s.spring_j = f.read<int32_t>("springs/j", Dims{h5::extent(S)});
  s.rest_length = f.read<double>("springs/rest_length", Dims{h5::extent(S)});
  s.stiffness = f.read<double>("springs/stiffness", Dims{h5::extent(S)});
  s.amplitude = f.read<double>("springs/amplitude", Dims{h5::extent(S)});
  s.damping = f.read<double>("springs/damping", Dims{h5::extent(S)});

  // agents and connectors
  const size_t A = rows_of(f, "agents/mass_index", sim::kAgentMasses, "A");
  s.agent_mass_index = f.read<int32_t>("agents/mass_index", Dims{h5::extent(A), sim::kAgentMasses});
  s.agent_spring_index = f.read<int32_t>("agents/spring_index", Dims{h5::extent(A), sim::kAgentSprings});
  const hsize_t Pa = static_cast<hsize_t>(sim::agent_param_count(s.constants));
  s.agent_params = f.read<double>("agents/params", Dims{h5::extent(A), Pa});
  const size_t C = rows_of(f, "connectors/spring_index", sim::kConnectorSprings, "C");
  s.connector_spring_index = f.read<int32_t>("connectors/spring_index", Dims{h5::extent(C), sim::kConnectorSprings});
  if (C > 0) {
    // the connector network is what the count of its weights says (sim::connector_param_count): per spring, or joint
    const bool joint = f.has("connector_params") &&
                       f.dims("connector_params") == Dims{h5::extent(sim::connector_param_count(true))};
    s.connector_params = f.read<double>("connector_params", Dims{h5::extent(sim::connector_param_count(joint))});
  } else {
    DIVCOLL_THROW_UNLESS(
        !f.has("connector_params"),
        path << ": connector_params is present but connectors/spring_index has 0 rows; it must be "
                "absent when the scene has no connectors");
  }

  // environment
  const h5::Node env = f.group("env");
  s.env.name = env.read_string("name");
  if (!config::is_known_environment(s.env.name)) {
    std::string known;
    for (const std::string& n : config::environment_names()) known += (known.empty() ? "" : ", ") + n;
    throw InputError(msg() << path << ": attribute 'name' of env is \"" << s.env.name
                           << "\", not a known environment (known: " << known << ")");
  }
  // every scalar field of sim::kEnvironmentFields; an optional one a file leaves out keeps its default
  for (const sim::EnvironmentField& k : sim::kEnvironmentFields)
    if (!k.optional || env.has_attribute(k.name)) s.env.*(k.field) = env.read_double(k.name);
  // the contact law (run.contact) and no_slip's retention: optional, absent in files written before them,
  // which are coulomb scenes
  if (env.has_attribute("contact")) {
    const std::string law = env.read_string("contact");
    DIVCOLL_THROW_UNLESS(sim::contact_law_from_name(law, &s.env.contact),
                         path << ": attribute 'contact' of env is \"" << law << "\", not a contact law (coulomb, no_slip)");
  }
  const size_t K = rows_of(f, "env/terrain", 3, "K");
  const std::vector<double> terrain = f.read<double>("env/terrain", Dims{h5::extent(K), 3});
  s.env.terrain.resize(K);
  for (size_t k = 0; k < K; ++k) s.env.terrain[k] = {terrain[3 * k], terrain[3 * k + 1], terrain[3 * k + 2]};

  try {
    sim::validate(s);
  } catch (const InputError& e) {
    throw InputError(path + ": " + e.what());
  }
  return s;
}

namespace {

void write_scene_to(h5::File& f, const sim::Scene& s) {
  // identity and constants
  f.write_string("format", kSceneFormat);
  f.write_int("version", kSceneVersion);
  for (const DoubleKey& k : kConstants) f.write_double(k.name, s.constants.*(k.field));
  f.write_int("n_sines", s.constants.n_sines);
  f.write_int("substeps", s.constants.substeps);

  // masses and springs
  const size_t N = s.mass.size(), S = s.spring_i.size();
  f.write("masses/x0", s.x0, Dims{h5::extent(N), 2});
  f.write("masses/m", s.mass, Dims{h5::extent(N)});
  f.write("springs/i", s.spring_i, Dims{h5::extent(S)});
  f.write("springs/j", s.spring_j, Dims{h5::extent(S)});
  f.write("springs/rest_length", s.rest_length, Dims{h5::extent(S)});
  f.write("springs/stiffness", s.stiffness, Dims{h5::extent(S)});
  f.write("springs/amplitude", s.amplitude, Dims{h5::extent(S)});
  f.write("springs/damping", s.damping, Dims{h5::extent(S)});

  // agents and connectors
  const size_t A = static_cast<size_t>(s.n_agents()), C = static_cast<size_t>(s.n_connectors());
  f.write("agents/mass_index", s.agent_mass_index, Dims{h5::extent(A), sim::kAgentMasses});
  f.write("agents/spring_index", s.agent_spring_index, Dims{h5::extent(A), sim::kAgentSprings});
  f.write("agents/params", s.agent_params,
          Dims{h5::extent(A), static_cast<hsize_t>(sim::agent_param_count(s.constants))});
  f.write("connectors/spring_index", s.connector_spring_index, Dims{h5::extent(C), sim::kConnectorSprings});
  if (C > 0) f.write("connector_params", s.connector_params, Dims{h5::extent(s.connector_params.size())});

  // environment
  const h5::Node env = f.create_group("env");
  env.write_string("name", s.env.name);
  for (const sim::EnvironmentField& k : sim::kEnvironmentFields) env.write_double(k.name, s.env.*(k.field));
  env.write_string("contact", sim::contact_law_name(s.env.contact));
  const size_t K = s.env.terrain.size();
  std::vector<double> terrain(3 * K);
  for (size_t k = 0; k < K; ++k) {
    terrain[3 * k] = k == 0 ? kMinusInfinity : s.env.terrain[k].x_start;
    terrain[3 * k + 1] = s.env.terrain[k].y_start;
    terrain[3 * k + 2] = s.env.terrain[k].slope;
  }
  env.write("terrain", terrain, Dims{h5::extent(K), 3});
}

}  // namespace

void write_scene(const std::string& path, const sim::Scene& s, bool overwrite) {
  sim::validate(s);
  DIVCOLL_THROW_UNLESS(config::is_known_environment(s.env.name),
                       "cannot write " << path << ": the scene's environment \"" << s.env.name
                                       << "\" is not a known environment");
  h5::File f = h5::File::create(path, overwrite);
  try {
    write_scene_to(f, s);
    f.close();
  } catch (...) {
    // leave no half-written file behind
    f.close_quietly();
    std::error_code ec;
    std::filesystem::remove(path, ec);
    throw;
  }
}

}  // namespace divcoll::io
