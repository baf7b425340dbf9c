// the task farm and the parallel row writes, under mpirun with 2 and 3 ranks
#include <gtest/gtest.h>
#include <mpi.h>

#include <cstdio>
#include <filesystem>
#include <string>

#include "io/h5.hpp"
#include "mpi/protocol.hpp"
#include "mpi/scheduler.hpp"

namespace divcoll {
namespace {

int rank_of(MPI_Comm c = MPI_COMM_WORLD) {
  int r = 0;
  MPI_Comm_rank(c, &r);
  return r;
}
int size_of(MPI_Comm c = MPI_COMM_WORLD) {
  int s = 1;
  MPI_Comm_size(c, &s);
  return s;
}

TEST(Farm, EveryItemIsComputedOnceAndResultsArriveInItemOrder) {
  ASSERT_GE(size_of(), 2) << "run me under mpirun -np 2 or more";
  const int n = 37;
  std::vector<std::string> items;
  if (rank_of() == 0)
    for (int i = 0; i < n; ++i) items.push_back(mpi::pack(static_cast<int64_t>(i)));
  int computed_here = 0;
  const mpi::FarmResult r = mpi::farm(MPI_COMM_WORLD, items, [&](const std::string& b) {
    ++computed_here;
    const int64_t i = mpi::unpack<int64_t>(b);
    return mpi::pack(i * i + 7);
  });
  ASSERT_EQ(static_cast<int>(r.owner.size()), n);
  // every item computed exactly once over all ranks
  int total = 0;
  MPI_Allreduce(&computed_here, &total, 1, MPI_INT, MPI_SUM, MPI_COMM_WORLD);
  EXPECT_EQ(total, n);
  // the master holds every result, in item order; a worker holds exactly the items it computed
  for (int i = 0; i < n; ++i) {
    EXPECT_GE(r.owner[i], 0);
    EXPECT_LT(r.owner[i], size_of());
    if (rank_of() == 0 || r.owner[i] == rank_of()) {
      ASSERT_FALSE(r.results[i].empty()) << "item " << i;
      EXPECT_EQ(mpi::unpack<int64_t>(r.results[i]), int64_t(i) * i + 7);
    } else {
      EXPECT_TRUE(r.results[i].empty());
    }
  }
  int mine = 0;
  for (int o : r.owner) mine += o == rank_of();
  EXPECT_EQ(mine, computed_here);
}

TEST(Farm, WorkersShareTheWorkWhenItemsAreSlow) {
  const int n = 12;
  std::vector<std::string> items(rank_of() == 0 ? n : 0, mpi::pack(int64_t{1}));
  const mpi::FarmResult r = mpi::farm(MPI_COMM_WORLD, items, [](const std::string&) {
    double s = 0;
    for (int k = 0; k < 3000000; ++k) s += 1e-9 * k;  // a few ms
    return mpi::pack(static_cast<int64_t>(s > 0));
  });
  std::vector<int> per_rank(size_of(), 0);
  for (int o : r.owner) ++per_rank[o];
  for (int q = 1; q < size_of(); ++q) EXPECT_GT(per_rank[q], 0) << "worker " << q << " got no item";
}

TEST(ParallelHdf5, EachRankWritesItsRowsOfOneDataset) {
  std::string path = (std::filesystem::temp_directory_path() / "divcoll_rows_XXXXXX").string();
  if (rank_of() == 0) path = std::string(mkdtemp(path.data())) + "/rows.h5";
  int len = static_cast<int>(path.size());
  MPI_Bcast(&len, 1, MPI_INT, 0, MPI_COMM_WORLD);
  path.resize(len);
  MPI_Bcast(path.data(), len, MPI_CHAR, 0, MPI_COMM_WORLD);
  const int rows = 10, width = 3;
  {
    io::h5::Handle fapl(H5Pcreate(H5P_FILE_ACCESS), H5Pclose);
    H5Pset_fapl_mpio(fapl.id(), MPI_COMM_WORLD, MPI_INFO_NULL);
    io::h5::File f = io::h5::File::create(path, true, fapl.id());
    // rows i with i % size == rank, value 100 i + column
    std::vector<int64_t> mine;
    std::vector<double> packed;
    for (int i = 0; i < rows; ++i)
      if (i % size_of() == rank_of()) {
        mine.push_back(i);
        for (int c = 0; c < width; ++c) packed.push_back(100.0 * i + c);
      }
    f.write_rows<double>("g/data", {rows, width}, mine, packed);
    f.close();
  }
  MPI_Barrier(MPI_COMM_WORLD);
  if (rank_of() == 0) {
    io::h5::File f = io::h5::File::open(path);
    const std::vector<double> all = f.read<double>("g/data", io::h5::Dims{rows, width});
    for (int i = 0; i < rows; ++i)
      for (int c = 0; c < width; ++c) EXPECT_EQ(all[i * width + c], 100.0 * i + c);
    std::filesystem::remove_all(std::filesystem::path(path).parent_path());
  }
}

}  // namespace
}  // namespace divcoll
