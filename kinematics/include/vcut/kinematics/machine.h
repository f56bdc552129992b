// A machine tool as a serial chain of nodes (ARCHITECTURE §3, seed 000 §2): the frame F
// (the bed), three linear and up to two rotary axes, the workpiece W and the tool T. The
// topology string is read from W inward to F, then outward to T ("WCAFXYZT": W sits on C,
// C on A, A on the frame; X on the frame, Y on X, Z on Y, the spindle on Z). Without F the
// frame sits right after W (the paper's gantry "WYXZCAT").
//
// At all-zero axis values every node frame coincides with F. A linear axis translates its
// node by value x direction in its parent's frame; a rotary axis turns it by value
// (right-hand rule about `axis`) around the line through `center`. Inside: mm and rad.
// Geometric errors (ISO 230-1 names, ARCHITECTURE §6) are part of the model.
#pragma once

#include <Eigen/Core>

#include <array>
#include <map>
#include <set>
#include <optional>
#include <string>
#include <utility>
#include <vector>

namespace vcut::kinematics {

enum class AxisKind { Linear, Rotary };

// One error term over the axis position: a constant (one value) or a table of
// (position, value) pairs interpolated linearly and held constant beyond its ends.
// Positions in mm (linear axes) or rad (rotary axes); values in mm or rad.
struct ErrorTable {
  std::vector<double> positions;  // ascending; empty = constant
  std::vector<double> values;     // one value when constant

  bool empty() const { return values.empty(); }
  double at(double position) const;
};

// The component errors of an axis, functions of its own position (ISO 230-1: for X,
// E_XX E_YX E_ZX are the translations along the frame's x y z, E_AX E_BX E_CX the rotations
// about them). They follow the ideal motion (ideal x error, seed 002 eq. 1.15) and turn the
// node about its own origin (linear axes: the frame origin carried by the axis; rotary
// axes: `center`).
struct ComponentErrors {
  std::array<ErrorTable, 3> translation_mm;  // along x, y, z
  std::array<ErrorTable, 3> rotation_rad;    // about x, y, z

  bool empty() const;
};

// Constant errors of where an axis is. Rotary axes: the location errors of the axis line
// (E_X0C E_Y0C E_Z0C offsets, E_A0C E_B0C tilts for C), applied in the parent's frame about
// `center` before the rotation, so the node turns about the displaced, tilted line and a
// tilt tilts the carried part at every angle. Linear axes: squareness (E_C0Y, E_B0Z,
// E_A0Z ...), a rotation of the axis's direction; offsets are meaningless there.
struct LocationErrors {
  Eigen::Vector3d offset_mm = Eigen::Vector3d::Zero();
  Eigen::Vector3d tilt_rad = Eigen::Vector3d::Zero();  // about the frame's x, y, z

