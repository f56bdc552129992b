// The whole pipeline of `vcut simulate`: job -> program -> poses -> moves -> cut stock ->
// machined mesh -> deviation from the design, as values (vcut::report writes the outputs).
#pragma once

#include <Eigen/Core>

#include <cstddef>
#include <cstdint>
#include <functional>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "vcut/io/job.h"
#include "vcut/pipeline/machine_check.h"
#include "vcut/pipeline/poses.h"
#include "vcut/removal/mesh.h"
#include "vcut/removal/move.h"
#include "vcut/removal/stock.h"
#include "vcut/removal/surface_difference.h"

namespace vcut::pipeline {

struct SimulateOptions {
  std::optional<double> resolution_mm;  // overrides engine.resolution
  std::optional<int> threads;           // overrides engine.threads (0 = all cores)
  double max_memory_mb = 0.0;           // refuse a stock larger than this; 0 = 75 % of RAM
  // Progress: (stage, done, total); from the calling thread.
  std::function<void(const std::string&, std::size_t, std::size_t)> progress;
};

struct RegionRecord {
  double depth_mm = 0.0;
  double area_mm2 = 0.0;
  Eigen::Vector3d centroid_mm = Eigen::Vector3d::Zero();
  Eigen::Vector3d deepest_mm = Eigen::Vector3d::Zero();
  std::vector<kinematics::SourceSpan> spans;  // the NC lines of the moves that made it, merged
  std::vector<int> tools;                     // T numbers; empty for untouched stock
  bool initial_stock = false;                 // part of the region was never cut
};

// Consecutive blocks with the same collision make one record.
struct CollisionRecord {
  removal::ProbeKind probe = removal::ProbeKind::Rapid;  // what collided: collision_kind, collision_part
  kinematics::SourceRange lines;                         // the first block's line to the last's in that file
  kinematics::SourceRef deepest_line;                    // of the deepest point
  int tool = 0;
  double depth_mm = 0.0;  // deepest overlap with material along the rays
  Eigen::Vector3d where_mm = Eigen::Vector3d::Zero();
  std::size_t moves = 0;  // moves that collided
  int first_block = -1, last_block = -1;
};

// A collision's kind as report.json names it (rapid_into_stock, shank_collision,
// holder_collision, spindle_stopped_cut) and the part of the tool ("cutting part", "shank",
// "holder").
const char* collision_kind(removal::ProbeKind probe);
const char* collision_part(removal::ProbeKind probe);

// Deviation from the design measured at every dexel endpoint (exact point-to-triangle), so
// the figures do not depend on meshing.
struct EndpointCheck {
  bool done = false;
  std::size_t points = 0;
  double max_gouge_mm = 0.0, max_excess_mm = 0.0;  // positive figures, 0 when none
  Eigen::Vector3d deepest_mm = Eigen::Vector3d::Zero();
  std::optional<kinematics::SourceRef> deepest_line;  // of the move that made the deepest gouge point
  std::size_t gouge_points = 0, excess_points = 0;    // beyond the tolerances
};

struct EngineCheck : removal::SurfaceDifference {
  double vdb_cut_s = 0.0, vdb_mesh_s = 0.0;
};

// With servo or machine errors the machine cuts with the actual poses; the nominal cut is
// made too, and this is how far the real part departs from the programmed one.
struct NominalCheck : removal::SurfaceDifference {
  std::optional<kinematics::SourceRef> max_line;  // of the actual surface's point farthest from the nominal one
};

struct SimulationResult {
  std::string job_name;
  std::size_t blocks = 0, poses = 0, moves = 0, cutting_moves = 0;
  std::size_t rotating_moves = 0;  // five-axis moves (the tool axis turns), cut in pieces
  PoseRun pose_run;                // the pose engine's output: time, events, contour error
  double resolution_mm = 0.0;
  int threads = 0;
  double initial_volume_mm3 = 0.0, final_volume_mm3 = 0.0, removed_volume_mm3 = 0.0;
  bool compared = false;
  double max_gouge_mm = 0.0, max_excess_mm = 0.0;
  std::vector<RegionRecord> gouges, excess;
  std::vector<CollisionRecord> collisions;
  bool machine_checked = false;  // the machine file has models or the job fixtures
  MachineCheck machine;          // the machine's bodies, fixtures and holder against each other
  std::vector<std::string> warnings;
  std::vector<double> histogram_edges_mm;
  std::vector<std::size_t> histogram_counts;
  std::vector<double> histogram_area_mm2;
  std::size_t machined_vertices = 0, machined_triangles = 0;
  std::vector<std::pair<std::string, double>> stage_seconds;
  double wall_time_s = 0.0;
  double peak_memory_mb = 0.0, stock_memory_mb = 0.0, estimated_memory_mb = 0.0;
  std::vector<std::pair<std::string, std::string>> input_hashes;  // path, sha256 (by the writer)
  std::vector<std::string> outputs;                               // files written, by the writer
  EndpointCheck endpoints;
  EngineCheck engines;
  NominalCheck nominal;
  // The values the outputs are made of (report::write_simulation).
  removal::SurfaceMesh machined;
  std::vector<double> deviation_mm;             // per machined vertex, with a design
  std::vector<int> move_blocks;                 // the block of each move cut (move ids), probes included
  std::optional<removal::TriangleMesh> design;  // placed as the job places it
  Eigen::AlignedBox3d stock_box;
  std::vector<std::string> input_files;  // every file the run read: job, machine, tools, programs, meshes
};

// The stages simulate runs, each testable alone (tests/pipeline/).

// What a run tells the user: the job's warnings, the program's, poses out of reach, the
// pose engine's.
std::vector<std::string> warnings_of(const io::Job& job, const PoseRun& run);

// 3. Moves: the pose run's densified poses (actual = false) or its actual path (servo,
// errors: PoseRun::actual_path) as the cut's moves; a move that turns the tool axis is cut
// in translation pieces within turn_tolerance_mm of the rigid motion (turn_tolerance_mm in
// poses.h: min(v / 10, gouge tolerance / 2) unless the job sets engine.turn_tolerance). With
// `probes` the shank and holder of each tool follow every move, and a feed move with the
// spindle stopped is probed first (collisions). The moves are made as the stock pulls them, a batch
// at a time (removal::MoveSource): the program's moves are never all held. A first pass at
// construction counts them, refuses a feed move with no tool (InputError) and keeps what
// attribution needs of each move, its block and what it stands for (5 bytes).
class CutMoves : public removal::MoveSource {
 public:
  CutMoves(const PoseRun& run, bool actual, bool probes, double turn_tolerance_mm);
  const std::vector<removal::Cutter>& cutters() const override { return cutters_; }
  bool next(std::vector<removal::Move>& out, std::size_t wanted) override;
  std::size_t size_hint() const override { return blocks_.size(); }
  // Hands the moves over again from the first (a second cut, a second look).
  void rewind();
  // The initial stock's box, before the first pass: material never leaves it, so a turning
  // move whose tool stands out of it (no point of its shank or holder ever inside, the
  // cutter only up to some height) needs the bound only for the cutter's part below that
  // height, and is cut in fewer pieces (removal::five_axis_split).
  void set_stock_box(const Eigen::AlignedBox3d& box) { stock_box_ = box; }

