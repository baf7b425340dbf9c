// reading trained connector weights back: the layout comes from the file (the dataset's `axes` attribute, or
// its schema row in a file without attributes), and a dataset of another shape or other axes is refused with
// a message naming it, the shape expected and the shape found.
#include "io/run_read.hpp"

#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <functional>
#include <string>
#include <vector>

#include "common/check.hpp"
#include "io/run_file.hpp"
#include "sim/scene.hpp"

namespace divcoll::io {
namespace {

namespace fs = std::filesystem;
using ::testing::HasSubstr;

// `rows` × `cols` weights 0, 1, 2, ... at connectors/weak_uniform/params of a new file (removed with it): a run
// file (its datasets get the schema's attributes) or a plain HDF5 file (no attributes)
struct WeightsFile {
  WeightsFile(const std::string& name, hsize_t rows, hsize_t cols, bool run_file)
      : path(fs::temp_directory_path() / (name + "_" + std::to_string(::getpid()) + ".h5")),
        file(h5::File::create(path.string(), true)) {
    if (run_file) file.write_string("format", run_file::kFormat);
    std::vector<double> v(rows * cols);
    for (size_t k = 0; k < v.size(); ++k) v[k] = static_cast<double>(k);
    std::vector<int64_t> all(rows);
    for (hsize_t r = 0; r < rows; ++r) all[r] = static_cast<int64_t>(r);
    file.write_rows<double>("connectors/weak_uniform/params", {rows, cols}, all, v);
  }
  ~WeightsFile() {
    file.close_quietly();
    fs::remove(path);
  }
  fs::path path;
  h5::File file;
};

// the refusal of `read`, which must name all of `parts`
void refused(const std::function<void()>& read, const std::vector<std::string>& parts) {
  try {
    read();
    ADD_FAILURE() << "accepted";
  } catch (const InputError& e) {
    for (const std::string& p : parts) EXPECT_THAT(e.what(), HasSubstr(p));
  }
}

const hsize_t Pc = static_cast<hsize_t>(sim::connector_param_count());
const std::string kParams = "connectors/weak_uniform/params";

TEST(ReadWeights, RowsComeFromTheFile) {
  const WeightsFile a("divcoll_read_weights_a", 2, Pc, true);
  const h5::File& f = a.file;
  const auto w = read_weights(f, "connectors/weak_uniform", 2);
  ASSERT_EQ(w.size(), 2u);
  ASSERT_EQ(w[1].size(), Pc);
  EXPECT_EQ(w[1][0], static_cast<double>(Pc));
  EXPECT_EQ(read_weights_row(f, "connectors/weak_uniform", 1), w[1]);
  // a file written before datasets had attributes: the layout of the schema's row
  const WeightsFile b("divcoll_read_weights_b", 3, Pc, false);
  const h5::File& g = b.file;
  EXPECT_EQ(read_weights(g, "connectors/weak_uniform", 3).size(), 3u);
}

TEST(ReadWeights, AnotherReplicateCountIsRefusedNamingBothShapes) {
  const WeightsFile c("divcoll_read_weights_c", 2, Pc, true);
  const h5::File& f = c.file;
  const std::string found = "(2, " + std::to_string(Pc) + ")", expected = "(3, " + std::to_string(Pc) + ")";
  refused([&] { read_weights(f, "connectors/weak_uniform", 3); }, {kParams, found, "expected " + expected});
  refused([&] { read_weights_row(f, "connectors/weak_uniform", 2); }, {"--replicate = 2", "[0, 1]"});
}

TEST(ReadWeights, WeightsOfAnotherLengthAreRefused) {
  // not P_c weights per replicate (a plain file: a run file's writer refuses such a dataset itself)
  const WeightsFile d("divcoll_read_weights_d", 2, 7, false);
  const h5::File& f = d.file;
  refused([&] { read_weights(f, "connectors/weak_uniform", 2); },
          {kParams, "(2, 7)", "connector_weight = " + std::to_string(Pc)});
  refused([&] { read_weights_row(f, "connectors/weak_uniform", 0); }, {kParams, "(2, 7)"});
}

TEST(ReadWeights, OtherAxesAreRefused) {
  // a dataset whose own `axes` attribute says it is something else than replicate × connector_weight
  const WeightsFile e("divcoll_read_weights_e", 2, Pc, false);
  const h5::File& f = e.file;
  {
    h5::Handle d(H5Dopen2(f.id(), kParams.c_str(), H5P_DEFAULT), H5Dclose);
    h5::Handle t(H5Tcopy(H5T_C_S1), H5Tclose);
    H5Tset_size(t.id(), H5T_VARIABLE);
    h5::Handle s(H5Screate(H5S_SCALAR), H5Sclose);
    h5::Handle a(H5Acreate2(d.id(), "axes", t.id(), s.id(), H5P_DEFAULT, H5P_DEFAULT), H5Aclose);
    const char* axes = "connector,connector_weight";
    ASSERT_GE(H5Awrite(a.id(), t.id(), &axes), 0);
  }
  refused([&] { read_weights(f, "connectors/weak_uniform", 2); },
          {kParams, "(connector,connector_weight)", "expected the axes (replicate,connector_weight)"});
  // and a group without weights
  refused([&] { read_weights(f, "connectors/weak_diverse", 2); }, {"no connectors/weak_diverse/params"});
}

TEST(ReadAnchors, RowsSetOnTheAgentsAndAnotherPopulationRefused) {
  // 3 agents' anchors in a run file: set on 3 agents; refused for 4 (naming both shapes), and refused where
  // the dataset's axes say it is something else
  const fs::path path = fs::temp_directory_path() / ("divcoll_read_anchors_" + std::to_string(::getpid()) + ".h5");
  {
    h5::File f = h5::File::create(path.string(), true);
    f.write_string("format", run_file::kFormat);
    const std::vector<int32_t> an = {0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11};
    f.write_rows<int32_t>("connectors/anchors", {3, 4}, {0, 1, 2}, an);
    std::vector<morph::Agent> three(3), four(4);
    read_anchors(f, "connectors/anchors", three);
    EXPECT_EQ(three[2].anchors.back_foot, 8);
    EXPECT_EQ(three[2].anchors.front_upper, 11);
    refused([&] { read_anchors(f, "connectors/anchors", four); },
            {"connectors/anchors", "(3, 4)", "expected (4, 4)", "4 agents in the population"});
    refused([&] { check_layout(f, "connectors/anchors", "agent,anchor", {3, 5}, "why"); }, {"expected (3, 5): why"});
    refused([&] { check_layout(f, "connectors/anchors", "env,agent", {3, 4}, "why"); },
            {"expected the axes (env,agent)"});
    refused([&] { check_layout(f, "connectors/none", "agent,anchor", {3, 4}, "why"); }, {"no connectors/none"});
    f.close_quietly();
  }
  fs::remove(path);
}

}  // namespace
}  // namespace divcoll::io
