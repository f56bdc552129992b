// `vcut compensate`: the program whose axis commands cancel the machine's geometric errors.
#pragma once

#include <cstddef>
#include <optional>
#include <string>

#include "vcut/io/job.h"
#include "vcut/pipeline/poses.h"

namespace vcut::pipeline {

// `vcut compensate`: for every densified pose, the axis commands whose error-aware forward
// kinematics put the tool on the nominal pose (kinematics::compensate), written in the
// program's dialect, one motion per pose with its source line as a comment. G-code: an axis
// program (X Y Z the linear axes zeroed so that at all-zero rotary axes the tip is at the
// programmed point, the convention of axis programs; A B C in deg). APT: the tool poses a
// tool-centre-point controller turns into those commands (the ideal forward kinematics of
// the compensated axes), as GOTO/x,y,z,i,j,k - provided the controller picks the same
// branch (near the pole, where both tie on rotary motion, it may not). Throws InputError
// when the machine has no geometric errors.
struct CompensationReport {
  std::size_t poses = 0;
  std::size_t not_converged = 0;
  double max_residual_tip_um = 0.0;
  double max_residual_axis_urad = 0.0;
  double max_error_before_um = 0.0;                     // uncompensated volumetric tip error
  std::optional<kinematics::SourceRef> max_error_line;  // none: at the start, before the first block
  std::string first_failure;                            // "file:line: note" of the first pose that did not converge
};
// The compensated program's text and what its making found; `vcut compensate` writes the text.
struct CompensatedProgram {
  CompensationReport report;
  std::string text;
};
CompensatedProgram compensate_program(const io::Job& job, const PoseRun& run);

}  // namespace vcut::pipeline
