// scene and trajectory files (SPEC §9): the parity files load, round trips are bit-exact, the written
// layout is the spec's, and damaged or wrong files are refused with a message naming the problem
#include "io/scene_file.hpp"

#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <hdf5.h>

#include <cmath>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>
#include <string>
#include <vector>

#include "common/check.hpp"
#include "io/h5.hpp"
#include "io/trajectory_file.hpp"
#include "testing.hpp"

namespace divcoll::io {
namespace {

namespace fs = std::filesystem;
using ::testing::HasSubstr;

struct ParityCase {
  const char* name;  // file stem after "scene" / "expected"
  int N, S, A, C, K;
  const char* env;
};
const ParityCase kParity[] = {
    {"0_flat", 11, 21, 1, 0, 1, "flat"},
    {"1_step_up", 22, 47, 2, 1, 2, "step_up"},
    {"2_gap", 33, 73, 3, 2, 3, "gap"},
    {"3_sticky", 22, 47, 2, 1, 1, "sticky"},
    {"4_treadmill", 22, 47, 2, 1, 1, "treadmill"},
};

std::string parity_scene(const ParityCase& c) { return testing::parity_dir() + "/scene" + c.name + ".h5"; }
std::string parity_expected(const ParityCase& c) {
  return testing::parity_dir() + "/expected" + c.name + ".h5";
}

// bitwise equality of two arrays (NaN and -0 included)
template <class T>
bool same_bits(const std::vector<T>& a, const std::vector<T>& b) {
  return a.size() == b.size() && (a.empty() || std::memcmp(a.data(), b.data(), a.size() * sizeof(T)) == 0);
}
bool same_bits(double a, double b) { return std::memcmp(&a, &b, sizeof a) == 0; }

void expect_same_scene(const sim::Scene& a, const sim::Scene& b) {
  const sim::Constants &ca = a.constants, &cb = b.constants;
  EXPECT_TRUE(same_bits(ca.dt, cb.dt) && same_bits(ca.omega, cb.omega) &&
              same_bits(ca.agent_alpha, cb.agent_alpha) && same_bits(ca.agent_kappa, cb.agent_kappa) &&
              same_bits(ca.conn_alpha, cb.conn_alpha) && same_bits(ca.conn_kappa_x, cb.conn_kappa_x) &&
              same_bits(ca.conn_kappa_v, cb.conn_kappa_v) && same_bits(ca.eps_len, cb.eps_len));
  EXPECT_EQ(ca.n_sines, cb.n_sines);
  EXPECT_EQ(ca.substeps, cb.substeps);
  const sim::Environment &ea = a.env, &eb = b.env;
  EXPECT_EQ(ea.name, eb.name);
  EXPECT_TRUE(same_bits(ea.gravity, eb.gravity) && same_bits(ea.damping, eb.damping) &&
              same_bits(ea.friction, eb.friction) && same_bits(ea.tangent_keep, eb.tangent_keep) &&
              same_bits(ea.belt_speed, eb.belt_speed) && same_bits(ea.wind_amp, eb.wind_amp) &&
              same_bits(ea.wind_period, eb.wind_period) && same_bits(ea.adhesion, eb.adhesion) &&
              same_bits(ea.adhesion_band, eb.adhesion_band) && same_bits(ea.no_slip_keep, eb.no_slip_keep));
  EXPECT_EQ(ea.contact, eb.contact);
  ASSERT_EQ(ea.terrain.size(), eb.terrain.size());
  for (size_t k = 0; k < ea.terrain.size(); ++k) {
    EXPECT_TRUE(same_bits(ea.terrain[k].x_start, eb.terrain[k].x_start)) << "segment " << k;
    EXPECT_TRUE(same_bits(ea.terrain[k].y_start, eb.terrain[k].y_start)) << "segment " << k;
    EXPECT_TRUE(same_bits(ea.terrain[k].slope, eb.terrain[k].slope)) << "segment " << k;
  }
  EXPECT_TRUE(same_bits(a.x0, b.x0));
  EXPECT_TRUE(same_bits(a.mass, b.mass));
  EXPECT_TRUE(same_bits(a.spring_i, b.spring_i));
  EXPECT_TRUE(same_bits(a.spring_j, b.spring_j));
  EXPECT_TRUE(same_bits(a.rest_length, b.rest_length));
  EXPECT_TRUE(same_bits(a.stiffness, b.stiffness));
  EXPECT_TRUE(same_bits(a.amplitude, b.amplitude));
  EXPECT_TRUE(same_bits(a.damping, b.damping));
  EXPECT_TRUE(same_bits(a.agent_mass_index, b.agent_mass_index));
  EXPECT_TRUE(same_bits(a.agent_spring_index, b.agent_spring_index));
  EXPECT_TRUE(same_bits(a.agent_params, b.agent_params));
  EXPECT_TRUE(same_bits(a.connector_spring_index, b.connector_spring_index));
  EXPECT_TRUE(same_bits(a.connector_params, b.connector_params));
}

// a fresh folder per test, removed afterwards
class FileTest : public ::testing::Test {
 protected:
  void SetUp() override {
    std::string templ = (fs::path(::testing::TempDir()) / "divcoll_io_XXXXXX").string();
    ASSERT_NE(mkdtemp(templ.data()), nullptr);
    dir_ = templ;
  }
  void TearDown() override {
    std::error_code ec;
    fs::remove_all(dir_, ec);
  }
  std::string file(const std::string& name) const { return (dir_ / name).string(); }
  fs::path dir_;
};

// the InputError message of read_scene, or "" if it reads the file
std::string read_refusal(const std::string& path) {
  try {
    read_scene(path);
  } catch (const InputError& e) {
    return e.what();
  }
  return "";
}

// raw HDF5 access to damage a written file
struct RawFile {
  hid_t id;
  explicit RawFile(const std::string& path) : id(H5Fopen(path.c_str(), H5F_ACC_RDWR, H5P_DEFAULT)) {}
  ~RawFile() { H5Fclose(id); }
  // replaces a float64 dataset by one of the given dims and values
  void replace(const char* name, const std::vector<hsize_t>& dims, const std::vector<double>& v) const {
    ASSERT_GE(H5Ldelete(id, name, H5P_DEFAULT), 0);
    hid_t space = H5Screate_simple(static_cast<int>(dims.size()), dims.data(), nullptr);
    hid_t d = H5Dcreate2(id, name, H5T_IEEE_F64LE, space, H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT);
    ASSERT_GE(d, 0);
    EXPECT_GE(H5Dwrite(d, H5T_NATIVE_DOUBLE, H5S_ALL, H5S_ALL, H5P_DEFAULT, v.data()), 0);
    H5Dclose(d);
    H5Sclose(space);
  }
  std::vector<double> read(const char* name) const {
    hid_t d = H5Dopen2(id, name, H5P_DEFAULT);
    hid_t space = H5Dget_space(d);
    std::vector<double> v(static_cast<size_t>(H5Sget_simple_extent_npoints(space)));
    H5Dread(d, H5T_NATIVE_DOUBLE, H5S_ALL, H5S_ALL, H5P_DEFAULT, v.data());
    H5Sclose(space);
    H5Dclose(d);
    return v;
  }
};

// ---- parity scenes ---------------------------------------------------------------------------------

TEST(SceneFile, ParityScenesLoad) {
  for (const ParityCase& c : kParity) {
    SCOPED_TRACE(c.name);
    const sim::Scene s = read_scene(parity_scene(c));
    EXPECT_EQ(s.n_masses(), c.N);
    EXPECT_EQ(s.n_springs(), c.S);
    EXPECT_EQ(s.n_agents(), c.A);
    EXPECT_EQ(s.n_connectors(), c.C);
    EXPECT_EQ(s.env.name, c.env);
    EXPECT_EQ(static_cast<int>(s.env.terrain.size()), c.K);
    EXPECT_EQ(s.env.terrain[0].x_start, -1e9);
    EXPECT_EQ(s.agent_params.size(), static_cast<size_t>(c.A) * 3509);
    EXPECT_EQ(s.connector_params.size(), c.C > 0 ? 1473u : 0u);
    EXPECT_EQ(s.constants.n_sines, 10);
    EXPECT_EQ(s.constants.dt, 0.004);
    EXPECT_EQ(s.constants.substeps, 0);  // absent in the parity files
  }
  // environment constants come through
  EXPECT_EQ(read_scene(parity_scene(kParity[3])).env.adhesion, 2.0);
  EXPECT_EQ(read_scene(parity_scene(kParity[4])).env.belt_speed, 0.05);
}

TEST_F(FileTest, SceneRoundTripIsBitExact) {
  for (const ParityCase& c : kParity) {
    SCOPED_TRACE(c.name);
    sim::Scene s = read_scene(parity_scene(c));
    s.constants.substeps = 3;
    const std::string out = file(std::string("scene") + c.name + ".h5");
    write_scene(out, s);
    expect_same_scene(s, read_scene(out));
  }
}

// the contact law and no_slip's retention are written and read back; files written before them (the parity
// scenes) read as coulomb with kappa_ns = 0
TEST_F(FileTest, SceneKeepsItsContactLaw) {
  sim::Scene s = read_scene(parity_scene(kParity[4]));
  EXPECT_EQ(s.env.contact, sim::ContactLaw::coulomb);
  EXPECT_EQ(s.env.no_slip_keep, 0.0);
  {
    const h5::File f = h5::File::open(parity_scene(kParity[4]));
    ASSERT_FALSE(f.group("env").has_attribute("contact")) << "the parity scenes predate the attribute";
  }
  s.env.contact = sim::ContactLaw::no_slip;
  s.env.no_slip_keep = 1.0 / 3.0;
  const std::string out = file("no_slip.h5");
  write_scene(out, s);
  const sim::Scene back = read_scene(out);
  expect_same_scene(s, back);
  EXPECT_EQ(back.env.contact, sim::ContactLaw::no_slip);
  EXPECT_EQ(h5::File::open(out).group("env").read_string("contact"), "no_slip");
}

TEST_F(FileTest, SceneWriteRefusesToOverwrite) {
  const sim::Scene s = read_scene(parity_scene(kParity[0]));
  const std::string out = file("s.h5");
  write_scene(out, s);
  try {
    write_scene(out, s);
    FAIL() << "overwrote an existing file";
  } catch (const InputError& e) {
    EXPECT_THAT(e.what(), HasSubstr("already exists"));
  }
  EXPECT_NO_THROW(write_scene(out, s, /*overwrite=*/true));
  EXPECT_NO_THROW(read_scene(out));
}

// every attribute and dataset of SPEC §9, with its type and dims, checked with the HDF5 API itself
TEST_F(FileTest, WrittenSceneHasTheSpecLayout) {
  for (int which : {0, 2}) {
    const ParityCase& c = kParity[which];
    SCOPED_TRACE(c.name);
    const std::string out = file(std::string("layout") + c.name + ".h5");
    write_scene(out, read_scene(parity_scene(c)));
    hid_t f = H5Fopen(out.c_str(), H5F_ACC_RDONLY, H5P_DEFAULT);
    ASSERT_GE(f, 0);

    auto attr_class = [](hid_t obj, const char* name) {
      if (H5Aexists(obj, name) <= 0) return H5T_NO_CLASS;
      hid_t a = H5Aopen(obj, name, H5P_DEFAULT);
      hid_t t = H5Aget_type(a);
      const H5T_class_t k = H5Tget_class(t);
      H5Tclose(t);
      H5Aclose(a);
      return k;
    };
    for (const char* a : {"dt", "omega", "agent_alpha", "agent_kappa", "conn_alpha", "conn_kappa_x",
                          "conn_kappa_v", "eps_len"})
      EXPECT_EQ(attr_class(f, a), H5T_FLOAT) << a;
    for (const char* a : {"version", "n_sines", "substeps"}) EXPECT_EQ(attr_class(f, a), H5T_INTEGER) << a;
    EXPECT_EQ(attr_class(f, "format"), H5T_STRING);
    hid_t env = H5Gopen2(f, "env", H5P_DEFAULT);
    ASSERT_GE(env, 0);
    EXPECT_EQ(attr_class(env, "name"), H5T_STRING);
    for (const char* a : {"gravity", "damping", "friction", "tangent_keep", "belt_speed", "wind_amp",
                          "wind_period", "adhesion", "adhesion_band"})
      EXPECT_EQ(attr_class(env, a), H5T_FLOAT) << a;
    H5Gclose(env);

    // datasets: dims and element type
    const hsize_t N = c.N, S = c.S, A = c.A, C = c.C, K = c.K;
    struct Expect {
      const char* name;
      std::vector<hsize_t> dims;
      hid_t type;
    };
    std::vector<Expect> expect = {
        {"masses/x0", {N, 2}, H5T_IEEE_F64LE},
        {"masses/m", {N}, H5T_IEEE_F64LE},
        {"springs/i", {S}, H5T_STD_I32LE},
        {"springs/j", {S}, H5T_STD_I32LE},
        {"springs/rest_length", {S}, H5T_IEEE_F64LE},
        {"springs/stiffness", {S}, H5T_IEEE_F64LE},
        {"springs/amplitude", {S}, H5T_IEEE_F64LE},
        {"springs/damping", {S}, H5T_IEEE_F64LE},
        {"agents/mass_index", {A, 11}, H5T_STD_I32LE},
        {"agents/spring_index", {A, 21}, H5T_STD_I32LE},
        {"agents/params", {A, 3509}, H5T_IEEE_F64LE},
        {"connectors/spring_index", {C, 5}, H5T_STD_I32LE},
        {"env/terrain", {K, 3}, H5T_IEEE_F64LE},
    };
    if (C > 0) expect.push_back({"connector_params", {1473}, H5T_IEEE_F64LE});
    for (const Expect& e : expect) {
      hid_t d = H5Dopen2(f, e.name, H5P_DEFAULT);
      ASSERT_GE(d, 0) << e.name;
      hid_t space = H5Dget_space(d), type = H5Dget_type(d);
      std::vector<hsize_t> dims(static_cast<size_t>(H5Sget_simple_extent_ndims(space)));
      H5Sget_simple_extent_dims(space, dims.data(), nullptr);
      EXPECT_EQ(dims, e.dims) << e.name;
      EXPECT_GT(H5Tequal(type, e.type), 0) << e.name;
      H5Tclose(type);
      H5Sclose(space);
      H5Dclose(d);
    }
    EXPECT_EQ(H5Lexists(f, "connector_params", H5P_DEFAULT) > 0, C > 0);
    H5Fclose(f);
    EXPECT_EQ(read_scene(out).env.terrain[0].x_start, -1e9);
  }
}

// the first terrain x_start is written as -1e9 whatever the scene holds
TEST_F(FileTest, FirstTerrainStartIsWrittenAsMinusOneBillion) {
  sim::Scene s = read_scene(parity_scene(kParity[1]));
  s.env.terrain[0].x_start = 0.0;
  const std::string out = file("s.h5");
  write_scene(out, s);
  EXPECT_EQ(read_scene(out).env.terrain[0].x_start, -1e9);
  EXPECT_EQ(read_scene(out).env.terrain[1].x_start, s.env.terrain[1].x_start);
}

// ---- bad scene files -------------------------------------------------------------------------------

class BadSceneFile : public FileTest {
 protected:
  // a good copy of a parity scene (scene2_gap has 3 terrain segments and connectors)
  std::string good(int which = 2) {
    const std::string out = file("good.h5");
    write_scene(out, read_scene(parity_scene(kParity[which])), /*overwrite=*/true);
    return out;
  }
};

TEST_F(BadSceneFile, MissingDataset) {
  const std::string p = good();
  {
    RawFile f(p);
    ASSERT_GE(H5Ldelete(f.id, "springs/stiffness", H5P_DEFAULT), 0);
  }
  EXPECT_THAT(read_refusal(p), HasSubstr("missing dataset springs/stiffness"));
  const std::string q = good();
  {
    RawFile f(q);
    ASSERT_GE(H5Ldelete(f.id, "connector_params", H5P_DEFAULT), 0);
  }
  EXPECT_THAT(read_refusal(q), HasSubstr("missing dataset connector_params"));
}

TEST_F(BadSceneFile, WrongShape) {
  const std::string p = good();
  {
    RawFile f(p);
    f.replace("masses/x0", {33, 3}, std::vector<double>(99, 0.0));
  }
  EXPECT_THAT(read_refusal(p), HasSubstr("masses/x0 has shape (33, 3), expected (33, 2)"));
  const std::string q = good();
  {
    RawFile f(q);
    f.replace("agents/params", {3, 3508}, std::vector<double>(3 * 3508, 0.0));
  }
  EXPECT_THAT(read_refusal(q), HasSubstr("agents/params has shape (3, 3508), expected (3, 3509)"));
}

TEST_F(BadSceneFile, NaNInPositionsAndParams) {
  const std::string p = good();
  {
    RawFile f(p);
    std::vector<double> x0 = f.read("masses/x0");
    x0[5] = std::numeric_limits<double>::quiet_NaN();
    f.replace("masses/x0", {33, 2}, x0);
  }
  EXPECT_THAT(read_refusal(p), HasSubstr("masses/x0[5] is NaN"));
  const std::string q = good();
  {
    RawFile f(q);
    std::vector<double> w = f.read("agents/params");
    w[4000] = std::numeric_limits<double>::infinity();
    f.replace("agents/params", {3, 3509}, w);
  }
  EXPECT_THAT(read_refusal(q), HasSubstr("agents/params[4000] is infinite"));
}

TEST_F(BadSceneFile, UnsortedAndNarrowTerrain) {
  const std::string p = good();
  {
    RawFile f(p);
    f.replace("env/terrain", {3, 3}, {-1e9, 0, 0, 0.5, -0.3, 0, 0.4, 0, 0});
  }
  const std::string unsorted = read_refusal(p);
  EXPECT_THAT(unsorted, HasSubstr("env/terrain: segment 2 starts at 0.4 u, before segment 1"));
  EXPECT_THAT(unsorted, HasSubstr("sorted"));
  const std::string q = good();
  {
    RawFile f(q);
    f.replace("env/terrain", {3, 3}, {-1e9, 0, 0, 0.5, -0.3, 0, 0.504, 0, 0});
  }
  EXPECT_THAT(read_refusal(q),
              HasSubstr("segment 2 starts at 0.504 u, only 0.004 u after segment 1 (the minimum "
                        "width is 0.01 u)"));
}

TEST_F(BadSceneFile, UnknownEnvironment) {
  const std::string p = good();
  {
    RawFile f(p);
    hid_t env = H5Gopen2(f.id, "env", H5P_DEFAULT);
    ASSERT_GE(H5Adelete(env, "name"), 0);
    H5Gclose(env);
  }
  EXPECT_THAT(read_refusal(p), HasSubstr("attribute 'name' of env is missing"));
  // write the name back as "moon" through the wrapper
  h5::File::open(p, /*writable=*/true).group("env").write_string("name", "moon");
  const std::string m = read_refusal(p);
  EXPECT_THAT(m, HasSubstr("\"moon\", not a known environment"));
  EXPECT_THAT(m, HasSubstr("known: flat, "));
  EXPECT_THAT(m, HasSubstr("treadmill"));
}

TEST_F(BadSceneFile, UnknownContactLawOrRetentionOutOfRange) {
  const std::string p = good();
  h5::File::open(p, /*writable=*/true).group("env").write_string("contact", "sticky_ish");
  EXPECT_THAT(read_refusal(p), HasSubstr("attribute 'contact' of env is \"sticky_ish\", not a contact law (coulomb, no_slip)"));
  const std::string q = good();
  h5::File::open(q, /*writable=*/true).group("env").write_double("no_slip_keep", 1.5);
  EXPECT_THAT(read_refusal(q), HasSubstr("env/no_slip_keep = 1.5 is out of range [0, 1]"));
}

TEST_F(BadSceneFile, MissingOrWrongFormat) {
  const std::string p = good();
  {
    RawFile f(p);
    ASSERT_GE(H5Adelete(f.id, "format"), 0);
  }
  EXPECT_THAT(read_refusal(p), HasSubstr("attribute 'format' is missing"));
  h5::File::open(p, /*writable=*/true).write_string("format", "divcoll-run");
  EXPECT_THAT(read_refusal(p),
              HasSubstr("attribute 'format' is \"divcoll-run\", expected \"divcoll-scene\""));
  // a trajectory file is not a scene file
  EXPECT_THAT(read_refusal(parity_expected(kParity[0])), HasSubstr("attribute 'format' is missing"));
}

TEST_F(BadSceneFile, NotHdf5AtAll) {
  const std::string text = file("scene.h5");
  std::ofstream(text) << "this is a text file, not a scene\n";
  const std::string m = read_refusal(text);
  EXPECT_THAT(m, HasSubstr(text));
  EXPECT_THAT(m, HasSubstr("is not an HDF5 file"));
  const std::string empty = file("empty.h5");
  std::ofstream{empty};
  EXPECT_THAT(read_refusal(empty), HasSubstr("is not an HDF5 file"));
  EXPECT_THAT(read_refusal(file("nowhere.h5")), HasSubstr("does not exist"));
}

TEST_F(BadSceneFile, TruncatedHdf5) {
  const std::string src = good();
  const auto size = fs::file_size(src);
  std::vector<char> bytes(size);
  std::ifstream(src, std::ios::binary).read(bytes.data(), static_cast<std::streamsize>(size));
  for (double fraction : {0.5, 0.1, 0.9}) {
    const std::string cut = file("cut.h5");
    std::ofstream(cut, std::ios::binary | std::ios::trunc)
        .write(bytes.data(), static_cast<std::streamsize>(static_cast<double>(size) * fraction));
    const std::string m = read_refusal(cut);
    EXPECT_THAT(m, HasSubstr(cut)) << "fraction " << fraction;
    EXPECT_THAT(m, HasSubstr("truncated")) << "fraction " << fraction;
  }
}

// ---- trajectory files ------------------------------------------------------------------------------

Trajectory make_trajectory(int T, int N, bool grad) {
  Trajectory t;
  t.steps = T;
  t.n_masses = N;
  for (int k = 0; k < (T + 1) * N * 2; ++k) {
    t.x.push_back(std::sin(0.37 * k) * 1e-3 + k);
    t.v.push_back(std::cos(1.3 * k) / 3.0);
  }
  for (int k = 0; k < (T + 1) * N; ++k) t.touch.push_back(static_cast<uint8_t>(k % 3 == 0));
  t.travel = 0.123456789012345;
  t.status = "unstable";
  t.v[7] = std::numeric_limits<double>::quiet_NaN();  // NaN survives bit-exact
  if (grad) {
    t.has_grad = true;
    t.n_agents = 2;
    for (int k = 0; k < 2 * 3509; ++k) t.grad_agent_params.push_back(1.0 / (k + 1));
    for (int k = 0; k < 1473; ++k) t.grad_connector_params.push_back(-k * 1e-7);
    for (int k = 0; k < 2 * N; ++k) t.grad_x0.push_back(k == 0 ? -0.0 : 0.5 * k);
    for (int k = 0; k < 47; ++k) t.grad_rest_length.push_back(std::exp(-k));
  }
  return t;
}

void expect_same_trajectory(const Trajectory& a, const Trajectory& b) {
  EXPECT_EQ(a.steps, b.steps);
  EXPECT_EQ(a.n_masses, b.n_masses);
  EXPECT_TRUE(same_bits(a.x, b.x));
  EXPECT_TRUE(same_bits(a.v, b.v));
  EXPECT_TRUE(same_bits(a.touch, b.touch));
  EXPECT_TRUE(same_bits(a.travel, b.travel));
  EXPECT_EQ(a.status, b.status);
  EXPECT_EQ(a.has_grad, b.has_grad);
  EXPECT_EQ(a.n_agents, b.n_agents);
  EXPECT_TRUE(same_bits(a.grad_agent_params, b.grad_agent_params));
  EXPECT_TRUE(same_bits(a.grad_connector_params, b.grad_connector_params));
  EXPECT_TRUE(same_bits(a.grad_x0, b.grad_x0));
  EXPECT_TRUE(same_bits(a.grad_rest_length, b.grad_rest_length));
}

TEST_F(FileTest, TrajectoryRoundTripIsBitExact) {
  for (bool grad : {false, true}) {
    const Trajectory t = make_trajectory(12, 22, grad);
    const std::string out = file(grad ? "tg.h5" : "t.h5");
    write_trajectory(out, t);
    expect_same_trajectory(t, read_trajectory(out));
    EXPECT_THROW(write_trajectory(out, t), InputError);  // no silent overwrite
    EXPECT_NO_THROW(write_trajectory(out, t, /*overwrite=*/true));
  }
  // no connector: grad/connector_params is not written
  Trajectory t = make_trajectory(3, 11, true);
  t.grad_connector_params.clear();
  const std::string out = file("nc.h5");
  write_trajectory(out, t);
  EXPECT_FALSE(h5::File::open(out).has("grad/connector_params"));
  expect_same_trajectory(t, read_trajectory(out));
}

TEST_F(FileTest, TrajectoryWriteRefusesBadShapes) {
  Trajectory t = make_trajectory(4, 3, true);
  t.touch.pop_back();
  EXPECT_THROW(write_trajectory(file("a.h5"), t), InputError);
  t = make_trajectory(4, 3, true);
  t.grad_x0.push_back(0);
  EXPECT_THROW(write_trajectory(file("b.h5"), t), InputError);
  t = make_trajectory(4, 3, false);
  t.status = "fine";
  try {
    write_trajectory(file("c.h5"), t);
    FAIL() << "wrote a bad status";
  } catch (const InputError& e) {
    EXPECT_THAT(e.what(), HasSubstr("status \"fine\""));
  }
  EXPECT_FALSE(fs::exists(file("a.h5")) || fs::exists(file("b.h5")) || fs::exists(file("c.h5")));
}

TEST(TrajectoryFile, ParityExpectedFilesLoad) {
  for (const ParityCase& c : kParity) {
    SCOPED_TRACE(c.name);
    const Trajectory t = read_trajectory(parity_expected(c));
    EXPECT_EQ(t.steps, 300);
    EXPECT_EQ(t.n_masses, c.N);
    EXPECT_EQ(t.x.size(), 301u * c.N * 2);
    EXPECT_EQ(t.v.size(), 301u * c.N * 2);
    EXPECT_TRUE(t.touch.empty());
    EXPECT_EQ(t.status, "ok");
    EXPECT_TRUE(std::isfinite(t.travel));
    ASSERT_TRUE(t.has_grad);
    EXPECT_EQ(t.n_agents, c.A);
    EXPECT_EQ(t.grad_agent_params.size(), static_cast<size_t>(c.A) * 3509);
    EXPECT_EQ(t.grad_connector_params.size(), c.C > 0 ? 1473u : 0u);
    EXPECT_EQ(t.grad_x0.size(), 2u * c.N);
    EXPECT_EQ(t.grad_rest_length.size(), static_cast<size_t>(c.S));
    // step 0 of the trajectory is the scene's x0
    const sim::Scene s = read_scene(parity_scene(c));
    EXPECT_TRUE(same_bits(std::vector<double>(t.x.begin(), t.x.begin() + 2 * c.N), s.x0));
    // travel is the mean x displacement
    double mean0 = 0, meanT = 0;
    for (int i = 0; i < c.N; ++i) {
      mean0 += t.x[2 * i] / c.N;
      meanT += t.x[(300 * c.N + i) * 2] / c.N;
    }
    EXPECT_NEAR(t.travel, meanT - mean0, 1e-12);
  }
}

TEST(TrajectoryFile, ScenesAreNotTrajectories) {
  try {
    read_trajectory(parity_scene(kParity[0]));
    FAIL() << "read a scene as a trajectory";
  } catch (const InputError& e) {
    EXPECT_THAT(e.what(), HasSubstr("missing dataset x"));
  }
}

}  // namespace
}  // namespace divcoll::io
