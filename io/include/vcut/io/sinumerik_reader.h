// The SINUMERIK 840D reader: a subset of Siemens 840D sl part programs (.mpf/.spf) in, Blocks
// out, in the workpiece frame in mm (inches converted, work offsets applied), each naming its
// line. Five-axis programs under TRAORI become tool poses (tip and unit tool axis, ORIWKS).
// Bad input is a vcut::InputError naming file:line:column; nothing else is ever thrown.
//
// Read (case-insensitive; blanks allowed between an address letter and its number,
// "N7 X -1320 Y -1320 Z 1000 A 0 C 0"; `;` starts a comment; lines starting with `%`, such as
// %_N_NAME_MPF, are headers and skipped):
//   N blocks; G0 G1 G2 G3 (G1 at the start, Siemens' default) with I J K (centre relative to the
//   start; I=AC(..) absolute) or CR= (negative: the arc longer than 180 deg); G4 (dwell: no
//   motion, its F is a time); G17 G18 G19; G90 G91 and X=AC(..) X=IC(..) on one coordinate;
//   G54..G57 (SinumerikOptions::work_offsets_mm) and G500 (no offset, the default); G70 G71
//   (inch/metric lengths) and G700 G710 (lengths and feed); G94 (mm/min) G93 (inverse time: F in
//   every G1/G2/G3 block); TURN=n (n more full turns of an arc); F S M3 M4 M5 T (a number, or
//   T="n" with a number) M6 D; G60 (exact stop, the default) G9 (exact stop in its block) G64
//   G641 G642 (blending) with ADIS= (G1/G2/G3) and ADISPOS= (G0) as Block::blend_tolerance_mm;
//   G601 G602 G603 G40 (accepted, no effect); M0 M1 M7 M8 M9 (ignored: no motion); M2 M17 M30
//   (end of the file). R0..R999 (0 at the start, kept across files): R1=10, R2=R1*2+SIN(30),
//   with + - * / ( ) SIN COS TAN ASIN ACOS ATAN2 SQRT ABS POT (square) TRUNC ROUND (angles in
//   degrees) and numbers such as 1.5EX3; any value may be such an expression after `=`: X=R1+5.
//   TRAORI (or TRAORI(1)) / TRAFOOF: TCP on/off. Under TRAORI, X Y Z are the tool tip and the
//   orientation is A3= B3= C3= (the tool vector in the workpiece frame, ORIWKS; components not
//   programmed are 0; normalised) or A B C (rotary axis positions: Blocks with end_rotary,
//   whose tool axis the pose engine solves through the machine). Without TRAORI, A B C are axis
//   words (Blocks with tool_pose false), as in the G-code reader.
//   ORIWKS ORIMKS (ORIMKS only while no vector is programmed), ORIVECT ORIPLANE (great circle),
//   ORIAXES, and the cone modes (Job planning, "Orientation programming along the peripheral
//   surface of a taper"), each exact, as a cone Block:
//     ORICONCW ORICONCCW about the cone axis A6= B6= C6= (kept until the next A6 B6 C6; CW is a
//     positive right-hand turn about it, clockwise seen looking along it, as the manual's
//     example turns 270 deg from (0,1,1) to (1,0,1) about +Z); A6 B6 C6
//       without an end vector A3 B3 C3 is a full turn on that cone (the manual's example);
//     ORICONIO A7= B7= C7= A3= B3= C3=: the circle on the unit sphere through the start, the
//       intermediate (A7 B7 C7, in the block with the end) and the end orientation, passing the
//       intermediate one;
//     ORICONTO A3= B3= C3=: the circle through the start, tangent there to the tool vector's
//       direction of motion at the end of the previous motion block (which must have turned it
//       under ORIVECT/ORIPLANE or a cone mode), through the end.
//   MSG("...") (ignored).
//   Programmable frames: TRANS ATRANS (X Y Z: the new zero), ROT AROT (X Y Z: angles, turned
//   about Z, the new Y, the new X; RPL=: in the active plane), SCALE ASCALE (factors > 0),
//   MIRROR AMIRROR (the axes named). The plain forms replace the whole programmable frame
//   (TRANS alone clears it), the A-forms add to it in its own axes; in a block of their own
//   their X Y Z are the frame's values. Points, arc centres and tool vectors A3 B3 C3 and cone
//   axes go through it; a mirror reverses G2/G3; an arc in a plane scaled unequally is an
//   error. A turned frame needs X Y Z known before its first move.
//   Program flow: labels NAME: and block numbers as targets of GOTOF GOTOB GOTO GOTOC; IF cond
//   GOTOx; IF / ELSE / ENDIF; WHILE / ENDWHILE; FOR var = a TO b / ENDFOR; REPEAT / UNTIL;
//   LOOP / ENDLOOP; CASE (expr) OF c GOTOF label ... [DEFAULT GOTOF label]; DEF REAL | INT |
//   BOOL name[=value], ...; conditions with == <> < > <= >= AND OR XOR NOT TRUE FALSE and
//   parentheses. A loop runs at most SinumerikOptions::max_lines blocks.
//   Subprograms: L123 [P n], CALL "NAME", NAME or NAME(values) [P n], from NAME.SPF / .MPF in
//   the calling file's folder, then SinumerikOptions::subroutine_path; PROC NAME(REAL A, INT
//   B) binds the values; M17, RET, M2, M30 return; nested at most 16 deep.
//   CYCLE81(RTP, RFP, SDIS, DP, DPR), CYCLE82(..., DTB), CYCLE83(RTP, RFP, SDIS, DP, DPR, FDEP,
//   FDPR, DAM, DTB, DTS, FRF, VARI), tapping CYCLE84 CYCLE840 and boring CYCLE85..CYCLE89
//   (RTP, RFP, SDIS, DP, DPR, ...) in G17, at the current X Y (Reader::cycle has the motions),
//   called directly or by MCALL (each later positioning block ends with it; MCALL alone ends
//   it).
//   CYCLE800(_FR, _TC, _ST, _MODE, _X0.._Z0, _A, _B, _C, _X1.._Z1, _DIR, _FR_I): the swivel
//   frame and the rotaries' turn (Reader::swivel has the rules); CYCLE800() deselects.
//   SUPA G53 G153 (X Y Z in machine coordinates this block), D0 (the tool's length off: X Y Z
//   place the gauge point) and D1.. (on), G74 and G75 FP=1 / FP=2 with X1= Y1= Z1= (the
//   machine's home / second home); these, and CYCLE800 turning or retracting, need the machine
//   (SinumerikOptions). G505..G599 offsets; T="NAME" (numbered in the order named); FNORM,
//   SETMS (no effect on the path).
// Refused always (the reader would otherwise approximate or change the program's flow):
// NUT= (the manual gives its range but not which cone it selects), A6 B6 C6 under ORICONIO or
// ORICONTO, A7 B7 C7 outside ORICONIO, PCALL/EXTCALL, VAR parameters, DEF of other types
// than REAL, INT and BOOL, CYCLE800's solid-angle mode, other cycles,
// tool vectors under ORIMKS, a tool vector after the orientation was set by rotary
// axis positions. Any other word is an error, or with unsupported_as_warning one warning per
// distinct word, then ignored.
#pragma once

