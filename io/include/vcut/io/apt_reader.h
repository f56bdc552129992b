// The APT CL-data reader: cutter-location files as CAM systems write them (the text form of
// ISO 4343 CLDATA: GOTO/, FROM/, CIRCLE/, CUTTER/, MULTAX/ ...) in, tool-pose Blocks out: tool
// tips and unit tool axes in the workpiece frame, mm (inches converted), each naming its line,
// and the cutters that the file's CUTTER/ statements describe.
// Bad input is a vcut::InputError naming file:line:column; nothing else is ever thrown.
//
// Statements read (case-insensitive; blanks anywhere between items), as SolidWorks CAM, NX,
// Creo and CATIA write them (docs/PROGRAMS.md has the details and the files they came from):
//   GOTO/x,y,z[,i,j,k] (the axis with or without MULTAX)  FROM/x,y,z[,i,j,k]
//   GODLTA/dx,dy,dz | GODLTA/d (along the tool axis)  GOHOME[/x,y,z[,i,j,k]] (a rapid; to FROM/)
//   RAPID | RAPID/ (the next motion only)  FEDRAT/f[,MMPM|IPM] | FEDRAT/MMPM|IPM,f
//   CUTTER/d[,r[,e[,f[,alpha[,beta[,h]]]]]][,]  TLDATA/MILL,d,r,h,taper,tip (NX)
//   LOADTL/n[,...]  LOAD/TOOL,n[,...] (NX; n = 0: numbered by its cutter)
//   MULTAX[/ON|OFF]  TLAXIS/i,j,k
//   CIRCLE/cx,cy,cz,i,j,k[,r[,tolerances]][,TIMES,n] then its GOTO/
//   INDIRV/i,j,k then TLON,GOFWD/(CIRCLE/cx,cy,cz,r),ON,[n,INTOF,](LINE/x1,y1,z1,x2,y2,z2)
//     (CATIA V5): from the current point along the circle, starting in the direction
//     INDIRV/ gives, to the line's n-th crossing (1 by default)
//   SPINDL/n[,RPM][,CLW|CCLW] | /RPM,n[,...] | /ON | /OFF
//   CSYS/ 3x4 matrix (SolidWorks CAM setups)  MSYS/origin,X axis,Y axis (NX)
//   CYCLE/DRILL|DEEP|DEEP2|BRKCHP|TAP|BORE|REAM,... | /OFF | /ON | /INIT: drilling cycles
//   UNITS/INCHES|MM  PPRINT, INSERT (comments)  END (a section end: reading goes on)
//   CUTCOM/LEFT|RIGHT[,XYPLAN][,n] ... CUTCOM/OFF (compensation in the XY plane, as G41/G42
//   and G40 with the CUTTER/'s radius; none on a centre path: NX's "$$ centerline data",
//   SolidWorks CAM's CSI_ statements, AptOptions::cutcom_on_centre)
//   FINI (the end: nothing after it is read)
//   `$` continues a statement on the next line (the rest of the line is a comment);
//   `$$` starts a comment (one that ends in '$' goes on, as Creo writes them); NX's
//   information listing's header and last line are skipped.
// Any other statement is ignored with one warning per distinct statement word (PARTNO,
// REMARK and TPRINT take the rest of their line as text). A line that is not WORD or
// WORD/parameters (G-code, APT source geometry "P1=POINT/...") is an error.
//
// Conventions:
// - The tool tip is the GOTO point (APT's control point: the lowest point on the tool axis)
//   and the tool axis (i,j,k), normalised, points from the tip toward the spindle. Blocks are
//   tool poses (tool_pose = true) whose axis turns on the great circle (OrientationMode::Vector).
// - Without MULTAX/ON a GOTO has 3 values and the axis is the last TLAXIS/ (0,0,1 at first);
//   with it, 3 or 6: a missing i,j,k keeps the previous axis.
// - CIRCLE/: the tool turns about the line (cx,cy,cz)+t(i,j,k) by the right-hand rule, i.e.
//   counterclockwise looking down on the circle from the tip of (i,j,k) (so (0,0,1) is G3 and
//   (0,0,-1) is G2 in the XY plane). The start (current point) and the end (the next GOTO) must
//   lie at distance r from that line within the arc tolerance; a change along (i,j,k) makes a
//   helix. An end point equal to the start is a full circle. Statements that do not move
//   (FEDRAT/, SPINDL/, PPRINT ...) may come between CIRCLE/ and its GOTO/; a motion may not.
// - The first motion of a program without FROM/ only sets the position: it makes no Block.
//   A motion that moves neither the tip nor the axis makes none either.
// - Cutters: CUTTER/ describes the tool of the next motion. With LOADTL/n it is tool n; without
//   any LOADTL/ it is tool 1, and a different CUTTER/ after tool 1 has cut becomes tool 2, and
//   so on. Parameters left out of CUTTER/ take the values of the plain shape: e = d/2 - r,
//   f = r, alpha = beta = 0, h = 4 d. Reader::do_cutter in apt_reader.cpp has the mapping
//   onto removal::Cutter (flat, ball, bull-nose, V-bit; tapers are an error).
#pragma once

#include <vcut/io/gcode_reader.h>
#include <vcut/kinematics/program.h>
#include <vcut/removal/cutter.h>

#include <Eigen/Core>
#include <iosfwd>
#include <map>
#include <set>
#include <string>

