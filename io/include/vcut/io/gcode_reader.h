// The G-code reader: RS274/NGC programs (LinuxCNC/Fanuc dialect, X Y Z core) in, Blocks out,
// in the workpiece frame in mm (inches converted, work offsets applied), each naming its line.
// Bad input is a vcut::InputError naming file:line:column; nothing else is ever thrown.
#pragma once

#include <vcut/kinematics/program.h>

#include <Eigen/Core>
#include <array>
#include <cstddef>
#include <functional>
#include <iosfwd>
#include <map>
#include <optional>
#include <set>
#include <string>
#include <vector>

namespace vcut::io {

struct GcodeOptions {
  // Work offsets by name ("G54".."G59.3"): the workpiece-frame position (mm) of that system's
  // zero. Block coordinates = programmed coordinates (in mm) + the active offset. Default all zero.
  std::map<std::string, Eigen::Vector3d> work_offsets_mm;
  bool unsupported_as_warning = false;  // an unsupported word: one warning per distinct word, then ignored
  // Whose rules the reader follows where controls differ: LinuxCNC (rs274ngc: a nested
  // comment is a warning, G80 shares group 1 with G0..G3), Fanuc/Haas, or Generic (the
  // dialect "gcode" and auto-detected files: rs274ngc's semantics, the controls' tolerance).
  enum class Flavor { Generic, LinuxCnc, Fanuc };
  Flavor flavor = Flavor::Generic;
  // I J K arcs whose end lies off the start's circle: accepted (the arc becomes a spiral, as
  // on the control) when the radii differ by at most arc_tolerance_mm, or by at most 0.1 % of
  // the radius (arc_tolerance_relative) and 100 x arc_tolerance_mm; beyond, an error naming
  // both radii. arc_tolerance_mm < 0: LinuxCNC 2.9's, 2 * 0.01 * sqrt(2) = 0.0283 mm in G21
  // and 2 * 0.001 * sqrt(2) = 0.00283 in in G20.
  double arc_tolerance_mm = -1.0;
  double arc_tolerance_relative = 0.001;
  // Block delete ('/' at the start of a line): the switch on skips those lines (the default,
  // as rs274 runs), off runs them.
  bool block_delete = true;
  // An M code the reader does not know (Haas M31 part counter, a machine's own M101...) is a
  // warning naming file:line, once per code, and the motion goes on; true makes it an error.
  // Program-flow codes (M97, M98, M99) are never ignored. m_codes_ignored are known to the
  // machine (its file's m_codes): no warning.
  bool unknown_m_code_as_error = false;
  std::set<int> m_codes_ignored;
  // Folders searched for the file <name>.ngc of a subroutine called but not defined in the
  // program (LinuxCNC's SUBROUTINE_PATH), after the calling program's own folder.
  std::vector<std::string> subroutine_path;
  // Lines read (executed or skipped) before the reader stops with an error: loops that never
  // end. Each loop pass counts its lines again.
  long long max_lines = 100'000'000;
  // M codes that switch tool-centre-point kinematics on (true) or off (false), such as
  // LinuxCNC's M428/M429 in its table-rotary-tilting demos: on acts like G43.4.
  std::map<int, bool> tcp_m_codes;
  // Where the machine is when the first file starts, and the reference positions G28 and G30
  // go to (#5161.. and #5181.., which G28.1 / G30.1 overwrite): G53 coordinates (the
  // workpiece frame without work offsets, mm) of the spindle's gauge point, so that a tool of
  // length L (tool_length_mm, by T number) puts its tip L along -spindle_axis from it.
  // LinuxCNC's standalone rs274 starts at 0 with zero references and no tool lengths; `vcut
  // program` does the same, a job starts at its machine's home. No start position: each axis
  // is unknown until programmed, and moves made before hold it at its first programmed value
  // (with a warning) - a motion no machine makes, for callers that know no machine.
  std::optional<Eigen::Vector3d> start_mm;
  std::array<Eigen::Vector3d, 2> reference_mm = {Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero()};
  std::array<std::array<double, 3>, 2> reference_rotary_deg = {};  // A B C at G28 / G30
  std::map<int, double> tool_length_mm;
  // Cutter radius compensation (G41/G42 D): the radius of each tool by T number (mm), from
  // the tool library. A D or a tool in the spindle not listed here is an error.
  std::map<int, double> tool_radius_mm;
  Eigen::Vector3d spindle_axis = Eigen::Vector3d::UnitZ();  // tip -> spindle, unit
  // The tool in the spindle when the first file starts (0: none; programs that never change
  // tools, like LinuxCNC's demos, run with the machine's current tool).
  int initial_tool = 0;
  // The machine's rotary axes, for G53.1 / G53.6 under a tilted work plane (G68.2). `orient`
  // puts into `to` the rotary words (rad; the machine's rotary letters given) that turn the
  // tool to `axis` (unit, tip -> spindle, workpiece frame) with the tip at `tip_mm`, with the
  // least rotary motion from `from` (tilt_sign +1 / -1: among the solutions whose tilting
  // axis - the rotary least parallel to the spindle - is >= 0 / <= 0), and returns "" - or
  // why the machine cannot (a limit, an unreachable axis). `tip_after_turn` gives where the
  // tip goes (workpiece frame, mm) when the rotary axes turn from `from` to `to` with the
  // linear axes held. Unset (no machine): G53.1 and G53.6 are errors, and rotary words
  // without TCP make an axis program.
  std::function<std::string(int tool, const Eigen::Vector3d& tip_mm, const Eigen::Vector3d& axis,
                            const kinematics::RotaryWords& from, int tilt_sign, kinematics::RotaryWords& to)>
      orient;
  std::function<Eigen::Vector3d(int tool, const Eigen::Vector3d& tip_mm, const kinematics::RotaryWords& from,
                                const kinematics::RotaryWords& to)>
      tip_after_turn;
  // For the SINUMERIK reader (SinumerikOptions), set by set_machine: the machine's rotary axis
  // letters, rotary axis 1 first, and the rotation the rotaries at given values give the tool's
  // frame on the workpiece (the machine's orientation equation).
  std::string rotary_axes;
  std::function<Eigen::Matrix3d(const kinematics::RotaryWords&)> frame_rotation;
  // The extra linear axes U V W the machine has (their letters). A U, V or W word for one it
  // lacks is an error naming the word, as on a LinuxCNC machine whose axis mask lacks it.
  // `vcut program` reads all three, as LinuxCNC's interpreter on a 9-axis machine; a job none
  // (vcut's machines move X Y Z and their rotaries).
  std::string extra_axes = "UVW";
  // Where the gauge point stands at all-zero axes (workpiece frame, mm): machine coordinate 0.
  Eigen::Vector3d machine_zero_mm = Eigen::Vector3d::Zero();
  // Probing (G38.2..G38.5; G31, Fanuc's skip and Mach3's probe): where along the move from
  // `from` to `to` (tips, workpiece frame, mm) the probe's tip first touches the stock, as a
  // fraction in [0, 1] (0: it starts inside), or none. A job sets it from its stock; unset
  // (`vcut program`), a probe trips 0.254 mm before its end, as LinuxCNC's standalone rs274
  // has it, with a warning.
  std::function<std::optional<double>(const Eigen::Vector3d& from, const Eigen::Vector3d& to)> probe_contact;
};
// Reads one program file; errors are vcut::InputError naming file:line:column.
// Appends to `program` (so several files can run in sequence; the modal state and the
// position carry over from the previous file when `state` is passed back in).
struct GcodeState;  // opaque modal state (define it in the header; fields are yours)
kinematics::Program read_gcode(const std::string& path, const GcodeOptions& options);
void read_gcode(std::istream& in, const std::string& name, const GcodeOptions& options, kinematics::Program& program,
                GcodeState& state);

// The modal state between lines and between files. Start from a default-constructed one
// (LinuxCNC's power-on modes: G17 G21 G90 G91.1 G94 G54 M5, no motion mode, no F, no tool;
// the position GcodeOptions::start_mm, or unknown) and pass the same one, with the same
// Program, for each file in sequence.
struct GcodeState {
  // SpindleSync: G33 (a straight feed at K per spindle revolution); RigidTap: G33.1 (down and
  // back at K per revolution); CubicSpline, QuadraticSpline: G5, G5.1 (LinuxCNC); Probe:
  // G38.2..G38.5; Nurbs: between G5.2 and G5.3.
  enum class Motion {
    None,
    Rapid,
    Linear,
    ArcClockwise,
    ArcCounterClockwise,
    Cycle,
    SpindleSync,
    RigidTap,
    CubicSpline,
    QuadraticSpline,
    Probe,
    Nurbs,
    Unsupported
  };
  enum class Plane { XY, ZX, YZ };  // G17, G18, G19

