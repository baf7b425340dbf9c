// DIR --status: every run of a study folder: done / running (job, stage, ETA) / waiting on its base / failed (its
// log's last lines) / not started, and an overall ETA. The job scripts record each run's job in
// DIR/<variant>/seed<k>.job
#pragma once

#include <string>

namespace divcoll::study {

// DIR --status: every run of the folder and what it is doing; 1 when a run failed, else 0
int status(const std::string& dir);

}  // namespace divcoll::study
