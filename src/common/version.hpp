// the build's provenance: DIVCOLL_VERSION (a compile definition) and the git commit of the build
#pragma once

namespace divcoll {
// the commit the binary was built from, "-dirty" appended if tracked files differed ("unknown" outside git)
const char* git_commit();
// the instruction set the build compiled the program for, beside its dispatched kernels (nn/kernel_path.hpp):
// "x86-64 baseline", "aarch64 baseline", or "-march=native" (any DIVCOLL_MARCH)
const char* build_target();
}  // namespace divcoll