namespace vcut::io {

struct AptOptions {
  // How far a CIRCLE/'s start or end point may lie off its circle (mm): CL files print 4 to 6
  // decimals, inches included (0.00005 in = 0.0013 mm).
  double arc_tolerance_mm = 0.002;
  // CUTCOM/ on CL points that are the tool's centre already (program.cutcom: centre): CAM
  // systems write the centre path with control compensation for wear only (SolidWorks CAM's
  // lead-in arcs are smaller than the tool); false: APT's meaning, the points are the part's
  // contour and the tool runs its radius beside them. NX's "$$ centerline data" says so itself.
  bool cutcom_on_centre = false;
};

struct AptProgram {
  kinematics::Program program;
  std::map<int, removal::Cutter> cutters;  // from CUTTER/, by LOADTL/ number (1 without LOADTL)
};

// The modal state between statements and between files: pass the same one, with the same
// AptProgram, for each file in sequence.
struct AptState {
  bool known = false;       // position known (after FROM/ or a first GOTO/)
  bool home_known = false;  // the FROM/ point, where GOHOME goes
  Eigen::Vector3d home_mm = Eigen::Vector3d::Zero();
  Eigen::Vector3d home_axis = Eigen::Vector3d::UnitZ();
  Eigen::Vector3d position_mm = Eigen::Vector3d::Zero();
  Eigen::Vector3d pose_axis = Eigen::Vector3d::UnitZ();  // the tool axis at position_mm
  Eigen::Vector3d axis = Eigen::Vector3d::UnitZ();       // the axis a motion without i,j,k ends with
  bool multax = false;
  bool inches = false;
  bool rapid_next = false;
  double feed_mm_per_min = 0.0;  // 0: no FEDRAT/ yet
  kinematics::SpindleState spindle = kinematics::SpindleState::Off;
  kinematics::SpindleState spindle_direction = kinematics::SpindleState::Clockwise;  // for SPINDL/ON
  double spindle_rpm = 0.0;
  bool loadtl_seen = false;
  int tool = 1;  // the tool of the next motion
  bool has_cutter = false;
  removal::Cutter cutter;     // the last CUTTER/
  bool cutter_bound = false;  // it has been given a tool number (a motion ran with it)
  std::string cutter_where;   // "file:line" of that CUTTER/
  // A CIRCLE/ waiting for its GOTO/.
  bool circle_pending = false;
  Eigen::Vector3d circle_center_mm = Eigen::Vector3d::Zero();
  Eigen::Vector3d circle_normal = Eigen::Vector3d::UnitZ();
  double circle_radius_mm = 0.0;
  std::string circle_where;  // "file:line:col"
  int circle_line = 0, circle_column = 0;
  std::set<std::string> warned;  // ignored statement words already warned about
  // CUTCOM/LEFT | RIGHT (the CL points are the part's contour; the control offsets the tool by
  // the CUTTER/'s radius) as G41/G42 in the XY plane, LinuxCNC's algorithm; CUTCOM/OFF as G40.
  GcodeState::CutterComp comp;
  // The frame the coordinates that follow are written in, in the workpiece frame:
  // workpiece = frame_rotation * written + frame_translation_mm (CSYS/, MSYS/).
  Eigen::Matrix3d frame_rotation = Eigen::Matrix3d::Identity();
  Eigen::Vector3d frame_translation_mm = Eigen::Vector3d::Zero();
  bool msys_seen = false;   // the first MSYS/ is the workpiece frame
  std::string setup_where;  // "file:line" of a CSYS/ no motion has followed yet
  Eigen::Matrix3d msys_rotation = Eigen::Matrix3d::Identity();
  Eigen::Vector3d msys_origin_mm = Eigen::Vector3d::Zero();
  int circle_turns = 1;  // CIRCLE/ ... TIMES,n
  // INDIRV/: the direction the next TLON,GOFWD/ starts in (workpiece frame, unit); zero: none.
  Eigen::Vector3d indirv = Eigen::Vector3d::Zero();
  // Why the CL points are the tool's centre, so that CUTCOM/ offsets nothing (empty: not known
  // to be): NX's "$$ centerline data", SolidWorks CAM's CSI_ statements.
  std::string centre_path;
  // CYCLE/ (drilling): each GOTO/ while it is on is a hole, its point on the surface.
  struct Cycle {
    bool on = false;
    // How the hole is made: DRILL; DEEP, DEEP2, BRKCHP in pecks; TAP, BORE, REAM out at feed.
    enum class Kind { None, Drill, Peck, FeedOut } kind = Kind::None;
    double depth_mm = 0.0;                      // FEDTO / DEPTH: below the point along the tool axis
    double clearance_mm = 0.0;                  // RAPTO / CLEAR: above the point, where the feed starts
    double retract_mm = -1.0;                   // RTRCTO: above the point after the hole; < 0: the start level
    double feed_mm_per_min = 0.0;               // MMPM / IPM; 0: the FEDRAT/
    double first_peck_mm = 0.0, peck_mm = 0.0;  // DEEP, BRKCHP: INCR / 1STPECK, SUBPECK / STEP
    std::string where;
  } cycle;
};

// Reads one CL file. Errors are vcut::InputError naming file:line:column.
AptProgram read_apt(const std::string& path, const AptOptions& options = {});
// Appends one CL file read from `in` (named `name` in errors and sources) to `out`. Memory:
// one statement at a time (lines up to 1 MiB, statements up to 1 MiB), plus the output.
void read_apt(std::istream& in, const std::string& name, const AptOptions& options, AptProgram& out, AptState& state);

}  // namespace vcut::io
