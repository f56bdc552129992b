// `vcut study densification`: how finely to densify a program for a required accuracy. The
// job is cut at a series of densification settings and at a much finer reference setting,
// all at the same resolution and engine; each setting's machined surface is measured
// against the reference's (every vertex of each against the other's triangles), so what is
// left is the error the coarser densification makes, not the voxels'.
#pragma once

#include <Eigen/Core>

#include <cstddef>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "vcut/io/job.h"

namespace vcut::pipeline {

// One densification setting (seed 000 §3); 0 = as in the job.
struct DensifySetting {
  double step_mm = 0.0;       // lambda: largest tip step per pose
  double angle_deg = 0.0;     // phi: largest orientation step per pose
  double tolerance_mm = 0.0;  // epsilon: tolerance mode (replaces lambda, phi and the chord tolerance)
};

// "step 0.5 mm", "angle 1 deg", "step 0.5 mm, angle 1 deg", "tolerance 0.01 mm".
std::string describe(const DensifySetting& setting);

struct StudyOptions {
  // The settings: --steps and/or --angles (paired by position when both are given), or
  // --tolerances. Every value a positive number.
  std::vector<double> steps_mm, angles_deg, tolerances_mm;
  // The reference; a missing value is the finest setting's divided by 4.
  std::optional<double> reference_step_mm, reference_angle_deg, reference_tolerance_mm;
  std::optional<double> accuracy_mm;    // default: the job's gouge tolerance
  std::optional<double> resolution_mm;  // overrides engine.resolution
  std::optional<int> threads;           // overrides engine.threads
  double max_memory_mb = 0.0;           // as for simulate
  // Before each run: its index (the reference is the last, `count - 1`), count, setting.
  std::function<void(std::size_t, std::size_t, const std::string&)> on_run;
  // Within a run: stage, done, total (simulate's progress).
  std::function<void(const std::string&, std::size_t, std::size_t)> progress;
};

struct StudyRow {
  DensifySetting setting;
  std::string label;  // describe(setting)
  std::size_t poses = 0, moves = 0;
  // Distance of this setting's machined surface from the reference's (mm), sharp edges
  // apart (surface_difference): max, RMS, 99th percentile, where the max is.
  double max_mm = 0.0, rms_mm = 0.0, p99_mm = 0.0;
  Eigen::Vector3d max_where_mm = Eigen::Vector3d::Zero();
  double edge_max_mm = 0.0;  // the largest distance at sharp edges (meshing: up to about v/2)
  std::size_t edge_vertices = 0;
  double wall_time_s = 0.0;  // poses, moves, cut and mesh
  bool meets = false;        // max_mm <= the accuracy
  std::string error;         // why this setting could not be run ("" = it ran)
};

struct StudyResult {
  std::string job_name;
  std::string varied;  // "step", "angle", "step+angle" or "tolerance"
  double resolution_mm = 0.0, accuracy_mm = 0.0;
  // The turning five-axis moves' pieces (CutMoves): within a tenth of the accuracy, so that
  // what a setting measures is its densification, not the pieces' (which differ between
  // settings and overcut by up to this).
  double turn_tolerance_mm = 0.0;
  int threads = 0;
  io::Engine engine = io::Engine::Dexel;
  std::vector<StudyRow> rows;  // in the order given
  StudyRow reference;
  int recommended = -1;  // index in rows of the coarsest (fewest poses) setting that meets the accuracy
  std::vector<std::string> warnings;
  std::vector<std::string> outputs;  // the files written (report::write_study)
  double wall_time_s = 0.0, peak_memory_mb = 0.0;
};

// Runs the study (report::write_study writes its files). Bad options or input are a vcut::InputError, and so is a study
// in which no setting could be run; a setting that cannot be run (e.g. a pose out of reach) is a row with its error.
StudyResult run_densification_study(const io::Job& job, const StudyOptions& options);

}  // namespace vcut::pipeline
