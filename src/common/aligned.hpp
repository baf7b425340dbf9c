// std::vector storage that starts on a cache line (64 bytes).
//
// Why: the network kernels (src/nn/mlp.cpp) load and store whole 64-byte vectors (AVX-512) from rows whose
// strides are whole cache lines, so when a buffer starts off a line every one of those accesses spans two
// lines. malloc only promises 16 bytes, and which of the four offsets a buffer gets depended on everything
// allocated before it, even on the size of the environment: the same agent training took 16.8 or 18.2 ms
// per agent from one process to the next (SPEC-identical results; measured in the agents stage of the quick
// preset). Buffers that the kernels sweep use this allocator so that the speed is the fast one every
// time, whatever came before.
#pragma once

#include <cstddef>
#include <new>
#include <vector>

namespace divcoll {

inline constexpr std::size_t kCacheLine = 64;

template <class T>
struct CacheLineAllocator {
  using value_type = T;
  CacheLineAllocator() noexcept = default;
  template <class U>
  CacheLineAllocator(const CacheLineAllocator<U>&) noexcept {}
  T* allocate(std::size_t n) {
    return static_cast<T*>(::operator new(n * sizeof(T), std::align_val_t{kCacheLine}));
  }
  void deallocate(T* p, std::size_t) noexcept { ::operator delete(p, std::align_val_t{kCacheLine}); }
  template <class U>
  bool operator==(const CacheLineAllocator<U>&) const noexcept {
    return true;
  }
};

// a vector whose data() is a multiple of 64 bytes
template <class T>
using LineVector = std::vector<T, CacheLineAllocator<T>>;

}  // namespace divcoll
