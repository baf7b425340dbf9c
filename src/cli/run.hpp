// `divcoll evolve` and `divcoll run`: the MPI entry of the pipeline. Every rank runs this; rank 0 is the
// master and the only printer. The run file is created (or, with --resume, reopened) by all ranks with
// MPI-IO and holds the resolved config and provenance as root attributes.
#pragma once

#include <string>
#include <vector>

#include "config/config.hpp"

namespace divcoll::cli {

struct RunArgs {
  std::string config;                  // TOML file
  std::vector<std::string> overrides;  // "section.key=value"
  std::string out;                     // run file; default <output.dir>/<run.name>.h5
  bool resume = false;                 // continue the run file if it exists (else start it)
  bool force = false;                  // overwrite an existing run file
  bool agents_only = false;            // `evolve`: only the agents stage
  std::string from;                    // --from STAGE: rerun STAGE and the later ones ...
  std::string base;                    // ... on a copy of this run file's earlier stages
};

// initialises MPI, runs, finalises; returns the exit code (2: bad input, 1: failure)
int run_main(int argc, char** argv, const RunArgs& args);
// the same inside an MPI session that is already open (MPI_COMM_WORLD; `divcoll study` runs many)
int run_session(const RunArgs& args);

}  // namespace divcoll::cli
