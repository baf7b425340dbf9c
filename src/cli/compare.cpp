// divcoll compare A.h5 B.h5: are two files' datasets identical, bit for bit? (attributes such as times
// and rank counts are provenance and are not compared). Exit 0 if identical, 1 if not, 2 on bad input.
#include <hdf5.h>

#include <cstdio>
#include <map>
#include <string>
#include <vector>

#include "cli/commands.hpp"
#include "common/check.hpp"
#include "io/h5.hpp"

namespace divcoll::cli {

std::map<std::string, std::pair<std::vector<hsize_t>, std::string>> datasets(const std::string& path) {
  io::h5::File f = io::h5::File::open(path);
  std::map<std::string, std::pair<std::vector<hsize_t>, std::string>> out;
  auto visit = [](hid_t obj, const char* name, const H5O_info_t* info, void* data) -> herr_t {
    if (info->type != H5O_TYPE_DATASET) return 0;
    auto& m = *static_cast<std::map<std::string, std::pair<std::vector<hsize_t>, std::string>>*>(data);
    io::h5::Handle d(H5Dopen2(obj, name, H5P_DEFAULT), H5Dclose);
    io::h5::Handle space(H5Dget_space(d.id()), H5Sclose);
    io::h5::Handle type(H5Dget_type(d.id()), H5Tclose);
    const int rank = H5Sget_simple_extent_ndims(space.id());
    std::vector<hsize_t> dims(rank > 0 ? rank : 0);
    if (rank > 0) H5Sget_simple_extent_dims(space.id(), dims.data(), nullptr);
    const size_t n = static_cast<size_t>(H5Sget_simple_extent_npoints(space.id())) * H5Tget_size(type.id());
    std::string bytes(n, '\0');
    if (n > 0 && H5Dread(d.id(), type.id(), H5S_ALL, H5S_ALL, H5P_DEFAULT, bytes.data()) < 0) return -1;
    m[name] = {dims, bytes};
    return 0;
  };
  if (H5Ovisit(f.id(), H5_INDEX_NAME, H5_ITER_INC, visit, &out) < 0)
    throw InputError(msg() << path << ": cannot read every dataset");
  return out;
}

std::string datasets_digest(const std::string& path) {
  uint64_t h = 14695981039346656037ull;  // FNV-1a, 64 bits
  auto feed = [&](const void* p, size_t n) {
    for (size_t i = 0; i < n; ++i) h = (h ^ static_cast<const unsigned char*>(p)[i]) * 1099511628211ull;
  };
  const auto all = datasets(path);
  for (const auto& [name, v] : all) {
    feed(name.c_str(), name.size() + 1);
    const uint64_t rank = v.first.size();
    feed(&rank, sizeof rank);
    for (hsize_t d : v.first) {
      const uint64_t x = d;
      feed(&x, sizeof x);
    }
    feed(v.second.data(), v.second.size());
  }
  char out[64];
  std::snprintf(out, sizeof out, "%016llx", static_cast<unsigned long long>(h));
  return out;
}

int compare(const std::string& a, const std::string& b) {
  const auto A = datasets(a), B = datasets(b);
  int differ = 0;
  for (const auto& [name, v] : A) {
    auto it = B.find(name);
    if (it == B.end()) {
      std::printf("only in %s: %s\n", a.c_str(), name.c_str());
      ++differ;
    } else if (it->second != v) {
      std::printf("differs: %s\n", name.c_str());
      ++differ;
    }
  }
  for (const auto& [name, v] : B)
    if (!A.count(name)) std::printf("only in %s: %s\n", b.c_str(), name.c_str()), ++differ;
  std::printf("%zu datasets compared: %s\n", A.size(), differ ? "DIFFERENT" : "identical");
  return differ ? 1 : 0;
}

}  // namespace divcoll::cli
