// the build's provenance: DIVCOLL_VERSION (a compile definition) and the git commit of the build
#pragma once

namespace divcoll {
// the commit the binary was built from, "-dirty" appended if tracked files differed ("unknown" outside git)
const char* git_commit();
}  // namespace divcoll