#include <vcut/io/gcode_reader.h>
#include <vcut/kinematics/program.h>

#include <Eigen/Core>
#include <array>
#include <cstddef>
#include <iosfwd>
#include <map>
#include <optional>
#include <set>
#include <string>
#include <vector>

namespace vcut::io {

struct SinumerikOptions {
  // Settable work offsets by name ("G54".."G57"): the workpiece-frame position (mm) of that
  // system's zero. Block coordinates = programmed coordinates (mm) + the active offset. G500
  // (the default) is no offset. Other names are not used.
  std::map<std::string, Eigen::Vector3d> work_offsets_mm;
  bool unsupported_as_warning = false;  // an unsupported word: one warning per word, ignored
  // M codes other than M0..M9, M17, M30: a warning once per code (none for m_codes_ignored,
  // the machine file's), or an error with unknown_m_code_as_error, as GcodeOptions has them.
  bool unknown_m_code_as_error = false;
  std::set<int> m_codes_ignored;
  // Radius mismatch allowed between the start and the end of a centre arc: the larger of this
  // and 0.1 % of the radius (the control's $MN_CIRCLE_ERROR_CONST, 0.01 mm, and
  // $MN_CIRCLE_ERROR_FACTOR, 0.001, as shipped).
  double arc_tolerance_mm = 0.01;
  // Blocks executed before a loop is taken to be endless (an error naming the line).
  long long max_lines = 100'000'000;
  // Folders searched, after the calling program's own, for a called subprogram NAME (NAME.SPF,
  // NAME.MPF, either case; L123: L123.SPF).
  std::vector<std::string> subroutine_path;
  // The machine, from a job (unset for `vcut program` without --machine), as the G-code reader
  // has it (GcodeOptions): `orient` and `tip_after_turn` turn the rotary axes for CYCLE800;
  // reference_mm are the gauge point's positions (workpiece frame, mm) at the machine's home
  // and second home, for G74, G75 FP=1 / FP=2 and CYCLE800's retraction; tool lengths (mm, by
  // T number) place the tip below the gauge point along spindle_axis.
  decltype(GcodeOptions::orient) orient;
  decltype(GcodeOptions::tip_after_turn) tip_after_turn;
  std::optional<std::array<Eigen::Vector3d, 2>> reference_mm;
  std::map<int, double> tool_length_mm;
  Eigen::Vector3d spindle_axis = Eigen::Vector3d::UnitZ();  // tip -> spindle, unit
  // The machine's rotary axis letters, rotary axis 1 first, as a Siemens swivel data record
  // counts them (the head's from the base outward, then the table's from the base inward):
  // CYCLE800 _MODE 192's _A and _B, and the frame those rotary positions give (the rotation of
  // the tool's frame on the workpiece).
  std::string rotary_axes;
  decltype(GcodeOptions::frame_rotation) frame_rotation;
  // The tool in the spindle when the first file starts (0: none), as GcodeOptions::initial_tool.
  int initial_tool = 0;
  // Where the spindle's gauge point stands when the first file starts (a job's machine home,
  // workpiece frame, mm); the tip is the initial tool's length below it. None: each axis is
  // unknown until programmed.
  std::optional<Eigen::Vector3d> start_mm;
  // SUPA / G53 / G153: the gauge point at all-zero axes (workpiece frame, mm), where machine
  // coordinate 0 lies (the workpiece zero without a machine).
  Eigen::Vector3d machine_zero_mm = Eigen::Vector3d::Zero();
};

// The modal state between lines and between files. Start from a default-constructed one
// (Siemens' reset values: G1 G17 G90 G71 G94 G500 G60 ORIWKS ORIVECT TRAFOOF, position unknown)
// and pass the same one, with the same Program, for each file in sequence.
struct SinumerikState {
  enum class Motion { Rapid, Linear, ArcClockwise, ArcCounterClockwise };
  enum class Plane { XY, ZX, YZ };  // G17, G18, G19

