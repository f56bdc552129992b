// The simulate stages in-process (the CLI tests are the end-to-end layer). Expected values are
// worked by hand from the geometry in the comments.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>
#include <vector>

#include "vcut/io/input_error.h"
#include "vcut/io/job.h"
#include "vcut/io/mesh_io.h"
#include "vcut/pipeline/poses.h"
#include "vcut/pipeline/simulate.h"
#include "vcut/removal/vdb_stock.h"
#include "../removal/test_meshes.h"

namespace vcut::pipeline {
namespace {
namespace fs = std::filesystem;

class Stages : public ::testing::Test {
 protected:
  void SetUp() override {
    dir = fs::temp_directory_path() /
          ("vcut_pipeline_" + std::string(::testing::UnitTest::GetInstance()->current_test_info()->name()));
    fs::remove_all(dir);
    fs::create_directories(dir);
    write("tools.yaml", "tools:\n  1: {type: flat, diameter: 10, flute_length: 25, shank_diameter: 10, length: 40}\n");
    // Line 7 slots the 60 mm box along X, 10 mm wide, the tip at z = -2.
    write("slot.ngc", "%\nG17 G21 G90 G94 G54\nT1 M6\nS10000 M3\nG0 X-10 Y20 Z5\nG1 Z-2 F500\nG1 X70\nG0 Z5\nM30\n%\n");
  }
  void TearDown() override { fs::remove_all(dir); }
  void write(const std::string& name, const std::string& text) { std::ofstream(dir / name) << text; }
  // A bundled machine file's text, its models found from a copy elsewhere.
  static std::string bundled_machine(const std::string& name) {
    const std::string folder = std::string(VCUT_SOURCE_DIR) + "/examples/machines/";
    std::ifstream bundled(folder + name + ".yaml");
    std::string machine((std::istreambuf_iterator<char>(bundled)), std::istreambuf_iterator<char>());
    for (std::size_t at = machine.find("file: models/"); at != std::string::npos;
         at = machine.find("file: models/", at + 1))
      machine.insert(at + 6, folder);
    return machine;
  }
  // The moves CutMoves makes of the tool in tools.yaml (written by the caller) plunging to
  // z = 0, then moving 10 mm along X while its axis turns `degrees` about Y, one move (densify
  // step and angle 1000), in a stock 50 mm tall at v = 0.1 mm with `engine` added to the
  // engine's settings and `report` to the job; the cut's cutters into `cutters`.
  std::vector<removal::Move> turning_moves(double degrees, const std::string& engine, const std::string& report,
                                           std::vector<removal::Cutter>* cutters = nullptr) {
    const double s = std::sin(degrees * M_PI / 180.0), c = std::cos(degrees * M_PI / 180.0);
    write("turn.apt",
          "UNITS/MM\nMULTAX/ON\nLOADTL/1\nSPINDL/12000,CLW\nRAPID\nGOTO/0,20,45,0,0,1\n"
          "FEDRAT/1000,MMPM\nGOTO/0,20,0,0,0,1\nGOTO/10,20,0," +
              std::to_string(s) + ",0," + std::to_string(c) + "\nFINI\n");
    write("job.yaml",
          "job: turn\nmachine: table-table-ac\ntools: tools.yaml\n"
          "program: {file: turn.apt, dialect: apt}\nstock: {box: {min: [-20, 0, -10], max: [30, 40, 40]}}\n"
          "engine: {kind: dexel, resolution: 0.1" +
              engine + "}\ndensify: {step: 1000, angle: 1000}\n" + report);
    const io::Job j = io::read_job((dir / "job.yaml").string());
    const PoseRun run = run_pose_engine(j, read_job_program(j), 0.1);
    CutMoves cut(run, false, false, turn_tolerance_mm(j, 0.1));
    cut.set_stock_box(removal::bounds_of(stock_shape(j)));
    std::vector<removal::Move> moves;
    while (cut.next(moves, 4096)) {
    }
    if (cutters != nullptr) *cutters = cut.cutters();
    return moves;
  }
  // A mesh that is one triangle, not a solid.
  void write_one_triangle(const std::string& name) {
    write(name,
          "solid f\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 0 0\nvertex 0 1 0\nendloop\nendfacet\n"
          "endsolid f\n");
  }
  io::Job job(const std::string& extra, const std::string& machine = "3axis", const std::string& engine = "dexel") {
    write("job.yaml", "job: slot\nmachine: " + machine + "\ntools: tools.yaml\nprogram: {file: slot.ngc}\n" +
                          "stock: {box: {min: [0, 0, -20], max: [60, 40, 0]}}\nengine: {kind: " + engine +
                          ", resolution: 0.1, threads: 2}\n" + extra);
    return io::read_job((dir / "job.yaml").string());
  }
  fs::path dir;
};

// The nominal-against-actual cut: the bundled three-axis machine with a constant Z positioning
// error E_ZZ of 30 um puts every tip 30 um off in z, so the slot's floor (line 7) lies 0.030 mm
// from the programmed one, its walls unchanged.
// - Against the design (the programmed slot) the dexel endpoints, exact, find the floor 0.030
//   mm off and nothing else.
// - The removed volume is the mean of the three ray families' (DexelStock::volume_mm3): the
//   z-rays see the floor's 60 x 10 mm2 move 0.03 mm, 18 mm3; the x- and y-rays, at cell centres
//   z = -1.95 and -2.05, cross no moved floor: the mean differs by 6 mm3 from the run without
//   errors.
// - The two machined surfaces differ by 0.030 mm over the floor; at its edges meshing places
//   the two surfaces' vertices up to v/2 apart (surface_difference), so the largest lies in
//   [0.030, 0.030 + 0.05] mm, on line 7.
TEST_F(Stages, MachineErrorsCutThePartTheMachineMakes) {
  const std::string machine = bundled_machine("3axis");
  ASSERT_EQ(machine.find("\nerrors:"), std::string::npos);
  write("machine.yaml", machine + "\nerrors: {E_ZZ: 30}\n");
  io::write_stl((dir / "part.stl").string(), removal::test::slotted_block(5.0, 2.0));
  const std::string design =
      "design: {file: part.stl}\nreport: {out: out, gouge_tolerance: 0.01, excess_tolerance: 0.01}\n";
  const std::string path = (dir / "machine.yaml").string();
  const SimulationResult nominal = simulate(job(design, path), {});
  EXPECT_FALSE(nominal.nominal.done);  // no errors asked: nothing to compare
  ASSERT_TRUE(nominal.endpoints.done);
  EXPECT_LT(std::max(nominal.endpoints.max_gouge_mm, nominal.endpoints.max_excess_mm), 1e-6);
  const SimulationResult actual = simulate(job(design + "errors: machine\n", path), {});
  ASSERT_TRUE(actual.endpoints.done);
  const double off = std::max(actual.endpoints.max_gouge_mm, actual.endpoints.max_excess_mm);
  EXPECT_NEAR(off, 0.030, 1e-6);
  EXPECT_LT(std::min(actual.endpoints.max_gouge_mm, actual.endpoints.max_excess_mm), 1e-6);
  EXPECT_NEAR(std::abs(actual.removed_volume_mm3 - nominal.removed_volume_mm3), 6.0, 0.01);
  ASSERT_TRUE(actual.nominal.done);
  EXPECT_GE(actual.nominal.max_mm, 0.030 - 1e-6);
  EXPECT_LE(actual.nominal.max_mm, 0.030 + 0.05);
  EXPECT_EQ(actual.pose_run.program.where(actual.nominal.max_line), "slot.ngc:7");
}

// The comparison stage alone: the slot (line 7, floor at z = -2, 10 mm wide over the 60 mm
// block) against a design whose slot is 1.97 mm deep: the whole floor, 60 x 10 = 600 mm2, is
// cut 0.030 mm too deep and nothing else is off. The exact endpoint check finds 0.030 mm; the
// one gouge region covers the floor (its area within a cell row of each edge: 0.1 mm x 2 x
// 70 mm), names line 7 and T1; every vertex is in the histogram once.
// The bundled SINUMERIK 3+2 example (examples/sinumerik/swivel_chamfer.mpf): CYCLE800 turns
// the AC trunnion to a frame at (0, -30, 0) turned 30 deg about X, where the 10 mm end mill
// faces the plane 4 mm below the frame's zero across the whole block (X -40..40, frame Y -17
// to 9 with the tool's radius). On the block (Y >= -30, Z <= 0), with v = Y + 30 and u = -Z,
// the frame's z is -v sin30 - u cos30: the chamfer removes 0.5 v + 0.866 u < 4, a triangle
// of legs 8 and 4 / cos30 (frame y stays within -2.4..7: inside the passes), 60 mm long:
// 60 x 8 x 4.6188 / 2 = 1108.5 mm3. Bound: v / 10 over the cut's 591 mm2 boundary, 6 mm3.
TEST_F(Stages, SinumerikSwivelExampleRemovesTheChamfer) {
  io::Job j = io::read_job(std::string(VCUT_SOURCE_DIR) + "/examples/sinumerik/swivel_chamfer.yaml");
  j.out_dir = (dir / "out").string();
  const SimulationResult r = simulate(j, {});
  EXPECT_NEAR(r.removed_volume_mm3, 60.0 * 8.0 * 4.0 / std::cos(M_PI / 6.0) / 2.0, 6.0);
}

TEST_F(Stages, CompareWithDesignFindsTheFloorTooDeep) {
  const io::Job j = job("report: {out: out, gouge_tolerance: 0.01, excess_tolerance: 0.01}\n");
  const PoseRun run = run_pose_engine(j, read_job_program(j), 0.1);
  CutMoves moves(run, false, true, 0.01);
  const removal::StockShape shape = stock_shape(j);
  const auto stock = make_stock(j, shape, 0.1, true);
  stock->cut(moves, {});
  const removal::SurfaceMesh machined = stock->surface();
  const removal::TriangleMesh design = removal::test::slotted_block(5.0, 1.97);
  const DesignComparison c = compare_with_design(j, machined, design, *stock, 0.1, run.program, moves.blocks());
  ASSERT_TRUE(c.endpoints.done);
  EXPECT_NEAR(c.max_gouge_mm, 0.030, 1e-5);
  EXPECT_LT(c.max_excess_mm, 1e-5);
  ASSERT_EQ(c.gouges.size(), 1u);
  EXPECT_NEAR(c.gouges[0].area_mm2, 600.0, 14.0);
  EXPECT_NEAR(c.gouges[0].depth_mm, 0.030, 1e-4);
  EXPECT_EQ(run.program.where(c.gouges[0].spans), std::vector<std::string>{"slot.ngc:7"});
  EXPECT_EQ(c.gouges[0].tools, std::vector<int>{1});
  EXPECT_TRUE(c.excess.empty());
  std::size_t counted = 0;
  for (std::size_t n : c.histogram_counts) counted += n;
  EXPECT_EQ(counted, machined.mesh.vertices_mm.size());
  EXPECT_EQ(c.deviation_mm.size(), machined.mesh.vertices_mm.size());
  EXPECT_TRUE(c.warnings.empty());
}

// CutMoves: a feed move with no tool is refused with its line; the stages compose as
// simulate does (a 60 x 10 x 2 slot: 1200 mm3).
TEST_F(Stages, MovesStockAndCutComposeAsSimulate) {
  write("slot.ngc", "G21 G90\nG0 X-10 Y20 Z5\nG1 Z-2 F500\n");
  const io::Job no_tool = job("");
  const PoseRun bare = run_pose_engine(no_tool, read_job_program(no_tool), 0.1);
  try {
    CutMoves(bare, false, false, 0.01);
    ADD_FAILURE() << "no InputError";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("slot.ngc:3: feed move with no tool"), std::string::npos) << e.what();
  }
  SetUp();
  const io::Job j = job("");
  const PoseRun run = run_pose_engine(j, read_job_program(j), 0.1);
  CutMoves cut(run, false, true, 0.01);
  EXPECT_EQ(cut.cutting_moves(), 2u);  // the plunge and the slot, one pose each (lines need no densifying)
  EXPECT_EQ(cut.rotating_moves(), 0u);
  const removal::StockShape shape = stock_shape(j);
  EXPECT_FALSE(design_of(j).has_value());
  EXPECT_GT(require_cuttable(j, cut, shape, 0.1, 0.0), 0.0);
  const auto stock = make_stock(j, shape, 0.1, true);
  const double removed = stock->cut(cut, {}).removed_volume_mm3;
  EXPECT_NEAR(removed, 1200.0, 6.0);
  EXPECT_NEAR(simulate(j, {}).removed_volume_mm3, removed, 1e-9);
  // engine: vdb makes the OpenVDB stock.
  EXPECT_NE(dynamic_cast<removal::VdbStock*>(make_stock(job("", "3axis", "vdb"), shape, 0.1, true).get()), nullptr);
}

// A streamed run (no servo, no errors: what simulate and study use) against the same run
// with every sample held: the same poses, time line, findings and moves, move by move (the
// streamed run's passes made later, after its moves, as simulate makes them). The
// first job has a rapid into the stock, the shank and holder probes and a feed move with the
// spindle stopped; the ring has arcs and helices; the demo more moves than a batch.
TEST_F(Stages, StreamedRunMakesTheSameMoves) {
  write("slot.ngc",
        "G21 G90 G94\nT1 M6\nS10000 M3\nG0 X10 Y10 Z5\nG0 Z-3\nG1 X40 F1000\nG1 Z-30\nG1 Y30\nG0 Z50\nM5\n"
        "G1 X60 Z-1 F500\nG1 X80\nM30\n");
  const std::vector<io::Job> jobs = {job(""), io::read_job(std::string(VCUT_SOURCE_DIR) + "/examples/ring/job.yaml"),
                                     io::read_job(std::string(VCUT_SOURCE_DIR) + "/examples/demo/job.yaml")};
  for (std::size_t k = 0; k < jobs.size(); ++k) {
    const io::Job& j = jobs[k];
    const std::string name = "job " + std::to_string(k);
    const PoseRun held = run_pose_engine(j, read_job_program(j), j.resolution_mm, nullptr, false);
    PoseRun streamed = run_pose_engine(j, read_job_program(j), j.resolution_mm, nullptr, true, true);
    ASSERT_FALSE(held.streamed);
    ASSERT_TRUE(streamed.streamed) << name;
    // Its two passes later, as simulate makes them after the cut: nothing of theirs yet, and
    // the moves are made (and counted) before them.
    ASSERT_TRUE(streamed.passes_pending) << name;
    EXPECT_EQ(streamed.poses, 0u);
    EXPECT_TRUE(streamed.timeline.t_s.empty());
    CutMoves b(streamed, false, true, turn_tolerance_mm(j, j.resolution_mm));
    const std::size_t moves_before_the_passes = b.count();
    finish_pose_run(j, streamed);
    EXPECT_FALSE(streamed.passes_pending);
    EXPECT_TRUE(streamed.densified.samples.empty());
    EXPECT_TRUE(streamed.feed.t_s.empty());
    ASSERT_EQ(streamed.poses, held.densified.samples.size()) << name;
    EXPECT_EQ(streamed.feed.cycle_time_s, held.feed.cycle_time_s) << name;
    EXPECT_EQ(streamed.timeline.t_s, held.timeline.t_s) << name;
    EXPECT_EQ(streamed.timeline.speed_mm_per_s, held.timeline.speed_mm_per_s) << name;
    EXPECT_EQ(held.timeline.t_s.size(), std::min<std::size_t>(held.poses, 4000)) << name;
    EXPECT_EQ(streamed.q_min, held.q_min);
    EXPECT_EQ(streamed.q_max, held.q_max);
    EXPECT_EQ(streamed.q_mean, held.q_mean);
    ASSERT_EQ(streamed.events.size(), held.events.size()) << name;
    for (std::size_t i = 0; i < held.events.size(); ++i) {
      EXPECT_EQ(streamed.events[i].kind, held.events[i].kind);
      EXPECT_EQ(streamed.program.where(streamed.events[i].lines), held.program.where(held.events[i].lines));
      EXPECT_EQ(streamed.events[i].detail, held.events[i].detail);
    }
    CutMoves a(held, false, true, turn_tolerance_mm(j, j.resolution_mm));
    EXPECT_EQ(a.count(), moves_before_the_passes);
    EXPECT_EQ(a.count(), b.count());
    EXPECT_EQ(a.cutting_moves(), b.cutting_moves());
    EXPECT_EQ(a.blocks(), b.blocks());
    EXPECT_GT(a.count(), k == 2 ? 4096u : 0u) << name;
    if (k == 0) {  // the collision job makes every kind of probe
      bool rapid = false, shank = false, stopped = false;
      for (std::size_t i = 0; i < a.blocks().size(); ++i) {
        rapid = rapid || a.probe_kind(i) == removal::ProbeKind::Rapid;
        shank = shank || a.probe_kind(i) == removal::ProbeKind::Shank;
        stopped = stopped || a.probe_kind(i) == removal::ProbeKind::SpindleStopped;
      }
      EXPECT_TRUE(rapid && shank && stopped);
    }
    for (int pass = 0; pass < 2; ++pass) {  // and again after a rewind
      std::vector<removal::Move> ma, mb;
      while (a.next(ma, 4096)) {
      }
      while (b.next(mb, 4096)) {
      }
      ASSERT_EQ(ma.size(), mb.size()) << name;
      for (std::size_t i = 0; i < ma.size(); ++i) {
        ASSERT_EQ(ma[i].start_mm, mb[i].start_mm) << name << " move " << i;
        ASSERT_EQ(ma[i].end_mm, mb[i].end_mm) << name << " move " << i;
        ASSERT_EQ(ma[i].axis, mb[i].axis) << name << " move " << i;
        ASSERT_EQ(ma[i].block, mb[i].block) << name << " move " << i;
        ASSERT_EQ(ma[i].rapid, mb[i].rapid) << name << " move " << i;
        ASSERT_EQ(ma[i].probe, mb[i].probe) << name << " move " << i;
      }
      a.rewind();
      b.rewind();
    }
  }
}

// engine.turn_tolerance sets how finely a turning move is cut. A ball end mill D6 (flute 25 mm)
// turns 10 deg about Y while its tip moves 10 mm, all of it inside a stock 50 mm tall (so the
// bound must hold for the whole cutter), one move (densify q = 1). The core is the axis from
// r = 3 to H - r = 22 mm above the tip; a turning cut takes it in 8 parts of 19 / 8 = 2.375 mm
// (an eighth of the core, longer than r / 2; removal::cutter_parts), part j's pivot c = 2.375j
// + 4.1875 mm above the tip, its reach 1.1875 mm: n pieces of phi = theta / n keep the part
// within reach phi / 2 + c phi^2 / 8 of the rigid motion (docs/POSE_ENGINE.md). Unset, the
// tolerance is min(v / 10, gouge tolerance / 2) as the densification's. At v = 0.1 with the
// gouge tolerance 0.05 mm that is 0.01 mm: 1.1875 theta / 0.02 = 10.36, n = 11 for the first
// six parts (at c = 16.0625 mm 0.009421 + 0.000505), 12 for the last two (11 at c = 18.4375:
// 0.009421 + 0.000580 > 0.01): 90. With the default gouge tolerance 0.01 mm, 0.005 mm: 21 for
// the first two (0.004935 + 0.000057 at c = 6.5625), 22 for the other six (21 at c = 8.9375:
// 0.004935 + 0.000077 > 0.005): 174. Set to 0.05 mm: 3 each (0.034543 + at most 0.008805 at
// c = 20.8125): 24.
TEST_F(Stages, TurnToleranceSetsTheTurningMovesPieces) {
  write("tools.yaml", "tools:\n  1: {type: ball, diameter: 6, corner_radius: 3, flute_length: 25}\n");
  struct Case {
    std::string engine, report;
    int pieces;
  };
  for (const Case& c :
       {Case{"", "report: {gouge_tolerance: 0.05}\n", 90}, Case{"", "", 174}, Case{", turn_tolerance: 0.05", "", 24}}) {
    const std::vector<removal::Move> moves = turning_moves(10.0, c.engine, c.report);
    const int turning = static_cast<int>(std::count_if(
        moves.begin(), moves.end(), [](const removal::Move& m) { return !m.rapid && m.axis.z() < 1.0 - 1e-9; }));
    EXPECT_EQ(turning, c.pieces) << c.engine << c.report;
  }
}

// A ball's turning move takes its parts halved (removal::halved_parts: 16 of 1.1875 mm, reach
// 0.59375 mm, pivots c = 1.1875i + 3.59375 mm) where they need no more pieces in all than its
// parts (8 of 2.375 mm, reach 1.1875 mm, c = 2.375j + 4.1875 mm), each part n pieces with
// reach phi / 2 + c phi^2 / 8 <= 0.01 mm (phi = theta / n), the cutter D6 (flute 25 mm) wholly
// inside the stock. Turning 1 deg (0.017453 rad): a part needs 2 (reach theta / 0.02 = 1.036;
// at n = 2 at most 0.005181 + 20.8125 * 9.52e-6 = 0.005379), 16 in all; a half 1 (0.518; at
// most 0.005181 + 21.40625 * 3.81e-5 = 0.005997), 16: the halves, each piece's core 1.1875 mm
// (flute 7.1875). Turning 2 deg: a part 3 (2.073; at n = 3 0.006909 + 0.000352), 24; a half 2
// (1.036), 32: the parts (flute 8.375).
TEST_F(Stages, ABallTurnsInHalfPartsWhereTheyTakeNoMorePieces) {
  write("tools.yaml", "tools:\n  1: {type: ball, diameter: 6, corner_radius: 3, flute_length: 25}\n");
  struct Case {
    double degrees;
    int pieces;
    double flute_mm;
  };
  for (const Case& c : {Case{1.0, 16, 7.1875}, Case{2.0, 24, 8.375}}) {
    std::vector<removal::Cutter> cutters;
    const std::vector<removal::Move> moves = turning_moves(c.degrees, ", turn_tolerance: 0.01", "", &cutters);
    int turning = 0;
    for (const removal::Move& m : moves) {
      if (m.rapid || m.axis.z() >= 1.0 - 1e-9) continue;
      ++turning;
      EXPECT_NEAR(cutters.at(static_cast<std::size_t>(m.cutter)).flute_length_mm, c.flute_mm, 1e-9)
          << c.degrees << " deg";
    }
    EXPECT_EQ(turning, c.pieces) << c.degrees << " deg";
  }
}

// Cutting moves that never come near the stock are refused before any cut (work offsets).
TEST_F(Stages, MovesAwayFromTheStockAreRefused) {
  write("slot.ngc", "G21 G90\nT1 M6\nS1000 M3\nG0 X500 Y500 Z5\nG1 Z-2 F500\nG1 X600\nM30\n");
  const io::Job j = job("");
  const PoseRun run = run_pose_engine(j, read_job_program(j), 0.1);
  CutMoves cut(run, false, false, 0.01);
  try {
    require_cuttable(j, cut, stock_shape(j), 0.1, 0.0);
    ADD_FAILURE() << "no InputError";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("never reach the stock"), std::string::npos) << e.what();
  }
}

