// The files a person or a program reads after a simulation: report.json (versioned schema)
// gouges.csv (one row per gouge or excess region) and collisions.csv (one per collision).
// Written atomically.
#pragma once

#include <string>

#include "vcut/io/job.h"
#include "vcut/pipeline/simulate.h"

namespace vcut::report {

inline constexpr const char* kReportSchemaVersion = "1.0";

// out_dir: the output folder, as report.json names it.
void write_report_json(const std::string& path, const std::string& out_dir, const io::Job& job,
                       const pipeline::SimulationResult& result);
void write_gouges_csv(const std::string& path, const pipeline::SimulationResult& result);
// collisions.csv: the tool's parts in the stock, then the machine's collisions and near misses.
void write_collisions_csv(const std::string& path, const pipeline::SimulationResult& result);

}  // namespace vcut::report
