#include "vcut/pipeline/simulate.h"

#include <Eigen/Geometry>
#include <tbb/global_control.h>
#include <tbb/info.h>
#include <tbb/task_group.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <fstream>
#include <limits>
#include <map>
#include <memory>
#include <set>
#include <sstream>
#include <utility>

#include "vcut/io/input_error.h"
#include "vcut/io/mesh_io.h"
#include "vcut/io/program_reader.h"
#include "vcut/pipeline/machine_check.h"
#include "vcut/pipeline/poses.h"
#include "vcut/removal/compare.h"
#include "vcut/removal/dexel_stock.h"
#include "vcut/removal/endpoint_check.h"
#include "vcut/removal/sweep.h"
#include "vcut/removal/vdb_stock.h"

namespace vcut::pipeline {

double peak_memory_mb() {
  std::ifstream status("/proc/self/status");
  std::string line;
  while (std::getline(status, line))
    if (line.rfind("VmHWM:", 0) == 0) return std::stod(line.substr(6)) / 1024.0;  // kB
  return 0.0;
}

namespace {

using Clock = std::chrono::steady_clock;

// The report page's playback: at most this many machine poses (up to about 6 MB of the page
// for a five-axis machine: 12 floats per node and frame), and ten times as many tool path points.
constexpr std::size_t kPlaybackFrames = 20000;

double total_ram_mb() {
  const long pages = ::sysconf(_SC_PHYS_PAGES), page = ::sysconf(_SC_PAGE_SIZE);
  return pages > 0 && page > 0 ? static_cast<double>(pages) * static_cast<double>(page) / (1024.0 * 1024.0) : 4096.0;
}

// Consecutive lines of one file merge into a span; in the order of file name, then line.
std::vector<kinematics::SourceSpan> merge_lines(const kinematics::Program& program,
                                                std::vector<kinematics::SourceRef> refs) {
  const auto key = [&](const kinematics::SourceRef& r) {
    return std::make_pair(std::cref(program.files[static_cast<std::size_t>(r.file)]), r.line);
  };
  std::sort(refs.begin(), refs.end(), [&](const auto& a, const auto& b) { return key(a) < key(b); });
  refs.erase(std::unique(refs.begin(), refs.end(),
                         [](const auto& a, const auto& b) { return a.file == b.file && a.line == b.line; }),
             refs.end());
  std::vector<kinematics::SourceSpan> out;
  for (std::size_t i = 0; i < refs.size();) {
    std::size_t j = i;
    while (j + 1 < refs.size() && refs[j + 1].file == refs[i].file && refs[j + 1].line == refs[j].line + 1) ++j;
    out.push_back({refs[i].file, refs[i].line, refs[j].line});
    i = j + 1;
  }
  return out;
}

// One record per run of consecutive blocks with the same kind of collision (a shank
// dragging through material for a hundred moves is one event): lines as a range, the
// deepest depth and where it was.
std::vector<CollisionRecord> collision_records(const std::vector<removal::Collision>& found, CutMoves& moves,
                                               const kinematics::Program& program) {
  std::vector<removal::Collision> sorted = found;
  std::sort(sorted.begin(), sorted.end(), [](const auto& a, const auto& b) { return a.move < b.move; });
  std::vector<CollisionRecord> out;
  std::map<removal::ProbeKind, std::size_t> open;  // kind -> its latest record
  for (const removal::Collision& c : sorted) {
    const auto move = static_cast<std::size_t>(c.move);
    const int block = moves.block(move);
    const kinematics::Block& b = program.blocks[static_cast<std::size_t>(block)];
    const removal::ProbeKind kind = moves.probe_kind(move);
    const auto it = open.find(kind);
    CollisionRecord* r = nullptr;
    if (it != open.end() && out[it->second].tool == b.tool && block <= out[it->second].last_block + 1)
      r = &out[it->second];
    if (r == nullptr) {
      open[kind] = out.size();
      r = &out.emplace_back();
      r->probe = kind;
      r->lines = {b.source, b.source};
      r->tool = b.tool;
      r->first_block = r->last_block = block;
    }
    if (block != r->last_block) {
      r->last_block = block;
      if (b.source.file == r->lines.first.file && b.source.line > r->lines.first.line) r->lines.last = b.source;
    }
    ++r->moves;
    if (c.depth_mm > r->depth_mm) {
      r->depth_mm = c.depth_mm;
      r->where_mm = c.where_mm;
      r->deepest_line = b.source;
    }
  }
  return out;
}

}  // namespace

const char* collision_kind(removal::ProbeKind probe) {
  switch (probe) {
    case removal::ProbeKind::Rapid:
      return "rapid_into_stock";
    case removal::ProbeKind::Shank:
      return "shank_collision";
    case removal::ProbeKind::Holder:
      return "holder_collision";
    case removal::ProbeKind::SpindleStopped:
      return "spindle_stopped_cut";
  }
  return "collision";
}

const char* collision_part(removal::ProbeKind probe) {
  switch (probe) {
    case removal::ProbeKind::Shank:
      return "shank";
    case removal::ProbeKind::Holder:
      return "holder";
    default:
      return "cutting part";
  }
}

std::vector<std::string> warnings_of(const io::Job& job, const PoseRun& run) {
  std::vector<std::string> warnings = job.warnings;
  warnings.insert(warnings.end(), run.program.warnings.begin(), run.program.warnings.end());
  for (const PoseEvent& e : run.events)
    if (e.kind == PoseEventKind::Unreachable)
      warnings.push_back(run.program.where(e.lines) + ": pose out of the machine's reach: " + e.detail);
  warnings.insert(warnings.end(), run.warnings.begin(), run.warnings.end());
  return warnings;
}

removal::StockShape stock_shape(const io::Job& job) {
  switch (job.stock.kind) {
    case io::StockSpec::Kind::Box:
      return job.stock.box;
    case io::StockSpec::Kind::Cylinder:
      return job.stock.cylinder;
    case io::StockSpec::Kind::Mesh:
      break;
  }
  removal::TriangleMesh mesh = io::read_mesh(job.stock.mesh_file);
  if (!removal::is_closed(mesh))
    throw InputError(
        job.stock.mesh_file, 0, 0,
        "stock mesh is not closed (every edge must join exactly two triangles), so its inside is undefined");
  if (removal::signed_volume_mm3(mesh) < 0.0)
    for (auto& t : mesh.triangles) std::swap(t[1], t[2]);
  return mesh;
}

std::optional<removal::TriangleMesh> design_of(const io::Job& job) {
  if (!job.design) return std::nullopt;
  removal::TriangleMesh design = placed_mesh(io::read_mesh(job.design->file), *job.design);
  const auto& t = design.triangles;
  const auto& x = design.vertices_mm;
  if (std::all_of(t.begin(), t.end(), [&](const Eigen::Vector3i& f) {
        return removal::degenerate_triangle(x[static_cast<std::size_t>(f[0])], x[static_cast<std::size_t>(f[1])],
                                            x[static_cast<std::size_t>(f[2])]);
      }))
    throw InputError(job.design->file, 0, 0, "design mesh has no triangle of nonzero area");
  return design;
}

// 3. Moves: every block's tool must be known; a five-axis move (the axis turning) is cut as
// translation pieces within the turn tolerance of the rigid motion (min(v/10, gouge
// tolerance / 2) unless the job sets engine.turn_tolerance: removal::five_axis_split, for
// the part of the cutter that can come inside the stock's box: turning_height; a long ball
// end mill part by part: removal::cutter_parts). With `probes`, the tool's shank and holder
// follow every move and a feed move made with the spindle stopped is probed before it cuts
// (collisions).
CutMoves::CutMoves(const PoseRun& run, bool actual, bool probes, double turn_tolerance_mm)
    : run_(run), actual_(actual), probes_(probes), rotation_bound_mm_(turn_tolerance_mm) {
  const kinematics::Program& program = run.program;
  removal::MoveList tools;
  for (const auto& b : program.blocks) {
    if (b.tool == 0) {
      if (b.kind != kinematics::MotionKind::Rapid)
        throw InputError(program.where(b.source) +
                         ": feed move with no tool in the spindle (expected T<n> M6 before it)");
      continue;
    }
    if (cutter_index_.count(b.tool)) continue;
    cutter_index_[b.tool] = static_cast<int>(tools.cutters.size());
    tools.cutters.push_back(run.tools.at(b.tool));
  }
  // The shank and holder of every tool (their cutters follow the tools' in the list).
  bodies_ = removal::add_tool_bodies(tools);
  cutters_ = std::move(tools.cutters);
  // The parts a long ball end mill turns in, after the shanks and holders (no body of their
  // own: the shank and holder follow the tool's moves).
  const std::size_t n_tools = cutter_index_.size();
  parts_.resize(n_tools);
  parts_first_.assign(n_tools, -1);
  halves_.resize(n_tools);
  for (std::size_t i = 0; i < n_tools; ++i) {
    parts_[i] = removal::cutter_parts(cutters_[i]);
    if (parts_[i].size() < 2) continue;
    parts_first_[i] = static_cast<int>(cutters_.size());
    for (const removal::CutterPart& part : parts_[i]) cutters_.push_back(part.cutter);
    if (cutters_[i].type != removal::CutterType::Ball) continue;
    halves_[i] = removal::halved_parts(parts_[i]);  // their cutters right after the parts'
    for (const removal::CutterPart& part : halves_[i]) cutters_.push_back(part.cutter);
  }
  if (run.streamed && !actual) {
    // Only the poses: the axis values are not needed for the moves unless a block's poses
    // start from the previous sample's axes (PoseRun::poses_need_axes).
    densifier_.emplace(program, run.densify_settings, run.densify_machine, !run.poses_need_axes);
  } else {
    samples_ = actual ? run.actual_path.size() : run.densified.samples.size();
  }
  rewind();
}

void CutMoves::counted() {
  if (counted_) return;
  rewind();
  std::vector<removal::Move> batch;
  while (next(batch, 4096)) batch.clear();
  rewind();
}

void CutMoves::record(const kinematics::ToolPose& from, const kinematics::ToolPose& to,
                      const std::vector<removal::Move>& moves, std::size_t first) {
  if (moves.size() == first) return;
  const bool rapid =
      run_.program.blocks[static_cast<std::size_t>(moves[first].block)].kind == kinematics::MotionKind::Rapid;
  cutting_moves_ += !rapid;
  rotating_moves_ += (from.axis - to.axis).norm() > 1e-12;
  for (std::size_t i = first; i < moves.size(); ++i) {
    const removal::Move& m = moves[i];
    blocks_.push_back(m.block);
    kinds_.push_back(m.rapid ? static_cast<std::uint8_t>(m.probe) : kCut);
    count_ += !m.rapid || m.probe == removal::ProbeKind::Rapid;
  }
}

void CutMoves::rewind() {
  sample_ = 1;
  // A pass from the first move to the last records the counts and attribution, once.
  recording_ = !counted_;
  if (recording_) {
    blocks_.clear();
    kinds_.clear();
    count_ = cutting_moves_ = rotating_moves_ = 0;
  }
  if (!densifier_) return;
  densifier_->rewind();
  pending_.clear();
  pending_next_ = 0;
  last_ = densifier_->start().pose;
}

bool CutMoves::step(kinematics::ToolPose& from, kinematics::ToolPose& to, int& block) {
  if (!densifier_) {
    if (sample_ >= samples_) return false;
    const std::size_t i = sample_++;
    from = actual_ ? run_.actual_path[i - 1].pose : run_.densified.samples[i - 1].pose;
    to = actual_ ? run_.actual_path[i].pose : run_.densified.samples[i].pose;
    block = actual_ ? run_.actual_path[i].block : run_.densified.samples[i].block;
    return true;
  }
  if (pending_next_ >= pending_.size()) {
    if (densifier_->done()) return false;
    pending_.clear();
    pending_next_ = 0;
    kinematics::BlockReport report;
    densifier_->next_block(pending_, report);
  }
  const kinematics::PoseSample& s = pending_[pending_next_++];
  from = last_;
  to = s.pose;
  block = s.block;
  last_ = s.pose;
  return true;
}

double CutMoves::turning_height(int cutter, const kinematics::ToolPose& from, const kinematics::ToolPose& to) const {
  const removal::Cutter& c = cutters_[static_cast<std::size_t>(cutter)];
  constexpr double kWhole = std::numeric_limits<double>::infinity();
  if (stock_box_.isEmpty()) return kWhole;
  const removal::ToolBody& body = bodies_[static_cast<std::size_t>(cutter)];
  // The pieces' tips leave the tip's path: the box grown for that (removal/move.h).
  const Eigen::AlignedBox3d box = removal::box_for_pieces(c, from.axis, to.axis, stock_box_);
  auto highest = [&](double radius_mm) {
    return removal::highest_point_in_box_mm(radius_mm, from.tip_mm, to.tip_mm, from.axis, to.axis, box);
  };
  // The cutter and the shank above it, at the wider one's radius: the bound is needed up to
  // that height, unless it reaches the shank (whose points then come inside) or the holder
  // comes inside; then for the whole cutter, as without a box.
  double radius_mm = c.radius_mm();
  if (body.shank >= 0) radius_mm = std::max(radius_mm, cutters_[static_cast<std::size_t>(body.shank)].radius_mm());
  double height_mm = highest(radius_mm);
  if (height_mm >= c.flute_length_mm ||
      (body.holder >= 0 &&
       highest(cutters_[static_cast<std::size_t>(body.holder)].radius_mm()) >= body.holder_height_mm))
    height_mm = kWhole;
  return height_mm;
}

void CutMoves::moves_into(const kinematics::ToolPose& from, const kinematics::ToolPose& to, int block,
                          std::vector<removal::Move>& out) const {
  const kinematics::Program& program = run_.program;
  const auto& b = program.blocks[static_cast<std::size_t>(block)];
  if (b.tool == 0) return;  // a rapid before the first tool change moves nothing
  removal::Move m;
  m.start_mm = from.tip_mm;
  m.end_mm = to.tip_mm;
  m.axis = to.axis;
  m.cutter = cutter_index_.at(b.tool);
  m.block = block;
  m.rapid = b.kind == kinematics::MotionKind::Rapid;
  const bool turns = (from.axis - to.axis).norm() > 1e-12;
  if (!turns && (m.end_mm - m.start_mm).norm() < 1e-12) return;
  // With probes, a feed move made with the spindle stopped is probed before it cuts.
  auto stopped_probe = [&](const removal::Move& piece) {
    if (!probes_ || piece.rapid || b.spindle != kinematics::SpindleState::Off) return;
    removal::Move stopped = piece;
    stopped.rapid = true;
    stopped.probe = removal::ProbeKind::SpindleStopped;
    out.push_back(stopped);
  };
  const double height_mm = turns ? turning_height(m.cutter, from, to) : 0.0;
  // The whole cutter's split (its pieces cut, or the shank and holder follow them).
  auto whole = [&] {
    return removal::five_axis_split(cutters_[static_cast<std::size_t>(m.cutter)], height_mm, from.axis, to.axis,
                                    rotation_bound_mm_);
  };
  const std::vector<removal::CutterPart>* parts = &parts_[static_cast<std::size_t>(m.cutter)];
  int first_part = parts_first_[static_cast<std::size_t>(m.cutter)];
  // A flat or bull-nose end mill part by part only where at least two of its parts (2 Rc long:
  // removal::cutter_parts) come inside the stock: each part takes as many pieces as a core 2 Rc
  // long, and the rays along the axis meet every part (W5's bull-nose, about 10 mm inside the
  // block with parts of 6 mm: its cut 1.03x slower by parts; the S-piece's flat end mill, its
  // 40 mm flute in the stock with parts of 10 mm: 0.71x).
  const bool by_parts =
      first_part >= 0 && (cutters_[static_cast<std::size_t>(m.cutter)].type == removal::CutterType::Ball ||
                          height_mm >= 2.0 * (*parts)[1].offset_mm);
  if (turns && by_parts && !m.rapid) {
    // Part by part (a rapid stays whole: its probe measures the longest overlap along a ray
    // with the whole tool), the pieces in the order of the instants they end at (the parts'
    // pieces are of different lengths), and with probes the shank and holder along the whole
    // cutter's pieces, each after the cuts up to its instant, as they follow the whole's.
    struct Timed {
      double until;
      bool probe;
      removal::Move move;
    };
    std::vector<Timed> timed;
    std::vector<removal::Move> pieces, bodies;
    // Piece k of n ends at the instant (k + 1) / n of the move.
    auto until = [&](std::size_t k) { return static_cast<double>(k + 1) / static_cast<double>(pieces.size()); };
    std::size_t highest;
    std::vector<removal::TurningSplit> splits =
        removal::part_splits(*parts, height_mm, from.axis, to.axis, rotation_bound_mm_, highest);
    // A ball's halved parts where they take no more pieces in all (W5's ball rows, whose moves
    // turn about 0.8 deg: a part of 2.375 mm takes 2 pieces, each half 1): as many pieces,
    // each over about half the rays.
    const std::vector<removal::CutterPart>& halves = halves_[static_cast<std::size_t>(m.cutter)];
    if (!halves.empty()) {
      std::size_t halves_highest;
      std::vector<removal::TurningSplit> halves_splits =
          removal::part_splits(halves, height_mm, from.axis, to.axis, rotation_bound_mm_, halves_highest);
      auto total = [](const std::vector<removal::TurningSplit>& s) {
        int n = 0;
        for (const removal::TurningSplit& split : s) n += split.pieces;
        return n;
      };
      if (total(halves_splits) <= total(splits)) {
        first_part += static_cast<int>(parts->size());  // the halves' cutters follow the parts'
        parts = &halves;
        splits = std::move(halves_splits);
        highest = halves_highest;
      }
    }
    for (std::size_t j = 0; j < parts->size(); ++j) {
      pieces.clear();
      removal::append_part_pieces(pieces, m, from.axis, to.axis, (*parts)[j], first_part + static_cast<int>(j),
                                  splits[j], j == highest);
      for (std::size_t k = 0; k < pieces.size(); ++k) timed.push_back({until(k), false, pieces[k]});
    }
    if (probes_) {
      pieces.clear();
      removal::append_five_axis_move(pieces, m, from.axis, to.axis, whole());
      for (std::size_t k = 0; k < pieces.size(); ++k) {
        bodies.clear();
        removal::append_body_probes(bodies, pieces[k], bodies_[static_cast<std::size_t>(m.cutter)]);
        for (const removal::Move& probe : bodies) timed.push_back({until(k), true, probe});
      }
    }
    std::stable_sort(timed.begin(), timed.end(), [](const Timed& p, const Timed& q) {
      return p.until < q.until || (p.until == q.until && !p.probe && q.probe);
    });
    for (const Timed& t : timed) {
      if (!t.probe) stopped_probe(t.move);
      out.push_back(t.move);
    }
    return;
  }
  const std::size_t first_piece = out.size();
  if (turns) {
    removal::append_five_axis_move(out, m, from.axis, to.axis, whole());
  } else {
    out.push_back(m);
  }
  if (!probes_) return;
  const std::vector<removal::Move> pieces(out.begin() + static_cast<std::ptrdiff_t>(first_piece), out.end());
  out.resize(first_piece);
  for (const removal::Move& piece : pieces) {
    stopped_probe(piece);
    out.push_back(piece);
    removal::append_body_probes(out, piece, bodies_[static_cast<std::size_t>(piece.cutter)]);
  }
}

bool CutMoves::next(std::vector<removal::Move>& out, std::size_t wanted) {
  const std::size_t before = out.size();
  kinematics::ToolPose from, to;
  int block = -1;
  while (out.size() - before < wanted) {
    if (!step(from, to, block)) {
      if (recording_) counted_ = true, recording_ = false;
      break;
    }
    const std::size_t first = out.size();
    moves_into(from, to, block, out);
    if (recording_) record(from, to, out, first);
  }
  return out.size() > before;
}

namespace {

// require_cuttable's three refusals, apart: simulate makes the stock while the program is read,
// and the reach check needs the program's moves.
void require_stock_thicker_than_a_cell(const io::Job& job, const Eigen::AlignedBox3d& stock_box, double resolution_mm) {
  // A stock thinner than a cell holds no node of the lattice across it: its surface cannot be
  // meshed (and the level set cannot hold it), so the machined mesh would come out empty.
  for (int a = 0; a < 3; ++a) {
    const double size_mm = stock_box.sizes()[a];
    if (size_mm >= resolution_mm * (1.0 - 1e-9)) continue;  // a stock as thick as a cell, less rounding, holds a node
    std::ostringstream msg;
    msg << "the stock is " << size_mm << " mm across in "
        << "xyz"[a] << ", less than the resolution " << resolution_mm
        << " mm: no cell fits across it (expected a resolution of at most " << size_mm << " mm, or a thicker stock)";
    throw InputError(job.file, job.stock.line, job.stock.column, msg.str());
  }
}

void require_reach(const io::Job& job, CutMoves& cut, const Eigen::AlignedBox3d& stock_box) {
  bool overlap = false;
  Eigen::AlignedBox3d path_box;
  std::vector<removal::Move> batch;
  cut.rewind();
  while (cut.next(batch, 4096)) {
    for (const auto& m : batch) {
      if (m.rapid) continue;
      path_box.extend(m.start_mm);
      path_box.extend(m.end_mm);
      const removal::TranslationSweep sweep(cut.cutters()[static_cast<std::size_t>(m.cutter)], m);
      overlap = overlap || sweep.bounds().intersects(stock_box);
    }
    batch.clear();
  }
  cut.rewind();
  if (!overlap && cut.cutting_moves() > 0) {
    std::ostringstream msg;
    msg << "the program's cutting moves never reach the stock (stock spans [" << stock_box.min().transpose() << "] to ["
        << stock_box.max().transpose() << "] mm";
    if (!path_box.isEmpty())
      msg << ", cutting moves span [" << path_box.min().transpose() << "] to [" << path_box.max().transpose() << "] mm";
    msg << "): check the work offsets and the stock";
    throw InputError(job.file, job.stock.line, job.stock.column, msg.str());
  }
}

double require_memory(const io::Job& job, const removal::StockShape& shape, double resolution_mm,
                      double max_memory_mb) {
  const bool use_dexel = job.engine != io::Engine::Vdb, use_vdb = job.engine != io::Engine::Dexel;
  std::size_t estimate_bytes = 0;
  if (use_dexel) estimate_bytes += removal::estimate_dexel_memory_bytes(shape, resolution_mm);
  if (use_vdb) estimate_bytes += removal::estimate_vdb_memory_bytes(shape, resolution_mm);
  const double estimate_mb = static_cast<double>(estimate_bytes) / (1024.0 * 1024.0);
  const double limit_mb = max_memory_mb > 0.0 ? max_memory_mb : 0.75 * total_ram_mb();
  if (estimate_mb > limit_mb) {
    std::ostringstream msg;
    msg << "resolution " << resolution_mm;
    msg.precision(0);
    msg << std::fixed << " mm needs about " << estimate_mb << " MB for this stock, more than the " << limit_mb
        << " MB allowed (--max-memory): choose a coarser resolution";
    msg.precision(3);
    throw InputError(msg.str());
  }
  return estimate_mb;
}

}  // namespace

double require_cuttable(const io::Job& job, CutMoves& cut, const removal::StockShape& shape, double resolution_mm,
                        double max_memory_mb) {
  const Eigen::AlignedBox3d stock_box = removal::bounds_of(shape);
  require_stock_thicker_than_a_cell(job, stock_box, resolution_mm);
  require_reach(job, cut, stock_box);
  return require_memory(job, shape, resolution_mm, max_memory_mb);
}

std::unique_ptr<removal::Stock> make_stock(const io::Job& job, const removal::StockShape& shape, double resolution_mm,
                                           bool merge_flat) {
  if (job.engine == io::Engine::Vdb) return std::make_unique<removal::VdbStock>(shape, resolution_mm);
  auto dexel = std::make_unique<removal::DexelStock>(shape, resolution_mm);
  dexel->set_flat_merging(merge_flat);
  return dexel;
}

DesignComparison compare_with_design(const io::Job& job, const removal::SurfaceMesh& machined,
                                     const removal::TriangleMesh& design, const removal::Stock& stock,
                                     double resolution_mm, const kinematics::Program& program,
                                     const std::vector<int>& move_blocks) {
  const double v = resolution_mm;
  DesignComparison out;
  auto block_of = [&](int move) -> kinematics::Block {
    return program.blocks[static_cast<std::size_t>(move_blocks[static_cast<std::size_t>(move)])];
  };
  const removal::DesignDistance distance(design);
  if (!distance.closed())
    out.warnings.push_back(io::display_name(job.design->file, job.file) +
                           ": design mesh is not closed; compared anyway (signs near its holes may be wrong)");
  removal::CompareSettings settings{job.gouge_tolerance_mm, job.excess_tolerance_mm};
  removal::Comparison cmp = removal::compare(machined, distance, settings);
  out.max_gouge_mm = cmp.max_gouge_mm;
  out.max_excess_mm = cmp.max_excess_mm;
  if (const auto* dexel = dynamic_cast<const removal::DexelStock*>(&stock)) {
    // Every dexel endpoint against the design, exactly: the summary's figures then do not
    // depend on meshing (the mesh's regions still give areas and outlines).
    const removal::EndpointDeviation found = removal::endpoint_deviation(*dexel, distance, settings);
    EndpointCheck& e = out.endpoints;
    e.done = true;
    e.points = found.points;
    e.max_gouge_mm = found.max_gouge_mm;
    e.max_excess_mm = found.max_excess_mm;
    e.gouge_points = found.gouge_points;
    e.excess_points = found.excess_points;
    if (found.max_gouge_mm > 0.0) {
      e.deepest_mm = found.deepest_mm;
      if (found.deepest_move >= 0) e.deepest_line = block_of(found.deepest_move).source;
    }
    out.max_gouge_mm = e.max_gouge_mm;
    out.max_excess_mm = e.max_excess_mm;
  }
  auto record = [&](const removal::Region& r) {
    RegionRecord rec;
    rec.depth_mm = r.depth_mm;
    rec.area_mm2 = r.area_mm2;
    rec.centroid_mm = r.centroid_mm;
    rec.deepest_mm = r.deepest_mm;
    std::vector<kinematics::SourceRef> refs;
    std::set<int> tools;
    for (int move : r.moves) {
      if (move < 0) {
        rec.initial_stock = true;
        continue;
      }
      const auto& b = block_of(move);
      refs.push_back(b.source);
      tools.insert(b.tool);
    }
    rec.spans = merge_lines(program, std::move(refs));
    rec.tools.assign(tools.begin(), tools.end());
    return rec;
  };
  for (const auto& r : cmp.gouges) out.gouges.push_back(record(r));
  for (const auto& r : cmp.excess) out.excess.push_back(record(r));
  // Histogram: 41 bins over +-4 tolerances plus two overflow bins, by vertex and area.
  const double span = 4.0 * std::max({job.gouge_tolerance_mm, job.excess_tolerance_mm, v});
  const int bins = 41;
  out.histogram_edges_mm.push_back(-std::numeric_limits<double>::infinity());
  for (int i = 0; i <= bins; ++i) out.histogram_edges_mm.push_back(-span + 2.0 * span * i / bins);
  out.histogram_edges_mm.push_back(std::numeric_limits<double>::infinity());
  out.histogram_counts.assign(bins + 2, 0);
  out.histogram_area_mm2.assign(bins + 2, 0.0);
  const std::vector<double>& area = cmp.vertex_area_mm2;
  for (std::size_t i = 0; i < cmp.deviation_mm.size(); ++i) {
    const double d = cmp.deviation_mm[i];
    const std::size_t bin =
        d < -span   ? 0
        : d >= span ? bins + 1
                    : 1 + std::min<std::size_t>(bins - 1, static_cast<std::size_t>((d + span) / (2.0 * span) * bins));
    ++out.histogram_counts[bin];
    out.histogram_area_mm2[bin] += area[i];
  }
  out.deviation_mm = std::move(cmp.deviation_mm);
  return out;
}

namespace {

// Work run beside the stages that follow it; waited for before what it uses goes away, also
// when one of them throws. Not cancelled then: a parallel loop cut short inside a constructor
// (the stock's rays) would leave objects half made for their destructors.
class Beside {
 public:
  template <class F>
  explicit Beside(F&& work) {
    group_.run(std::forward<F>(work));
  }
  ~Beside() {
    if (waited_) return;
    try {
      group_.wait();
    } catch (...) {  // the run is stopping for another error already
    }
  }
  Beside(const Beside&) = delete;
  Beside& operator=(const Beside&) = delete;
  // Rethrows what the work threw.
  void wait() {
    waited_ = true;
    group_.wait();
  }

