// The main() of the GoogleTest executables run under mpiexec: MPI started
// and finished around the tests, one report (rank 0's), and the exit status
// failed on every rank when a test failed on any.
#pragma once

#include <gtest/gtest.h>
#include <mpi.h>

inline int run_tests_under_mpi(int argc, char** argv) {
  MPI_Init(&argc, &argv);
  ::testing::InitGoogleTest(&argc, argv);
  int rank = 0;
  MPI_Comm_rank(MPI_COMM_WORLD, &rank);
  if (rank != 0) // one report
    delete ::testing::UnitTest::GetInstance()->listeners().Release(
        ::testing::UnitTest::GetInstance()->listeners().default_result_printer());
  const int failed = RUN_ALL_TESTS();
  int any = failed;
  MPI_Allreduce(&failed, &any, 1, MPI_INT, MPI_MAX, MPI_COMM_WORLD);
  MPI_Finalize();
  return any;
}
