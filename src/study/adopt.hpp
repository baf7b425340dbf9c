// --adopt RUN.h5: a complete run file made elsewhere taken into the study folder, if its stored config is, key by
// key, the study's run of its (variant, seed) (--variant, else its folder's name); else InputError naming the first
// differing key, nothing written
#pragma once

#include <string>

namespace divcoll::study {

// --adopt RUN.h5: takes the complete run file `run_file` into the folder as the study's run of its (variant,
// seed); `variant` names the variant ("": its folder's name, else the run of its seed whose config it has)
int adopt(const std::string& study_file, const std::string& dir, const std::string& run_file, const std::string& variant);

}  // namespace divcoll::study
