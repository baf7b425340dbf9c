// environment tables (configs/environments.toml, SPEC §3): read, checked, placed in a scene
#pragma once

#include <string>
#include <vector>

#include "sim/scene.hpp"

namespace divcoll::config {

// one table of environments.toml: constants plus terrain relative to the scene front x_f
struct EnvironmentTable {
  sim::Environment physics;              // name and constants; terrain left empty
  std::vector<sim::Segment> relative;    // (dx, y, slope) segments relative to x_f
};

// the text of configs/environments.toml as compiled into the binary
const char* embedded_environments_toml();

// parses and checks a TOML text of environment tables; throws InputError naming the table, key and
// allowed range on a bad key or value. `origin` names the source in messages.
std::vector<EnvironmentTable> parse_environments(const std::string& toml_text, const std::string& origin);

// the built-in tables (parsed once)
const std::vector<EnvironmentTable>& builtin_environments();
// names of the built-in environments, flat first, in file order
std::vector<std::string> environment_names();
// the 12 novel environments (every built-in one but flat)
std::vector<std::string> novel_environment_names();
bool is_known_environment(const std::string& name);
// the named built-in table; throws InputError listing the known names if there is none
const EnvironmentTable& environment_table(const std::string& name);

// the environment placed for a scene whose largest initial x is `max_x0`:
// features start at x_f = max_x0 + 0.05 (SPEC §3); the first segment is flat ground at y = 0;
// its contact law is `law` (the run's run.contact: config::run_physics)
sim::Environment place_environment(const EnvironmentTable& table, double max_x0, sim::ContactLaw law);

}  // namespace divcoll::config