  // Counted on the first pass that hands every move over (the reach check's, or the cut's), or
  // on a pass of their own when asked before one (which rewinds: not in the middle of a pass).
  std::size_t count() { return counted(), count_; }  // the moves that cut or are a rapid's probe ("moves")
  std::size_t cutting_moves() { return counted(), cutting_moves_; }    // feed moves of the program path
  std::size_t rotating_moves() { return counted(), rotating_moves_; }  // of those, moves that turn the tool axis
  // By move id (the order handed over): the program block it came from, and for a probe
  // (it cuts nothing) what it stands for.
  int block(std::size_t move) { return counted(), blocks_[move]; }
  removal::ProbeKind probe_kind(std::size_t move) { return counted(), static_cast<removal::ProbeKind>(kinds_[move]); }
  const std::vector<int>& blocks() { return counted(), blocks_; }

 private:
  static constexpr std::uint8_t kCut = 0xff;
  // The next move of the path: the pose it starts from, the one it ends on and that one's
  // block; false after the last. From the run's poses, or (a streamed run) densified again.
  bool step(kinematics::ToolPose& from, kinematics::ToolPose& to, int& block);
  void counted();
  // The counts and attribution of the moves just made (out[first..]) from one pose to the next.
  void record(const kinematics::ToolPose& from, const kinematics::ToolPose& to, const std::vector<removal::Move>& out,
              std::size_t first);
  // The height above the tip below which the cutter's points matter for a move that turns the
  // axis from `from` to `to` (+inf: all of them).
  double turning_height(int cutter, const kinematics::ToolPose& from, const kinematics::ToolPose& to) const;
  // Appends the moves from one pose to the next (of `block`).
  void moves_into(const kinematics::ToolPose& from, const kinematics::ToolPose& to, int block,
                  std::vector<removal::Move>& out) const;

