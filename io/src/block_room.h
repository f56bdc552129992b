// Room for the Blocks of a long program, for the program readers. Internal to vcut::io.
#pragma once

#include <cstddef>
#include <cstdint>
#include <exception>
#include <vector>

#if defined(__linux__)
#include <sys/mman.h>
#include <unistd.h>
#endif

namespace vcut::io::detail {

// The Blocks of a long program are hundreds of MB written once, and first touches of fresh
// pages are what reading them costs most: ask Linux for transparent huge pages on the reserved
// room, so that they fault per 2 MiB instead of per 4 KiB (300 MB on the development VM: 1.0 s
// of page faults without, 0.04 s with). Advice only: where it is refused nothing changes.
inline void prefer_huge_pages(void* data, size_t bytes) {
#if defined(__linux__) && defined(MADV_HUGEPAGE)
  constexpr size_t kWorthIt = size_t{8} << 20;
  const long page = ::sysconf(_SC_PAGESIZE);
  if (bytes < kWorthIt || page <= 0) return;
  const auto p = static_cast<uintptr_t>(page);
  const auto first = reinterpret_cast<uintptr_t>(data);
  const uintptr_t begin = (first + p - 1) / p * p;
  const uintptr_t end = (first + bytes) / p * p;
  if (end > begin) ::madvise(reinterpret_cast<void*>(begin), end - begin, MADV_HUGEPAGE);
#else
  (void)data;
  (void)bytes;
#endif
}

// Reserves room for `more` Blocks beyond those in `blocks`, on huge pages where Linux grants
// them; too large a request leaves the vector to grow as it goes.
template <class T>
void reserve_blocks(std::vector<T>& blocks, std::size_t more) {
  try {
    blocks.reserve(blocks.size() + more);
    prefer_huge_pages(blocks.data() + blocks.size(), (blocks.capacity() - blocks.size()) * sizeof(T));
  } catch (const std::exception&) {
  }
}

}  // namespace vcut::io::detail
