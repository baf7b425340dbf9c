// the divcoll executable: simulate writes what SPEC §9 says, bad input gives a message and a non-zero
// exit, and nothing that exists is overwritten without --force
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <set>
#include <string>
#include <sys/wait.h>
#include <unistd.h>

#include "common/version.hpp"
#include "config/environments.hpp"
#include "io/scene_file.hpp"
#include "io/trajectory_file.hpp"
#include "io/h5.hpp"
#include "io/run_file.hpp"
#include "sim/engine.hpp"
#include "testing.hpp"

namespace divcoll {
namespace {

namespace fs = std::filesystem;

using testing::Exec;
Exec run(const std::string& args) { return testing::run_divcoll(args); }

class Cli : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / ("divcoll_cli_" + std::to_string(::getpid()) + "_" +
                                        ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }
  std::string path(const std::string& name) const { return (dir_ / name).string(); }
  fs::path dir_;
};

TEST_F(Cli, SimulateWritesTrajectoryAndGradientsEqualToTheLibrary) {
  const std::string scene = testing::parity_dir() + "/scene1_step_up.h5";
  const Exec r = run("simulate --scene " + scene + " --steps 120 --out " + path("t.h5") + " --grad");
  ASSERT_EQ(r.code, 0) << r.out;
  const io::Trajectory t = io::read_trajectory(path("t.h5"));
  sim::RunOptions opt;
  opt.steps = 120;
  opt.grad = true;
  opt.record = true;
  const sim::RunResult want = sim::simulate(io::read_scene(scene), opt);
  EXPECT_EQ(t.steps, 120);
  EXPECT_EQ(t.x, want.x);
  EXPECT_EQ(t.v, want.v);
  EXPECT_EQ(t.touch, want.touch);
  EXPECT_EQ(t.travel, want.travel);
  EXPECT_EQ(t.status, "ok");
  EXPECT_EQ(t.grad_connector_params, want.grad_connector_params);
  EXPECT_EQ(t.grad_x0, want.grad_x0);
  // the same output again is refused, and the file is untouched
  const auto before = fs::last_write_time(path("t.h5"));
  const Exec again = run("simulate --scene " + scene + " --steps 10 --out " + path("t.h5"));
  EXPECT_NE(again.code, 0);
  EXPECT_NE(again.out.find("--force"), std::string::npos) << again.out;
  EXPECT_EQ(fs::last_write_time(path("t.h5")), before);
  EXPECT_EQ(io::read_trajectory(path("t.h5")).steps, 120);
}

TEST_F(Cli, BadInputIsRefusedWithAMessageAndNonZeroExit) {
  std::ofstream(path("text.h5")) << "not hdf5\n";
  struct Case {
    std::string args, expect;
  };
  const std::string good = testing::parity_dir() + "/scene0_flat.h5";
  const Case cases[] = {
      {"simulate --scene " + path("text.h5") + " --steps 10 --out " + path("o.h5"), "not an HDF5 file"},
      {"simulate --scene " + path("missing.h5") + " --steps 10 --out " + path("o.h5"), "missing.h5"},
      {"simulate --scene " + good + " --steps 0 --out " + path("o.h5"), "--steps"},
      {"simulate --scene " + good + " --steps 10 --out " + path("nodir/o.h5"), "does not exist"},
      {"scene --kind pair --env moon --out " + path("s.h5"), "unknown environment 'moon'"},
      {"scene --kind chain --agents 1 --out " + path("s.h5"), "--agents"},
      {"scene --kind blob --out " + path("s.h5"), "--kind"},
      {"frobnicate", "unknown command 'frobnicate'"},
      // run configs: refused before any work, naming the key and the allowed range
      {"evolve " + testing::source_dir() + "/configs/tiny.toml agents.population=0 --out " + path("r.h5"),
       "agents.population"},
      {"evolve " + testing::source_dir() + "/configs/tiny.toml agents.populaton=5 --out " + path("r.h5"),
       "did you mean agents.population"},
      {"evolve " + testing::source_dir() + "/configs/tiny.toml agents.episode_steps=0 --out " + path("r.h5"),
       "agents.episode_steps"},
      {"run " + testing::source_dir() + "/configs/tiny.toml scaling.sizes=1,3 --out " + path("r.h5"), "scaling.sizes"},
      {"run " + testing::source_dir() + "/configs/tiny.toml connectors.batch_pairs=50 --out " + path("r.h5"),
       "agents.population"},
      {"run " + testing::source_dir() + "/configs/tiny.toml deploy.environments=flat,moon --out " + path("r.h5"),
       "moon"},
      {"evolve " + path("text.h5") + " --out " + path("r.h5"), "text.h5"},
      // report: through divcoll_post.report under /usr/bin/python3
      {"report " + good + " --out " + path("rep"), "is not a divcoll run file"},
      {"report " + path("text.h5") + " --out " + path("rep"), "cannot read"},
      {"report " + path("missing.h5"), "missing.h5"},
      {"run " + testing::source_dir() + "/configs/tiny.toml connectors.replicates=-1 --out " + path("r.h5"),
       "connectors.replicates = -1 is out of range [1, 1000]"},
      {"run " + testing::source_dir() + "/configs/tiny.toml agents.population=ten --out " + path("r.h5"),
       "agents.population"},
      {"run " + testing::source_dir() + "/configs/tiny.toml deploy.episode_steps=0 --out " + path("r.h5"),
       "deploy.episode_steps"},
      {"run " + testing::source_dir() + "/configs/tiny.toml scaling.draws=50 --out " + path("r.h5"), "scaling.draws"},
      {"run " + testing::source_dir() + "/configs/tiny.toml run.stages=agents,dance --out " + path("r.h5"), "dance"},
      {"run " + testing::source_dir() + "/configs/tiny.toml run.contact=slippy --out " + path("r.h5"), "run.contact"},
      {"run " + testing::source_dir() + "/configs/tiny.toml connectors.network=joint --out " + path("r.h5"),
       "connectors.network = joint has one hidden state per connector"},
      {"run " + testing::source_dir() + "/configs/tiny.toml --resume --force --out " + path("r.h5"), "contradict"},
      {"run " + testing::source_dir() + "/configs/tiny.toml --from deploy --out " + path("r.h5"), "--base"},
      {"run " + testing::source_dir() + "/configs/tiny.toml --from dance --base " + good + " --out " + path("r.h5"),
       "--from"},
      {"run " + testing::source_dir() + "/configs/tiny.toml --from deploy --base " + good + " --out " + path("r.h5"),
       "not a usable run file"},
      {"run " + testing::source_dir() + "/configs/tiny.toml --out " + path("text.h5") + "/r.h5", "output folder"},
      {"export " + good + " --what pair --out " + path("s.h5"), "not a divcoll run file"},
      {"export " + good + " --what dance --out " + path("s.h5"), "--what"},
  };
  // bad input exits 2 (an internal failure would exit 1, a crash 134)
  for (const Case& c : cases) {
    const Exec r = run(c.args);
    EXPECT_EQ(r.code, 2) << c.args << "\n" << r.out;
    EXPECT_NE(r.out.find(c.expect), std::string::npos) << c.args << "\n" << r.out;
  }
  EXPECT_FALSE(fs::exists(path("o.h5")));
  EXPECT_FALSE(fs::exists(path("r.h5")));
  EXPECT_FALSE(fs::exists(path("s.h5")));
}

TEST_F(Cli, SceneCommandWritesAChainThatSimulates) {
  const Exec w = run("scene --kind chain --agents 5 --env obstacle --seed 3 --out " + path("c.h5"));
  ASSERT_EQ(w.code, 0) << w.out;
  const sim::Scene s = io::read_scene(path("c.h5"));
  EXPECT_EQ(s.n_agents(), 5);
  EXPECT_EQ(s.n_connectors(), 4);
  EXPECT_EQ(s.env.name, "obstacle");
  const Exec r = run("simulate --scene " + path("c.h5") + " --steps 50 --out " + path("t.h5"));
  EXPECT_EQ(r.code, 0) << r.out;
  EXPECT_NE(r.out.find("status ok"), std::string::npos) << r.out;
}

// the connector stiffness of `divcoll scene` is the config's (config/pipeline.hpp), the paper's without --config
TEST_F(Cli, SceneTakesTheConnectorStiffnessFromTheConfig) {
  { std::ofstream(path("k.toml")) << "[connectors]\nweak_stiffness = 1234.0\nstrong_stiffness = 45678.0\n"; }
  const std::vector<std::pair<std::string, double>> cases = {
      {"", 5000.0}, {" --config " + path("k.toml"), 1234.0}, {" --config " + path("k.toml") + " --connector strong", 45678.0}};
  for (const auto& [extra, k] : cases) {
    const Exec w = run("scene --kind pair --force --out " + path("p.h5") + extra);
    ASSERT_EQ(w.code, 0) << w.out;
    const sim::Scene s = io::read_scene(path("p.h5"));
    ASSERT_EQ(s.n_connectors(), 1);
    for (int sp : s.connector_spring_index) EXPECT_EQ(s.stiffness[sp], k) << extra;
  }
  const Exec bad = run("scene --kind pair --out " + path("q.h5") + " --config " + path("nope.toml"));
  EXPECT_NE(bad.code, 0);
}

// run.contact reaches the scene file (`divcoll scene --config`), and simulating that file runs the scene's law:
// the same travel, bit for bit, as the library on the same scene, and not coulomb's
TEST_F(Cli, SceneTakesTheContactLawFromTheConfigAndSimulatesIt) {
  { std::ofstream(path("ns.toml")) << "[run]\ncontact = \"no_slip\"\n"; }
  for (const char* env : {"ice", "treadmill"}) {
    const Exec w = run(std::string("scene --kind pair --env ") + env + " --force --out " + path("ns.h5") + " --config " +
                       path("ns.toml"));
    ASSERT_EQ(w.code, 0) << w.out;
    const Exec c = run(std::string("scene --kind pair --env ") + env + " --force --out " + path("cb.h5"));
    ASSERT_EQ(c.code, 0) << c.out;
    const sim::Scene s = io::read_scene(path("ns.h5")), cs = io::read_scene(path("cb.h5"));
    EXPECT_EQ(s.env.contact, sim::ContactLaw::no_slip) << env;
    EXPECT_EQ(cs.env.contact, sim::ContactLaw::coulomb) << env;
    EXPECT_EQ(s.env.no_slip_keep, config::environment_table(env).physics.no_slip_keep);
    const Exec r = run("simulate --scene " + path("ns.h5") + " --steps 200 --force --out " + path("nt.h5"));
    ASSERT_EQ(r.code, 0) << r.out;
    sim::RunOptions opt;
    opt.steps = 200;
    const double lib = sim::simulate(s, opt).travel, coulomb = sim::simulate(cs, opt).travel;
    const double file = io::h5::File::open(path("nt.h5")).read_double("travel");
    EXPECT_EQ(file, lib) << env;
    EXPECT_NE(file, coulomb) << env;
  }
}

}  // namespace
}  // namespace divcoll

