// Time along the densified poses (ARCHITECTURE §5, seed 000 eqs. 5-7, seed 001): a
// jerk-limited S-curve per block with look-ahead junction speeds, bounded by the programmed
// feed (G94 mm/min, G93 inverse time), by each machine axis's velocity, acceleration and
// jerk through the kinematics at every densified pose, by exact stop (G61/G9) or blending
// (G64 P); rapids at axis speed. Every pose gets a time stamp. Units: mm, s, mm/s.
#pragma once

#include <cstddef>
#include <functional>
#include <vector>

#include "vcut/kinematics/densify.h"
#include "vcut/kinematics/machine.h"
#include "vcut/kinematics/program.h"

namespace vcut::kinematics {

struct FeedSettings {
  // Path limits used where no machine is given, or in addition to the machine's axes.
  double path_acceleration_mm_per_s2 = 2000.0;
  double path_jerk_mm_per_s3 = 50000.0;
  double rapid_mm_per_min = 10000.0;  // rapid path speed when no machine is given
  int lookahead_blocks = 1000;        // junction speeds see at least this many blocks ahead
  double start_speed_mm_per_s = 0.0;  // program start and end (seed 000: 0)
  double end_speed_mm_per_s = 0.0;
  // Corner rule where a block gives no G64 P: the blend arc may pass this far (mm) from the
  // programmed corner. 0 stops at every corner.
  double default_blend_tolerance_mm = 0.01;
  // F in axis blocks (rotary words without TCP): see FeedInterpretation. The path parameter
  // stays the tip's arc length; the block's cruise is set so that it lasts L / F, L the
  // length F applies to.
  FeedInterpretation axis_feed = FeedInterpretation::LinuxCnc;
  // Keep FeedPlan::path_s and spans, the timing between the samples that the interpolator's
  // periods need (servo); without it the plan holds the samples' times and speeds only.
  bool timing = true;
};

// One piece of the path parameter's motion at constant jerk: s(tau) = s0 + v0 tau + a0 tau^2/2
// + jerk tau^3/6 for tau in [0, duration_s], from t0_s. The parameter is the tip's arc length
// (mm) or, for blocks whose tip stands still, the rotary motion (deg).
struct JerkPhase {
  double t0_s = 0.0, s0 = 0.0, v0 = 0.0, a0 = 0.0, jerk = 0.0, duration_s = 0.0;
  double at(double tau) const { return s0 + tau * (v0 + tau * (0.5 * a0 + jerk * tau / 6.0)); }
};

// One S-curve of the plan: the moves into samples first_sample .. last_sample, from t0_s.
struct SpanTiming {
  std::size_t first_sample = 1, last_sample = 0;
  double t0_s = 0.0, duration_s = 0.0;
  std::vector<JerkPhase> phases;  // t0_s and s0 absolute (plan time, FeedPlan::path_s)
};

struct FeedPlan {
  std::vector<double> t_s;             // per sample of the densified list, ascending
  std::vector<double> speed_mm_per_s;  // path speed of the tip at each sample
  std::vector<double> block_time_s;    // per program block
  double cycle_time_s = 0.0;
  // Where a machine axis limit (not the programmed feed) set the speed: sample indices.
  std::vector<int> axis_limited_samples;
  // The timing between the samples: the path parameter at each sample (cumulative over the
  // program, mm or deg) and each span's jerk phases, so that the path can be evaluated at any
  // instant (the interpolator's periods), not only at the samples. Empty without
  // FeedSettings::timing.
  std::vector<double> path_s;
  std::vector<SpanTiming> spans;
};

// Where the timed path is at an instant: on the move into sample `segment` (from segment - 1)
// at `fraction` of that move's path parameter. Before the start: segment 1, fraction 0;
// after the end: the last sample. Instants are asked for in ascending order (a cursor: O(1)
// amortised per call); an earlier instant restarts the search.
struct PathPosition {
  std::size_t segment = 1;
  double fraction = 0.0;
};
class PathCursor {
 public:
  explicit PathCursor(const FeedPlan& plan) : plan_(plan) {}
  PathPosition at(double t_s);

 private:
  const FeedPlan& plan_;
  std::size_t span_ = 0, phase_ = 0, segment_ = 1;
  double last_t_s_ = 0.0;
};

// `samples` from densify(); with a `machine` (may be null) their axis values and its limits
// count: every segment's path speed is then also bounded so that each axis stays within its
// velocity, acceleration and jerk. Blocks whose
// tip stands still while the tool turns are timed on the rotary motion (LinuxCNC: F in
// deg/min; the path limits then read deg/s^2 and deg/s^3); their tip speed is 0.
FeedPlan plan_feed(const Program& program, const std::vector<PoseSample>& samples, const Machine* machine,
                   const FeedSettings& settings);

// plan_feed without holding the samples (the default run: no servo, so no timing between
// them): the program is densified (densify's Densifier) and timed in one pass that holds
// a bounded look-ahead, whatever its length. Every sample is visited in order with its time
// and tip speed (plan_feed's t_s and speed_mm_per_s, the same bytes), and after its samples
// each block with densify's report, its time (block_time_s) and whether a machine axis set
// its speed (axis_limited_samples). The feed machine is the densify machine's. Returns the
// cycle time (s).
struct FeedStreamVisitor {
  std::function<void(std::size_t index, const PoseSample& sample, double t_s, double speed_mm_per_s)> sample;
  std::function<void(std::size_t block, const BlockReport& report, double time_s, bool axis_limited)> block;
};
double stream_feed(const Program& program, const DensifySettings& densify_settings, const DensifyMachine& machine,
                   const FeedSettings& settings, const FeedStreamVisitor& visit);

}  // namespace vcut::kinematics
