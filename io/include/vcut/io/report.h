// The files a person or a program reads after a simulation: report.json (versioned schema)
// and gouges.csv (one row per gouge or excess region). Written atomically.
#pragma once

#include <string>

#include "vcut/io/job.h"
#include "vcut/io/simulate.h"

namespace vcut::io {

inline constexpr const char* kReportSchemaVersion = "1.0";

void write_report_json(const std::string& path, const Job& job, const SimulationResult& result);
void write_gouges_csv(const std::string& path, const SimulationResult& result);

}  // namespace vcut::io