  bool empty() const { return offset_mm.isZero(0.0) && tilt_rad.isZero(0.0); }
};

struct AxisSpec {
  char letter = 'X';
  AxisKind kind = AxisKind::Linear;
  Eigen::Vector3d direction = Eigen::Vector3d::UnitX();  // linear: motion; rotary: turning axis
  Eigen::Vector3d center_mm = Eigen::Vector3d::Zero();   // rotary: a point on the axis line
  std::optional<std::pair<double, double>> limits;       // mm or rad; none = continuous
  double max_velocity_per_s = 0.0;                       // mm/s or rad/s; 0 = not given
  double max_acceleration_per_s2 = 0.0;                  // mm/s^2 or rad/s^2
  double max_jerk_per_s3 = 0.0;                          // mm/s^3 or rad/s^3
  ComponentErrors errors;
  LocationErrors location;
};

// A display or collision mesh hung on a node: its own coordinates are placed at `origin_mm`
// of the frame at all-zero axes (seed 000 Table 7).
struct ModelSpec {
  std::string file;
  Eigen::Vector3d origin_mm = Eigen::Vector3d::Zero();
  std::string name;  // as reports name it ("spindle head"); empty: the file's stem
};

// How the control reads F in an axis block (rotary words without TCP; seed 001 §4):
// LinuxCnc: F is the X Y Z path's speed when a linear axis moves, else the rotary axes'
//   (deg/min) - LinuxCNC's interpreter, SINUMERIK without TRAORI;
// Combined: F is the speed of the combined length sqrt(dx^2 + dy^2 + dz^2 + da^2 + db^2 +
//   dc^2), mm and deg alike - Fanuc, Haas;
// Tip: F is the tool tip's speed in the workpiece (as under TCP).
enum class FeedInterpretation { LinuxCnc, Combined, Tip };

struct MachineSpec {
  std::string name;
  std::string topology = "WXYZFT";
  std::vector<AxisSpec> axes;
  Eigen::Vector3d gauge_point_mm = Eigen::Vector3d::Zero();       // spindle nose at all-zero axes
  Eigen::Vector3d spindle_axis = Eigen::Vector3d::UnitZ();        // tip -> spindle, at all-zero axes
  Eigen::Vector3d workpiece_origin_mm = Eigen::Vector3d::Zero();  // programming zero at zero
  std::map<char, std::vector<ModelSpec>> models;                  // by node letter (an axis, W, T or F)
  double singularity_angle_rad = 0.1 * 3.14159265358979323846 / 180.0;
  // The machine file's feed_interpretation; none: by the program's dialect.
  std::optional<FeedInterpretation> feed_interpretation;
  // The reference position (G28, and where a program starts): axis values by letter (mm,
  // rad), the axes not named at 0. The second reference (G30): none means the first.
  std::map<char, double> home;
  std::optional<std::map<char, double>> second_home;
  // M codes this machine's control runs without a path effect (a part counter, a chip
  // conveyor): read without a warning.
  std::set<int> ignored_m_codes;
};

// A finding about a MachineSpec: `key` is the path of the offending entry ("topology",
// "axes.A.axis", "spindle.axis", ...), `message` what is wrong or was expected.
struct SpecProblem {
  std::string key;
  std::string message;
  bool warning = false;  // true: the spec was repaired (a vector normalised) and can be used
};

// Checks a spec and repairs what can be repaired (vectors within 1e-6 of unit length are
// normalised, with a warning). Problems that are not warnings make the spec unusable.
std::vector<SpecProblem> validate(MachineSpec& spec);

// Axis values in the machine's axis order (mm, rad): at most five, no heap.
using AxisValues = Eigen::Matrix<double, Eigen::Dynamic, 1, 0, 5, 1>;  // order X Y Z A B C

// The immutable model, shared read-only across threads (Pinocchio's model/data split).
class Machine {
 public:
  // `spec` must have passed validate() without errors; throws std::invalid_argument if not.
  explicit Machine(MachineSpec spec);

  const MachineSpec& spec() const { return spec_; }
  const std::string& name() const { return spec_.name; }
  int axis_count() const { return static_cast<int>(spec_.axes.size()); }
  const AxisSpec& axis(int i) const { return spec_.axes[static_cast<size_t>(i)]; }
  int axis_index(char letter) const;  // -1 when the machine has no such axis
  std::string axis_letters() const;   // in axis order, e.g. "XYZAC"

  // Axis indices of each chain, from the frame outward.
  const std::vector<int>& workpiece_chain() const { return workpiece_chain_; }
  const std::vector<int>& tool_chain() const { return tool_chain_; }

  // The rotary axes in the order of the orientation equation
  //   u_w = R(k_1, s_1 q_1) R(k_2, s_2 q_2) u_0
  // (workpiece-side axes from W inward with s = -1, then tool-side axes from F outward with
  // s = +1). rotary(0) is the one whose free angle appears when the tool axis lies along it.
  int rotary_count() const { return static_cast<int>(rotary_.size()); }
  int rotary_axis(int k) const { return rotary_[static_cast<size_t>(k)].first; }
  double rotary_sign(int k) const { return rotary_[static_cast<size_t>(k)].second; }

  bool has_errors() const { return has_errors_; }
  AxisValues zero() const { return AxisValues::Zero(axis_count()); }

 private:
  MachineSpec spec_;
  std::vector<int> workpiece_chain_, tool_chain_;
  std::vector<std::pair<int, double>> rotary_;
  bool has_errors_ = false;
};

}  // namespace vcut::kinematics
