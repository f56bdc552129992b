// Google Benchmark of one move's cut per cutter shape: a 0.5 mm finishing-style move
// through a box stock, and the swept-volume distance alone.
#include <benchmark/benchmark.h>

#include "vcut/removal/dexel_stock.h"
#include "vcut/removal/sweep.h"
#include "vcut/removal/vdb_stock.h"

namespace {

using vcut::removal::Cutter;
using vcut::removal::CutterType;

Cutter make(CutterType type) {
  Cutter c;
  c.type = type;
  c.diameter_mm = 6.0;
  c.corner_radius_mm = type == CutterType::Ball ? 3.0 : type == CutterType::BullNose ? 1.0 : 0.0;
  c.tip_angle_deg = type == CutterType::VBit ? 90.0 : 0.0;
  c.flute_length_mm = 20.0;
  c.length_mm = 30.0;
  return c;
}

void BM_SweepDistance(benchmark::State& state) {
  const Cutter c = make(static_cast<CutterType>(state.range(0)));
  vcut::removal::Move m;
  m.start_mm = {0, 0, 0};
  m.end_mm = {0.5, 0.0, state.range(1) ? -0.1 : 0.0};
  const vcut::removal::TranslationSweep sweep(c, m);
  Eigen::Vector3d x(0.3, 1.0, 0.5);
  for (auto _ : state) {
    benchmark::DoNotOptimize(sweep.distance(x));
    x.x() += 1e-9;
  }
}
BENCHMARK(BM_SweepDistance)->ArgsProduct({{0, 1, 2, 3}, {0, 1}})->ArgNames({"shape", "ramp"});

// A raster row of 0.5 mm moves 1 mm deep into a fresh box (ramping 0.01 mm per move when
// `ramp`); time per move, for each engine (0 OpenVDB, 1 tri-dexel) and cutter shape
// (0 flat, 1 ball, 2 bull-nose, 3 V-bit).
template <class Engine>
void cut_moves(benchmark::State& state) {
  const Cutter c = make(static_cast<CutterType>(state.range(0)));
  const double v = state.range(1) / 1000.0;
  const double ramp = state.range(2) ? 0.01 : 0.0;
  constexpr int kMoves = 100;
  for (auto _ : state) {
    state.PauseTiming();
    Engine stock(vcut::removal::BoxShape{{0, 0, -10}, {60, 20, 0}}, v);
    vcut::removal::MoveList list;
    list.cutters.push_back(c);
    for (int i = 0; i < kMoves; ++i) {
      vcut::removal::Move m;
      m.start_mm = {5.0 + 0.5 * i, 10.0, -1.0 - ramp * i};
      m.end_mm = {5.5 + 0.5 * i, 10.0, -1.0 - ramp * (i + 1)};
      list.moves.push_back(m);
    }
    state.ResumeTiming();
    benchmark::DoNotOptimize(stock.cut(list, {}));
  }
  state.SetItemsProcessed(state.iterations() * kMoves);
}
void BM_CutMovesVdb(benchmark::State& state) { cut_moves<vcut::removal::VdbStock>(state); }
void BM_CutMovesDexel(benchmark::State& state) { cut_moves<vcut::removal::DexelStock>(state); }
BENCHMARK(BM_CutMovesVdb)
    ->ArgsProduct({{0, 1, 2}, {100, 50}, {0}})
    ->ArgNames({"shape", "voxel_um", "ramp"})
    ->Unit(benchmark::kMillisecond);
BENCHMARK(BM_CutMovesDexel)
    ->ArgsProduct({{0, 1, 2, 3}, {100, 50}, {0, 1}})
    ->ArgNames({"shape", "spacing_um", "ramp"})
    ->Unit(benchmark::kMillisecond);

}  // namespace

BENCHMARK_MAIN();