  Motion motion = Motion::None;  // None until G0..G3; G80 sets it back
  int cycle = 0;                 // the canned cycle's G code x10 (810 for G81) when Motion::Cycle
  int probe = 0;                 // 382..385 (G38.2..G38.5) when Motion::Probe
  Plane plane = Plane::XY;
  bool inches = false;               // G20
  bool incremental = false;          // G91
  bool arc_center_absolute = false;  // G90.1 (default G91.1)
  std::string work_offset = "G54";   // the active coordinate system

  Eigen::Vector3d position_mm = Eigen::Vector3d::Zero();  // workpiece frame, where known
  // Known from the start when GcodeOptions::start_mm is given; an axis becomes unknown after
  // an ignored code that moved it (program.unsupported: warn) until it is programmed again.
  std::array<bool, 3> known = {false, false, false};
  // Blocks (indices into Program::blocks) emitted while an axis was unknown: they hold that
  // axis still, and take its value when it is first programmed.
  std::array<std::vector<std::size_t>, 3> pending;

  // Rotary axes A B C (rad) as last programmed; once any is programmed the program is an
  // axis program (Block::tool_pose false: X Y Z are the linear axes, A B C axis values).
  kinematics::RotaryWords rotary;
  bool rotary_program = false;
  // U V W (mm, work offsets applied) as last programmed, and their G5x and G92 offsets
  // (#5227.. + 20 k, #5217..): LinuxCNC's extra linear axes, 0 at the start.
  kinematics::ExtraAxes extra;
  std::array<double, 3> g5x_extra_mm = {0.0, 0.0, 0.0}, g92_extra_mm = {0.0, 0.0, 0.0};
  // Tool centre point: G43.4 (or a job-mapped M code) takes X Y Z as the tip in the workpiece
  // frame and A B C as the rotary axes; G43.5 takes I J K as the tool axis; G43/G49 end it.
  enum class Tcp { Off, Angles, Vector };
  Tcp tcp = Tcp::Off;
  Eigen::Vector3d tool_axis = Eigen::Vector3d::UnitZ();  // G43.5: the last I J K, unit
  bool exact_stop = false;                               // G61 / G61.1 (G64 clears it)
  double blend_tolerance_mm = -1.0;                      // G64 P; < 0: none given

