// `vcut check --json`: the findings as JSON (schema vcut-check/1).
#pragma once

#include <string>

#include "vcut/io/job.h"
#include "vcut/pipeline/check.h"

namespace vcut::report {

// Written atomically.
void write_check_json(const std::string& path, const io::Job& job, const pipeline::CheckResult& result);

}  // namespace vcut::report