// The machine check runs after the cut, beside the mesh, but its bodies are read before the cut:
// a machine model that is not a solid stops the run with the model's file named, and the cut
// never starts (no progress reported for it). Reading the models inside the check's own task
// would fail this: the error would then come when the check is waited for, after the mesh.
TEST_F(Stages, ABadMachineModelStopsTheRunBeforeTheCut) {
  write_one_triangle("flat.stl");
  std::string machine = bundled_machine("3axis");
  const std::size_t at = machine.find("  Z: [{file:");
  ASSERT_NE(at, std::string::npos);
  machine.insert(at + 6, "{file: " + (dir / "flat.stl").string() + ", name: plate}, ");
  write("m.yaml", machine);
  SimulateOptions options;
  std::vector<std::string> stages;
  options.progress = [&](const std::string& stage, std::size_t, std::size_t) { stages.push_back(stage); };
  try {
    simulate(job("", (dir / "m.yaml").string()), options);
    ADD_FAILURE() << "no InputError";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("flat.stl: machine model on Z: not a closed mesh"), std::string::npos)
        << e.what();
  }
  EXPECT_EQ(std::count(stages.begin(), stages.end(), "cut"), 0);
  // The same job with the bundled machine runs through, the cut reported.
  stages.clear();
  const SimulationResult r = simulate(job(""), options);
  EXPECT_GT(std::count(stages.begin(), stages.end(), "cut"), 0);
  EXPECT_GT(r.removed_volume_mm3, 0.0);
}

