#include "stages/driver.hpp"

namespace divcoll::stages {

bool complete(const io::h5::Node& file, const std::string& group) {
  return file.has(group) && file.group(group).has_attribute("status") &&
         file.group(group).read_string("status") == "complete";
}

}  // namespace divcoll::stages
