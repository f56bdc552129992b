// The outputs of a run (report::write_simulation): written under the run's thread count.
#include <gtest/gtest.h>
#include <tbb/global_control.h>

#include <filesystem>
#include <string>

#include "vcut/io/job.h"
#include "vcut/pipeline/simulate.h"
#include "vcut/report/outputs.h"

namespace vcut::report {
namespace {
namespace fs = std::filesystem;

// `--threads 1` held for the cut but not for the outputs, which ran their tasks on every core.
// Under an outer limit of 3 (so that a missing inner limit shows on any machine), the write
// stage sees the run's own count.
TEST(Outputs, WrittenUnderTheRunsThreadCount) {
  const io::Job job = io::read_job(std::string(VCUT_SOURCE_DIR) + "/examples/ring/job.yaml");
  const fs::path out = fs::temp_directory_path() / ("vcut_outputs_" + std::to_string(::getpid()));
  fs::remove_all(out);
  fs::create_directories(out);
  tbb::global_control outer(tbb::global_control::max_allowed_parallelism, 3);
  for (const int threads : {1, 2}) {
    pipeline::SimulateOptions options;
    options.threads = threads;
    pipeline::SimulationResult result = pipeline::simulate(job, options);
    EXPECT_EQ(result.threads, threads);
    std::size_t seen = 0;
    write_simulation(out.string(), job, result, [&](const std::string& stage, std::size_t, std::size_t) {
      if (stage == "write") seen = tbb::global_control::active_value(tbb::global_control::max_allowed_parallelism);
    });
    EXPECT_EQ(seen, static_cast<std::size_t>(threads));
    EXPECT_TRUE(fs::exists(out / "machined.stl"));
    EXPECT_TRUE(fs::exists(out / "report.json"));
  }
  fs::remove_all(out);
}

}  // namespace
}  // namespace vcut::report