// The stock is made while the program is read, yet the errors come in the order the stages
// read their inputs: with a program naming a tool the library lacks and a stock mesh that is
// not closed, the program's error; with the program mended, the stock's.
TEST_F(Stages, TheProgramsErrorComesBeforeTheStocksMadeBesideIt) {
  write_one_triangle("flat.stl");
  auto error_of = [&](const std::string& program) {
    write("slot.ngc", program);
    write("job.yaml",
          "job: slot\nmachine: 3axis\ntools: tools.yaml\nprogram: {file: slot.ngc}\n"
          "stock: {mesh: flat.stl}\nengine: {kind: dexel, resolution: 0.1, threads: 2}\n");
    try {
      simulate(io::read_job((dir / "job.yaml").string()), SimulateOptions{});
    } catch (const InputError& e) {
      return std::string(e.what());
    }
    return std::string("no InputError");
  };
  const std::string both = error_of("G21 G90\nT9 M6\nG0 X0 Y0 Z5\nG1 Z-2 F500\nM30\n");
  EXPECT_NE(both.find("tool T9 is not in the tool library"), std::string::npos) << both;
  const std::string stock = error_of("G21 G90\nT1 M6\nG0 X0 Y0 Z5\nG1 Z-2 F500\nM30\n");
  EXPECT_NE(stock.find("stock mesh is not closed"), std::string::npos) << stock;
  // A program's error while a good stock is being made: the run waits for it, then stops.
  write("slot.ngc", "G21 G90\nT9 M6\nG0 X0 Y0 Z5\nG1 Z-2 F500\nM30\n");
  EXPECT_THROW(simulate(job(""), SimulateOptions{}), InputError);
}

