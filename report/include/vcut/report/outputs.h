// `vcut simulate`'s output folder: machined.stl, deviation.ply (with a design), the
// snapshots, gouges.csv, report.html and report.json, from a simulation's values.
#pragma once

#include <cstddef>
#include <functional>
#include <string>

#include "vcut/io/job.h"
#include "vcut/pipeline/simulate.h"

namespace vcut::report {

// Writes every output into `out_dir` (which must exist and be writable: io::ensure_writable_folder),
// each atomically. Fills result.input_hashes and result.outputs, adds the "write" stage to
// result.stage_seconds and its time to result.wall_time_s. `progress` (may be empty) hears
// ("write", 0, 1) as it starts.
void write_simulation(const std::string& out_dir, const io::Job& job, pipeline::SimulationResult& result,
                      const std::function<void(const std::string&, std::size_t, std::size_t)>& progress = {});

}  // namespace vcut::report
