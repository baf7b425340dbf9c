// mpi/agree.hpp under mpirun with 2 and 3 ranks: the check that every rank made the same HDF5 calls on a file
// opened with MPI-IO (io/h5.hpp Journal) passes when they did and stops every rank when one read alone
#include <gtest/gtest.h>
#include <mpi.h>
#include <unistd.h>

#include <filesystem>
#include <string>

#include "common/check.hpp"
#include "io/h5.hpp"
#include "mpi/agree.hpp"

namespace divcoll {
namespace {

TEST(SymmetricIo, AReadByOneRankAloneIsCaughtOnEveryRank) {
  int rank = 0, size = 1;
  MPI_Comm_rank(MPI_COMM_WORLD, &rank);
  MPI_Comm_size(MPI_COMM_WORLD, &size);
  if (size < 2) GTEST_SKIP() << "needs 2 ranks";
  io::h5::enable_journal(true);
  // one path for every rank: rank 0's process id
  long pid = static_cast<long>(::getpid());
  MPI_Bcast(&pid, 1, MPI_LONG, 0, MPI_COMM_WORLD);
  const std::string path = (std::filesystem::temp_directory_path() / ("divcoll_agree_" + std::to_string(pid) + ".h5")).string();
  io::h5::Handle fapl(H5Pcreate(H5P_FILE_ACCESS), H5Pclose);
  H5Pset_fapl_mpio(fapl.id(), MPI_COMM_WORLD, MPI_INFO_NULL);
  {
    io::h5::File f = io::h5::File::create(path, true, fapl.id());
    f.write_int("a", 7);
    f.write_string("b", "x");
    EXPECT_EQ(f.read_int("a"), 7);  // every rank reads: the same calls
    EXPECT_NO_THROW(mpi::check_symmetric_io(MPI_COMM_WORLD, "the first check"));
    EXPECT_TRUE(io::h5::journal().since_check.empty());
    if (rank == 0) {
      EXPECT_EQ(f.read_string("b"), "x");  // rank 0 alone
    }
    try {
      mpi::check_symmetric_io(MPI_COMM_WORLD, "the second check");
      ADD_FAILURE() << "rank " << rank << ": a read by rank 0 alone was not caught";
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find("different HDF5 calls on the run file before the second check"), std::string::npos)
          << e.what();
    }
    f.close();
  }
  io::h5::enable_journal(false);
  MPI_Barrier(MPI_COMM_WORLD);
  if (rank == 0) std::filesystem::remove(path);
}

}  // namespace
}  // namespace divcoll
