// a fixture for build.layering_catches_violations: science code reaching up into the HDF5 layer
#include "collective/builders.hpp"
#include "io/h5.hpp"
