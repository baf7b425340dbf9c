// what the stages and the commands read back from a run file: the populations an agents stage wrote, the
// trained connector weights (replicates × P_c), the anchors stored with the connectors stage, and the
// comma-separated name lists of the stage attributes. Rank-local reads; nothing here knows MPI.
#pragma once

#include <string>
#include <string_view>
#include <vector>

#include "evo/evolution.hpp"
#include "io/h5.hpp"
#include "morph/agent.hpp"

namespace divcoll::io {

// the layout of `path` as its file gives it (run_file::layout) checked against what the caller expects: the
// axes `axes` (comma-separated) and the shape `dims`; InputError naming the dataset, the shape and axes
// found and the shape expected with `why` (e.g. "13 environments × 100 agents, as deploy's config says")
void check_layout(const h5::Node& file, const std::string& path, std::string_view axes, const h5::Dims& dims,
                  const std::string& why);
// `path` read after check_layout
template <class T>
std::vector<T> read_checked(const h5::Node& file, const std::string& path, std::string_view axes,
                            const h5::Dims& dims, const std::string& why) {
  check_layout(file, path, axes, dims, why);
  return file.read<T>(path, dims);
}

// names as one comma-separated attribute value, and back
std::string join(const std::vector<std::string>& v);
std::vector<std::string> split(const std::string& s);

// every row of a pool group written by the agents stage (gen_NNN or final); `survived` if given gets its
// survived column
std::vector<evo::Individual> read_pool(const h5::Node& file, const std::string& g, std::vector<uint8_t>* survived);
// the final population of a run file's agents stage (`group` = agents or a graded population's agents)
std::vector<evo::Individual> read_final_population(const h5::Node& file, const std::string& group = "agents");

// the weights layout of trained connectors: one row of P_c = sim::connector_param_count() values per
// replicate (sim::connector_param_count(true) with connectors.network = joint), rows × P_c in the run file
// (`<group>/params`)
std::vector<std::vector<double>> split_weights(const std::vector<double>& flat, size_t rows);
std::vector<double> join_weights(const std::vector<std::vector<double>>& rows);
// `<group>/params` with the layout the file gives it (run_file::layout: its axes must be replicate,
// connector_weight and P_c long); InputError naming the dataset, the shape expected and the shape found
// unless it also has `replicates` rows
std::vector<std::vector<double>> read_weights(const h5::Node& file, const std::string& group, int replicates);
// one replicate's row of `<group>/params` (any number of rows in the file; `row` checked against it)
std::vector<double> read_weights_row(const h5::Node& file, const std::string& group, int row);

// where the anchors of the population in `population_group` are stored: `<prefix>connectors/anchors` for
// `<prefix>agents` (connectors/anchors for the main population, graded/<name>/connectors/anchors for a graded one)
std::string anchors_path(const std::string& population_group);
// the anchors of a population as stored (population × 4: back foot, front foot, back upper, front upper)
std::vector<int32_t> anchors_rows(const std::vector<morph::Agent>& agents);
// the stored anchors set on `agents` (the dataset's layout checked: agent × anchor, one row per agent)
void read_anchors(const h5::Node& file, const std::string& path, std::vector<morph::Agent>& agents);

}  // namespace divcoll::io
