// The program's blocks, stored compactly once the reader is done with them (issue #22: memory
// that does not grow by a Block, 304 bytes, per move). A reader appends blocks and may change
// the ones it has not sealed (axes not yet known, a corner to round, a tilted plane's frame);
// seal_before(i) hands the blocks before i over, and whole chunks of 128 of them are then
// encoded against their chunk's first block (stored whole) and, for the start of the move,
// the block before: a field that equals its prediction costs a bit. A raster's G1 X move is
// about 12 bytes. Blocks are read by value (a sealed block is decoded, in O(1), from its chunk);
// what was appended comes back bit for bit.
#pragma once

#include <cstddef>
#include <cstdint>
#include <deque>
#include <iterator>
#include <vector>

#include "vcut/kinematics/program_block.h"

namespace vcut::kinematics {

class BlockList {
 public:
  BlockList();
  BlockList(const BlockList& other);
  BlockList(BlockList&& other) noexcept;
  BlockList& operator=(const BlockList& other);
  BlockList& operator=(BlockList&& other) noexcept;
  ~BlockList() = default;

  std::size_t size() const { return sealed_ + tail_.size(); }
  bool empty() const { return size() == 0; }
  // Block i, by value (a copy of an open block, the decoding of a sealed one).
  Block operator[](std::size_t i) const;
  Block at(std::size_t i) const;  // throws std::out_of_range
  Block front() const { return at(0); }
  Block back() const { return at(size() - 1); }

  void push_back(const Block& block) { tail_.push_back(block); }
  // Block i to change in place: only a block not yet sealed (i >= sealed()); throws
  // std::logic_error otherwise (a reader's error, not the program's).
  Block& edit(std::size_t i);
  // The blocks before first_open will not change again: whole chunks of them are encoded.
  void seal_before(std::size_t first_open);
  std::size_t sealed() const { return sealed_; }
  std::size_t open() const { return tail_.size(); }
  void clear();
  // Bytes held (chunks, their index and the open blocks), for the memory tests.
  std::size_t memory_bytes() const;

  class const_iterator {
   public:
    using iterator_category = std::random_access_iterator_tag;
    using value_type = Block;
    using difference_type = std::ptrdiff_t;
    using pointer = void;
    using reference = Block;
    const_iterator() = default;
    const_iterator(const BlockList* list, std::size_t i) : list_(list), i_(i) {}
    Block operator*() const { return (*list_)[i_]; }
    Block operator[](difference_type n) const { return (*list_)[i_ + static_cast<std::size_t>(n)]; }
    const_iterator& operator++() { return ++i_, *this; }
    const_iterator operator++(int) { return {list_, i_++}; }
    const_iterator& operator--() { return --i_, *this; }
    const_iterator operator--(int) { return {list_, i_--}; }
    const_iterator& operator+=(difference_type n) { return i_ += static_cast<std::size_t>(n), *this; }
    const_iterator& operator-=(difference_type n) { return i_ -= static_cast<std::size_t>(n), *this; }
    const_iterator operator+(difference_type n) const { return {list_, i_ + static_cast<std::size_t>(n)}; }
    const_iterator operator-(difference_type n) const { return {list_, i_ - static_cast<std::size_t>(n)}; }
    difference_type operator-(const const_iterator& o) const {
      return static_cast<difference_type>(i_) - static_cast<difference_type>(o.i_);
    }
    bool operator==(const const_iterator& o) const { return i_ == o.i_; }
    bool operator!=(const const_iterator& o) const { return i_ != o.i_; }
    bool operator<(const const_iterator& o) const { return i_ < o.i_; }

   private:
    const BlockList* list_ = nullptr;
    std::size_t i_ = 0;
  };
  const_iterator begin() const { return {this, 0}; }
  const_iterator end() const { return {this, size()}; }

  static constexpr std::size_t kChunk = 128;

 private:
  struct Chunk {
    Block anchor;                       // its first block, whole
    std::vector<std::uint8_t> bytes;    // the records of the others
    std::vector<std::uint16_t> offset;  // of record k (k = 1 .. kChunk - 1) at offset[k - 1]
  };
  void decode(std::size_t i, Block& out) const;
  void fresh_id();

  std::vector<Chunk> chunks_;
  std::size_t sealed_ = 0;  // chunks_.size() * kChunk
  std::deque<Block> tail_;  // blocks sealed_ .. size() - 1
  std::uint64_t id_ = 0;    // names this list's sealed blocks in the decoding cache
};

}  // namespace vcut::kinematics
