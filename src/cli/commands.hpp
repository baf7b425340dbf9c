// the subcommands of `divcoll` (src/cli/main.cpp registers them with CLI11)
#pragma once

#include <cstdint>
#include <map>
#include <string>
#include <utility>
#include <vector>

#include "morph/agent.hpp"
#include "config/config.hpp"

namespace divcoll::cli {

// divcoll simulate --scene S.h5 --steps T --out TRAJ.h5 [--grad] [--force]
struct SimulateArgs {
  std::string scene, out;
  int steps = 1000;
  bool grad = false;
  bool force = false;
  double memory_limit_gb = 0;  // 0: 80% of MemAvailable
};
int simulate(const SimulateArgs& a);

// divcoll scene --kind agent|pair|chain --env NAME --out S.h5 [--agents N] [--seed S] [--connector weak|strong]
//               [--uniform] [--config RUN.toml] [--force]
struct SceneArgs {
  std::string kind = "pair", env = "flat", out, connector = "weak";
  std::string config;  // the connector stiffness comes from this config's [connectors], the contact law from its
                       // run.contact (default: the paper's)
  int agents = 2;
  uint64_t seed = 1;
  bool uniform = false;
  bool force = false;
};
int scene(const SceneArgs& a);

// divcoll export RUN.h5 --what alone|pair|specialist|chain ... --out S.h5: the scene of one stored episode
struct ExportArgs {
  std::string run, out, what = "pair", env = "flat", type = "weak_diverse@diverse", variant = "diverse";
  int agent = 0, replicate = 0, pair = 0, size = 5, draw = 0;
  bool force = false;
};
int export_scene(const ExportArgs& a);

// divcoll demo --out DIR: a pair on flat and in a novel environment, simulated, travel in body lengths
struct DemoArgs {
  std::string out = "out/demo", env = "step_up";
  std::string run;     // a run file: its trained agents and weak diverse-trained connector (else random ones)
  bool movie = false;  // also render the two episodes as MP4 (divcoll_post.movie --episode)
  uint64_t seed = 1;
  int steps = 1000;
};
int demo(const DemoArgs& a);

// divcoll tether RUN.h5 --out DIR [--pairs N] [--replicate R] [--steps T]: what the run's tethers do to each agent of
// its deployed pairs (collective::tether_effect), every environment of its deployment
struct TetherArgs {
  std::string run, out = "out/tether";
  int pairs = 20, replicate = 0;
  int steps = 0;  // 0: the run's deploy.episode_steps
  bool force = false;
};
int tether(const TetherArgs& a);

// divcoll report RUN.h5 --out DIR: the report pages of a run file (divcoll_post.report under find_python())
struct ReportArgs {
  std::string run, out = "out/report";
  bool movie = false;  // also render the supplementary movie into the page
  std::string keep;    // a study folder only: also copy it as manifest, base config and run summaries to here
};
int report(const ReportArgs& a);  // replaces the process with Python; returns only by throwing

// divcoll movie RUN.h5 --out DIR: the paper's Supplementary Movie as MP4 (divcoll_post.movie, ffmpeg)
struct MovieArgs {
  std::string run, out = "out/movie";
  bool quick = false;  // fewer frames and environments (tests)
};
int movie(const MovieArgs& a);  // replaces the process with Python; returns only by throwing

// the Python the postprocessing (the divcoll_post package) runs under: $DIVCOLL_PYTHON, else the first python3 on
// PATH that imports numpy, h5py and matplotlib, else /usr/bin/python3; `why` says which rule chose it
struct PythonChoice {
  std::string path, why;
};
PythonChoice find_python();
// the postprocess/ folder that holds the divcoll_post package
std::string find_postprocess_dir();
// runs `python -m <module>` of divcoll_post (e.g. "divcoll_post.movie") with args (and --divcoll <this binary>)
// under find_python(), printing which Python; waits and returns its exit status (-1 when it could not start)
int run_python(const std::string& module, const std::vector<std::string>& args);

// divcoll bench: steps per second per core and speed against error
struct BenchArgs {
  double seconds = 0.5;  // minimum timed wall time per row
  bool quick = false;    // fewer rows
  std::string config;    // the connector stiffness comes from this config's [connectors] (default: the paper's)
  std::vector<int> pacmap;  // when given: only the cost of one PaCMAP fit of each of these numbers of states
};
int bench(const BenchArgs& a);

// divcoll gd-compare: gradient rules on the same random agents
struct GdCompareArgs {
  int agents = 20, epochs = 15, steps = 1000;
  uint64_t seed = 1;
};
int gd_compare(const GdCompareArgs& a);

// divcoll grad-diag RUN.h5: the backpropagated gradient of a connector batch objective against finite
// differences, at several horizons and perturbation scales (src/cli/grad_diag.cpp)
struct GradDiagArgs {
  std::string run, kind = "weak_uniform", horizons = "100,250,500,1000", scales = "1e-6,1e-5,1e-4,1e-3,1e-2,1e-1";
  std::vector<std::string> overrides;  // section.key=value on the run file's config
  int pairs = 16, directions = 2, window = 0, train_iterations = 0;
};
int grad_diag(const GradDiagArgs& a);
// a run file's config (with overrides) and final agents with their anchors (InputError if it has none)
struct RunAgents {
  config::RunConfig cfg;
  std::vector<morph::Agent> agents;
  // how these commands run the run's episodes (the anchors' too): under its contact law (run.contact), the
  // networks in double whatever run.precision says
  sim::RunPhysics physics;
};
RunAgents load_run_agents(const std::string& run, const std::vector<std::string>& overrides);

// divcoll connector-opt RUN.h5 [key=value ...] --out PREFIX: connector training with the [connectors] keys
// in one process on a run file's agents, then the trained pairs and their agents alone on flat
struct ConnectorOptArgs {
  std::string run, out, label = "run";
  std::vector<std::string> overrides;
  int eval_pairs = 32;
  std::string eval_steps = "1000,3000";
  bool force = false;
};
int connector_opt(const ConnectorOptArgs& a);

// divcoll compare A B: 0 if every dataset is bit-identical, 1 if not
int compare(const std::string& a, const std::string& b);
// every dataset of a file: path → (dims, raw bytes in the file's own type); attributes are left out
std::map<std::string, std::pair<std::vector<unsigned long long>, std::string>> datasets(const std::string& path);
// one 64-bit digest (FNV-1a, hex) of every dataset's path, shape and bytes, in path order
std::string datasets_digest(const std::string& path);

// divcoll schema [--check RUN.h5]: the run-file schema as markdown (mpi/README.md's tables), or a run file's
// disagreements with it (0 none, 1 some)
int schema(const std::string& check);

// divcoll envs: the built-in environments
int envs();

// refuses an existing output that is a directory ("give the <noun>'s path") or not a regular file (a device
// node: never replaced, even with --force); returns whether the output exists
bool check_existing_output(const std::string& path, const char* noun);

// refuses to overwrite an existing file unless forced, and always refuses an output that is a directory,
// not a regular file (a device node: never replaced, even with --force), or one of `inputs`
void check_output_path(const std::string& path, bool force, const std::vector<std::string>& inputs = {});

}  // namespace divcoll::cli
