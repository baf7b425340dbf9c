// writing rows of a dataset (io/h5.hpp Node::write_rows): a run of consecutive rows goes out as one block with
// a memory space of its shape, other row sets as a union of single rows, rows given out of order are sorted with
// their values; either way each row's values land in that row, rows not written keep what they had, and rows
// out of range or given twice are refused.
#include "io/h5.hpp"

#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <string>
#include <vector>

#include "common/check.hpp"

namespace divcoll::io {
namespace {

namespace fs = std::filesystem;

// the value of element (row, a, b) of a 6 × 2 × 3 dataset in these tests
double value(int64_t row, int a, int b, double base) { return base + 100.0 * row + 10.0 * a + b; }

std::vector<double> packed_rows(const std::vector<int64_t>& rows, double base) {
  std::vector<double> v;
  for (int64_t r : rows)
    for (int a = 0; a < 2; ++a)
      for (int b = 0; b < 3; ++b) v.push_back(value(r, a, b, base));
  return v;
}

// reads back the 6 × 2 × 3 dataset g/x of the file at `path` and expects row r to hold value(r, ·, ·, base[r])
void expect_rows(const std::string& path, const double (&base)[6]) {
  h5::File f = h5::File::open(path);
  const std::vector<double> all = f.read<double>("g/x", h5::Dims{6, 2, 3});
  ASSERT_EQ(all.size(), 36u);
  for (int64_t r = 0; r < 6; ++r)
    for (int a = 0; a < 2; ++a)
      for (int b = 0; b < 3; ++b) EXPECT_EQ(all[(r * 2 + a) * 3 + b], value(r, a, b, base[r])) << r << " " << a << " " << b;
  f.close();
}

// each test's files in a folder of its own, removed afterwards whatever the test did (as tests/io/run_file_test.cpp)
class H5WriteRows : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / ("divcoll_h5_test_" + std::to_string(::getpid()));
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }
  std::string path(const std::string& n) const { return (dir_ / n).string(); }

 private:
  fs::path dir_;
};

TEST_F(H5WriteRows, RunsOfRowsAndScatteredRowsLandInTheirRows) {
  const std::string file = path("rows.h5");
  const h5::Dims dims = {6, 2, 3};
  {
    h5::File f = h5::File::create(file, true);
    // every row (one run), then a run in the middle, then rows that are not a run
    f.write_rows<double>("g/x", dims, {0, 1, 2, 3, 4, 5}, packed_rows({0, 1, 2, 3, 4, 5}, 0.0));
    f.write_rows<double>("g/x", dims, {2, 3, 4}, packed_rows({2, 3, 4}, 0.5));
    f.write_rows<double>("g/x", dims, {0, 5}, packed_rows({0, 5}, 0.25));
    // a single row, and no rows at all (a rank with nothing to write)
    f.write_rows<double>("g/x", dims, {1}, packed_rows({1}, 0.125));
    f.write_rows<double>("g/x", dims, {}, {});
    f.close();
  }
  expect_rows(file, {0.25, 0.125, 0.5, 0.5, 0.5, 0.25});
}

TEST_F(H5WriteRows, RowsOutOfRangeAreRefused) {
  const std::string file = path("range.h5");
  {
    h5::File f = h5::File::create(file, true);
    const h5::Dims dims = {6, 2, 3};
    EXPECT_THROW(f.write_rows<double>("g/x", dims, {5, 6}, packed_rows({5, 6}, 0.0)), InputError);   // a run
    EXPECT_THROW(f.write_rows<double>("g/y", dims, {-1, 0}, packed_rows({-1, 0}, 0.0)), InputError);  // a run
    EXPECT_THROW(f.write_rows<double>("g/z", dims, {0, 7}, packed_rows({0, 7}, 0.0)), InputError);   // not a run
    f.close();
  }
}

TEST_F(H5WriteRows, RowsGivenOutOfOrderLandInTheirRows) {
  const std::string file = path("order.h5");
  const h5::Dims dims = {6, 2, 3};
  {
    h5::File f = h5::File::create(file, true);
    f.write_rows<double>("g/x", dims, {0, 1, 2, 3, 4, 5}, packed_rows({0, 1, 2, 3, 4, 5}, 0.0));
    f.write_rows<double>("g/x", dims, {5, 0, 3}, packed_rows({5, 0, 3}, 0.5));
    f.close();
  }
  expect_rows(file, {0.5, 0.0, 0.0, 0.5, 0.0, 0.5});
}

TEST_F(H5WriteRows, ARowGivenTwiceIsRefused) {
  const std::string file = path("twice.h5");
  {
    h5::File f = h5::File::create(file, true);
    EXPECT_THROW(f.write_rows<double>("g/x", {6, 2, 3}, {3, 1, 3}, packed_rows({3, 1, 3}, 0.0)), InputError);
    f.close();
  }
}

// the one way a file's objects and attributes are dropped (a stage redone with --from, a generation written after the
// last commit): a link that is there goes, one that is not is no error
TEST_F(H5WriteRows, RemoveDropsALinkOrAnAttributeIfThereIsOne) {
  {
    h5::File f = h5::File::create(path("r.h5"), true);
    f.write<double>("g/x", {1, 2}, {2});
    f.create_group("g/sub");
    f.write_string("note", "n");
    EXPECT_TRUE(f.remove("g/x"));
    EXPECT_FALSE(f.remove("g/x"));
    EXPECT_FALSE(f.remove("nothing/here"));
    EXPECT_TRUE(f.remove("g"));  // a group with what it holds
    EXPECT_TRUE(f.remove_attribute("note"));
    EXPECT_FALSE(f.remove_attribute("note"));
    f.close();
  }
  h5::File f = h5::File::open(path("r.h5"));
  EXPECT_FALSE(f.has("g"));
  EXPECT_FALSE(f.has_attribute("note"));
}

}  // namespace
}  // namespace divcoll::io