  const PoseRun& run_;
  bool actual_, probes_;
  double rotation_bound_mm_;
  Eigen::AlignedBox3d stock_box_;  // empty: the whole tool needs the bound
  std::vector<removal::Cutter> cutters_;
  std::map<int, int> cutter_index_;        // T number -> cutters_
  std::vector<removal::ToolBody> bodies_;  // the shank and holder of each tool's cutter
  // Each tool's cutter's parts for turning moves (removal::cutter_parts), their cutters in
  // cutters_ from parts_first_ (the whole cutter where it is one part).
  std::vector<std::vector<removal::CutterPart>> parts_;
  std::vector<int> parts_first_;
  // A ball's parts halved (removal::halved_parts), their cutters right after its parts': a
  // turning move takes them where they need no more pieces than parts_ (none for other cutters).
  std::vector<std::vector<removal::CutterPart>> halves_;
  std::size_t samples_ = 0, sample_ = 1;            // poses in all, the next one to move into
  std::optional<kinematics::Densifier> densifier_;  // a streamed run's poses
  std::vector<kinematics::PoseSample> pending_;     // of its current block
  std::size_t pending_next_ = 0;
  kinematics::ToolPose last_;
  std::vector<int> blocks_;
  std::vector<std::uint8_t> kinds_;  // ProbeKind, or kCut
  std::size_t count_ = 0, cutting_moves_ = 0, rotating_moves_ = 0;
  bool counted_ = false, recording_ = false;
};
// 4. The job's stock: its box or cylinder, or its mesh read (closed, turned outward).
removal::StockShape stock_shape(const io::Job& job);
// The job's design mesh placed as the job says (rotate, then translate), or none.
std::optional<removal::TriangleMesh> design_of(const io::Job& job);

// Refuses, as an InputError, a cut that cannot be what was meant: cutting moves that never
// come near the stock (work offsets), or a stock whose estimated memory at this resolution
// (both engines' with engine: both) exceeds max_memory_mb (0: 75 % of RAM). Returns the
// estimate (MB).
double require_cuttable(const io::Job& job, CutMoves& moves, const removal::StockShape& shape, double resolution_mm,
                        double max_memory_mb);
// 5. The stock the cut goes into: tri-dexel, or OpenVDB with engine: vdb. merge_flat: the
// dexel mesher merges flat regions into large triangles (off where two cuts' meshes are
// compared to a few um: merged blocks cut gentle creases differently in two meshes).
std::unique_ptr<removal::Stock> make_stock(const io::Job& job, const removal::StockShape& shape, double resolution_mm,
                                           bool merge_flat);

// 7. The machined surface against the design: the deviation of every vertex, the gouge and
// excess regions with the NC lines of the moves that made them (move_blocks: each move id's
// block), the histogram (41 bins over +-4 tolerances and two overflow bins, by vertex and
// area), and with the dexel engine every ray endpoint checked exactly (then the maxima are
// those, independent of meshing). stock_box: the stock shape's bounds (the rays' origin).
struct DesignComparison {
  double max_gouge_mm = 0.0, max_excess_mm = 0.0;
  std::vector<RegionRecord> gouges, excess;
  std::vector<double> histogram_edges_mm;
  std::vector<std::size_t> histogram_counts;
  std::vector<double> histogram_area_mm2;
  std::vector<double> deviation_mm;  // per machined vertex
  EndpointCheck endpoints;
  std::vector<std::string> warnings;  // a design mesh that is not closed
};
DesignComparison compare_with_design(const io::Job& job, const removal::SurfaceMesh& machined,
                                     const removal::TriangleMesh& design, const removal::Stock& stock,
                                     double resolution_mm, const kinematics::Program& program,
                                     const std::vector<int>& move_blocks);

// Runs the job. Bad input is a vcut::InputError.
SimulationResult simulate(const io::Job& job, const SimulateOptions& options);

// Peak resident memory of this process so far (MB), from /proc/self/status.
double peak_memory_mb();

}  // namespace vcut::pipeline
