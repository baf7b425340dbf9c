// the run configuration: presets parse, paper.toml is the defaults, bad keys, types, ranges and impossible
// combinations are refused naming the key, overrides get the same checks, and to_toml / flat round-trip
#include "config/config.hpp"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <fstream>
#include <iterator>

#include <string>
#include <vector>

#include "common/check.hpp"
#include "config/environments.hpp"
#include "testing.hpp"

namespace divcoll::config {
namespace {

using ::testing::HasSubstr;
using ::testing::Not;

std::string preset(const std::string& name) { return testing::source_dir() + "/configs/" + name; }

// the message of the InputError that parsing `text` raises (a test failure if it is accepted)
std::string refusal(const std::string& text, const std::vector<std::string>& overrides = {}) {
  try {
    parse_config(text, "test.toml", overrides);
  } catch (const InputError& e) {
    return e.what();
  }
  ADD_FAILURE() << "accepted:\n" << text;
  return "";
}

// flat() of two configs, key by key, so a failure names the key
void expect_same(const RunConfig& a, const RunConfig& b) {
  const auto fa = flat(a), fb = flat(b);
  ASSERT_EQ(fa.size(), fb.size());
  for (size_t i = 0; i < fa.size(); ++i) {
    EXPECT_EQ(fa[i].first, fb[i].first);
    EXPECT_EQ(fa[i].second, fb[i].second) << fa[i].first;
  }
  EXPECT_TRUE(a == b);
}

TEST(ConfigPresets, AllParse) {
  for (const char* name : {"paper.toml", "quick.toml", "tiny.toml"}) {
    EXPECT_NO_THROW(load_config(preset(name))) << name;
  }
  const RunConfig tiny = load_config(preset("tiny.toml"));
  EXPECT_EQ(tiny.agents.population, 6);
  EXPECT_EQ(tiny.agents.generations, 2);
  EXPECT_EQ(tiny.agents.epochs, 2);
  EXPECT_EQ(tiny.agents.episode_steps, 100);
  EXPECT_EQ(tiny.run.name, "tiny");
}

TEST(ConfigPresets, PaperIsTheDefaults) {
  const RunConfig paper = load_config(preset("paper.toml"));
  expect_same(paper, default_config());
  // and the defaults are the paper's counts
  const RunConfig& d = paper;
  EXPECT_EQ(d.run.seed, 1u);
  EXPECT_EQ(d.run.stages, stage_names());  // every stage of the pipeline, in its order
  EXPECT_EQ(d.analysis.dtw_every, 10);  // SPEC §8.1: every 10th step, band 10%
  EXPECT_EQ(d.analysis.dtw_band, 0.1);
  EXPECT_EQ(d.analysis.max_states, 10000);  // SPEC §8.2
  EXPECT_EQ(d.analysis.bootstrap_resamples, 1000);  // SPEC §8.3
  EXPECT_EQ(d.agents.population, 100);
  EXPECT_EQ(d.agents.generations, 15);
  EXPECT_EQ(d.agents.epochs, 15);
  EXPECT_EQ(d.agents.episode_steps, 1000);
  EXPECT_EQ(d.agents.gd_step, 0.16);
  EXPECT_EQ(d.agents.body_flip_p, 1.0 / 28);
  EXPECT_EQ(d.agents.spring_flip_p, 1.0 / 21);
  EXPECT_EQ(d.agents.uniqueness_k, 5);
  EXPECT_EQ(d.connectors.weak_stiffness, 5000.0);
  EXPECT_EQ(d.connectors.strong_stiffness, 30000.0);
  EXPECT_EQ(d.connectors.amplitude, 0.6);  // SPEC §6.2
  EXPECT_EQ(d.connectors.lr, 3e-3);
  EXPECT_EQ(d.connectors.kinds.size(), 4u);
  // the paper's 13 (SPEC §3), flat first, each a table of configs/environments.toml (which may hold more)
  EXPECT_EQ(d.deploy.environments,
            (std::vector<std::string>{"flat", "decline", "gap", "ice", "incline", "low_gravity", "obstacle", "sand",
                                      "step_down", "step_up", "sticky", "treadmill", "wind"}));
  for (const std::string& e : d.deploy.environments) EXPECT_TRUE(is_known_environment(e)) << e;
  EXPECT_EQ(d.deploy.episode_steps, 3000);
  EXPECT_EQ(d.scaling.sizes, (std::vector<int>{5, 10, 20}));
  EXPECT_TRUE(d.graded.enabled);
  EXPECT_EQ(d.output.dir, "runs");
}

// paper.toml writes out every key with its meaning, unit and range, as the program documents them: below its own
// header it is to_toml() of the defaults, word for word, so a new key or a changed meaning shows up here
TEST(ConfigPresets, PaperWritesOutEveryKeyAsDocumented) {
  std::ifstream in(preset("paper.toml"));
  const std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  const std::string generated = to_toml(default_config());
  const size_t a = text.find("\n[run]\n"), b = generated.find("\n[run]\n");
  ASSERT_NE(a, std::string::npos);
  ASSERT_NE(b, std::string::npos);
  EXPECT_EQ(text.substr(a), generated.substr(b))
      << "configs/paper.toml differs from the documented defaults: rewrite its body (from [run]) with to_toml of the "
         "defaults, e.g. the `config` attribute of a run file of paper.toml";
}

// the quick preset runs every stage of the paper's pipeline, each count at most the paper's and the
// expensive ones smaller; what it leaves out stays at the paper value
TEST(ConfigPresets, QuickIsTheDemoScale) {
  const RunConfig q = load_config(preset("quick.toml"));
  const RunConfig p = load_config(preset("paper.toml"));
  EXPECT_EQ(q.run.stages, p.run.stages);
  EXPECT_TRUE(q.graded.enabled);
  for (auto [quick, paper] : {std::pair{q.agents.population, p.agents.population},
                              std::pair{q.agents.generations, p.agents.generations},
                              std::pair{q.agents.epochs, p.agents.epochs},
                              std::pair{q.connectors.replicates, p.connectors.replicates},
                              std::pair{q.connectors.iterations, p.connectors.iterations},
                              std::pair{q.connectors.batch_pairs, p.connectors.batch_pairs},
                              std::pair{q.deploy.pairs, p.deploy.pairs},
                              std::pair{q.specialists.replicates, p.specialists.replicates},
                              std::pair{q.specialists.iterations, p.specialists.iterations},
                              std::pair{q.scaling.draws, p.scaling.draws},
                              std::pair{q.graded.population, p.graded.population},
                              std::pair{q.deploy.hidden_subsample, p.deploy.hidden_subsample},
                              std::pair{q.analysis.max_states, p.analysis.max_states}})
    EXPECT_LT(quick, paper);
  EXPECT_LE(q.connectors.episode_steps, p.connectors.episode_steps);
  EXPECT_LE(q.deploy.episode_steps, p.deploy.episode_steps);
  EXPECT_LT(*std::max_element(q.scaling.sizes.begin(), q.scaling.sizes.end()),
            *std::max_element(p.scaling.sizes.begin(), p.scaling.sizes.end()));
  EXPECT_EQ(q.deploy.environments, p.deploy.environments) << "the demo visits every environment";
  EXPECT_EQ(q.connectors.weak_stiffness, p.connectors.weak_stiffness);
  EXPECT_EQ(q.connectors.init_out_gain, p.connectors.init_out_gain);
}

TEST(ConfigSchema, KeysHaveTheAgreedNames) {
  const std::vector<std::string> expected = {"run.seed",
                                             "run.name",
                                             "run.stages",
                                             "run.progress_every_s",
                                             "run.stop_grace_s",
                                             "run.memory_limit_gb",
                                             "run.precision",
                                             "run.contact",
                                             "agents.population",
                                             "agents.generations",
                                             "agents.epochs",
                                             "agents.episode_steps",
                                             "agents.gd_rule",
                                             "agents.gd_step",
                                             "agents.adam_lr",
                                             "agents.rest_move_max",
                                             "agents.rest_length_min",
                                             "agents.rest_length_max",
                                             "agents.body_flip_p",
                                             "agents.spring_flip_p",
                                             "agents.rest_jitter_sd", "agents.selection",
                                             "agents.uniqueness_k",
                                             "agents.body_fixed",
                                             "agents.springs_fixed",
                                             "agents.rest_moves",
                                             "connectors.replicates",
                                             "connectors.iterations",
                                             "connectors.batch_pairs",
                                             "connectors.episode_steps",
                                             "connectors.weak_stiffness",
                                             "connectors.strong_stiffness",
                                             "connectors.amplitude",
                                             "connectors.damping",
                                             "connectors.follower",
                                             "connectors.optimizer",
                                             "connectors.lr",
                                             "connectors.clip_norm",
                                             "connectors.clip",
                                             "connectors.init_out_gain",
                                             "connectors.init",
                                             "connectors.network",
                                             "connectors.init_noise",
                                             "connectors.kinds",
                                             "connectors.lr_schedule",
                                             "connectors.lr_final",
                                             "connectors.bptt_window",
                                             "connectors.horizon_start",
                                             "connectors.horizon_ramp",
                                             "connectors.grad_samples",
                                             "connectors.grad_sigma",
                                             "connectors.keep_best",
                                             "connectors.validation_pairs",
                                             "connectors.es_popsize",
                                             "connectors.es_sigma",
                                             "deploy.episode_steps",
                                             "deploy.pairs",
                                             "deploy.environments",
                                             "deploy.hidden_subsample",
                                             "deploy.early_step",
                                             "deploy.uniform_agents",
                                             "deploy.feature_placement",
                                             "deploy.references",
                                             "specialists.replicates",
                                             "specialists.iterations",
                                             "scaling.sizes",
                                             "scaling.draws",
                                             "scaling.episode_steps",
                                             "graded.enabled",
                                             "graded.population",
                                             "analysis.dtw_every",
                                             "analysis.dtw_band",
                                             "analysis.max_states",
                                             "analysis.bootstrap_resamples",
                                             "analysis.alone_protocol",
                                             "analysis.dtw_cost",
                                             "analysis.dtw_step",
                                             "analysis.dtw_norm",
                                             "analysis.cell_scale",
                                             "analysis.calibrated_cell_scale",
                                             "analysis.familiarity_on",
                                             "output.dir",
                                             "output.checkpoint_every",
                                             "output.checkpoint_interval_s"};
  EXPECT_EQ(config_keys(), expected);
}

TEST(ConfigSchema, MarkdownListsEveryKey) {
  const std::string md = schema_markdown();
  for (const std::string& key : config_keys()) EXPECT_THAT(md, HasSubstr("| `" + key + "` |")) << key;
  size_t rows = 0;
  for (char c : md) rows += c == '\n';
  EXPECT_EQ(rows, config_keys().size() + 2);  // header and rule
  EXPECT_THAT(md, HasSubstr("[2, 100000]"));  // agents.population's range
}

// the configuration manual's key table is the schema's (regenerate it with `divcoll keys`)
TEST(ConfigSchema, ReadmeTableIsTheSchema) {
  const std::string manual = testing::doc("configs/README.md");
  ASSERT_FALSE(manual.empty()) << "configs/README.md not found";
  EXPECT_NE(manual.find(schema_markdown()), std::string::npos)
      << "configs/README.md's key table differs from the schema: replace it with the output of `divcoll keys`";
}

TEST(ConfigSchema, DefaultsAreValidAndAnEmptyFileGivesThem) {
  EXPECT_NO_THROW(validate(default_config()));
  expect_same(parse_config("", "empty.toml"), default_config());
  // a bare struct is not a config
  EXPECT_THROW(validate(RunConfig{}), InputError);
}

TEST(ConfigErrors, UnknownKeySuggestsTheNearOne) {
  const std::string m = refusal("[agents]\npopulaton = 3\n");
  EXPECT_THAT(m, HasSubstr("unknown key agents.populaton in test.toml"));
  EXPECT_THAT(m, HasSubstr("did you mean agents.population?"));
  // a key in the wrong section points to where it lives
  EXPECT_THAT(refusal("[agents]\nbatch_pairs = 3\n"), HasSubstr("did you mean connectors.batch_pairs?"));
  // and so does one outside every section
  EXPECT_THAT(refusal("seed = 3\n"), HasSubstr("did you mean run.seed?"));
}

TEST(ConfigErrors, UnknownSectionSuggestsTheNearOne) {
  const std::string m = refusal("[agnets]\npopulation = 3\n");
  EXPECT_THAT(m, HasSubstr("unknown section [agnets]"));
  EXPECT_THAT(m, HasSubstr("did you mean [agents]?"));
}

TEST(ConfigErrors, WrongTypeNamesKeyAndTypes) {
  EXPECT_THAT(refusal("[agents]\npopulation = \"100\"\n"),
              HasSubstr("agents.population must be an integer, got a string"));
  EXPECT_THAT(refusal("[agents]\npopulation = 12.0\n"),
              HasSubstr("agents.population must be an integer, got a floating-point number"));
  EXPECT_THAT(refusal("[agents]\nbody_fixed = 1\n"), HasSubstr("agents.body_fixed must be a boolean"));
  EXPECT_THAT(refusal("[scaling]\nsizes = 5\n"), HasSubstr("scaling.sizes must be a list of integers"));
  EXPECT_THAT(refusal("[agents]\ngd_step = \"big\"\n"), HasSubstr("agents.gd_step must be a number"));
  EXPECT_THAT(refusal("agents = 3\n"), HasSubstr("must be a section [agents]"));
  // an integer is a fine double
  EXPECT_EQ(parse_config("[agents]\ngd_step = 1\n", "t").agents.gd_step, 1.0);
}

TEST(ConfigErrors, OutOfRangeNamesKeyAndRange) {
  EXPECT_THAT(refusal("[agents]\npopulation = 0\n"),
              HasSubstr("agents.population = 0 is out of range [2, 100000]"));
  EXPECT_THAT(refusal("[connectors]\nreplicates = -1\n"),
              HasSubstr("connectors.replicates = -1 is out of range [1, 1000]"));
  EXPECT_THAT(refusal("[run]\nseed = -5\n"), HasSubstr("run.seed = -5 is out of range"));
  EXPECT_THAT(refusal("[agents]\nepisode_steps = 0\n"),
              HasSubstr("agents.episode_steps = 0 is out of range"));
  EXPECT_THAT(refusal("[deploy]\nepisode_steps = 0\n"),
              HasSubstr("deploy.episode_steps = 0 is out of range"));
  // open lower bound, closed upper bound, NaN
  EXPECT_THAT(refusal("[agents]\ngd_step = 0.0\n"),
              HasSubstr("agents.gd_step = 0.0 is out of range (0, 10]"));
  EXPECT_NO_THROW(parse_config("[agents]\ngd_step = 10.0\n", "t"));
  EXPECT_THAT(refusal("[agents]\nbody_flip_p = 1.5\n"),
              HasSubstr("agents.body_flip_p = 1.5 is out of range [0, 1]"));
  EXPECT_THAT(refusal("[connectors]\nlr = nan\n"), HasSubstr("connectors.lr = nan is out of range"));
  EXPECT_THAT(refusal("[connectors]\namplitude = 1.0\n"), HasSubstr("connectors.amplitude = 1.0 is out of range [0, 0.9]"));
  // larger than an int holds
  EXPECT_THAT(refusal("[agents]\nepochs = 9999999999999\n"),
              HasSubstr("agents.epochs = 9999999999999 is out of"));
  // the message says where
  EXPECT_THAT(refusal("[agents]\n\npopulation = 0\n"), HasSubstr("test.toml, line 3"));
}

TEST(ConfigErrors, ListElementsChecked) {
  EXPECT_THAT(refusal("[scaling]\nsizes = [5, 1]\n"),
              HasSubstr("scaling.sizes[1] = 1 is out of range [2, 1000]"));
  EXPECT_THAT(refusal("[scaling]\nsizes = []\n"), HasSubstr("scaling.sizes must list at least one value"));
  EXPECT_THAT(refusal("[scaling]\nsizes = [5, 5]\n"), HasSubstr("scaling.sizes lists 5 twice"));
  const std::string env = refusal("[deploy]\nenvironments = [\"flat\", \"moon\"]\n");
  EXPECT_THAT(env, HasSubstr("deploy.environments[1] = \"moon\" is not one of"));
  EXPECT_THAT(env, HasSubstr("treadmill"));  // the known names are listed
  EXPECT_THAT(refusal("[deploy]\nenvironments = [\"ice\"]\n"),
              HasSubstr("deploy.environments must list flat"));
  EXPECT_THAT(refusal("[run]\nstages = [\"agents\", \"agents\"]\n"),
              HasSubstr("run.stages lists \"agents\" twice"));
  EXPECT_THAT(refusal("[connectors]\nkinds = [\"weak_uniform\", 3]\n"),
              HasSubstr("connectors.kinds[1] must be a string, got an integer"));
  EXPECT_THAT(refusal("[agents]\ngd_rule = \"keepbest\"\n"), HasSubstr("did you mean keep_best?"));
}

TEST(ConfigErrors, ImpossibleCombinationsNameBothKeys) {
  // a uniform batch pairs agent i with its clone, i < batch_pairs
  const std::string batch =
      refusal("[agents]\npopulation = 10\n[connectors]\nbatch_pairs = 20\n[deploy]\npairs = 10\n");
  EXPECT_THAT(batch, HasSubstr("connectors.batch_pairs = 20"));
  EXPECT_THAT(batch, HasSubstr("agents.population = 10"));
  // fine with diverse kinds only, or without the connectors stage
  EXPECT_NO_THROW(
      parse_config("[agents]\npopulation = 10\n[connectors]\nbatch_pairs = 20\nkinds = "
                   "[\"weak_diverse\"]\n[deploy]\npairs = 10\n"
                   "[run]\nstages = [\"agents\", \"connectors\", \"deploy\"]\n",
                   "t"));
  const std::string pairs =
      refusal("[agents]\npopulation = 10\n[connectors]\nbatch_pairs = 10\n[deploy]\npairs = 11\n");
  EXPECT_THAT(pairs, HasSubstr("deploy.pairs = 11"));
  EXPECT_THAT(pairs, HasSubstr("agents.population = 10"));
  // uniqueness needs k other agents, in the graded populations too
  const std::string k = refusal("[agents]\nuniqueness_k = 100\n");
  EXPECT_THAT(k, HasSubstr("agents.uniqueness_k = 100"));
  EXPECT_THAT(k, HasSubstr("agents.population = 100"));
  EXPECT_THAT(refusal("[graded]\npopulation = 5\n"), HasSubstr("graded.population = 5"));
  EXPECT_NO_THROW(parse_config("[graded]\npopulation = 5\nenabled = false\n", "t"));
  // chains of N distinct agents
  const std::string chain =
      refusal("[agents]\npopulation = 10\n[connectors]\nbatch_pairs = 10\n[deploy]\npairs = 10\n");
  EXPECT_THAT(chain, HasSubstr("scaling.sizes has 20"));
  EXPECT_THAT(chain, HasSubstr("agents.population = 10"));
  EXPECT_THAT(refusal("[connectors]\nkinds = [\"weak_uniform\", \"strong_diverse\"]\n"),
              HasSubstr("connectors.kinds lacks weak_diverse"));
  // weak is weaker than strong
  const std::string stiff = refusal("[connectors]\nweak_stiffness = 4e4\n");
  EXPECT_THAT(stiff, HasSubstr("connectors.weak_stiffness = 40000.0"));
  EXPECT_THAT(stiff, HasSubstr("connectors.strong_stiffness = 30000.0"));
  // rest lengths need room to move
  const std::string rest = refusal("[agents]\nrest_length_min = 1.0\nrest_length_max = 1.0\n");
  EXPECT_THAT(rest, HasSubstr("agents.rest_length_min"));
  EXPECT_THAT(rest, HasSubstr("agents.rest_length_max"));
  // a fixed body keeps its shape
  EXPECT_THAT(refusal("[agents]\nbody_fixed = true\n"), HasSubstr("agents.body_flip_p"));
  EXPECT_THAT(refusal("[agents]\nbody_fixed = true\nbody_flip_p = 0.0\n"), HasSubstr("agents.rest_moves"));
  EXPECT_THAT(refusal("[agents]\nbody_fixed = true\nbody_flip_p = 0.0\nrest_moves = false\n"),
              HasSubstr("agents.rest_jitter_sd"));
  EXPECT_NO_THROW(
      parse_config("[agents]\nbody_fixed = true\nbody_flip_p = 0.0\nrest_moves = false\n"
                   "rest_jitter_sd = 0.0\n",
                   "t"));
  EXPECT_THAT(refusal("[agents]\nsprings_fixed = true\n"), HasSubstr("agents.spring_flip_p"));
  EXPECT_THAT(
      refusal("[agents]\nbody_fixed = true\nbody_flip_p = 0.0\nrest_moves = false\nrest_jitter_sd = 0.0\n"
              "springs_fixed = true\nspring_flip_p = 0.0\n"),
      HasSubstr("agents.generations"));
  // specialists and scaling run in novel environments
  EXPECT_THAT(refusal("[deploy]\nenvironments = [\"flat\"]\n"), HasSubstr("run.stages has specialists"));
}

TEST(ConfigErrors, AHorizonLongerThanTheEpisodeIsRefused) {
  EXPECT_THAT(refusal("[connectors]\nepisode_steps = 200\nhorizon_start = 300\n"),
              HasSubstr("connectors.horizon_start (300) must not exceed connectors.episode_steps (200)"));
  EXPECT_NO_THROW(parse_config("[connectors]\nepisode_steps = 200\nhorizon_start = 200\n", "test.toml"));
}

TEST(ConfigErrors, MalformedTomlNamesTheFile) {
  EXPECT_THAT(refusal("[agents\npopulation = 3\n"), HasSubstr("test.toml"));
  EXPECT_THAT(
      [] {
        try {
          load_config("/nonexistent/x.toml");
        } catch (const InputError& e) {
          return std::string(e.what());
        }
        return std::string();
      }(),
      HasSubstr("cannot read config file /nonexistent/x.toml"));
}

TEST(ConfigOverrides, ApplyWithTheSameChecks) {
  const RunConfig c = parse_config(
      "[agents]\npopulation = 50\n", "t",
      {"agents.population=12", "run.name=demo", "deploy.environments=flat, ice", "scaling.sizes=3,5",
       "agents.gd_rule=adam", "run.seed = 7", "agents.gd_step=0.5",
       "connectors.kinds=[\"weak_uniform\", \"weak_diverse\"]", "run.name=\"quoted\"",
       "connectors.batch_pairs=8", "deploy.pairs=8", "scaling.draws=4", "agents.rest_moves=false", "output.dir=out/runs"});
  EXPECT_EQ(c.agents.population, 12);  // the override wins over the file
  EXPECT_EQ(c.run.name, "quoted");     // the later override wins
  EXPECT_EQ(c.deploy.environments, (std::vector<std::string>{"flat", "ice"}));
  EXPECT_EQ(c.scaling.sizes, (std::vector<int>{3, 5}));
  EXPECT_EQ(c.agents.gd_rule, "adam");
  EXPECT_EQ(c.run.seed, 7u);
  EXPECT_EQ(c.agents.gd_step, 0.5);
  EXPECT_EQ(c.connectors.kinds.size(), 2u);
  EXPECT_FALSE(c.agents.rest_moves);
  EXPECT_EQ(c.output.dir, "out/runs");
  EXPECT_EQ(apply_overrides(default_config(), {"scaling.sizes=7"}).scaling.sizes, std::vector<int>{7});

  const std::string range = refusal("", {"agents.population=0"});
  EXPECT_THAT(range, HasSubstr("agents.population = 0 is out of range [2, 100000]"));
  EXPECT_THAT(range, HasSubstr("command-line override"));
  const std::string unknown = refusal("", {"agents.populaton=3"});
  EXPECT_THAT(unknown, HasSubstr("unknown key agents.populaton"));
  EXPECT_THAT(unknown, HasSubstr("did you mean agents.population?"));
  EXPECT_THAT(refusal("", {"agents.population=abc"}),
              HasSubstr("agents.population must be an integer, got abc"));
  EXPECT_THAT(refusal("", {"agents.population=\"12\""}),
              HasSubstr("agents.population must be an integer, got a string"));
  EXPECT_THAT(refusal("", {"agents.population=12\nagents.epochs=3"}), HasSubstr("agents.population must be"));
  EXPECT_THAT(refusal("", {"population=3"}), HasSubstr("must look like section.key=value"));
  EXPECT_THAT(refusal("", {"agents.population"}), HasSubstr("must look like section.key=value"));
  EXPECT_THAT(refusal("", {"deploy.environments=flat,moon"}), HasSubstr("\"moon\" is not one of"));
  EXPECT_THAT(refusal("", {"scaling.sizes=1"}), HasSubstr("scaling.sizes[0] = 1 is out of range"));
  // and the cross-key checks
  const std::string batch = refusal("", {"agents.population=20", "deploy.pairs=20", "scaling.sizes=5"});
  EXPECT_THAT(batch, HasSubstr("connectors.batch_pairs = 100"));
  EXPECT_THAT(batch, HasSubstr("agents.population = 20"));
}

TEST(ConfigRoundTrip, ToTomlParsesBackEqual) {
  std::vector<RunConfig> configs = {default_config(), load_config(preset("quick.toml")),
                                    load_config(preset("tiny.toml"))};
  configs.push_back(apply_overrides(
      default_config(),
      {"run.name=a-b_c.d", "agents.gd_step=0.1", "agents.rest_jitter_sd=1e-7", "run.seed=9223372036854775807",
       "connectors.weak_stiffness=1234.5678901234567", "run.progress_every_s=0.1"}));
  for (const RunConfig& c : configs) {
    const std::string text = to_toml(c);
    expect_same(parse_config(text, "resolved.toml"), c);
    // every key is written, each with a comment above it
    for (const auto& [key, value] : flat(c)) {
      const std::string name = key.substr(key.find('.') + 1);
      EXPECT_THAT(text, HasSubstr("\n" + name + " = ")) << key;
    }
    EXPECT_THAT(text, HasSubstr("# size of the evolved population"));
  }
  EXPECT_EQ(configs.back().agents.rest_jitter_sd, 1e-7);
  EXPECT_EQ(configs.back().connectors.weak_stiffness, 1234.5678901234567);
}

TEST(ConfigRoundTrip, FlatPairsAreOverrides) {
  const RunConfig c = load_config(preset("quick.toml"));
  const auto pairs = flat(c);
  EXPECT_EQ(pairs.size(), config_keys().size());
  std::vector<std::string> overrides;
  for (const auto& [key, value] : pairs) {
    EXPECT_THAT(value, Not(HasSubstr("\n"))) << key;
    overrides.push_back(key + "=" + value);
  }
  expect_same(apply_overrides(default_config(), overrides), c);
  // strings bare, numbers as in TOML
  const auto find = [&](const std::string& k) {
    for (const auto& [key, value] : pairs)
      if (key == k) return value;
    return std::string("?");
  };
  EXPECT_EQ(find("agents.population"), "24");
  EXPECT_EQ(find("run.name"), "quick");
  EXPECT_EQ(find("agents.gd_step"), "0.16");
  EXPECT_EQ(find("scaling.sizes"), "[3, 5]");
  EXPECT_EQ(find("graded.enabled"), "true");
}

// run.contact and run.precision reach the run's scenes and episodes as one value, sim::RunPhysics: the defaults
// are the spec's (coulomb, double), each key sets its own field, a name that is neither is refused
TEST(ConfigPhysics, RunPhysicsIsTheConfigsContactAndPrecision) {
  EXPECT_EQ(run_physics(default_config()), (sim::RunPhysics{sim::ContactLaw::coulomb, false}));
  EXPECT_EQ(run_physics(apply_overrides(default_config(), {"run.contact=no_slip"})),
            (sim::RunPhysics{sim::ContactLaw::no_slip, false}));
  EXPECT_EQ(run_physics(apply_overrides(default_config(), {"run.precision=float_networks"})),
            (sim::RunPhysics{sim::ContactLaw::coulomb, true}));
  RunConfig c = default_config();
  c.run.contact = "sticky";
  EXPECT_THROW(run_physics(c), InputError);
  c = default_config();
  c.run.precision = "half";
  EXPECT_THROW(run_physics(c), InputError);
}

TEST(ConfigStages, EnabledFollowsListAndGradedSwitch) {
  RunConfig c = default_config();
  EXPECT_TRUE(stage_enabled(c, "graded"));
  c.graded.enabled = false;
  EXPECT_FALSE(stage_enabled(c, "graded"));
  c = parse_config("[run]\nstages = [\"agents\"]\n", "t");
  EXPECT_TRUE(stage_enabled(c, "agents"));
  EXPECT_FALSE(stage_enabled(c, "deploy"));
}

}  // namespace
// the study's variant keys: impossible combinations are refused naming both keys
TEST(ConfigErrors, VariantKeysNeedTheirCounterparts) {
  EXPECT_THAT(refusal("[analysis]\nalone_protocol = \"training_length\"\n"),
              AllOf(HasSubstr("analysis.alone_protocol = training_length"), HasSubstr("deploy.early_step = 0")));
  EXPECT_THAT(refusal("[deploy]\nearly_step = 3000\n"),
              AllOf(HasSubstr("deploy.early_step = 3000"), HasSubstr("deploy.episode_steps = 3000")));
  EXPECT_THAT(refusal("[deploy]\nuniform_agents = \"held_out\"\n"),
              AllOf(HasSubstr("connectors.batch_pairs + deploy.pairs = 200"), HasSubstr("agents.population = 100")));
  EXPECT_THAT(refusal("[deploy]\nfeature_placement = \"behind\"\n"), HasSubstr("deploy.feature_placement"));
  EXPECT_THAT(refusal("[run]\ncontact = \"sticky\"\n"), AllOf(HasSubstr("run.contact"), HasSubstr("no_slip")));
  EXPECT_THAT(refusal("[analysis]\ncell_scale = 0.0\n"), HasSubstr("analysis.cell_scale = 0"));
  EXPECT_THAT(refusal("[connectors]\nclip = \"pair\"\n"), HasSubstr("connectors.clip"));
  EXPECT_THAT(refusal("[analysis]\nfamiliarity_on = \"outputs\"\n"), HasSubstr("analysis.familiarity_on"));
  EXPECT_THAT(refusal("[connectors]\ndamping = -1.0\n"), HasSubstr("connectors.damping"));
  EXPECT_THAT(refusal("[connectors]\ndamping = 60.0\n"), HasSubstr("connectors.damping"));
  EXPECT_THAT(refusal("[connectors]\nclip = \"per_pair\"\noptimizer = \"es\"\n"),
              AllOf(HasSubstr("connectors.clip = per_pair"), HasSubstr("connectors.optimizer = es")));
  // and the consistent combinations pass
  const RunConfig ok = parse_config("", "test", {"deploy.early_step=1000", "analysis.alone_protocol=training_length",
                                                 "agents.population=150", "connectors.batch_pairs=50",
                                                 "deploy.uniform_agents=held_out"});
  EXPECT_EQ(ok.deploy.early_step, 1000);
  EXPECT_EQ(ok.deploy.uniform_agents, "held_out");
  EXPECT_EQ(parse_config("", "test", {"connectors.clip=per_pair"}).connectors.clip, "per_pair");
}

}  // namespace divcoll::config
