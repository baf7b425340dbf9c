// a fixture for build.layering_catches_violations: the engine reaching up into mpi/ and io/
#include "mpi/driver.hpp"
#include "sim/scene.hpp"
