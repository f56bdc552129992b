// BlockList: what goes in comes back bit for bit, sealed or open, in any order of reading, and
// a raster's sealed blocks cost a small fraction of a Block. The expected values are the
// blocks appended (a round trip), compared field by field on their bytes (-0.0 and NaN too).
#include "vcut/kinematics/block_list.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <limits>
#include <random>
#include <stdexcept>
#include <string>
#include <vector>

namespace vcut::kinematics {
namespace {

template <class T>
bool same_bytes(const T& a, const T& b) {
  return std::memcmp(&a, &b, sizeof(T)) == 0;
}

bool same_vec(const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
  for (int k = 0; k < 3; ++k)
    if (!same_bytes(a[k], b[k])) return false;
  return true;
}

// Every field of Block (program_block.h), by its bytes.
std::string differs(const Block& a, const Block& b) {
  if (a.kind != b.kind) return "kind";
  if (!same_vec(a.start_mm, b.start_mm)) return "start_mm";
  if (!same_vec(a.end_mm, b.end_mm)) return "end_mm";
  if (!same_vec(a.center_mm, b.center_mm)) return "center_mm";
  if (!same_vec(a.normal, b.normal)) return "normal";
  if (a.turns != b.turns) return "turns";
  if (a.tool_pose != b.tool_pose) return "tool_pose";
  if (!same_vec(a.start_axis, b.start_axis)) return "start_axis";
  if (!same_vec(a.end_axis, b.end_axis)) return "end_axis";
  for (std::size_t k = 0; k < 3; ++k) {
    if (!same_bytes(a.start_rotary.angle_rad[k], b.start_rotary.angle_rad[k])) return "start_rotary.angle";
    if (a.start_rotary.given[k] != b.start_rotary.given[k]) return "start_rotary.given";
    if (!same_bytes(a.end_rotary.angle_rad[k], b.end_rotary.angle_rad[k])) return "end_rotary.angle";
    if (a.end_rotary.given[k] != b.end_rotary.given[k]) return "end_rotary.given";
    if (!same_bytes(a.start_extra.value_mm[k], b.start_extra.value_mm[k])) return "start_extra.value";
    if (a.start_extra.given[k] != b.start_extra.given[k]) return "start_extra.given";
    if (!same_bytes(a.end_extra.value_mm[k], b.end_extra.value_mm[k])) return "end_extra.value";
    if (a.end_extra.given[k] != b.end_extra.given[k]) return "end_extra.given";
  }
  if (a.orientation != b.orientation) return "orientation";
  if (!same_vec(a.cone_axis, b.cone_axis)) return "cone_axis";
  if (!same_bytes(a.feed_mm_per_min, b.feed_mm_per_min)) return "feed";
  if (a.feed_mode != b.feed_mode) return "feed_mode";
  if (a.exact_stop != b.exact_stop) return "exact_stop";
  if (!same_bytes(a.blend_tolerance_mm, b.blend_tolerance_mm)) return "blend";
  if (a.tool != b.tool) return "tool";
  if (a.spindle != b.spindle) return "spindle";
  if (!same_bytes(a.spindle_rpm, b.spindle_rpm)) return "rpm";
  if (a.source.file != b.source.file) return "source.file";
  if (a.source.line != b.source.line) return "source.line";
  return "";
}

// Blocks that change every field now and then, most of them continuing from the last (the
// start at the previous end), with lines going forward, back (a subprogram) and far.
std::vector<Block> random_blocks(std::mt19937& rng, std::size_t n) {
  std::uniform_real_distribution<double> x(-500.0, 500.0);
  std::uniform_int_distribution<int> pick(0, 99);
  std::vector<Block> out;
  Block b;
  for (std::size_t i = 0; i < n; ++i) {
    Block next = b;
    next.start_mm = b.end_mm;
    next.start_axis = b.end_axis;
    next.start_rotary = b.end_rotary;
    next.start_extra = b.end_extra;
    next.end_mm[pick(rng) % 3] = x(rng);
    next.source.line = pick(rng) < 90 ? b.source.line + 1 : pick(rng) < 50 ? b.source.line - 40 : 1000000 + pick(rng);
    if (pick(rng) < 5) next.start_mm = {x(rng), -0.0, x(rng)};  // a jump
    if (pick(rng) < 10) next.kind = static_cast<MotionKind>(pick(rng) % 3), next.center_mm = {x(rng), x(rng), x(rng)};
    if (pick(rng) < 5) next.normal = -next.normal, next.turns = 1 + pick(rng) % 4;
    if (pick(rng) < 5) next.tool_pose = !next.tool_pose;
    if (pick(rng) < 10) next.end_axis = Eigen::Vector3d(x(rng), x(rng), x(rng)).normalized();
    if (pick(rng) < 5) next.start_axis = Eigen::Vector3d::UnitX();
    if (pick(rng) < 10) {
      const std::size_t k = static_cast<std::size_t>(pick(rng) % 3);
      next.end_rotary.angle_rad[k] = x(rng) / 100.0;
      next.end_rotary.given[k] = !next.end_rotary.given[k];
    }
    if (pick(rng) < 3) next.start_rotary.given[1] = !next.start_rotary.given[1];
    if (pick(rng) < 5) {  // U V W
      const std::size_t k = static_cast<std::size_t>(pick(rng) % 3);
      next.end_extra.value_mm[k] = x(rng);
      next.end_extra.given[k] = true;
    }
    if (pick(rng) < 2) next.start_extra.value_mm[2] = -0.0;
    if (pick(rng) < 5) next.orientation = static_cast<OrientationMode>(pick(rng) % 4), next.cone_axis = {0, x(rng), 1};
    if (pick(rng) < 20)
      next.feed_mm_per_min = pick(rng) < 50 ? x(rng) + 600.0 : std::numeric_limits<double>::quiet_NaN();
    if (pick(rng) < 5)
      next.feed_mode = next.feed_mode == FeedMode::InverseTime ? FeedMode::UnitsPerMinute : FeedMode::InverseTime;
    if (pick(rng) < 10) next.exact_stop = !next.exact_stop;
    if (pick(rng) < 5) next.blend_tolerance_mm = pick(rng) < 50 ? -0.0 : 0.05;
    if (pick(rng) < 3) next.tool = pick(rng), next.spindle = static_cast<SpindleState>(pick(rng) % 3);
    if (pick(rng) < 5) next.spindle_rpm = x(rng) * 20.0;
    if (pick(rng) < 2) next.source.file = pick(rng) % 4;
    out.push_back(next);
    b = next;
  }
  return out;
}

TEST(BlockList, SealedBlocksComeBackBitForBit) {
  std::mt19937 rng(22);
  const std::vector<Block> blocks = random_blocks(rng, 5000);
  BlockList list;
  for (std::size_t i = 0; i < blocks.size(); ++i) {
    list.push_back(blocks[i]);
    if (i % 300 == 299) list.seal_before(i - 100);  // as a reader does, some blocks left open
  }
  ASSERT_EQ(list.size(), blocks.size());
  ASSERT_GT(list.sealed(), 4000u);
  EXPECT_EQ(list.sealed() % BlockList::kChunk, 0u);
  for (std::size_t i = 0; i < blocks.size(); ++i) ASSERT_EQ(differs(list[i], blocks[i]), "") << "block " << i;
  // Backwards, and at random: the decoding does not depend on what was read before.
  for (std::size_t i = blocks.size(); i-- > 0;) ASSERT_EQ(differs(list[i], blocks[i]), "") << "block " << i;
  std::uniform_int_distribution<std::size_t> any(0, blocks.size() - 1);
  for (int k = 0; k < 3000; ++k) {
    const std::size_t i = any(rng);
    ASSERT_EQ(differs(list.at(i), blocks[i]), "") << "block " << i;
  }
  // Iteration, copies and moves.
  std::size_t i = 0;
  for (const Block& b : list) EXPECT_EQ(differs(b, blocks[i++]), "");
  const BlockList copy = list;
  BlockList moved = std::move(list);
  for (std::size_t j = 0; j < blocks.size(); j += 7) {
    EXPECT_EQ(differs(copy[j], blocks[j]), "");
    EXPECT_EQ(differs(moved[j], blocks[j]), "");
  }
  EXPECT_EQ(differs(moved.back(), blocks.back()), "");
}

TEST(BlockList, OnlyOpenBlocksChange) {
  std::mt19937 rng(5);
  const std::vector<Block> blocks = random_blocks(rng, 600);
  BlockList list;
  for (const Block& b : blocks) list.push_back(b);
  list.seal_before(300);  // two whole chunks: 256
  EXPECT_EQ(list.sealed(), 256u);
  EXPECT_THROW(list.edit(255), std::logic_error);
  EXPECT_THROW(list.edit(600), std::logic_error);
  EXPECT_THROW(list.at(600), std::out_of_range);
  list.edit(256).end_mm.x() = 1.5;
  EXPECT_EQ(list[256].end_mm.x(), 1.5);
  list.seal_before(600);
  EXPECT_EQ(list[256].end_mm.x(), 1.5);  // the change is what was sealed
  EXPECT_EQ(differs(list[257], blocks[257]), "");
}

// A raster's G1 X moves (only X and the line change): about 12 bytes a block once sealed,
// against sizeof(Block) held open (304 on x86-64).
TEST(BlockList, ARasterCostsAFewBytesABlock) {
  BlockList list;
  Block b;
  b.feed_mm_per_min = 2000.0;
  b.tool = 1;
  b.spindle = SpindleState::Clockwise;
  b.end_mm = {0.0, 0.0, 19.0};
  const std::size_t n = 100000;
  for (std::size_t i = 0; i < n; ++i) {
    b.start_mm = b.end_mm;
    b.end_mm.x() = 50.0 * static_cast<double>(i % 1000) / 1000.0;
    b.source.line = static_cast<int>(i) + 7;
    list.push_back(b);
    list.seal_before(list.size());
  }
  const double per_block = static_cast<double>(list.memory_bytes()) / n;
  // Per block: a 1-byte mask, a 1-byte line (the next one: 0), 8 bytes of X and a 2-byte
  // offset, 12 bytes; per chunk of 128 the first block whole with the chunk's two vectors
  // (sizeof(Block) + 48 bytes, ~2.75 a block), the list of chunks growing by doubling: at most
  // 12 + 2 x 2.75 = 17.5. Storing the start (the previous end) would add 24 bytes a block.
  EXPECT_LT(per_block, 12.0 + 2.0 * (sizeof(Block) + 48.0) / BlockList::kChunk);
  EXPECT_GT(per_block, 12.0);
  EXPECT_EQ(list[n - 1].end_mm.x(), b.end_mm.x());
  EXPECT_EQ(list[n - 1].start_mm, list[n - 2].end_mm);
}

}  // namespace
}  // namespace vcut::kinematics