  double feed_mm_per_min = 0.0;  // 0: no F yet
  double spindle_rpm = 0.0;
  kinematics::SpindleState spindle = kinematics::SpindleState::Off;
  bool inverse_time = false;     // G93: F is 1 / minutes per move
  int tool = 0;                  // in the spindle (after M6)
  int selected_tool = -1;        // last T word, -1 if none
  std::set<std::string> warned;  // unsupported words already warned about

  // Programmed X Y Z (mm) + g5x + g92 = workpiece frame. The coordinate systems' offsets live
  // in the parameters as in LinuxCNC (#5221 + 20 k .. for G54 + k, mm), taken from
  // GcodeOptions::work_offsets_mm when the first file starts; selecting a system (G54..) or
  // G10 on the active one brings g5x_mm up to date.
  Eigen::Vector3d g5x_mm = Eigen::Vector3d::Zero();
  Eigen::Vector3d g92_mm = Eigen::Vector3d::Zero();  // G92 offset (#5211..#5213)
  // Numbered parameters #1..#5601 (index = number; empty until the first file starts) and
  // the named ones: globals (#<_name>) and the main program's locals.
  std::vector<double> parameters;
  // Fanuc 30i's added common variables #98000..#98499 and #100000..#199999 (vacant until set).
  std::map<int, double> added_commons;
  std::map<std::string, double> globals, locals;
  // Canned cycles (G81..G89): the height (mm, program coordinates) the series of cycles
  // started at: G98 goes back to it, and in G91 R counts from it.
  double cycle_initial_z_mm = 0.0;
  bool retract_to_r = false;  // G99 (set when the first file starts: G99 as rs274ngc, G98 for Fanuc)
  // Sticky cycle words as last given (program units; R and Z as written, G91 increments
  // included): a later line of the same series may give only X and Y.
  double cycle_r = 0.0, cycle_z = 0.0, cycle_q = 0.0, cycle_p = 0.0;
  // G5: the last spline's second control point (mm, workpiece frame), for the next G5 without
  // I J (LinuxCNC: the mirror of it through the start continues the curve smoothly).
  std::optional<Eigen::Vector2d> spline_control_mm;
  // G5.2 .. G5.3 (LinuxCNC NURBS, Motion::Nurbs): the control points so far (X Y in mm,
  // workpiece frame, and the weight P; the first is where G5.2 started), the order L, the feed.
  struct Nurbs {
    std::vector<Eigen::Vector3d> points;
    int order = 3;
    double feed_mm_per_min = 0.0;
  };
  std::optional<Nurbs> nurbs;
  // Fanuc G68 in G17: programmed X Y turn by rotation_rad about rotation_center_mm (program
  // coordinates, mm) before the work offsets apply; G69 sets it back to 0.
  double rotation_rad = 0.0;
  Eigen::Vector2d rotation_center_mm = Eigen::Vector2d::Zero();
  // LinuxCNC's rotation of the active coordinate system (G10 L2 R, #5230 + 20 k, deg there):
  // workpiece = Rz(system_rotation_rad) (programmed + G92) + G5x offset.
  double system_rotation_rad = 0.0;
  // G68.2 tilted work plane (until G69 or the program's end): the reader works on in the
  // feature frame (programmed coordinates + the offsets, as without it) and its blocks go out
  // as workpiece = twp_rotation * q + twp_translation_mm, tool poses with the rotary axes'
  // values (G53.1 / G53.6 turn them), as on a control's tilted-plane mode (twp_feature).
  // Without TCP, in a program that uses G68.2 or G43, the rotaries may also stand turned
  // outside it (after G69, or a rotary word): X Y Z are then the machine's (the point the tip
  // would be at with the rotaries at zero) and the same transform, from the machine, takes
  // them to the workpiece (twp on, twp_feature off).
  bool twp = false;
  bool twp_feature = false;
  bool twp_used = false;     // G68.2 came in this program
  bool length_comp = false;  // G43 / G43.1 / G43.2 on (G49, G43.4, G43.5 end it)
  // G43.1 X Y Z (and G43.2 added to it): the control's tool length offset (mm) while it is on;
  // G28 / G30 and G28.1 count the tip that far from the gauge point, as LinuxCNC does.
  std::optional<Eigen::Vector3d> dynamic_length_mm;
  Eigen::Matrix3d twp_rotation = Eigen::Matrix3d::Identity();
  Eigen::Vector3d twp_translation_mm = Eigen::Vector3d::Zero();

