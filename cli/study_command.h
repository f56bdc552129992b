// `vcut study densification JOB --steps|--angles|--tolerances ...`: how finely to densify a
// program for a required accuracy (exit 1 when no setting meets it).
#pragma once

#include <CLI/CLI.hpp>

#include <optional>
#include <string>

#include "vcut/pipeline/study.h"

namespace vcut::cli {

struct StudyCommand {
  CLI::App* densification = nullptr;
  std::string job, out;
  pipeline::StudyOptions options;
  double resolution_mm = 0.0, accuracy_mm = 0.0, reference_step_mm = 0.0, reference_angle_deg = 0.0,
         reference_tolerance_mm = 0.0;
  int threads = -1;
  bool quiet = false;
};

void add_study_command(CLI::App& app, StudyCommand& command);
// Runs it if it was given and returns its exit code; nothing when it was not. Bad input:
// vcut::InputError.
std::optional<int> run_study_command(const StudyCommand& command);

}  // namespace vcut::cli
