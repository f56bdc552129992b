// `vcut study densification`'s files: study.csv, study.json, study.svg and study.png.
#pragma once

#include <string>

#include "vcut/io/job.h"
#include "vcut/pipeline/study.h"

namespace vcut::report {

// Written atomically into `folder`; their paths go to s.outputs.
void write_study(const std::string& folder, pipeline::StudyResult& s, const io::Job& job);

}  // namespace vcut::report
