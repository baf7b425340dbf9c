// the run file's layout as one table (mpi/README.md "Run-file layout", generated from it by `divcoll schema`).
//
// Every group and dataset of a run file has one row: its path (relative to the root; a `{name}`
// placeholder stands for one path segment, e.g. `connectors/{kind}/params`), its element type, its named
// axes (`env, type, replicate, pair`), its unit and a one-line doc. Axes are a second small table: an
// axis has a fixed length and fixed labels (`xy` = x, y), or labels read from an attribute or dataset of
// an enclosing group (`env` = the stage's `environments`), or plain indices.
//
// The io::h5 layer calls attributes() whenever it creates a dataset in a run file (root attribute
// format = "divcoll-run"), so every dataset carries `axes`, `unit` and `doc` attributes and, for each
// labelled axis, `labels_<axis>` (comma separated); a dataset without a row, of another element type or
// another number of dimensions is an internal error there. check() compares a whole file with the table.
//
// A stage that writes rows "through the schema" names its axis lengths, and the table gives the dims:
//   run_file::write_rows<double>(file, p, {{"env", E}, {"type", T}, {"replicate", R}, {"pair", NP}}, rows, v)
// (or file.write_rows<double>(p, run_file::shape(p, {...}), rows, v)).
#pragma once

#include <map>
#include <string>
#include <string_view>
#include <cstdint>
#include <utility>
#include <vector>

#include "io/h5.hpp"

namespace divcoll::io::run_file {

inline constexpr const char* kFormat = "divcoll-run";

// one named axis
struct Axis {
  enum class Labels { none, fixed, attribute, dataset };
  std::string name;
  Labels labels = Labels::none;
  // fixed: the labels, comma separated; attribute / dataset: the name of the attribute (comma separated
  // text) or dataset (its values) looked up on the enclosing groups, nearest first
  std::string source;
  hsize_t length = 0;  // > 0: the same in every run (fixed labels: their count); 0: set by the run
  std::string doc;
  hsize_t alt_length = 0;  // > 0: the one other length a fixed axis may have (the joint connector network's weights)
  bool fits(hsize_t n) const { return length == 0 || n == length || (alt_length > 0 && n == alt_length); }
  // "1473", or "1473 or 3013"
  std::string lengths() const;
};

// one group or dataset
struct Entry {
  std::string path;        // relative to the root ("" for the root); {name} matches one path segment
  std::string dtype;       // "group", or the element type: float64, float32, int64, int32, uint8
  std::string axes;        // datasets: axis names, comma separated, one per dimension
  std::string unit;        // datasets: BL, u, 1, index, count, bits, code, ...
  std::string doc;         // one line
  std::string attributes;  // groups: the attributes the program writes on it, comma separated
  bool graded = false;     // also written under graded/{population}/ (the graded stage's populations)
  bool optional = false;   // written only when a non-default key asks for it (the connector optimisation keys)
  bool is_group() const { return dtype == "group"; }
  std::vector<std::string> axis_names() const;
};

// the tables (entries() includes the graded/{population}/ copies of the rows marked graded)
const std::vector<Axis>& axes();
const std::vector<Entry>& entries();
const Axis* find_axis(std::string_view name);
// the row of a group or dataset path ("deploy/collectives/travel_bl"); the most literal row wins
// (connectors/state/params over connectors/{kind}/params); nullptr if none
const Entry* find(std::string_view path);
// the dataset row of `path`; std::logic_error (an internal error) if there is none
const Entry& dataset(std::string_view path);

// dims of dataset `path` in its axes' order: fixed axes from the table, the others from `lengths`
// (std::logic_error naming the axis if one is missing)
h5::Dims shape(std::string_view path, const std::map<std::string, hsize_t>& lengths);

// creates (or writes in place) dataset `path` of the root `file` with the dims shape() gives, and writes the
// listed rows (h5::Node::write_rows: with MPI-IO every rank calls it); the schema's attributes come with it
template <class T>
void write_rows(const h5::File& file, const std::string& path, const std::map<std::string, hsize_t>& lengths,
                const std::vector<int64_t>& rows, const std::vector<T>& packed) {
  file.write_rows<T>(path, shape(path, lengths), rows, packed);
}

// the layout of dataset `path` as the file gives it: its dims, with the axis names of its `axes` attribute (a
// file written before datasets had attributes: its schema row's). InputError naming the dataset, the axes and
// shape expected and those found, unless its axes are `expected_axes` and each axis of fixed length (e.g.
// connector_weight = P_c) has that length
struct Layout {
  std::vector<std::string> axes;
  h5::Dims dims;
};
Layout layout(const h5::Node& root, const std::string& path, std::string_view expected_axes);

// the string attributes a new dataset of a run file gets (axes, unit, doc, labels_<axis>); none when
// `root` is not a run file. std::logic_error if the dataset has no row or disagrees with it (element
// type, number of dimensions, a fixed length or the count of its labels).
std::vector<std::pair<std::string, std::string>> attributes(const h5::Node& root, const std::string& path,
                                                            const std::string& dtype, const h5::Dims& dims);

// every disagreement between a run file and the table, one sentence each (empty: the file is the table):
// a group or dataset without a row, a group attribute its row does not list, a dataset whose element
// type, dims or attributes differ from its row; with `every_row`, also each row the file lacks
// (a complete run of every stage has them all)
std::vector<std::string> check(const h5::File& f, bool every_row = false);

// mpi/README.md's run-file tables: the axes, then every group and dataset
std::string markdown();

// a copy of a run file turned into the start of a new run that computes stage `from` and the later ones
// (divcoll run --from): their groups dropped, the earlier stages' provenance kept as base_git_commit and
// base_start_time, the run's end and resume counts gone, and the new run's config, provenance (this binary,
// `start_time`) and `derived_from` written
void derive(const h5::Node& root, const std::string& from, const std::string& config_toml,
            const std::string& start_time, const std::string& derived_from);

}  // namespace divcoll::io::run_file
