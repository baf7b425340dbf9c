#include "config/environments.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <set>

#include "common/check.hpp"
#include "config/toml_parse.hpp"

namespace divcoll::config {
namespace {

// every scalar key with its allowed range: sim::kEnvironmentFields (documented in configs/environments.toml)
using Key = sim::EnvironmentField;

double number_of(const toml::node& n, const std::string& where) {
  if (auto v = n.value<double>()) return *v;
  throw InputError(msg() << where << " must be a number");
}

void read_table(const toml::table& t, const std::string& where, sim::Environment& env,
                std::vector<sim::Segment>& rel) {
  for (auto&& [k, node] : t) {
    const std::string key(k.str());
    const std::string at = where + "." + key;
    if (key == "terrain") {
      const toml::array* arr = node.as_array();
      DIVCOLL_THROW_UNLESS(arr, at << " must be a list of [dx, y, slope] triples");
      rel.clear();
      for (size_t i = 0; i < arr->size(); ++i) {
        const toml::array* seg = (*arr)[i].as_array();
        const std::string ai = at + "[" + std::to_string(i) + "]";
        DIVCOLL_THROW_UNLESS(seg && seg->size() == 3, ai << " must be a triple [dx, y, slope]");
        sim::Segment s{number_of((*seg)[0], ai + "[0] (dx)"), number_of((*seg)[1], ai + "[1] (y)"),
                       number_of((*seg)[2], ai + "[2] (slope)")};
        DIVCOLL_THROW_UNLESS(std::isfinite(s.x_start) && std::isfinite(s.y_start) && std::isfinite(s.slope),
                             ai << " must be finite");
        DIVCOLL_THROW_UNLESS(std::abs(s.y_start) <= 100 && std::abs(s.slope) <= 10,
                             ai << ": y must lie in [-100, 100] and slope in [-10, 10]");
        if (i == 0) {
          DIVCOLL_THROW_UNLESS(s.x_start >= 0, ai << ": dx must be >= 0 (got " << s.x_start << ")");
        } else {
          DIVCOLL_THROW_UNLESS(s.x_start >= rel.back().x_start + 0.01,
                               ai << ": dx must exceed the previous segment's by at least 0.01 u (got "
                                  << s.x_start << " after " << rel.back().x_start << ")");
        }
        rel.push_back(s);
      }
      continue;
    }
    const Key* found = nullptr;
    for (const Key& kk : sim::kEnvironmentFields)
      if (key == kk.name) found = &kk;
    if (!found) {
      std::string known = "terrain";
      for (const Key& kk : sim::kEnvironmentFields) known += std::string(", ") + kk.name;
      throw InputError(msg() << "unknown key " << at << " (known keys: " << known << ")");
    }
    const double v = number_of(node, at);
    const bool ok = std::isfinite(v) && (found->lo_open ? v > found->lo : v >= found->lo) && v <= found->hi;
    DIVCOLL_THROW_UNLESS(ok, at << " = " << v << " is out of range " << (found->lo_open ? "(" : "[")
                                << found->lo << ", " << found->hi << "]");
    env.*(found->field) = v;
  }
}

}  // namespace

std::vector<EnvironmentTable> parse_environments(const std::string& text, const std::string& origin) {
  toml::table root = parse_toml_table(text, origin);
  sim::Environment defaults;
  std::vector<sim::Segment> default_rel;
  if (auto* d = root["defaults"].as_table()) read_table(*d, origin + ": [defaults]", defaults, default_rel);
  std::vector<EnvironmentTable> out;
  for (auto&& [k, node] : root) {
    const std::string name(k.str());
    if (name == "defaults") continue;
    const toml::table* t = node.as_table();
    DIVCOLL_THROW_UNLESS(t, origin << ": top-level key " << name << " must be a table [" << name << "]");
    EnvironmentTable et{defaults, default_rel};
    et.physics.name = name;
    read_table(*t, origin + ": [" + name + "]", et.physics, et.relative);
    out.push_back(std::move(et));
  }
  DIVCOLL_THROW_UNLESS(!out.empty(), origin << ": no environment tables");
  return out;
}

const std::vector<EnvironmentTable>& builtin_environments() {
  static const std::vector<EnvironmentTable> tables = [] {
    auto t = parse_environments(embedded_environments_toml(), "configs/environments.toml");
    // toml++ keeps tables sorted by key; put flat first, the rest in name order
    std::stable_partition(t.begin(), t.end(), [](const EnvironmentTable& e) { return e.physics.name == "flat"; });
    return t;
  }();
  return tables;
}

std::vector<std::string> environment_names() {
  std::vector<std::string> n;
  for (const auto& t : builtin_environments()) n.push_back(t.physics.name);
  return n;
}

std::vector<std::string> novel_environment_names() {
  std::vector<std::string> n;
  for (const auto& t : builtin_environments())
    if (t.physics.name != "flat") n.push_back(t.physics.name);
  return n;
}

bool is_known_environment(const std::string& name) {
  for (const auto& t : builtin_environments())
    if (t.physics.name == name) return true;
  return false;
}

const EnvironmentTable& environment_table(const std::string& name) {
  for (const auto& t : builtin_environments())
    if (t.physics.name == name) return t;
  std::string known;
  for (const auto& t : builtin_environments()) known += (known.empty() ? "" : ", ") + t.physics.name;
  throw InputError(msg() << "unknown environment '" << name << "' (known: " << known << ")");
}

sim::Environment place_environment(const EnvironmentTable& table, double max_x0, sim::ContactLaw law) {
  sim::Environment env = table.physics;
  env.contact = law;
  const double xf = max_x0 + 0.05;
  env.terrain.clear();
  env.terrain.push_back(sim::Segment{-1e9, 0.0, 0.0});
  for (const auto& r : table.relative) {
    env.terrain.push_back(sim::Segment{xf + r.x_start, r.y_start, r.slope});
  }
  return env;
}

}  // namespace divcoll::config
