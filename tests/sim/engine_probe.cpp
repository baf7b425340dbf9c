// the engine alone, for builds that have no MPI, HDF5 or TOML: a cross-compiled AArch64 engine run under qemu-user
// (tests/cross/aarch64_engine.sh). It reads scenes in a plain binary form, runs each for 300 steps with gradients and
// prints, per scene, a digest (FNV-1a) of the positions, velocities, contacts, travel and every gradient block, and
// the kernel path it ran, and the digest of common/dmath's functions on a fixed grid (common/dmath_grid.hpp). Built
// on the host with DIVCOLL_PROBE_HDF5, `engine_probe --write-scenes DIR SCENE.h5...`
// first writes the binary form of scene files (io/scene_file.hpp).
//   engine_probe SCENE.bin...                     one line per scene: "<file> <digest>", then "kernels <path>"
//   engine_probe --write-scenes DIR SCENE.h5...   (host build only)
// Both forms are little-endian with 64-bit doubles and 32-bit ints, which both architectures share.
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <stdexcept>
#include <string>
#include <vector>

#include "common/dmath_grid.hpp"
#include "nn/kernel_path.hpp"
#include "sim/engine.hpp"
#ifdef DIVCOLL_PROBE_HDF5
#include "io/scene_file.hpp"
#endif

namespace {
using divcoll::sim::Scene;

template <class T>
void put(std::ofstream& o, const T& x) { o.write(reinterpret_cast<const char*>(&x), sizeof x); }
template <class T>
void put(std::ofstream& o, const std::vector<T>& v) {
  put(o, static_cast<uint64_t>(v.size()));
  o.write(reinterpret_cast<const char*>(v.data()), static_cast<std::streamsize>(v.size() * sizeof(T)));
}
template <class T>
void get(std::ifstream& in, T& x) {
  if (!in.read(reinterpret_cast<char*>(&x), sizeof x)) throw std::runtime_error("truncated scene");
}
template <class T>
void get(std::ifstream& in, std::vector<T>& v) {
  uint64_t n = 0;
  get(in, n);
  if (n > (uint64_t(1) << 32)) throw std::runtime_error("bad scene");
  v.resize(n);
  if (!in.read(reinterpret_cast<char*>(v.data()), static_cast<std::streamsize>(n * sizeof(T))))
    throw std::runtime_error("truncated scene");
}

// every field of a scene, in one fixed order (Constants and Segment are plain doubles and ints)
template <class Stream, class Fn>
void fields(Stream& s, Scene& sc, Fn&& f) {
  f(s, sc.constants);
  for (const auto& ef : divcoll::sim::kEnvironmentFields) f(s, sc.env.*(ef.field));
  f(s, sc.env.contact);
  f(s, sc.env.terrain);
  f(s, sc.x0), f(s, sc.mass), f(s, sc.spring_i), f(s, sc.spring_j), f(s, sc.rest_length), f(s, sc.stiffness);
  f(s, sc.amplitude), f(s, sc.damping), f(s, sc.agent_mass_index), f(s, sc.agent_spring_index);
  f(s, sc.agent_params), f(s, sc.connector_spring_index), f(s, sc.connector_params);
}

uint64_t fnv(uint64_t h, const void* p, size_t n) {
  for (size_t i = 0; i < n; ++i) h = (h ^ static_cast<const unsigned char*>(p)[i]) * 1099511628211ull;
  return h;
}
template <class T>
uint64_t fnv(uint64_t h, const std::vector<T>& v) { return fnv(h, v.data(), v.size() * sizeof(T)); }

int probe(int argc, char** argv) {
  for (int k = 1; k < argc; ++k) {
    std::ifstream in(argv[k], std::ios::binary);
    if (!in) throw std::runtime_error(std::string("cannot read ") + argv[k]);
    Scene sc;
    fields(in, sc, [](std::ifstream& s, auto& x) { get(s, x); });
    divcoll::sim::RunOptions opt;
    opt.steps = 300;
    opt.grad = true;
    opt.record = true;
    const divcoll::sim::RunResult r = divcoll::sim::simulate(sc, opt);
    uint64_t h = 14695981039346656037ull;
    h = fnv(h, &r.travel, sizeof r.travel);
    h = fnv(h, &r.status, sizeof r.status);
    for (const std::vector<double>* v : {&r.x, &r.v, &r.grad_agent_params, &r.grad_connector_params, &r.grad_x0,
                                         &r.grad_rest_length})
      h = fnv(h, *v);
    h = fnv(h, r.touch);
    std::string name = argv[k];
    name = name.substr(name.find_last_of('/') + 1);
    std::printf("%s %016llx travel %.17g\n", name.c_str(), static_cast<unsigned long long>(h), r.travel);
  }
  std::printf("dmath %016llx\n", static_cast<unsigned long long>(divcoll::test::dmath_grid_digest()));
  std::printf("kernels %s\n", divcoll::nn::kernel_path_name(divcoll::nn::kernel_path()));
  return 0;
}
}  // namespace

int main(int argc, char** argv) {
  try {
    if (argc > 2 && std::strcmp(argv[1], "--write-scenes") == 0) {
#ifdef DIVCOLL_PROBE_HDF5
      for (int k = 3; k < argc; ++k) {
        Scene sc = divcoll::io::read_scene(argv[k]);
        std::string name = argv[k];
        name = name.substr(name.find_last_of('/') + 1);
        name = name.substr(0, name.rfind('.')) + ".bin";
        std::ofstream out(std::string(argv[2]) + "/" + name, std::ios::binary);
        fields(out, sc, [](std::ofstream& s, auto& x) { put(s, x); });
        if (!out) throw std::runtime_error("cannot write " + name);
      }
      return 0;
#else
      throw std::runtime_error("--write-scenes needs the host build (with HDF5)");
#endif
    }
    if (argc < 2) throw std::runtime_error("usage: engine_probe SCENE.bin... | --write-scenes DIR SCENE.h5...");
    return probe(argc, argv);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "engine_probe: %s\n", e.what());
    return 2;
  }
}
