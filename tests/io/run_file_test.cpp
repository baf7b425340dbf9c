// the run-file schema: lookup by path (the most literal row wins), shapes from axis lengths, the
// attributes a new dataset of a run file gets (and the refusals of a dataset the table does not have),
// check() of a whole file, and the run-file manual's tables (mpi/README.md). The whole tiny pipeline's file against
// the table is checked in tests/cli/cli_test.cpp (Cli.RunWritesEveryPromisedDatasetOfEachImplementedStage).
#include "io/run_file.hpp"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <filesystem>
#include <set>
#include <stdexcept>
#include <string>
#include <vector>

#include <unistd.h>

#include "testing.hpp"

namespace divcoll::io::run_file {
namespace {

namespace fs = std::filesystem;
using ::testing::Contains;
using ::testing::HasSubstr;
using D = h5::Dims;

std::string row_of(const std::string& path) {
  const Entry* e = find(path);
  return e ? e->path : "(none)";
}

TEST(RunFileSchema, LookupByPathPrefersTheLiteralRow) {
  // path in a file -> its row ("(none)": no row)
  const std::vector<std::pair<std::string, std::string>> cases = {
      {"deploy/collectives/travel_bl", "deploy/collectives/travel_bl"},
      {"/deploy/collectives/travel_bl", "deploy/collectives/travel_bl"},
      {"connectors/weak_diverse/params", "connectors/{kind}/params"},
      {"connectors/state/params", "connectors/state/params"},
      {"specialists/ice/curve_bl", "specialists/{env}/curve_bl"},
      {"agents/gen_012/params", "agents/{generation}/params"},
      {"agents/final/survived", "agents/{generation}/survived"},
      {"scaling/n20/diverse_agents", "scaling/n{N}/diverse_agents"},
      {"graded/same_shape/agents/final/cells", "graded/{population}/agents/{generation}/cells"},
      {"graded/same_shape/connectors/state/adam_v", "graded/{population}/connectors/state/adam_v"},
      {"graded/same_shape/deploy/pairs/status", "graded/{population}/deploy/pairs/status"},
      // a graded population's connectors train as the main ones, keep-best's rows included
      {"graded/same_shape/connectors/weak_diverse/val_bl", "graded/{population}/connectors/{kind}/val_bl"},
      {"", ""},
      {"deploy/collectives/travel", "(none)"},
      {"scaling/m20/diverse_agents", "(none)"},  // n{N} needs its prefix
  };
  for (const auto& [path, row] : cases) EXPECT_EQ(row_of(path), row) << path;
  EXPECT_EQ(row_of("deploy"), "deploy");
  EXPECT_TRUE(find("deploy")->is_group());
  EXPECT_THROW(dataset("deploy"), std::logic_error);
  EXPECT_THROW(dataset("deploy/nothing"), std::logic_error);
}

TEST(RunFileSchema, EveryRowIsWellFormed) {
  std::set<std::string> paths, used_axes;
  for (const Entry& e : entries()) {
    EXPECT_TRUE(paths.insert(e.path).second) << "two rows for " << e.path;
    EXPECT_FALSE(e.doc.empty()) << e.path;
    EXPECT_EQ(find(e.path), &e) << "the row of its own path is " << row_of(e.path);
    if (e.is_group()) {
      EXPECT_TRUE(e.axes.empty() && e.unit.empty()) << e.path;
      continue;
    }
    EXPECT_THAT((std::vector<std::string>{"float64", "float32", "int64", "int32", "uint8"}), Contains(e.dtype)) << e.path;
    EXPECT_FALSE(e.unit.empty()) << e.path;
    EXPECT_FALSE(e.axes.empty()) << e.path;
    for (const std::string& a : e.axis_names()) {
      EXPECT_NE(find_axis(a), nullptr) << e.path << ": axis " << a;
      used_axes.insert(a);
    }
    // its enclosing group has a row
    EXPECT_NE(find(e.path.substr(0, e.path.rfind('/'))), nullptr) << e.path;
  }
  for (const Axis& a : axes()) {
    EXPECT_TRUE(used_axes.count(a.name)) << "axis " << a.name << " is used by no dataset";
    if (a.labels == Axis::Labels::fixed) {
      EXPECT_GT(a.length, 0u) << a.name;
    }
  }
}

TEST(RunFileSchema, ShapeFromAxisLengths) {
  EXPECT_EQ(shape("deploy/collectives/travel_bl", {{"env", 4}, {"type", 8}, {"replicate", 1}, {"pair", 4}}),
            (D{4, 8, 1, 4}));
  // fixed axes need no length
  EXPECT_EQ(shape("connectors/weak_uniform/params", {{"replicate", 3}}), (D{3, 1473}));
  EXPECT_EQ(shape("agents/gen_001/rest_pos", {{"agent", 12}}), (D{12, 11, 2}));
  EXPECT_EQ(shape("deploy/hidden/weak_diverse@diverse/states", {{"env", 2}, {"replicate", 1}, {"pair", 3}, {"sample", 5}}),
            (D{2, 1, 3, 5, 32}));
  try {
    shape("deploy/collectives/travel_bl", {{"env", 4}, {"type", 8}, {"pair", 4}});
    ADD_FAILURE() << "a missing axis length was accepted";
  } catch (const std::logic_error& e) {
    EXPECT_THAT(e.what(), HasSubstr("replicate"));
  }
}

class RunFileWrite : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / ("divcoll_run_file_test_" + std::to_string(::getpid()));
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }
  std::string path(const std::string& n) const { return (dir_ / n).string(); }
  // a run file with a deploy group of two environments and three types
  h5::File run_file(const std::string& n) const {
    h5::File f = h5::File::create(path(n), true);
    f.write_string("format", kFormat);
    const h5::Node g = f.create_group("deploy");
    g.write_string("environments", "flat,ice");
    g.write_string("types", "a@uniform,a@diverse,b@uniform");
    return f;
  }
  fs::path dir_;
};

