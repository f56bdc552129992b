// Google Benchmark of the pose engine per pose: forward and inverse kinematics on a
// table-table AC trunnion and a head-head AC fork head, ideal and with geometric errors,
// and error compensation. Issue #3's target: <= 1 us per inverse kinematics.
#include <benchmark/benchmark.h>

#include <cmath>
#include <filesystem>
#include <random>
#include <vector>

#include "vcut/io/gcode_reader.h"
#include "vcut/io/machine_file.h"

#include "vcut/kinematics/compensation.h"
#include "vcut/kinematics/feed_planner.h"
#include "vcut/kinematics/forward_kinematics.h"
#include "vcut/kinematics/pose_chain.h"
#include "vcut/kinematics/inverse_kinematics.h"
#include "vcut/kinematics/servo.h"

namespace {

using namespace vcut::kinematics;

AxisSpec axis(char letter, AxisKind kind, Eigen::Vector3d dir, Eigen::Vector3d center, double lo, double hi) {
  AxisSpec a;
  a.letter = letter;
  a.kind = kind;
  a.direction = dir;
  a.center_mm = center;
  a.limits = std::make_pair(lo, hi);
  return a;
}

Machine make(bool head_head, bool errors) {
  MachineSpec s;
  const Eigen::Vector3d x = Eigen::Vector3d::UnitX(), z = Eigen::Vector3d::UnitZ();
  s.topology = head_head ? "WFXYZCAT" : "WCAFXYZT";
  s.axes = {axis('X', AxisKind::Linear, x, Eigen::Vector3d::Zero(), -500, 500),
            axis('Y', AxisKind::Linear, Eigen::Vector3d::UnitY(), Eigen::Vector3d::Zero(), -500, 500),
            axis('Z', AxisKind::Linear, z, Eigen::Vector3d::Zero(), -500, 500),
            axis('A', AxisKind::Rotary, x, {0, head_head ? 0.0 : 20.0, head_head ? 180.0 : 10.0}, -2.0, 2.0),
            axis('C', AxisKind::Rotary, z, Eigen::Vector3d::Zero(), -2 * M_PI, 2 * M_PI)};
  if (errors) {
    for (AxisSpec& a : s.axes) {
      for (int i = 0; i < 3; ++i) {
        a.errors.translation_mm[static_cast<size_t>(i)] = {{-500, 0, 500}, {0.01, -0.005, 0.02}};
        a.errors.rotation_rad[static_cast<size_t>(i)] = {{-500, 500}, {20e-6, -30e-6}};
      }
      a.location.tilt_rad = {30e-6, -20e-6, 10e-6};
      if (a.kind == AxisKind::Rotary) a.location.offset_mm = {0.01, -0.02, 0.005};
    }
  }
  return Machine(s);
}

std::vector<AxisValues> samples(const Machine& m) {
  std::mt19937 rng(1);
  std::uniform_real_distribution<double> lin(-200, 200), ang(-1.5, 1.5);
  std::vector<AxisValues> out;
  for (int n = 0; n < 1024; ++n) {
    AxisValues q(5);
    q << lin(rng), lin(rng), lin(rng), ang(rng), 2 * ang(rng);
    out.push_back(q);
  }
  (void)m;
  return out;
}

void BM_Forward(benchmark::State& state) {
  const Machine m = make(state.range(0) != 0, state.range(1) != 0);
  const std::vector<AxisValues> qs = samples(m);
  const Geometry g = state.range(1) ? Geometry::Actual : Geometry::Ideal;
  size_t i = 0;
  for (auto _ : state) benchmark::DoNotOptimize(forward(m, qs[i++ & 1023], 50.0, g));
  state.SetItemsProcessed(state.iterations());
}
BENCHMARK(BM_Forward)->ArgNames({"head_head", "errors"})->Args({0, 0})->Args({0, 1})->Args({1, 0})->Args({1, 1});

void BM_Inverse(benchmark::State& state) {
  const Machine m = make(state.range(0) != 0, false);
  std::vector<ToolPose> poses;
  for (const AxisValues& q : samples(m)) poses.push_back(forward(m, q, 50.0));
  const std::vector<AxisValues> qs = samples(m);
  size_t i = 0;
  for (auto _ : state) {
    const size_t k = i++ & 1023;
    benchmark::DoNotOptimize(inverse(m, poses[k], 50.0, &qs[(k + 1023) & 1023]));
  }
  state.SetItemsProcessed(state.iterations());
}
BENCHMARK(BM_Inverse)->ArgNames({"head_head"})->Arg(0)->Arg(1);

// Inverse kinematics of a machine with errors: the ideal solve, then compensation.
void BM_InverseCompensated(benchmark::State& state) {
  const Machine m = make(state.range(0) != 0, true);
  std::vector<ToolPose> poses;
  for (const AxisValues& q : samples(m)) poses.push_back(forward(m, q, 50.0));
  size_t i = 0;
  for (auto _ : state) {
    const size_t k = i++ & 1023;
    const IkResult r = inverse(m, poses[k], 50.0);
    benchmark::DoNotOptimize(compensate(m, poses[k], 50.0, r.q()));
  }
  state.SetItemsProcessed(state.iterations());
}
BENCHMARK(BM_InverseCompensated)->ArgNames({"head_head"})->Arg(0)->Arg(1);

// Feed planning (S-curves, look-ahead, time stamps) of a zig-zag: 10,000 blocks of 10 mm
// turning 90 deg (every corner binds, one S-curve per block), 10 samples each: 100,001
// samples. Items: samples per second.
void BM_PlanFeed(benchmark::State& state) {
  Program program;
  program.files = {"zigzag.ngc"};
  Eigen::Vector3d at = Eigen::Vector3d::Zero();
  for (int k = 0; k < 10000; ++k) {
    Block b;
    b.start_mm = at;
    at += k % 2 ? Eigen::Vector3d(10, 0, 0) : Eigen::Vector3d(0, 10, 0);
    b.end_mm = at;
    b.feed_mm_per_min = 3000;
    b.blend_tolerance_mm = 0.02;
    program.blocks.push_back(b);
  }
  std::vector<PoseSample> samples(1);
  samples[0].block = -1;
  for (size_t i = 0; i < program.blocks.size(); ++i) {
    const Block& b = program.blocks[i];
    for (int q = 1; q <= 10; ++q) {
      PoseSample s;
      s.pose.tip_mm = b.start_mm + (b.end_mm - b.start_mm) * (q / 10.0);
      s.block = static_cast<int>(i);
      samples.push_back(s);
    }
  }
  const FeedSettings settings;
  for (auto _ : state) benchmark::DoNotOptimize(plan_feed(program, samples, nullptr, settings).cycle_time_s);
  state.SetItemsProcessed(state.iterations() * static_cast<int64_t>(samples.size()));
}
BENCHMARK(BM_PlanFeed)->Unit(benchmark::kMillisecond);

// The pose engine on a five-axis program (issue #5's benchmark): densification (ORIVECT,
// lambda 0.1 mm, phi 0.5 deg), inverse kinematics per pose on the table-table AC trunnion and
// feed planning with the axis limits. 4,510 blocks (the size of LinuxCNC's impeller demo) of
// a smooth five-axis path: the tip on a spiral, the axis tilting 10..40 deg and turning.
// Items: densified poses per second (target >= 200,000/s).
// Densify `program` on `m` (lambda 0.1 mm, phi 0.5 deg, tool `tool` 50 mm long) and plan its
// feed with the axis limits, per iteration; items are densified poses.
void run_pose_engine(benchmark::State& state, const Program& program, const Machine& m, int tool) {
  PoseChainSettings settings;
  settings.densify.step_mm = 0.1;
  settings.densify.angle_step_rad = 0.5 * M_PI / 180.0;
  size_t poses = 0;
  for (auto _ : state) {
    const PoseChain chain = run_pose_chain(program, m, {{tool, 50.0}}, settings);
    benchmark::DoNotOptimize(chain.feed.cycle_time_s);
    poses = chain.densified.samples.size();
  }
  state.counters["poses"] = static_cast<double>(poses);
  state.SetItemsProcessed(state.iterations() * static_cast<int64_t>(poses));
}

void BM_PoseEngine(benchmark::State& state) {
  const Machine m = make(false, false);
  Program program;
  program.files = {"spiral.apt"};
  auto pose_at = [](int k) {
    const double s = k / 4510.0, turn = 6.0 * 2 * M_PI * s;
    const double tilt = (10.0 + 30.0 * s) * M_PI / 180.0;
    ToolPose p;
    p.tip_mm = {(20 + 40 * s) * std::cos(turn), (20 + 40 * s) * std::sin(turn), -10.0 * s};
    p.axis = {std::sin(tilt) * std::cos(turn), std::sin(tilt) * std::sin(turn), std::cos(tilt)};
    return p;
  };
  for (int k = 0; k < 4510; ++k) {
    Block b;
    const ToolPose a = pose_at(k), c = pose_at(k + 1);
    b.start_mm = a.tip_mm;
    b.end_mm = c.tip_mm;
    b.start_axis = a.axis;
    b.end_axis = c.axis;
    b.feed_mm_per_min = 2000;
    b.tool = 1;
    program.blocks.push_back(b);
  }
  run_pose_engine(state, program, m, 1);
}
BENCHMARK(BM_PoseEngine)->Unit(benchmark::kMillisecond);

// The same on LinuxCNC's own five-axis impeller demo (linuxcnc-uspace installs it; 4,510 lines,
// G93 inverse-time feeds, TCP switched on by M428 with X Y Z the tip and A C the rotary axes),
// read by vcut's G-code reader, on the bundled xyzac-trt (LinuxCNC's sim): densification (axes
// linear between the blocks' A C, the linear axes solved for the tip), time stamps with the
// axis limits. Issue #5's target: >= 200,000 densified poses per second.
void BM_PoseEngineImpeller(benchmark::State& state) {
  const std::string path =
      "/usr/share/doc/linuxcnc/examples/sample-configs/sim/axis/vismach/5axis/table-rotary-tilting/demos/"
      "impeller-7bl-xyzac.ngc";
  std::error_code ec;
  if (!std::filesystem::exists(path, ec)) {
    state.SkipWithError("LinuxCNC's impeller demo is not installed (apt-get install linuxcnc-uspace)");
    return;
  }
  vcut::io::GcodeOptions options;
  options.tcp_m_codes = {{428, true}, {429, false}};
  const Program program = vcut::io::read_gcode(path, options);
  const Machine m(vcut::io::read_machine_file(vcut::io::resolve_machine("xyzac-trt")));
  state.counters["blocks"] = static_cast<double>(program.blocks.size());
  run_pose_engine(state, program, m, 0);
}
BENCHMARK(BM_PoseEngineImpeller)->Unit(benchmark::kMillisecond);

}  // namespace

namespace {

// The servo per interpolation period (issue #20): five axes of seed 004's second-order loop
// stepped on a moving command. Items: axis-samples (periods x axes); target >= 10 M/s.
void BM_ServoLoop(benchmark::State& state) {
  ServoSettings settings;
  settings.period_s = 0.001;
  settings.axes = {ServoAxis{}};
  std::vector<AxisValues> commands(1000, AxisValues::Zero(5));
  for (int k = 0; k < 1000; ++k) {
    const double t = k * 1e-3;
    commands[static_cast<size_t>(k)] << 100.0 * std::sin(t), 80.0 * std::cos(t), 5.0 * t, 0.3 * std::sin(2.0 * t),
        0.5 * t;
  }
  ServoLoop loop(settings, commands.front());
  for (auto _ : state) {
    for (const AxisValues& c : commands) loop.step(c);
    benchmark::DoNotOptimize(loop.position());
  }
  state.SetItemsProcessed(state.iterations() * 1000 * 5);
}
BENCHMARK(BM_ServoLoop);

}  // namespace
