#include "study/eta.hpp"

#include <cstdio>
#include <exception>

#include "config/config.hpp"
#include "io/h5.hpp"

namespace divcoll::study {

void StageTimes::add(const std::string& path, const std::vector<int>& stages) {
  const auto& names = config::stage_names();
  try {
    io::h5::File f = io::h5::File::open(path);
    for (int k : stages)
      if (f.has(names[k]) && f.group(names[k]).has_attribute("wall_s"))
        seconds_[k].push_back(f.group(names[k]).read_double("wall_s"));
  } catch (const std::exception&) {
    // timings only feed the ETA
  }
}

double StageTimes::mean(int stage) const {
  const auto it = seconds_.find(stage);
  if (it == seconds_.end() || it->second.empty()) return -1.0;
  double m = 0;
  for (double x : it->second) m += x;
  return m / static_cast<double>(it->second.size());
}

std::string clock_text(double s) {
  char b[32];
  if (s < 0) return "unknown";
  if (s < 3600) std::snprintf(b, sizeof b, "%dm%02ds", static_cast<int>(s) / 60, static_cast<int>(s) % 60);
  else std::snprintf(b, sizeof b, "%dh%02dm", static_cast<int>(s) / 3600, static_cast<int>(s) % 3600 / 60);
  return b;
}

}  // namespace divcoll::study