TEST_F(RunFileWrite, ANewDatasetGetsItsRowsAttributesAndLabels) {
  h5::File f = run_file("a.h5");
  const std::vector<double> v(2 * 3 * 1 * 2, 1.0);
  f.write_rows<double>("deploy/collectives/travel_bl", {2, 3, 1, 2}, {0, 1}, v);
  // also through a subgroup node (the path the schema sees is the one from the root)
  f.group("deploy").write_rows<int32_t>("diverse_pairs", {2, 2}, {0, 1}, {0, 1, 2, 3});
  f.close();
  // read back with check(): nothing differs
  const h5::File r = h5::File::open(path("a.h5"));
  const auto problems = check(r);
  EXPECT_TRUE(problems.empty()) << ::testing::PrintToString(problems);
  // and the values themselves
  const auto attr = [&](const std::string& obj, const std::string& a) {
    h5::Handle o(H5Oopen(r.id(), obj.c_str(), H5P_DEFAULT), H5Oclose);
    h5::Handle at(H5Aopen(o.id(), a.c_str(), H5P_DEFAULT), H5Aclose);
    h5::Handle t(H5Tcopy(H5T_C_S1), H5Tclose);
    H5Tset_size(t.id(), H5T_VARIABLE);
    char* s = nullptr;
    EXPECT_GE(H5Aread(at.id(), t.id(), &s), 0) << obj << " " << a;
    std::string out = s ? s : "";
    H5free_memory(s);
    return out;
  };
  EXPECT_EQ(attr("deploy/collectives/travel_bl", "axes"), "env,type,replicate,pair");
  EXPECT_EQ(attr("deploy/collectives/travel_bl", "unit"), "BL");
  EXPECT_EQ(attr("deploy/collectives/travel_bl", "labels_env"), "flat,ice");
  EXPECT_EQ(attr("deploy/collectives/travel_bl", "labels_type"), "a@uniform,a@diverse,b@uniform");
  EXPECT_EQ(attr("deploy/diverse_pairs", "labels_slot"), "posterior,anterior");
  EXPECT_EQ(attr("deploy/diverse_pairs", "doc"), dataset("deploy/diverse_pairs").doc);
}

TEST_F(RunFileWrite, WriteRowsThroughTheSchemaTakesTheDimsFromTheAxes) {
  h5::File f = run_file("w.h5");
  // 2 environments (the group's labels) x 3 types x 1 replicate x 2 pairs; rank 0 writes both rows
  std::vector<double> v(12);
  for (size_t k = 0; k < v.size(); ++k) v[k] = 0.5 * static_cast<double>(k);
  write_rows<double>(f, "deploy/collectives/travel_u", {{"env", 2}, {"type", 3}, {"replicate", 1}, {"pair", 2}}, {0, 1}, v);
  EXPECT_EQ(f.dims("deploy/collectives/travel_u"), (D{2, 3, 1, 2}));
  EXPECT_EQ(f.read<double>("deploy/collectives/travel_u"), v);
  // fixed axes need no length; a missing one is an internal error
  write_rows<int32_t>(f, "deploy/diverse_pairs", {{"pair", 1}}, {0}, {4, 5});
  EXPECT_EQ(f.dims("deploy/diverse_pairs"), (D{1, 2}));
  EXPECT_THROW(write_rows<double>(f, "deploy/agents/travel_u", {{"agent", 3}}, {}, {}), std::logic_error);
  f.close();
  const auto problems = check(h5::File::open(path("w.h5")));
  EXPECT_TRUE(problems.empty()) << ::testing::PrintToString(problems);
}

