// What a machine gives to more threads before any of vcut's own work is asked of it (issue 24):
// a fixed amount of arithmetic, and a fixed sweep over memory, shared out over 1 to 16 threads
// by TBB as the engines share out theirs. On the lent 16-core machine of the thirty-first
// session the cut's tile loop reached 0.65 of its list-scheduled bound on every job, and these
// two say how much of that is the machine (clock under load, memory bandwidth) and how much the
// code: wall time per run, the same work at every thread count.
#include <benchmark/benchmark.h>
#include <tbb/global_control.h>
#include <tbb/parallel_for.h>

#include <cmath>
#include <cstddef>
#include <cstdint>
#include <vector>

namespace {

constexpr std::size_t kChunks = 1024;  // pieces of work handed out, far more than threads

// Arithmetic: each chunk a chain of square roots and products that stays in registers, as a
// kernel's inner loop does (about a millisecond a chunk on one core of this VM).
void BM_ScalingCompute(benchmark::State& state) {
  tbb::global_control limit(tbb::global_control::max_allowed_parallelism, static_cast<std::size_t>(state.range(0)));
  std::vector<double> out(kChunks);
  for (auto _ : state) {
    tbb::parallel_for(std::size_t{0}, kChunks, [&](std::size_t c) {
      double x = 1.0 + static_cast<double>(c) * 1e-6, y = 0.5;
      for (int i = 0; i < 100000; ++i) {
        x = std::sqrt(x * x + y) * 0.999;
        y = y * 0.9999 + 1e-7 * x;
      }
      out[c] = x + y;
    });
    benchmark::DoNotOptimize(out.data());
  }
  state.SetItemsProcessed(state.iterations() * static_cast<std::int64_t>(kChunks));
}
BENCHMARK(BM_ScalingCompute)->ArgName("threads")->Arg(1)->Arg(2)->Arg(4)->Arg(8)->Arg(16)->UseRealTime();

// Memory: 512 MB read and written once a run, each chunk its own stretch (the stock's rays are
// hundreds of MB, each tile touching its own).
void BM_ScalingMemory(benchmark::State& state) {
  tbb::global_control limit(tbb::global_control::max_allowed_parallelism, static_cast<std::size_t>(state.range(0)));
  constexpr std::size_t kWords = (std::size_t{512} << 20) / sizeof(std::uint64_t);
  std::vector<std::uint64_t> data(kWords, 1);
  for (auto _ : state) {
    tbb::parallel_for(std::size_t{0}, kChunks, [&](std::size_t c) {
      const std::size_t first = c * kWords / kChunks, last = (c + 1) * kWords / kChunks;
      for (std::size_t i = first; i < last; ++i) data[i] = data[i] * 3 + 1;
    });
    benchmark::DoNotOptimize(data.data());
  }
  state.SetBytesProcessed(state.iterations() * static_cast<std::int64_t>(2 * kWords * sizeof(std::uint64_t)));
}
BENCHMARK(BM_ScalingMemory)->ArgName("threads")->Arg(1)->Arg(2)->Arg(4)->Arg(8)->Arg(16)->UseRealTime();

}  // namespace
