#include "vcut/kinematics/block_list.h"

#include <atomic>
#include <cstring>
#include <stdexcept>
#include <string>

namespace vcut::kinematics {
namespace {

// The encoding of block k >= 1 of its chunk: a bit mask (LEB128) of the fields that differ from
// their prediction, the line's distance from the anchor's line + k (zigzag LEB128), then each
// differing field's bytes, in the order of Fields below. Predictions: the chunk's first block
// (the anchor) for every field but the start's, which is the previous block's end (pose, tool
// axis and rotary words). Fields compare by their bytes, so -0.0 and NaN payloads survive.

void put_varint(std::vector<std::uint8_t>& out, std::uint64_t v) {
  while (v >= 0x80) {
    out.push_back(static_cast<std::uint8_t>(v | 0x80));
    v >>= 7;
  }
  out.push_back(static_cast<std::uint8_t>(v));
}

std::uint64_t get_varint(const std::uint8_t*& p) {
  std::uint64_t v = 0;
  for (int shift = 0;; shift += 7) {
    const std::uint8_t byte = *p++;
    v |= static_cast<std::uint64_t>(byte & 0x7f) << shift;
    if (!(byte & 0x80)) return v;
  }
}

// Rotary words and extra axes: which of the three were given, as bits.
template <class Words>
std::uint8_t given_bits(const Words& r) {
  return static_cast<std::uint8_t>(r.given[0] | r.given[1] << 1 | r.given[2] << 2);
}
template <class Words>
void set_given(Words& r, std::uint8_t bits) {
  for (int k = 0; k < 3; ++k) r.given[static_cast<std::size_t>(k)] = (bits >> k) & 1;
}

// What a block's start is predicted from: the previous block's end.
struct Ends {
  Eigen::Vector3d tip_mm, axis;
  RotaryWords rotary;
  ExtraAxes extra;
};
Ends ends_of(const Block& b) { return {b.end_mm, b.end_axis, b.end_rotary, b.end_extra}; }

// Every field in one order for the writer and the reader. V visits (value, prediction).
template <class V>
void fields(V& v, Block& b, const Block& anchor, const Ends& prev) {
  for (int k = 0; k < 3; ++k) v(b.end_mm[k], anchor.end_mm[k]);
  v(b.feed_mm_per_min, anchor.feed_mm_per_min);
  v(b.kind, anchor.kind);
  for (int k = 0; k < 3; ++k) v(b.start_mm[k], prev.tip_mm[k]);
  for (int k = 0; k < 3; ++k) v(b.center_mm[k], anchor.center_mm[k]);
  for (int k = 0; k < 3; ++k) v(b.normal[k], anchor.normal[k]);
  v(b.turns, anchor.turns);
  v(b.tool_pose, anchor.tool_pose);
  for (int k = 0; k < 3; ++k) v(b.start_axis[k], prev.axis[k]);
  for (int k = 0; k < 3; ++k) v(b.end_axis[k], anchor.end_axis[k]);
  for (std::size_t k = 0; k < 3; ++k) v(b.start_rotary.angle_rad[k], prev.rotary.angle_rad[k]);
  v.given(b.start_rotary, prev.rotary);
  for (std::size_t k = 0; k < 3; ++k) v(b.end_rotary.angle_rad[k], anchor.end_rotary.angle_rad[k]);
  v.given(b.end_rotary, anchor.end_rotary);
  for (std::size_t k = 0; k < 3; ++k) v(b.start_extra.value_mm[k], prev.extra.value_mm[k]);
  v.given(b.start_extra, prev.extra);
  for (std::size_t k = 0; k < 3; ++k) v(b.end_extra.value_mm[k], anchor.end_extra.value_mm[k]);
  v.given(b.end_extra, anchor.end_extra);
  v(b.orientation, anchor.orientation);
  for (int k = 0; k < 3; ++k) v(b.cone_axis[k], anchor.cone_axis[k]);
  v(b.feed_mode, anchor.feed_mode);
  v(b.exact_stop, anchor.exact_stop);
  v(b.blend_tolerance_mm, anchor.blend_tolerance_mm);
  v(b.tool, anchor.tool);
  v(b.spindle, anchor.spindle);
  v(b.spindle_rpm, anchor.spindle_rpm);
  v(b.source.file, anchor.source.file);
}

struct Writer {
  std::uint64_t mask = 0;
  int bit = 0;
  std::vector<std::uint8_t> payload;
  template <class T>
  void operator()(T& value, const T& predicted) {
    if (std::memcmp(&value, &predicted, sizeof(T)) != 0) {
      mask |= std::uint64_t{1} << bit;
      const auto* bytes = reinterpret_cast<const std::uint8_t*>(&value);
      payload.insert(payload.end(), bytes, bytes + sizeof(T));
    }
    ++bit;
  }
  template <class Words>
  void given(Words& value, const Words& predicted) {
    std::uint8_t g = given_bits(value);
    (*this)(g, given_bits(predicted));
  }
};

struct Reader {
  std::uint64_t mask = 0;
  int bit = 0;
  const std::uint8_t* p = nullptr;
  template <class T>
  void operator()(T& value, const T& predicted) {
    if ((mask >> bit) & 1) {
      std::memcpy(&value, p, sizeof(T));
      p += sizeof(T);
    } else {
      value = predicted;
    }
    ++bit;
  }
  template <class Words>
  void given(Words& value, const Words& predicted) {
    std::uint8_t g = 0;
    (*this)(g, given_bits(predicted));
    set_given(value, g);
  }
};

void encode(const Block& block, const Block& anchor, std::size_t k, const Ends& prev, std::vector<std::uint8_t>& out) {
  Writer w;
  Block b = block;
  fields(w, b, anchor, prev);
  put_varint(out, w.mask);
  const std::int64_t line =
      static_cast<std::int64_t>(block.source.line) - anchor.source.line - static_cast<std::int64_t>(k);
  put_varint(out, (static_cast<std::uint64_t>(line) << 1) ^ static_cast<std::uint64_t>(line >> 63));
  out.insert(out.end(), w.payload.begin(), w.payload.end());
}

void decode_record(const std::uint8_t* p, const Block& anchor, std::size_t k, const Ends& prev, Block& out) {
  Reader r;
  r.mask = get_varint(p);
  const std::uint64_t z = get_varint(p);
  const std::int64_t line = static_cast<std::int64_t>(z >> 1) ^ -static_cast<std::int64_t>(z & 1);
  r.p = p;
  out = anchor;
  fields(r, out, anchor, prev);
  out.source.line = static_cast<int>(anchor.source.line + static_cast<std::int64_t>(k) + line);
}

std::atomic<std::uint64_t> next_id{1};

// The block decoded last on this thread: consecutive reads of one block (a move's pieces) and
// of the next one (its start is the previous end) cost one record.
struct Decoded {
  std::uint64_t id = 0;
  std::size_t index = 0;
  Block block;
};
thread_local Decoded last_decoded;

}  // namespace

BlockList::BlockList() { fresh_id(); }
BlockList::BlockList(const BlockList& other) : chunks_(other.chunks_), sealed_(other.sealed_), tail_(other.tail_) {
  fresh_id();
}
BlockList::BlockList(BlockList&& other) noexcept
    : chunks_(std::move(other.chunks_)), sealed_(other.sealed_), tail_(std::move(other.tail_)), id_(other.id_) {
  other.sealed_ = 0;
  other.chunks_.clear();
  other.tail_.clear();
  other.fresh_id();
}
BlockList& BlockList::operator=(const BlockList& other) {
  if (this != &other) {
    chunks_ = other.chunks_;
    sealed_ = other.sealed_;
    tail_ = other.tail_;
    fresh_id();
  }
  return *this;
}
BlockList& BlockList::operator=(BlockList&& other) noexcept {
  if (this != &other) {
    chunks_ = std::move(other.chunks_);
    sealed_ = other.sealed_;
    tail_ = std::move(other.tail_);
    id_ = other.id_;
    other.sealed_ = 0;
    other.chunks_.clear();
    other.tail_.clear();
    other.fresh_id();
  }
  return *this;
}

void BlockList::fresh_id() { id_ = next_id.fetch_add(1, std::memory_order_relaxed); }

void BlockList::clear() {
  chunks_.clear();
  tail_.clear();
  sealed_ = 0;
  fresh_id();
}

Block BlockList::operator[](std::size_t i) const {
  if (i >= sealed_) return tail_[i - sealed_];
  Decoded& d = last_decoded;
  if (d.id != id_ || d.index != i) decode(i, d.block), d.id = id_, d.index = i;
  return d.block;
}

Block BlockList::at(std::size_t i) const {
  if (i >= size()) throw std::out_of_range("block " + std::to_string(i) + " of a program of " + std::to_string(size()));
  return (*this)[i];
}

Block& BlockList::edit(std::size_t i) {
  if (i < sealed_ || i >= size())
    throw std::logic_error("block " + std::to_string(i) + " is sealed (or past the end) and cannot change");
  return tail_[i - sealed_];
}

void BlockList::decode(std::size_t i, Block& out) const {
  const Chunk& c = chunks_[i / kChunk];
  const std::size_t k = i % kChunk;
  if (k == 0) {
    out = c.anchor;
    return;
  }
  // The previous block's end: the last one decoded on this thread, or its record.
  Ends prev;
  const Decoded& d = last_decoded;
  if (k == 1) {
    prev = ends_of(c.anchor);
  } else if (d.id == id_ && d.index == i - 1) {
    prev = ends_of(d.block);
  } else {
    Block before;
    const Ends unused{Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero(), RotaryWords{}, ExtraAxes{}};
    decode_record(c.bytes.data() + c.offset[k - 2], c.anchor, k - 1, unused, before);
    prev = ends_of(before);  // the end fields do not depend on the prediction of the start
  }
  decode_record(c.bytes.data() + c.offset[k - 1], c.anchor, k, prev, out);
}

void BlockList::seal_before(std::size_t first_open) {
  while (sealed_ + kChunk <= first_open && tail_.size() >= kChunk) {
    Chunk c;
    c.anchor = tail_.front();
    c.offset.reserve(kChunk - 1);
    for (std::size_t k = 1; k < kChunk; ++k) {
      c.offset.push_back(static_cast<std::uint16_t>(c.bytes.size()));
      encode(tail_[k], c.anchor, k, ends_of(tail_[k - 1]), c.bytes);
    }
    c.bytes.shrink_to_fit();
    chunks_.push_back(std::move(c));
    tail_.erase(tail_.begin(), tail_.begin() + static_cast<std::ptrdiff_t>(kChunk));
    sealed_ += kChunk;
  }
}

std::size_t BlockList::memory_bytes() const {
  std::size_t bytes = chunks_.capacity() * sizeof(Chunk) + tail_.size() * sizeof(Block);
  for (const Chunk& c : chunks_) bytes += c.bytes.capacity() + c.offset.capacity() * sizeof(std::uint16_t);
  return bytes;
}

}  // namespace vcut::kinematics