// The machine check's warnings come when it is waited for, after the comparison, yet they are
// listed where its stage stands: the program's (an M code the machine lacks, line 4), then the
// machine's (a fixture in the stock), then the comparison's (a design that is not closed).
TEST_F(Stages, WarningsComeInTheStagesOrder) {
  write("slot.ngc", "G21 G90\nT1 M6\nS1000 M3\nM123\nG0 X-10 Y20 Z5\nG1 Z-2 F500\nG1 X70\nG0 Z5\nM30\n");
  write_one_triangle("part.stl");
  const std::string clamp = std::string(VCUT_SOURCE_DIR) + "/examples/machine-collision/clamp.stl";
  const SimulationResult r = simulate(job("design: {file: part.stl}\nfixtures: [{file: " + clamp + "}]\n"), {});
  ASSERT_EQ(r.warnings.size(), 3u);
  EXPECT_NE(r.warnings[0].find("slot.ngc:4:1: M code M123 is not one the machine file declares"), std::string::npos)
      << r.warnings[0];
  EXPECT_EQ(r.warnings[1], "fixture clamp intersects the stock at the start");
  EXPECT_NE(r.warnings[2].find("part.stl: design mesh is not closed"), std::string::npos) << r.warnings[2];
}

}  // namespace
}  // namespace vcut::pipeline