namespace divcoll {
namespace {

TEST_F(Cli, ExistingRunFileIsNeitherOverwrittenNorResumedWithAnotherConfig) {
  const std::string cfg = testing::source_dir() + "/configs/tiny.toml";
  const std::string env = "OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1 ";
  ASSERT_EQ(std::system((env + testing::divcoll_binary() + " evolve " + cfg + " --out " + path("r.h5") + " > /dev/null").c_str()), 0);
  const auto before = fs::last_write_time(path("r.h5"));
  const Exec again = run("evolve " + cfg + " --out " + path("r.h5"));
  EXPECT_EQ(again.code, 2) << again.out;
  EXPECT_NE(again.out.find("--resume"), std::string::npos) << again.out;
  const Exec other = run("evolve " + cfg + " agents.epochs=3 --out " + path("r.h5") + " --resume");
  EXPECT_NE(other.code, 0) << other.out;
  EXPECT_NE(other.out.find("agents.epochs"), std::string::npos) << other.out;
  EXPECT_EQ(fs::last_write_time(path("r.h5")), before);
  // the finished run resumes to itself
  const Exec same = run("evolve " + cfg + " --out " + path("r.h5") + " --resume");
  EXPECT_EQ(same.code, 0) << same.out;
  EXPECT_NE(same.out.find("stage agents: complete in the run file"), std::string::npos) << same.out;
}

}  // namespace
}  // namespace divcoll