  Motion motion = Motion::Linear;
  Plane plane = Plane::XY;
  bool incremental = false;   // G91
  bool inch = false;          // G70 / G700: lengths in inches
  bool inch_feed = false;     // G700: F in inches per minute too
  bool inverse_time = false;  // G93
  std::string work_offset = "G500";

  Eigen::Vector3d position_mm = Eigen::Vector3d::Zero();  // workpiece frame, where known
  std::array<bool, 3> known = {false, false, false};      // X Y Z programmed yet?
  // Blocks (indices into Program::blocks) made while an axis was unknown: they hold it still
  // and take its value when it is first programmed.
  std::array<std::vector<std::size_t>, 3> pending;

  // Rotary axes A B C (rad) as last programmed (given: known to the reader).
  kinematics::RotaryWords rotary;
  bool rotary_program = false;  // A B C programmed without TRAORI: axis blocks from then on
  bool traori = false;
  bool orimks = false;
  kinematics::OrientationMode orientation = kinematics::OrientationMode::Vector;
  Eigen::Vector3d tool_axis = Eigen::Vector3d::UnitZ();  // the last tool vector, unit
  int axis_set_by_rotary_line = 0;                       // > 0: the orientation was last set by A B C on that line
  Eigen::Vector3d cone_axis = Eigen::Vector3d::Zero();   // A6 B6 C6, unit; zero: none yet
  // How a cone mode's cone is given: by A6 B6 C6 (ORICONCW/CCW, `orientation` says which way),
  // through A7 B7 C7 (ORICONIO) or by the tangent (ORICONTO); the last two are made
  // counterclockwise about the axis they determine.
  enum class ConeBy { Axis, Intermediate, Tangent };
  ConeBy cone_by = ConeBy::Axis;
  // The tool vector's unit direction of motion at the end of the last motion block; zero where
  // that block did not turn it on a great circle or a cone (ORICONTO starts along it).
  Eigen::Vector3d axis_tangent = Eigen::Vector3d::Zero();

