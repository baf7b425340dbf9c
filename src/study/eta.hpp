// how long a study's runs still take: seconds per computed stage, measured on its finished runs (each stage
// group's wall_s), and the clock text of a duration
#pragma once

#include <map>
#include <string>
#include <vector>

namespace divcoll::study {

class StageTimes {
 public:
  // adds the wall_s of the stages `stages` (indices into config::stage_names()) of the run file `path` (a file that
  // cannot be read adds nothing: timings only feed the ETA)
  void add(const std::string& path, const std::vector<int>& stages);
  // the mean seconds of a stage, or -1 when no run of it has ended
  double mean(int stage) const;

 private:
  std::map<int, std::vector<double>> seconds_;
};

// "12m05s" below an hour, "3h02m" above, "unknown" for a negative time
std::string clock_text(double seconds);

}  // namespace divcoll::study