namespace divcoll {
namespace {

// the stages write the datasets they promise, with the shapes mpi/README.md gives
// connectors.network = joint through the pipeline's first three stages: 3013 weights per trained connector, every
// deployment episode run, no hidden states kept, and the file matches the run-file schema
TEST_F(Cli, TheJointConnectorNetworkTrainsAndDeploys) {
  const std::string cfg = testing::source_dir() + "/configs/tiny.toml";
  const Exec r = run("run " + cfg + " connectors.network=joint run.stages=agents,connectors,deploy --out " + path("j.h5"));
  ASSERT_EQ(r.code, 0) << r.out;
  const io::h5::File f = io::h5::File::open(path("j.h5"));
  EXPECT_EQ(f.dims("connectors/weak_diverse/params")[1], static_cast<hsize_t>(sim::connector_param_count(true)));
  for (uint8_t st : f.read<uint8_t>("deploy/collectives/status")) EXPECT_EQ(st, 0);
  EXPECT_FALSE(f.has("deploy/hidden"));
  const Exec checked = run("schema --check " + path("j.h5"));
  EXPECT_EQ(checked.code, 0) << checked.out;
}

TEST_F(Cli, RunWritesEveryPromisedDatasetOfEachImplementedStage) {
  const std::string cfg = testing::source_dir() + "/configs/tiny.toml";
  const Exec r = run("run " + cfg + " --out " + path("run.h5"));  // every stage
  ASSERT_EQ(r.code, 0) << r.out;
  const io::h5::File f = io::h5::File::open(path("run.h5"));
  // every group and dataset has its row of the run-file schema (types, dims along the named axes, the
  // axes / unit / doc / labels attributes), and every row is in the file (tests/io/run_file_test.cpp)
  for (const std::string& p : io::run_file::check(f, /*every_row=*/true)) ADD_FAILURE() << p;
  const Exec checked = run("schema --check " + path("run.h5"));
  EXPECT_EQ(checked.code, 0) << checked.out;
  EXPECT_NE(checked.out.find("every group and dataset matches the run-file schema"), std::string::npos) << checked.out;
  io::h5::File::create(path("other.h5"), true).write_string("format", "divcoll-scene");
  const Exec refused = run("schema --check " + path("other.h5"));
  EXPECT_EQ(refused.code, 2) << refused.out;
  EXPECT_NE(refused.out.find("is not a divcoll run file"), std::string::npos) << refused.out;
  using D = io::h5::Dims;
  const hsize_t P = 6, G = 2, R = 1, I = 2, E = 4, T = 8, NP = 4, Pa = 3509, Pc = 1473;
  // agents
  EXPECT_EQ(f.group("agents").read_string("status"), "complete");
  for (hsize_t g = 0; g <= G; ++g) {
    const std::string gen = "agents/gen_00" + std::to_string(g);
    const hsize_t M = g == 0 ? P : 2 * P;
    EXPECT_EQ(f.dims(gen + "/params"), (D{M, Pa}));
    EXPECT_EQ(f.dims(gen + "/rest_pos"), (D{M, 11, 2}));
    EXPECT_EQ(f.dims(gen + "/survived"), (D{M}));
    const auto surv = f.read<uint8_t>(gen + "/survived");
    EXPECT_EQ(std::count(surv.begin(), surv.end(), 1), static_cast<long>(P)) << gen;
  }
  EXPECT_EQ(f.dims("agents/final/params"), (D{P, Pa}));
  // connectors
  EXPECT_EQ(f.group("connectors").read_string("status"), "complete");
  const auto anchors = f.read<int32_t>("connectors/anchors", D{P, 4});
  for (int32_t a : anchors) EXPECT_TRUE(a >= 0 && a < 11);
  for (const char* kind : {"weak_uniform", "weak_diverse", "strong_uniform", "strong_diverse"}) {
    const std::string k = std::string("connectors/") + kind;
    EXPECT_EQ(f.dims(k + "/params"), (D{R, Pc})) << kind;
    const auto curve = f.read<double>(k + "/curve_bl", D{I, R});
    for (double c : curve) EXPECT_TRUE(std::isfinite(c)) << kind;
    for (double w : f.read<double>(k + "/params")) ASSERT_TRUE(std::isfinite(w)) << kind;
  }
  // deploy
  EXPECT_EQ(f.group("deploy").read_string("status"), "complete");
  EXPECT_EQ(f.dims("deploy/agents/travel_bl"), (D{E, P}));
  EXPECT_EQ(f.dims("deploy/collectives/travel_bl"), (D{E, T, R, NP}));
  const auto st = f.read<uint8_t>("deploy/collectives/status");
  const auto tr = f.read<double>("deploy/collectives/travel_bl");
  for (size_t q = 0; q < st.size(); ++q) EXPECT_EQ(std::isfinite(tr[q]), st[q] == 0) << "episode " << q;
  const auto pairs = f.read<int32_t>("deploy/diverse_pairs", D{NP, 2});
  for (hsize_t q = 0; q < NP; ++q) EXPECT_NE(pairs[2 * q], pairs[2 * q + 1]) << "a diverse pair is two agents";
  // specialists: one weak diverse connector per novel environment, deployed there
  const hsize_t EN = E - 1, RS = 1, IS = 2;
  EXPECT_EQ(f.group("specialists").read_string("status"), "complete");
  EXPECT_EQ(f.group("specialists").read_string("environments"), "step_up,gap,ice");
  for (const char* env : {"step_up", "gap", "ice"}) {
    const std::string g = std::string("specialists/") + env;
    EXPECT_EQ(f.dims(g + "/params"), (D{RS, Pc})) << env;
    for (double c : f.read<double>(g + "/curve_bl", D{IS, RS})) EXPECT_TRUE(std::isfinite(c)) << env;
  }
  EXPECT_EQ(f.dims("specialists/travel_bl"), (D{EN, RS, NP}));
  const auto sst = f.read<uint8_t>("specialists/status");
  const auto stb = f.read<double>("specialists/travel_bl");
  for (size_t q = 0; q < sst.size(); ++q) EXPECT_EQ(std::isfinite(stb[q]), sst[q] == 0) << "specialist episode " << q;
  // specialists differ from the flat-trained weak diverse connector (they trained elsewhere)
  EXPECT_NE(f.read<double>("specialists/ice/params"), f.read<double>("connectors/weak_diverse/params"));
  // scaling: chains of 2 and 3, uniform and diverse, every environment
  const hsize_t S = 2, DR = 2;
  EXPECT_EQ(f.group("scaling").read_string("status"), "complete");
  EXPECT_EQ(f.read<int64_t>("scaling/sizes"), (std::vector<int64_t>{2, 3}));
  EXPECT_EQ(f.dims("scaling/travel_bl"), (D{E, S, 2, R, DR}));
  for (hsize_t n : {2, 3}) {
    const auto ag = f.read<int32_t>("scaling/n" + std::to_string(n) + "/diverse_agents", D{R * DR, n});
    for (hsize_t c = 0; c < R * DR; ++c) {
      std::set<int32_t> distinct(ag.begin() + c * n, ag.begin() + (c + 1) * n);
      EXPECT_EQ(distinct.size(), n) << "a diverse chain is N different agents";
      for (int32_t a : distinct) EXPECT_TRUE(a >= 0 && a < static_cast<int32_t>(P));
    }
  }
  const auto cst = f.read<uint8_t>("scaling/status");
  const auto ctb = f.read<double>("scaling/travel_bl");
  for (size_t q = 0; q < cst.size(); ++q) EXPECT_EQ(std::isfinite(ctb[q]), cst[q] == 0) << "chain episode " << q;
  EXPECT_FALSE(fs::exists(path("run.h5.ckpt"))) << "the checkpoint is removed when the run completes";

  // graded diversity: two populations of one body shape, their connectors and deployment
  const hsize_t GP = 4;
  EXPECT_EQ(f.group("graded").read_string("status"), "complete");
  const auto shape = static_cast<int64_t>(f.group("graded").read_int("shape_cells"));
  const auto main_cells = f.read<int64_t>("agents/final/cells");
  EXPECT_NE(std::find(main_cells.begin(), main_cells.end(), shape), main_cells.end()) << "the shape is the main population's";
  for (const char* pop : {"same_shape", "same_shape_springs"}) {
    const std::string g = std::string("graded/") + pop;
    EXPECT_EQ(f.group(g).read_string("status"), "complete") << pop;
    EXPECT_TRUE(f.group(g).has_attribute("diversity_sources")) << pop;
    for (int64_t c : f.read<int64_t>(g + "/agents/final/cells", D{GP})) EXPECT_EQ(c, shape) << pop;
    // rest positions stay at the lattice: every agent of the population has the same ones
    const auto rp = f.read<double>(g + "/agents/final/rest_pos", D{GP, 11, 2});
    for (hsize_t i = 1; i < GP; ++i)
      EXPECT_TRUE(std::equal(rp.begin(), rp.begin() + 22, rp.begin() + 22 * i)) << pop << " agent " << i;
    EXPECT_EQ(f.dims(g + "/connectors/weak_diverse/params"), (D{R, Pc})) << pop;
    EXPECT_EQ(f.dims(g + "/deploy/agents/travel_bl"), (D{E, GP})) << pop;
    EXPECT_EQ(f.dims(g + "/deploy/pairs/travel_bl"), (D{E, R, NP})) << pop;
  }
  const auto sp = f.read<int64_t>("graded/same_shape_springs/agents/final/springs");
  for (int64_t x : sp) EXPECT_EQ(x, f.group("graded").read_int("shape_springs"));
  const auto p0 = f.read<double>("graded/same_shape_springs/agents/final/params", D{GP, Pa});
  EXPECT_FALSE(std::equal(p0.begin(), p0.begin() + Pa, p0.begin() + Pa)) << "controllers from different seeds";

  // analysis (SPEC §8): the re-simulated episodes reproduce deploy's travel bit for bit; a DTW per agent of
  // every ok pair, zero-free (tethered agents move differently) and finite exactly where deploy's pair was ok
  EXPECT_EQ(f.group("analysis").read_string("status"), "complete");
  EXPECT_EQ(f.group("analysis").read_string("types"), "weak_uniform@uniform,weak_diverse@diverse");
  EXPECT_EQ(f.group("analysis/adversity").read_int("deploy_mismatches"), 0);
  const int type_index[2] = {0, 3};  // weak_uniform@uniform, weak_diverse@diverse among deploy's 8 types
  for (int t = 0; t < 2; ++t) {
    const std::string type = t == 0 ? "weak_uniform@uniform" : "weak_diverse@diverse";
    const auto dtw = f.read<double>("analysis/adversity/" + type + "/dtw", D{E, R, NP, 2});
    const auto ws = f.read<uint8_t>("analysis/adversity/" + type + "/worse_slot", D{E, R, NP});
    for (hsize_t e = 0; e < E; ++e)
      for (hsize_t q = 0; q < NP; ++q) {
        const size_t k = e * NP + q;
        const bool ok = st[((e * T + type_index[t]) * R) * NP + q] == 0;
        for (int slot = 0; slot < 2; ++slot) {
          EXPECT_EQ(std::isfinite(dtw[2 * k + slot]), ok) << type << " env " << e << " pair " << q;
          if (ok) {
            EXPECT_GT(dtw[2 * k + slot], 0.0) << type;
          }
        }
        EXPECT_LE(ws[k], 1);
      }
    // the worse agent is the one that travelled less alone
    const auto alone = f.read<double>("deploy/agents/travel_bl");
    if (t == 1)
      for (hsize_t e = 0; e < E; ++e)
        for (hsize_t q = 0; q < NP; ++q) {
          const double a0 = alone[e * P + pairs[2 * q]], a1 = alone[e * P + pairs[2 * q + 1]];
          EXPECT_EQ(ws[e * NP + q], a1 < a0 ? 1 : 0);
        }
    const auto counts = f.read<int64_t>("analysis/familiarity/" + type + "/counts", D{EN, R, 6});
    const auto ns = f.read<int64_t>("analysis/familiarity/" + type + "/n_states", D{EN, R, 2});
    for (hsize_t k = 0; k < EN; ++k) {
      // every state is in exactly one class; the classes' cells are what the states occupy
      EXPECT_EQ(counts[k * 6] + counts[k * 6 + 1] + counts[k * 6 + 2], ns[k * 2] + ns[k * 2 + 1]) << type;
      EXPECT_GT(ns[k * 2], 0) << type;
      EXPECT_LE(ns[k * 2], 500) << "at most max_states (= hidden_subsample here) per environment";
      EXPECT_EQ(counts[k * 6 + 3] > 0, counts[k * 6] > 0);
    }
    EXPECT_EQ(f.dims("analysis/familiarity/" + type + "/embedding"), (D{EN, R, 1000, 2}));
  }
  EXPECT_EQ(f.dims("analysis/adversity/summary"), (D{2, 2, 3}));
  EXPECT_EQ(f.dims("analysis/familiarity/table"), (D{EN, 3, 3}));

  // export: the scene of a stored episode simulates to the stored travel, bit for bit
  struct Case {
    std::string args, dataset;
    size_t index;
    int steps;
  };
  const std::vector<Case> cases = {
      {"--what alone --env gap --agent 3", "deploy/agents/travel_u", 2 * P + 3, 200},
      {"--what pair --env ice --type strong_uniform@diverse --pair 2", "deploy/collectives/travel_u",
       ((3 * T + 5) * R + 0) * NP + 2, 200},
      {"--what specialist --env step_up --pair 1", "specialists/travel_u", 1, 200},
      {"--what chain --env gap --size 3 --variant diverse --draw 1", "scaling/travel_u",
       (((2 * S + 1) * 2 + 1) * R + 0) * DR + 1, 200}};
  for (size_t c = 0; c < cases.size(); ++c) {
    const std::string scene = path("ex" + std::to_string(c) + ".h5"), traj = path("tr" + std::to_string(c) + ".h5");
    const Exec e = run("export " + path("run.h5") + " " + cases[c].args + " --out " + scene);
    ASSERT_EQ(e.code, 0) << cases[c].args << "\n" << e.out;
    const Exec sim = run("simulate --scene " + scene + " --steps " + std::to_string(cases[c].steps) + " --out " + traj);
    ASSERT_EQ(sim.code, 0) << sim.out;
    const double stored = f.read<double>(cases[c].dataset)[cases[c].index];
    EXPECT_EQ(io::h5::File::open(traj).read_double("travel"), stored) << cases[c].args;
  }
  // hidden states (SPEC §8.2): K = 500 / 4 per episode, sorted distinct indices, and the very activations
  // of the connector's second hidden layer at those steps (checked by rerunning one exported episode)
  const hsize_t K = 125;
  for (const char* type : {"weak_uniform@uniform", "weak_diverse@diverse"}) {
    const std::string g = std::string("deploy/hidden/") + type;
    const auto idx = f.read<int32_t>(g + "/index", D{E, R, NP, K});
    const auto hs = f.read<float>(g + "/states", D{E, R, NP, K, 32});
    for (size_t ep = 0; ep < E * R * NP; ++ep)
      for (size_t k = 0; k < K; ++k) {
        ASSERT_TRUE(idx[ep * K + k] >= 0 && idx[ep * K + k] < 200 * 5) << type;
        if (k) {
          ASSERT_LT(idx[ep * K + k - 1], idx[ep * K + k]) << type << " episode " << ep;
        }
      }
    for (float h : hs) ASSERT_TRUE(h > -1.0f && h < 1.0f) << type << ": tanh activations";
  }
  {
    const std::string scene = path("hid.h5");
    ASSERT_EQ(run("export " + path("run.h5") + " --what pair --env ice --type weak_diverse@diverse --pair 2 --out " + scene).code, 0);
    sim::Simulator sim;
    sim::RunOptions opt;
    opt.steps = 200;
    opt.record_hidden = true;
    const sim::RunResult rr = sim.run(io::read_scene(scene), opt);
    const auto idx = f.read<int32_t>("deploy/hidden/weak_diverse@diverse/index");
    const auto hs = f.read<float>("deploy/hidden/weak_diverse@diverse/states");
    const size_t ep = (3 * R + 0) * NP + 2;  // ice, replicate 0, pair 2
    for (size_t k = 0; k < K; ++k)
      for (int q = 0; q < 32; ++q)
        ASSERT_EQ(hs[(ep * K + k) * 32 + q], static_cast<float>(rr.hidden[static_cast<size_t>(idx[ep * K + k]) * 32 + q]))
            << "state " << k << " unit " << q;
  }

  const Exec nope = run("export " + path("run.h5") + " --what pair --env moon --out " + path("x.h5"));
  EXPECT_EQ(nope.code, 2);
  EXPECT_NE(nope.out.find("'moon' is not in the run file"), std::string::npos) << nope.out;

  // --from deploy: a new run file with the base's agents and connectors, deploy rerun with new keys
  const Exec bad = run("run " + cfg + " run.stages=agents,connectors,deploy agents.epochs=3 --from deploy --base " +
                       path("run.h5") + " --out " + path("re.h5"));
  EXPECT_EQ(bad.code, 2) << bad.out;
  EXPECT_NE(bad.out.find("agents.epochs"), std::string::npos) << bad.out;
  EXPECT_FALSE(fs::exists(path("re.h5")));
  const Exec same_out = run("run " + cfg + " --from deploy --base " + path("run.h5") + " --out " + path("run.h5"));
  EXPECT_EQ(same_out.code, 2) << same_out.out;
  const Exec re = run("run " + cfg + " run.stages=agents,connectors,deploy deploy.episode_steps=100 --from deploy --base " +
                      path("run.h5") + " --out " + path("re.h5"));
  ASSERT_EQ(re.code, 0) << re.out;
  const io::h5::File g = io::h5::File::open(path("re.h5"));
  EXPECT_EQ(g.read<double>("agents/final/params"), f.read<double>("agents/final/params"));
  EXPECT_EQ(g.read<double>("connectors/weak_diverse/params"), f.read<double>("connectors/weak_diverse/params"));
  EXPECT_EQ(g.dims("deploy/collectives/travel_bl"), (D{E, T, R, NP}));
  EXPECT_NE(g.read<double>("deploy/agents/travel_u"), f.read<double>("deploy/agents/travel_u"))
      << "deploy reran with 100 steps instead of 200";
  EXPECT_FALSE(g.has("specialists")) << "stages from --from on are dropped from the copy";
  EXPECT_NE(g.read_string("derived_from").find("run.h5"), std::string::npos);
  EXPECT_TRUE(g.has_attribute("base_git_commit")) << "the earlier stages' commit is kept";
  EXPECT_EQ(g.read_string("git_commit"), git_commit()) << "the new stages' commit is this build's";

  // tether: one row per (environment, deployment, pair, tether), then the page drawn from that table by
  // divcoll_post.tether, naming the command; an existing table is not overwritten without --force
  const Exec t = run("tether " + path("run.h5") + " --pairs 2 --steps 50 --out " + path("tether"));
  ASSERT_EQ(t.code, 0) << t.out;
  std::ifstream csv(path("tether/tether.csv"));
  std::string line;
  int lines = 0, free_rows = 0;
  while (std::getline(csv, line)) lines += 1, free_rows += line.find(",free,") != std::string::npos;
  EXPECT_EQ(lines, 1 + static_cast<int>(E) * 2 * 2 * 4);
  EXPECT_EQ(free_rows, static_cast<int>(E) * 2 * 2);
  std::ifstream md(path("tether/tether.md"));
  const std::string page((std::istreambuf_iterator<char>(md)), std::istreambuf_iterator<char>());
  EXPECT_NE(page.find("command `divcoll tether " + path("run.h5") + " --pairs 2 --replicate 0 --steps 50`"),
            std::string::npos) << page;
  EXPECT_NE(page.find("| flat | trained |"), std::string::npos) << page;
  EXPECT_TRUE(fs::is_regular_file(path("tether/tether.png")));
  const Exec again = run("tether " + path("run.h5") + " --pairs 1 --steps 50 --out " + path("tether"));
  EXPECT_EQ(again.code, 2) << again.out;
  EXPECT_NE(again.out.find("--force"), std::string::npos) << again.out;
}

}  // namespace
}  // namespace divcoll
