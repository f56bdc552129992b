// Morton (Z-order) codes of lattice cells: the bits of x, y and z interleaved, so that cells
// close in the code are close in space (the mesher's brick cells, the endpoint check's order).
#pragma once

#include <cstdint>

namespace vcut::removal {

// The low 21 bits of x spread to every third bit (bit b -> bit 3b).
constexpr std::uint64_t morton_spread(std::uint64_t x) {
  x &= 0x1fffff;
  x = (x | x << 32) & 0x1f00000000ffffULL;
  x = (x | x << 16) & 0x1f0000ff0000ffULL;
  x = (x | x << 8) & 0x100f00f00f00f00fULL;
  x = (x | x << 4) & 0x10c30c30c30c30c3ULL;
  x = (x | x << 2) & 0x1249249249249249ULL;
  return x;
}

// Cell (x, y, z), each below 2^21: bit 3b + a is bit b of the index along axis a.
constexpr std::uint64_t morton_code(std::uint64_t x, std::uint64_t y, std::uint64_t z) {
  return morton_spread(x) | morton_spread(y) << 1 | morton_spread(z) << 2;
}

}  // namespace vcut::removal