TEST_F(RunFileWrite, ADatasetTheSchemaDoesNotHaveIsRefused) {
  h5::File f = run_file("b.h5");
  const auto refused = [&](auto write, const std::string& what) {
    try {
      write();
      ADD_FAILURE() << "accepted: " << what;
    } catch (const std::logic_error& e) {
      EXPECT_THAT(e.what(), HasSubstr(what));
    }
  };
  refused([&] { f.write_rows<double>("deploy/other", {2}, {0, 1}, {1.0, 2.0}); }, "no schema row for dataset deploy/other");
  refused([&] { f.write_rows<float>("deploy/agents/travel_bl", {2, 3}, {}, std::vector<float>{}); }, "float32 elements");
  refused([&] { f.write_rows<double>("deploy/agents/travel_u", {2, 3, 1}, {}, std::vector<double>{}); }, "axes are env,agent");
  refused([&] { f.write_rows<uint8_t>("deploy/agents/status", {3, 3}, {}, std::vector<uint8_t>{}); },
          "axis env has length 3 but 2 labels");
  refused([&] { f.write_rows<double>("connectors/weak_uniform/params", {1, 7}, {}, std::vector<double>{}); },
          "always 1473");
  // outside a run file nothing is looked up
  h5::File other = h5::File::create(path("scene.h5"), true);
  other.write_string("format", "divcoll-scene");
  EXPECT_NO_THROW(other.write<double>("deploy/other", {1.0}, {1}));
}

TEST_F(RunFileWrite, CheckNamesWhatTheSchemaLacks) {
  {
    // written before the file says it is a run file, so the writer does not look anything up
    h5::File f = h5::File::create(path("c.h5"), true);
    f.write<double>("deploy/other", {1.0}, {1});
    f.write<double>("deploy/agents/travel_bl", {1.0, 2.0}, {1, 2});
    f.group("deploy").write_string("colour", "blue");
    f.write_string("format", kFormat);
    f.write_string("planet", "mars");
    f.close();
  }
  const h5::File r = h5::File::open(path("c.h5"));
  const auto problems = check(r);
  const auto has = [&](const std::string& s) {
    for (const auto& p : problems)
      if (p.find(s) != std::string::npos) return true;
    return false;
  };
  EXPECT_TRUE(has("deploy/other: no row in the schema")) << ::testing::PrintToString(problems);
  EXPECT_TRUE(has("/: attribute planet is not in the schema's row"));
  EXPECT_TRUE(has("deploy: attribute colour is not in the schema's row deploy"));
  EXPECT_TRUE(has("deploy/agents/travel_bl: attribute axes missing"));
  EXPECT_TRUE(has("deploy/agents/travel_bl: axis env has length 1 but 0 labels"));
  EXPECT_FALSE(has("deploy/agents/travel_bl: no row"));
  // every row: a complete run has them all; this file has few
  const auto all = check(r, true);
  EXPECT_GT(all.size(), problems.size());
}

// the run-file manual's tables are the schema's (regenerate them with `divcoll schema`)
// divcoll run --from on a copy of a run file: the groups of --from's stage and the later ones go, the earlier ones stay
// with their provenance as base_*, and the copy is a new run (its config, this binary, no end)
TEST_F(RunFileWrite, DeriveKeepsTheEarlierStagesAndStartsANewRun) {
  {
    h5::File f = run_file("base.h5");
    for (const char* g : {"agents", "connectors", "analysis"}) f.create_group(g).write_string("status", "complete");
    f.write_string("config", "old");
    f.write_string("git_commit", "c0");
    f.write_string("start_time", "t0");
    f.write_string("end_time", "t1");
    f.write_int("resumed", 2);
    derive(f, "deploy", "new", "t2", "base.h5 (stages before deploy)");
    f.close();
  }
  h5::File f = h5::File::open(path("base.h5"));
  EXPECT_TRUE(f.has("agents"));
  EXPECT_TRUE(f.has("connectors"));
  EXPECT_FALSE(f.has("deploy"));
  EXPECT_FALSE(f.has("analysis"));
  EXPECT_EQ(f.read_string("config"), "new");
  EXPECT_EQ(f.read_string("base_git_commit"), "c0");
  EXPECT_EQ(f.read_string("base_start_time"), "t0");
  EXPECT_EQ(f.read_string("start_time"), "t2");
  EXPECT_EQ(f.read_string("derived_from"), "base.h5 (stages before deploy)");
  EXPECT_FALSE(f.has_attribute("end_time"));
  EXPECT_FALSE(f.has_attribute("resumed"));
  EXPECT_TRUE(f.has_attribute("git_commit"));
}

TEST(RunFileSchema, ReadmeTablesAreTheSchema) {
  const std::string manual = testing::doc("mpi/README.md");
  ASSERT_FALSE(manual.empty()) << "mpi/README.md not found";
  EXPECT_NE(manual.find(markdown()), std::string::npos)
      << "mpi/README.md's run-file tables differ from the schema: replace them with the output of `divcoll schema`";
  // and the tables name every row and axis
  const std::string md = markdown();
  for (const Axis& a : axes()) EXPECT_THAT(md, HasSubstr("| `" + a.name + "` |"));
  EXPECT_THAT(md, HasSubstr("| `deploy/collectives/travel_bl` | float64 | env × type × replicate × pair | BL |"));
  EXPECT_THAT(md, HasSubstr("| `[graded/{population}/]agents/{generation}/params` |"));
}

}  // namespace
}  // namespace divcoll::io::run_file