  bool exact_stop = true;        // G60 (default); G64 G641 G642 clear it
  double adis_mm = -1.0;         // ADIS=; < 0: none given
  double adispos_mm = -1.0;      // ADISPOS=
  double feed_mm_per_min = 0.0;  // 0: no F yet
  double spindle_rpm = 0.0;
  kinematics::SpindleState spindle = kinematics::SpindleState::Off;
  bool tool_offset_off = false;           // D0: X Y Z place the gauge point, the tip a tool length below
  std::map<std::string, int> tool_names;  // T="NAME": numbered 1, 2, ... in the order named
  int tool = 0;                           // in the spindle (after M6)
  int selected_tool = -1;                 // last T, -1 if none
  std::vector<double> r;                  // R0..R999 (sized when the first file starts)
  // The programmable frame (TRANS ROT SCALE MIRROR and their additive A-forms): a programmed
  // point p lies at work offset + frame_translation_mm + frame_linear * p in the workpiece frame.
  Eigen::Matrix3d frame_linear = Eigen::Matrix3d::Identity();
  Eigen::Vector3d frame_translation_mm = Eigen::Vector3d::Zero();
  // CYCLE800's swivel frame, between the work offset and the programmable frame: a point p of
  // the programmable frame lies at work offset + swivel_translation_mm + swivel_rotation *
  // (frame_translation_mm + frame_linear * p).
  Eigen::Matrix3d swivel_rotation = Eigen::Matrix3d::Identity();
  Eigen::Vector3d swivel_translation_mm = Eigen::Vector3d::Zero();
  bool swivel_plane = false;  // a CYCLE800 plane is on (not deselected)
  // MCALL CYCLE81/82/83(...): the drilling cycle every positioning block ends with; empty: none.
  std::string modal_cycle;
  std::vector<std::optional<double>> modal_cycle_args;
  std::set<std::string> warned;  // unsupported words already warned about
};

// Reads one program file; errors are vcut::InputError naming file:line:column.
kinematics::Program read_sinumerik(const std::string& path, const SinumerikOptions& options = {});
// Appends one program read from `in` (named `name` in errors and sources) to `program`.
// Memory: the file's lines (jumps and loops go back to them; lines up to 1 MiB), plus the output.
void read_sinumerik(std::istream& in, const std::string& name, const SinumerikOptions& options,
                    kinematics::Program& program, SinumerikState& state);

}  // namespace vcut::io
