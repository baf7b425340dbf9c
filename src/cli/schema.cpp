// divcoll schema: the run-file schema as mpi/README.md's markdown tables, or a run file checked against it
#include <cstdio>
#include <string>

#include "cli/commands.hpp"
#include "common/check.hpp"
#include "io/h5.hpp"
#include "io/run_file.hpp"

namespace divcoll::cli {

int schema(const std::string& check) {
  if (check.empty()) return std::printf("%s", io::run_file::markdown().c_str()) < 0;
  const io::h5::File f = io::h5::File::open(check);
  if (!f.has_attribute("format") || f.read_string("format") != io::run_file::kFormat)
    throw InputError(check + " is not a divcoll run file (its root attribute format is not \"" +
                     io::run_file::kFormat + "\")");
  const auto problems = io::run_file::check(f);
  for (const std::string& p : problems) std::printf("%s\n", p.c_str());
  std::printf("%s: %s\n", check.c_str(),
              problems.empty() ? "every group and dataset matches the run-file schema"
                               : (std::to_string(problems.size()) + " difference(s) from the run-file schema").c_str());
  return problems.empty() ? 0 : 1;
}

}  // namespace divcoll::cli