  // Cutter radius compensation as LinuxCNC's interpreter does it (G41/G42, G41.1/G42.1, G40):
  // the tool's path is offset by the radius in the plane (G17 XY, G18 ZX); each move is held
  // until the next one decides its end (a concave corner moves it back to the offset paths'
  // meeting point; a convex corner gets an arc of the tool radius about the programmed corner).
  struct CutterComp {
    enum class Side { Off, Left, Right };
    Side side = Side::Off;
    double radius_mm = 0.0;  // > 0 compensates; 0 (a tool of no radius) moves as programmed
    // The largest radius compensated with so far (mm). A corner under 0.05 rad counts as
    // tangent (rs274's rule): the arc after it starts where the move before ends, up to 0.05
    // times the radius off its offset circle (the machine spirals to its end).
    double max_radius_mm = 0.0;
    bool first_move = true;                                // the next move is the entry move
    bool arc_not_allowed = false;                          // the move after G40 must be straight
    Eigen::Vector3d program_mm = Eigen::Vector3d::Zero();  // the last programmed (uncompensated) end
    struct Held {
      kinematics::Block block;
      Eigen::Vector2d direction = Eigen::Vector2d::Zero();  // straight: the programmed direction
      double sweep_rad = 0.0;                               // arc: the programmed sweep
    };
    std::vector<Held> held;                              // moves whose end the next corner may still move
    Eigen::Vector2d endpoint = Eigen::Vector2d::Zero();  // where the held move starts (gouge checks)
    bool endpoint_valid = false;
    std::optional<Eigen::Vector3d> machine_mm;  // after G40: the last compensated end, where the machine is
  };
  CutterComp comp;
};

}  // namespace vcut::io
