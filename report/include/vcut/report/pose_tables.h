// The pose engine's results as CSV tables (`vcut poses`): one row per densified pose, one per
// block, and with --every-period one per interpolation period of the servo.
#pragma once

#include <string>

#include "vcut/io/job.h"
#include "vcut/pipeline/poses.h"

namespace vcut::report {

// The pose engine with every interpolation period of the servo streamed into a CSV at
// `periods_path` (vcut poses --every-period): t, block, source, the commanded and the actual
// axis values by letter (mm, deg), commanded tip, actual tip and tool axis, contour_error_um.
// Written atomically (the file appears when the run is done); an InputError when the job has
// no servo.
pipeline::PoseRun run_pose_engine_with_periods(const io::Job& job, const std::string& periods_path);

// One row per program block: block, source, kind, q, time_s, nonlinear_error_mm (and where),
// singular, unreachable, and with servo or errors the contour error of its interpolation
// periods (servo) or its poses (errors only): max, RMS, where. Written atomically.
void write_blocks_csv(const std::string& path, const io::Job& job, const pipeline::PoseRun& run);

// One row per densified pose: block, source, t, x y z (tip), i j k (axis), the axis values by
// letter (mm, deg), feed (mm/min); with servo or errors also actual_x .. actual_k and
// contour_error_um. Written atomically.
void write_poses_csv(const std::string& path, const io::Job& job, const pipeline::PoseRun& run);

}  // namespace vcut::report