 private:
  tbb::task_group group_;
  bool waited_ = false;
};

}  // namespace

SimulationResult simulate(const io::Job& job, const SimulateOptions& options) {
  const auto t_start = Clock::now();
  auto t_stage = t_start;
  SimulationResult result;
  auto stage_done = [&](const char* name) {
    const auto now = Clock::now();
    result.stage_seconds.emplace_back(name, std::chrono::duration<double>(now - t_stage).count());
    t_stage = now;
  };
  auto progress = [&](const std::string& stage, std::size_t done, std::size_t total) {
    if (options.progress) options.progress(stage, done, total);
  };
  result.job_name = job.name;
  result.resolution_mm = options.resolution_mm.value_or(job.resolution_mm);
  const int threads = options.threads.value_or(job.threads);
  result.threads = threads > 0 ? threads : tbb::info::default_concurrency();
  tbb::global_control limit(tbb::global_control::max_allowed_parallelism, static_cast<std::size_t>(result.threads));
  const double v = result.resolution_mm;
  if (!(v > 0.0) || !std::isfinite(v)) throw InputError("--resolution: expected a positive number of mm");

  // 4. The stock, and the design, made beside the program's reading (1-3): they need nothing
  // from it, and setting up a big stock's rays takes longer than the reading (W1 on 2 threads:
  // 173 MB of rays, 0.04-0.2 s, against 0.08 s for the program on one thread). Both before the
  // cut, so that a file that cannot be used stops the run at once; a program that cannot be read
  // is still the error reported first, then the moves', then the stock side's.
  struct StockSide {
    std::optional<removal::StockShape> shape;
    std::optional<removal::TriangleMesh> design;  // kept for the report page
    double estimated_mb = 0.0;
    std::unique_ptr<removal::Stock> primary, second;
  } side;
  Beside stock_side([&] {
    side.shape = stock_shape(job);
    side.design = design_of(job);
    const Eigen::AlignedBox3d box = removal::bounds_of(*side.shape);
    require_stock_thicker_than_a_cell(job, box, v);
    side.estimated_mb = require_memory(job, *side.shape, v, options.max_memory_mb);
    // The primary engine makes the outputs; with engine: both the OpenVDB one checks it.
    side.primary = make_stock(job, *side.shape, v, true);
    if (job.engine == io::Engine::Both) side.second = std::make_unique<removal::VdbStock>(*side.shape, v);
  });

  // 1. Program and 2. poses: the pose engine (densified poses with axis values, time, and
  // with servo or machine errors the actual poses, which are what the machine cuts). A
  // streamed run's two passes over the program (the poses counted, then timed, with the
  // findings) come later, with the machine check (4b): the moves need nothing they find.
  result.pose_run = run_pose_engine(job, read_job_program(job), v, nullptr, true, true);
  const PoseRun& run = result.pose_run;
  const kinematics::Program& program = run.program;
  result.blocks = program.blocks.size();
  stage_done("read");

  // 3. Moves: the actual poses (servo, errors) when there are any, else the nominal; with
  // the nominal ones as well for the nominal cut.
  const bool cut_actual = !run.actual_path.empty();
  const double turn_mm = turn_tolerance_mm(job, v);
  CutMoves moves(run, cut_actual, true, turn_mm);
  std::optional<CutMoves> nominal_moves;
  if (cut_actual) nominal_moves.emplace(run, false, false, turn_mm);
  stage_done("densify");

  // 4, its end: the stock side waited for (the time it outlasted the reading), the moves against it.
  stock_side.wait();
  // Each input once: a job without a tool library file names none, a program simulated
  // without a job file is its own job file.
  std::vector<std::string> hashed;
  auto hash = [&hashed](const std::string& f) {
    if (!f.empty() && std::find(hashed.begin(), hashed.end(), f) == hashed.end()) hashed.push_back(f);
  };
  for (const std::string& f : {job.file, job.machine_file, job.tools_file}) hash(f);
  for (const std::string& f : job.program_files) hash(f);
  const removal::StockShape& shape = *side.shape;
  if (job.stock.kind == io::StockSpec::Kind::Mesh) hash(job.stock.mesh_file);
  const Eigen::AlignedBox3d stock_box = removal::bounds_of(shape);
  moves.set_stock_box(stock_box);
  if (nominal_moves) nominal_moves->set_stock_box(stock_box);
  std::optional<removal::TriangleMesh> design_mesh = std::move(side.design);
  if (design_mesh) hash(job.design->file);
  require_reach(job, moves, stock_box);
  result.estimated_memory_mb = side.estimated_mb;
  // Counted as the reach check pulled them (the first pass over the moves).
  result.moves = moves.count();
  result.cutting_moves = moves.cutting_moves();
  result.rotating_moves = moves.rotating_moves();
  // A machine-error run compares the actual with the nominal part (a few um): no flat merging.
  const bool merge_flat = !cut_actual;
  if (auto* dexel = dynamic_cast<removal::DexelStock*>(side.primary.get())) dexel->set_flat_merging(merge_flat);
  std::unique_ptr<removal::Stock> primary = std::move(side.primary), second = std::move(side.second);
  removal::Stock& stock = *primary;
  result.initial_volume_mm3 = stock.volume_mm3();
  stage_done("stock");

  // 4b. The machine: its bodies, the fixtures and the tool's parts against each other at every
  // pose and between poses (machine_check.h). The bodies are read here, before the cut, so that
  // a bad model stops the run; the check itself runs after the cut, beside the mesh and the
  // comparison, which it shares nothing with, after the pose engine's passes (it places the
  // page's frames by the number of poses): each pass over the program, densified again, is
  // one thread's work, and on their own they stood on the run's path (W1, 16 threads: the
  // machine stage 0.09 of 2.19 s). Without models or fixtures the tool alone is posed, for the
  // page's playback.
  result.machine_checked = has_machine_bodies(job, run);
  for (const auto& [node, models] : run.machine->spec().models)
    for (const kinematics::ModelSpec& m : models) hash(m.file);
  for (const io::DesignSpec& f : job.fixtures) hash(f.file);
  MachineCheckOptions machine_options;
  machine_options.clearance_mm = job.machine_clearance_mm;
  machine_options.playback_frames = kPlaybackFrames;
  MachineChecker machine_checker(job, run, machine_options);
  stage_done("machine");

  // 5. Cut.
  removal::CutOptions cut_options;
  cut_options.collision_tolerance_mm = job.collision_tolerance_mm;
  cut_options.progress = [&](std::size_t done, std::size_t total) { progress("cut", done, total); };
  const removal::CutResult cut = stock.cut(moves, cut_options);
  result.removed_volume_mm3 = cut.removed_volume_mm3;
  result.final_volume_mm3 = stock.volume_mm3();
  result.stock_memory_mb = static_cast<double>(stock.memory_bytes()) / (1024.0 * 1024.0);
  auto block_of = [&](int move) -> kinematics::Block {
    return program.blocks[static_cast<std::size_t>(moves.block(static_cast<std::size_t>(move)))];
  };
  result.collisions = collision_records(cut.collisions, moves, program);
  stage_done("cut");
  // The pose engine's passes and the machine check beside the mesh and the comparison (not the
  // cut, so that its stage times the cut alone).
  Beside machine_check([&] {
    finish_pose_run(job, result.pose_run);
    result.machine = machine_checker.run();
  });

  // 6. Mesh.
  progress("mesh", 0, 1);
  removal::SurfaceMesh machined = stock.surface();
  result.machined_vertices = machined.mesh.vertices_mm.size();
  result.machined_triangles = machined.mesh.triangles.size();
  if (machined.mesh.triangles.empty()) {
    // Less than half a cell's volume left is nothing the lattice can show.
    if (result.final_volume_mm3 < 0.5 * v * v * v) {
      result.warnings.push_back("the program cuts the whole stock away: the machined mesh is empty");
    } else {
      std::ostringstream msg;
      msg << "the machined mesh is empty, but " << result.final_volume_mm3
          << " mm3 of stock is left, all of it thinner than the resolution (" << v
          << " mm): choose a finer resolution to see it";
      result.warnings.push_back(msg.str());
    }
  }
  stage_done("mesh");

  if (second) {
    // engine: both — cut again with the OpenVDB engine; the distance between the two
    // machined surfaces, both ways, is the self-check.
    progress("check", 0, 1);
    const auto t0 = Clock::now();
    moves.rewind();
    second->cut(moves, removal::CutOptions{job.collision_tolerance_mm, {}});
    const auto t1 = Clock::now();
    const removal::SurfaceMesh other = second->surface();
    result.engines.vdb_cut_s = std::chrono::duration<double>(t1 - t0).count();
    result.engines.vdb_mesh_s = std::chrono::duration<double>(Clock::now() - t1).count();
    static_cast<removal::SurfaceDifference&>(result.engines) =
        removal::surface_difference(machined, other, v, removal::kSharpEdgeDeg);
    stage_done("check");
  }

  if (cut_actual) {
    // The machine cut with the actual poses; cut the nominal ones too (same engine) and
    // measure how far the real part departs from the programmed one.
    progress("nominal", 0, 1);
    std::unique_ptr<removal::Stock> nominal = make_stock(job, shape, v, merge_flat);
    nominal->cut(*nominal_moves, removal::CutOptions{job.collision_tolerance_mm, {}});
    const removal::SurfaceMesh nominal_surface = nominal->surface();
    static_cast<removal::SurfaceDifference&>(result.nominal) =
        removal::surface_difference(machined, nominal_surface, v);
    // The NC line: the machined vertex nearest the largest difference.
    double best = std::numeric_limits<double>::infinity();
    for (std::size_t i = 0; i < machined.mesh.vertices_mm.size(); ++i) {
      const double d = (machined.mesh.vertices_mm[i] - result.nominal.max_where_mm).squaredNorm();
      if (d < best && machined.vertex_move[i] >= 0) {
        best = d;
        result.nominal.max_line = block_of(machined.vertex_move[i]).source;
      }
    }
    stage_done("nominal");
  }

  // 7. Compare.
  std::vector<double> deviation;
  if (design_mesh) {
    progress("compare", 0, 1);
    DesignComparison cmp = compare_with_design(job, machined, *design_mesh, stock, v, program, moves.blocks());
    result.warnings.insert(result.warnings.end(), cmp.warnings.begin(), cmp.warnings.end());
    result.compared = true;
    result.max_gouge_mm = cmp.max_gouge_mm;
    result.max_excess_mm = cmp.max_excess_mm;
    result.gouges = std::move(cmp.gouges);
    result.excess = std::move(cmp.excess);
    result.histogram_edges_mm = std::move(cmp.histogram_edges_mm);
    result.histogram_counts = std::move(cmp.histogram_counts);
    result.histogram_area_mm2 = std::move(cmp.histogram_area_mm2);
    result.endpoints = cmp.endpoints;
    deviation = std::move(cmp.deviation_mm);
    stage_done("compare");
  }

  // The wait for the passes and the machine check, if they outlasted the rest, counts as the
  // machine stage. Their warnings go first, as their stages come first: the job's, the
  // program's and the poses', then the machine's.
  machine_check.wait();
  result.poses = run.poses;
  std::vector<std::string> early = warnings_of(job, run);
  early.insert(early.end(), result.machine.warnings.begin(), result.machine.warnings.end());
  result.warnings.insert(result.warnings.begin(), early.begin(), early.end());
  for (auto& [name, seconds] : result.stage_seconds)
    if (name == "machine") seconds += std::chrono::duration<double>(Clock::now() - t_stage).count();
  t_stage = Clock::now();

  result.input_files = std::move(hashed);
  result.machined = std::move(machined);
  result.deviation_mm = std::move(deviation);
  result.move_blocks = moves.blocks();
  result.design = std::move(design_mesh);
  result.stock_box = stock_box;
  result.wall_time_s = std::chrono::duration<double>(Clock::now() - t_start).count();
  result.peak_memory_mb = peak_memory_mb();
  return result;
}

}  // namespace vcut::pipeline
