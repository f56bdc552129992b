// Reads RS274/NGC as LinuxCNC's interpreter does (src/emc/rs274ngc: interp_read.cc for the
// words, interp_convert.cc for the order of execution within a line, interp_arc.cc for arcs)
// for the three-axis subset named in gcode_reader.h. Where this reader differs on purpose it
// says so next to the code. Memory: one line at a time, plus the Blocks.
#include <fmt/format.h>
#include <vcut/io/gcode_reader.h>
#include <vcut/io/input_error.h>

#include <Eigen/Geometry>

#include "cutter_comp.h"
#include "plane_arc.h"
#include "reader_util.h"
#include "rs274_expression.h"

#include <algorithm>
#include <charconv>
#include <climits>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <istream>
#include <map>
#include <memory>
#include <new>
#include <optional>
#include <stdexcept>
#include <system_error>

namespace vcut::io {
namespace {

using kinematics::Block;
using kinematics::MotionKind;
using kinematics::Program;
using kinematics::SpindleState;
using Motion = GcodeState::Motion;
using Plane = GcodeState::Plane;

using detail::kMmPerInch;
// Any number beyond this (mm, mm/min, rpm, s, turns, tool numbers) is a typo or garbage:
// a 1 km stroke or a 1000 m/min feed exists on no milling machine.
constexpr double kMaxMagnitude = 1e6;
// Feeds: programs write F99999 or more for "as fast as the machine goes" (LinuxCNC clamps to
// the machine's limits, and so does the feed planner); beyond this it is garbage.
constexpr double kMaxFeed_mm_per_min = 1e9;
using detail::kSamePointMm;

// rs274ngc has 15 G and 5 M modal groups: a line with more codes than this is garbage.
constexpr size_t kMaxCodesPerLine = 32;

constexpr char kAxisLetter[3] = {'X', 'Y', 'Z'};
constexpr char kCenterLetter[3] = {'I', 'J', 'K'};

using detail::column_at;
using detail::describe;
using detail::is_digit;
using detail::is_letter;
using detail::num;
using detail::rotary_step;
using detail::rotary_steps;
using detail::upper;

bool is_blank(char c) { return c == ' ' || c == '\t'; }

size_t skip_blanks(const std::string& s, size_t i) {
  while (i < s.size() && is_blank(s[i])) ++i;
  return i;
}

bool is_whole(double v) { return v == std::floor(v); }

struct Word {
  bool present = false;
  double value = 0.0;
  int column = 0;
};

struct Code {       // one G or M word
  int number = -1;  // G: value x 10 (G59.1 = 591); M: the value; -1: not of a known shape
  int column = 0;
  std::string text;  // canonical ("G1" for G01) where the shape is known, else as written
};

struct Line {
  std::array<Word, 26> words;  // by letter; G, M, N and O are not stored here
  Word radius, angle;          // LinuxCNC's polar words @ (distance) and ^ (angle, deg)
  Word round, chamfer;         // Fanuc ,R (corner radius) and ,C (chamfer) to the next line
  std::vector<Code> g;
  std::vector<Code> m;
  void clear() {
    words.fill(Word{});
    radius = angle = round = chamfer = Word{};
    g.clear();
    m.clear();
  }
};

// What this reader knows about a G code. Groups follow rs274ngc's modal groups.
enum Group {
  kNonModal = 0,
  kMotion = 1,
  kPlane = 2,
  kDistance = 3,
  kArcDistance = 4,
  kFeedMode = 5,
  kUnits = 6,
  kCutterComp = 7,
  kToolLength = 8,
  kReturnMode = 10,
  kCoordinateSystem = 12,
  kPathControl = 13,
  kSpindleMode = 14,
  kLatheMode = 15,
  kRotation = 16,  // Fanuc G68 / G69
  kGroupCount = 17
};

const char* group_name(int group) {
  switch (group) {
    case kNonModal:
      return "non-modal (group 0)";
    case kMotion:
      return "motion (group 1)";
    case kPlane:
      return "plane (group 2)";
    case kDistance:
      return "distance mode (group 3)";
    case kArcDistance:
      return "arc distance mode (group 4)";
    case kFeedMode:
      return "feed mode (group 5)";
    case kUnits:
      return "units (group 6)";
    case kCutterComp:
      return "cutter compensation (group 7)";
    case kToolLength:
      return "tool length offset (group 8)";
    case kReturnMode:
      return "canned-cycle return (group 10)";
    case kCoordinateSystem:
      return "coordinate system (group 12)";
    case kPathControl:
      return "path control (group 13)";
    case kSpindleMode:
      return "spindle speed mode (group 14)";
    case kRotation:
      return "coordinate rotation (group 16)";
    case kLatheMode:
      return "lathe diameter mode (group 15)";
    default:
      return "?";
  }
}

struct GInfo {
  int group = -1;  // -1: a code rs274ngc does not have
  bool supported = false;
  bool uses_axes = false;  // unsupported codes that take the X Y Z words of their line
  bool all_axes = false;   // ... and move or re-reference every axis when none is named
  const char* what = nullptr;
};

// Every G code (x10) that rs274ngc has, with its group; the supported ones first.
struct GEntry {
  int code;
  GInfo info;
};
// clang-format off
constexpr GEntry kGCodes[] = {
    {0, {kMotion, true}}, {10, {kMotion, true}}, {20, {kMotion, true}}, {30, {kMotion, true}},
    {800, {kMotion, true}},
    {40, {kNonModal, true}},  // G4 dwell: no motion
    {90, {kNonModal, true}},  // G9 exact stop at the end of this line's move
    {170, {kPlane, true}}, {180, {kPlane, true}}, {190, {kPlane, true}},
    {200, {kUnits, true}}, {210, {kUnits, true}},
    // G40, G41/G42 D (radius from the tool library), G41.1/G42.1 D (a diameter).
    {400, {kCutterComp, true}}, {410, {kCutterComp, true}}, {411, {kCutterComp, true}},
    {420, {kCutterComp, true}}, {421, {kCutterComp, true}},
    // G43/G49: accepted without effect. Blocks are tool-tip positions and the programmed
    // point is taken to be the tip, which is what a CAM post with G43 H means; tool lengths
    // are the machine model's business.
    {430, {kToolLength, true}}, {490, {kToolLength, true}},
    {434, {kToolLength, true}}, {435, {kToolLength, true}},  // tool centre point (Fanuc)
    // G43.1 / G43.2: tool length offsets from the line's axis words (or H): like G43, no
    // effect on the tip's path; the axis words are taken, not moved to.
    {431, {kToolLength, true}}, {432, {kToolLength, true}},
    {540, {kCoordinateSystem, true}}, {550, {kCoordinateSystem, true}},
    {560, {kCoordinateSystem, true}}, {570, {kCoordinateSystem, true}},
    {580, {kCoordinateSystem, true}}, {590, {kCoordinateSystem, true}},
    {591, {kCoordinateSystem, true}}, {592, {kCoordinateSystem, true}},
    {593, {kCoordinateSystem, true}},
    // G61/G61.1/G64: exact stop vs. blending changes the timing, not the programmed path;
    // Block::exact_stop and blend_tolerance_mm carry it to the feed planner.
    {610, {kPathControl, true}}, {611, {kPathControl, true}}, {640, {kPathControl, true}},
    {900, {kDistance, true}}, {910, {kDistance, true}},
    {901, {kArcDistance, true}}, {911, {kArcDistance, true}},
    {940, {kFeedMode, true}},
    {970, {kSpindleMode, true}},
    {980, {kReturnMode, true}}, {990, {kReturnMode, true}},
    {930, {kFeedMode, true}},
    // Canned cycles in G17 (others are refused where they are used).
    {730, {kMotion, true}}, {810, {kMotion, true}}, {820, {kMotion, true}}, {830, {kMotion, true}},
    {850, {kMotion, true}}, {890, {kMotion, true}},
    {100, {kNonModal, true}},  // G10 L2 / L20 (coordinate systems); L1 L10 L11 (tool table)
    {530, {kNonModal, true}},  // G53: this line's G0/G1 in machine (workpiece-frame) coordinates
    {920, {kNonModal, true}}, {921, {kNonModal, true}}, {922, {kNonModal, true}}, {923, {kNonModal, true}},
    {520, {kNonModal, true}},  // G52: a local offset, LinuxCNC's G92 offsets set to the axis words
    // G28 / G30: through the line's point to the reference position; G28.1 / G30.1 store it.
    {280, {kNonModal, true}}, {300, {kNonModal, true}}, {281, {kNonModal, true}}, {301, {kNonModal, true}},

    // G5 (cubic) and G5.1 (quadratic) splines in G17: straight moves within 1 um of the curve.
    {50, {kMotion, true}}, {51, {kMotion, true}},
    // G5.2 .. G5.3: a NURBS of the control points on the lines between, in G17.
    {52, {kMotion, true}}, {53, {kMotion, true}},
    // G33 (threading: a straight feed at K per revolution), G33.1 (rigid tapping).
    {330, {kMotion, true}}, {331, {kMotion, true}},
    // G38.2 / G38.3 probe toward the stock, G38.4 / G38.5 away from it (error / no error
    // without a change of contact); G31 (Fanuc's skip, Mach3's probe) is G38.3 on its line only.
    {382, {kMotion, true}}, {383, {kMotion, true}}, {384, {kMotion, true}}, {385, {kMotion, true}},
    {310, {kNonModal, true}},
    {740, {kMotion, false, true, false, "canned cycle"}},
    {760, {kMotion, false, true, false, "canned cycle"}},
    {840, {kMotion, false, true, false, "canned cycle"}},
    {860, {kMotion, false, true, false, "canned cycle"}},
    {870, {kMotion, false, true, false, "canned cycle"}},
    {880, {kMotion, false, true, false, "canned cycle"}},
    {171, {kPlane, false, false, false, "UVW plane"}},
    {181, {kPlane, false, false, false, "UVW plane"}},
    {191, {kPlane, false, false, false, "UVW plane"}},
    {950, {kFeedMode, false, false, false, "feed per revolution"}},
    {960, {kSpindleMode, false, false, false, "constant surface speed"}},
    {70, {kLatheMode, false, false, false, "lathe diameter/radius mode"}},
    // Fanuc G68 X Y R (rotation of the programmed XY about a centre) and G69 (cancel); G68.2
    // (tilted work plane) with G53.1 / G53.6 (the rotaries turn the tool to it).
    {680, {kRotation, true}}, {690, {kRotation, true}}, {682, {kRotation, true}},
    {531, {kNonModal, true}}, {536, {kNonModal, true}},
    {80, {kLatheMode, false, false, false, "lathe diameter/radius mode"}},
    {700, {kMotion, false, true, false, "lathe cycle"}}, {710, {kMotion, false, true, false, "lathe cycle"}},
    {711, {kMotion, false, true, false, "lathe cycle"}}, {712, {kMotion, false, true, false, "lathe cycle"}},
    {720, {kMotion, false, true, false, "lathe cycle"}}, {721, {kMotion, false, true, false, "lathe cycle"}},
    {722, {kMotion, false, true, false, "lathe cycle"}},
};

GInfo g_info(int g) {
  for (const GEntry& e : kGCodes) {
    if (e.code == g) return e.info;
  }
  return {};  // a code rs274ngc does not have
}

// M codes: groups as rs274ngc (4 stop, 6 tool change, 7 spindle, 8 coolant, 9 overrides).
int m_group(int m) {
  switch (m) {
    case 0: case 1: case 2: case 30: case 60: return 4;
    case 6: case 61: return 6;
    case 62: case 63: case 64: case 65: case 66: case 67: case 68: return 5;
    case 70: case 71: case 72: case 73: return 10;
    case 3: case 4: case 5: return 7;
    case 7: case 8: case 9: return 8;
    case 48: case 49: case 50: case 51: case 52: case 53: return 9;
    default: return -1;
  }
}
// clang-format on

// Supported: the path-changing ones, and those that leave the path alone (pauses, coolant,
// overrides M48..M53, digital and analog I/O M62..M68).
bool m_supported(int m) {
  return (m >= 0 && m <= 9) || m == 30 || (m >= 48 && m <= 53) || m == 60 || m == 61 || (m >= 62 && m <= 68) ||
         (m >= 70 && m <= 73);
}

bool valid_offset_name(const std::string& name) {
  static const char* const kNames[] = {"G54", "G55", "G56", "G57", "G58", "G59", "G59.1", "G59.2", "G59.3"};
  for (const char* n : kNames) {
    if (name == n) return true;
  }
  return false;
}

void validate_options(const std::string& name, const GcodeOptions& options) {
  if (!(options.arc_tolerance_mm <= kMaxMagnitude)) {  // NaN too; < 0 is the default
    throw InputError(
        name, 0, 0,
        "arc tolerance " + num(options.arc_tolerance_mm) + " mm in the options (expected a finite value >= 0)");
  }
  if (!(options.arc_tolerance_relative >= 0.0 && options.arc_tolerance_relative <= 1.0)) {
    throw InputError(name, 0, 0,
                     "relative arc tolerance " + num(options.arc_tolerance_relative) +
                         " in the options (expected a value from 0 to 1)");
  }
  for (const auto& [key, offset] : options.work_offsets_mm) {
    if (!valid_offset_name(key)) {
      throw InputError(name, 0, 0, "work offset '" + key + "' in the options (expected one of G54..G59, G59.1..G59.3)");
    }
    for (int a = 0; a < 3; ++a) {
      if (!std::isfinite(offset[a]) || std::abs(offset[a]) > kMaxMagnitude) {
        throw InputError(name, 0, 0,
                         "work offset " + key + " " + kAxisLetter[a] + " = " + num(offset[a]) +
                             " mm in the options (expected a finite value within +-1e6 mm)");
      }
    }
  }
}

// The coordinate system of a G54..G59.3 code (x10): 0..8.
int system_index(int code) { return code <= 590 ? (code - 540) / 10 : 6 + (code - 591); }

// One program file being read: its stream, where the reader is in it, and its '%' state.
struct Source {
  std::istream* in = nullptr;
  std::unique_ptr<std::ifstream> owned;  // a subroutine file the reader opened
  std::string name;
  int file_index = 0;
  int line = 0;                   // number of the line last read
  std::streamoff offset = 0;      // where the next line starts
  std::streamoff line_start = 0;  // where the line last read starts
  bool seekable = false;
  bool seen_content = false;  // a non-blank line has been read (the opening '%' is one)
  bool opened_with_percent = false;
  // Lone CR line ends (old Macintosh files, some senders): the part of the last physical
  // line after a CR, still to be read as lines, and whether a '\n' ended that physical line.
  std::string after_cr;
  bool after_cr_newline = false;
  std::streamoff begin = 0;  // where the file's first line starts (Fanuc GOTO searches from it)
  bool executed = false;     // a block of this file has run (a later O number ends the program)
};

// A place to read on from: the line after `line`, at byte `offset` of `source`.
struct Mark {
  Source* source = nullptr;
  std::streamoff offset = 0;
  int line = 0;
};

struct Loop {
  enum class Kind { While, Do, Repeat } kind = Kind::While;
  std::string label;
  Mark start;                // While: its own line (re-read to test); Do, Repeat: the line after
  double remaining = 0.0;    // Repeat: passes still to run
  std::size_t if_depth = 0;  // conditionals open when the loop began
  std::string where;         // file:line of the opening line
};

// What M70 saves and M72 restores (LinuxCNC: units, distance modes, feed mode, plane, tool
// length mode, coordinate system, path control, retract mode, spindle, feed and speed).
constexpr int kG5xParameter = 5221;  // X of G54; + 20 per system, Y Z A B C U V W follow X
constexpr int kG92Parameter = 5211;  // X of the G92 offset

struct ModalState {
  bool inches, incremental, arc_center_absolute, inverse_time, exact_stop, retract_to_r;
  GcodeState::Plane plane;
  GcodeState::Tcp tcp;
  double blend_tolerance_mm, feed_mm_per_min, spindle_rpm;
  kinematics::SpindleState spindle;
  std::string work_offset;  // the coordinate system (its offsets are read again on M72)
  // The G92 / G52 offsets as they were (M72 puts them back, #5210..#5219 with them).
  Eigen::Vector3d g92_mm;
  std::array<double, 3> g92_extra_mm;
  double g92_on;
};

// The main program or one subroutine call.
struct Frame {
  // An o-word call (LinuxCNC), a Fanuc macro call G65 (its own locals #1..#33), or a
  // subprogram M98 / M97 (the caller's locals).
  enum class Kind { OWord, Macro, Subprogram };
  Kind kind = Kind::OWord;
  std::string sub;         // canonical o-word name; empty for the main program
  std::string call_where;  // file:line of the call
  Mark return_to;
  Mark body;                                   // Fanuc calls: where the program starts (repeats with L)
  long long repeats_left = 0;                  // Fanuc calls: passes after this one
  std::vector<std::pair<int, Mark>> do_loops;  // Fanuc WHILE [..] DOm: m, the WHILE line
  std::array<double, 33> saved_numbered{};     // the caller's #1..#30 (#1..#33 for G65)
  std::map<std::string, double> saved_locals;  // the caller's named locals
  std::vector<Loop> loops;
  std::vector<std::pair<std::string, std::string>> ifs;  // label, file:line of the if
  std::optional<ModalState> autorestore;                 // M73: restored when this call returns
  bool modal = false;                                    // a Fanuc G66 call: no modal call from inside it
};

struct SubDefinition {
  Mark body;            // the line after "o<name> sub"
  std::string where;    // file:line of the sub line
  bool called = false;  // a call has found it
};

// An o-word line: "o<name> keyword ..." or "o123 keyword ...".
struct OLine {
  std::string label;     // canonical
  std::string keyword;   // lower case; empty for a Fanuc program number
  std::size_t rest = 0;  // index after the keyword
  int column = 0;        // of the 'O'
};

struct Assignment {
  detail::ParameterRef target;
  double value = 0.0;
  int column = 0;
};

class Reader : public detail::ValueContext, public detail::CompHost {
 public:
  Reader(const GcodeOptions& options, Program& program, GcodeState& state)
      : options_(options), program_(program), state_(state) {}

  void run(std::istream& in, const std::string& name);
  // After an error: the blocks read in a tilted plane go to the workpiece frame as well, so
  // that what was read before the error is well formed.
  void emit_frames() {
    if (state_.twp) twp_emit();
  }

  // detail::ValueContext
  double numbered_parameter(int number, int column) override;
  double named_parameter(const std::string& name, int column) override;
  bool named_parameter_exists(const std::string& name) override;
  [[noreturn]] void fail(int column, const std::string& message) const override {
    throw InputError(current_->name, current_->line, column, message + call_chain());
  }
  bool fanuc_macros() const override { return options_.flavor == GcodeOptions::Flavor::Fanuc; }

 private:
  std::string where(int column) const {
    return current_->name + ":" + std::to_string(current_->line) + ":" + std::to_string(column);
  }
  std::string here() const { return current_->name + ":" + std::to_string(current_->line); }
  void warn(int column, const std::string& message) { program_.warnings.push_back(where(column) + ": " + message); }
  // An unsupported word: an error, or (unsupported_as_warning) one warning per distinct key.
  void unsupported(int column, const std::string& key, const std::string& message) {
    if (!options_.unsupported_as_warning) fail(column, message);
    if (state_.warned.insert(key).second) warn(column, message + "; ignored");
  }

  // Lines and jumps.
  bool next_line(std::string& text);
  Mark mark_after() const { return {current_, current_->offset, current_->line}; }
  Mark mark_this() const { return {current_, current_->line_start, current_->line - 1}; }
  void jump(const Mark& mark);
  bool line(std::string& text);

  // o-words.
  static bool o_line(const std::string& s, OLine& o);
  bool o_word(const std::string& s, const OLine& o);
  // Reads on (not executing) to the line "o<label> keyword" with a keyword of `ends`.
  OLine skip_to(const std::string& label, std::initializer_list<const char*> ends, const std::string& opened,
                std::string& text);
  double condition(const std::string& s, const OLine& o);
  void call(const std::string& s, const OLine& o);
  void leave_sub(const std::string& s, const OLine& o);
  SubDefinition* find_sub(const std::string& name, int column);
  Source* open_file(const std::filesystem::path& path, int column, const char* what);
  bool read_to_sub(const std::string& name);
  Frame& frame() { return frames_.back(); }
  std::string call_chain() const;

  void lex(const std::string& s, size_t i);

  // Fanuc custom macro B: IF / WHILE / END / GOTO statements, G65 / M98 / M97 calls, M99.
  int macro_statement(std::string& text, size_t i);
  void go_to_sequence(double number, int column);
  bool find_sequence(long long number, Mark& found);
  Mark find_program(long long number, int column, const std::string& caller);
  void check_after_end();
  Mark locate_program(long long number, int column, const std::string& caller);
  void fanuc_call(Frame::Kind kind, long long program, long long repeats, int column, const std::string& what,
                  const std::vector<std::pair<int, double>>& arguments = {}, bool modal = false);
  // Fanuc G66 P L <arguments>: the macro called after each line that moves an axis, until G67.
  struct ModalCall {
    long long program = 0, repeats = 1;
    std::string what;  // "G66 P9010"
    std::vector<std::pair<int, double>> arguments;
  };
  std::optional<ModalCall> modal_call_;
  bool fanuc_return();
  double fanuc_system_variable(int number, int column);
  static bool added_common(int number) {
    return (number >= 98000 && number <= 98499) || (number >= 100000 && number <= 199999);
  }
  void set_variable(int number, double value, int column, const std::string& text);
  double word_value(const std::string& s, size_t& i, char letter, std::string& text);
  size_t skip_comment(const std::string& s, size_t i);
  bool execute();
  // execute()'s steps, in rs274ngc's order within a line. LineCodes: the line's codes by
  // modal group and what they imply, shared by the steps.
  struct LineCodes {
    std::array<const Code*, kGroupCount> g{};
    const Code* axis_user = nullptr;  // an ignored code that takes the axis words
    bool axis_user_all = false;
    const Code* non_modal = nullptr;
    const Code* rotation = nullptr;
    const Code* length_axes = nullptr;  // G43.1 / G43.2 take X Y Z
    bool homes = false, stores_home = false, rotates = false, sets_offsets = false;
    bool dwell_axis = false;          // Fanuc G4 X / U: seconds, not an axis
    std::array<const Code*, 11> m{};  // by M group 0..10
    bool m_code[74] = {};             // supported M codes present, by number (M2 and M30 end the program)
    bool program_end = false;
    const Code* flow = nullptr;  // M97, M98 or M99
    std::string p_user;          // the code that took the P word
    bool was_cycle = false;      // a canned cycle was the motion mode before the line
    int previous_cycle = 0;
    int axis_column = INT_MAX;  // the first axis word
  };
  bool macro_call();
  LineCodes codes_of_line();
  void read_m_codes(LineCodes& c);
  void check_letters(LineCodes& c);
  void set_feed_speed_tool(LineCodes& c);
  void use_p(LineCodes& c, const std::string& code);
  void set_plane_and_frames(LineCodes& c);
  void set_modes(LineCodes& c);
  bool run_motion(LineCodes& c);
  bool call_or_return(const LineCodes& c);
  void check_unused_words();

  double unit() const { return state_.inches ? kMmPerInch : 1.0; }
  detail::ArcTolerance arc_tolerance() const {
    // LinuxCNC 2.9: 2 * 0.01 * sqrt(2) mm in G21, 2 * 0.001 * sqrt(2) in in G20.
    const double absolute_mm = options_.arc_tolerance_mm >= 0.0 ? options_.arc_tolerance_mm
                               : state_.inches                  ? 2.0 * 0.001 * M_SQRT2 * kMmPerInch
                                                                : 2.0 * 0.01 * M_SQRT2;
    return {absolute_mm, options_.arc_tolerance_relative, 100.0 * absolute_mm};
  }
  const Word& word(char letter) const { return line_words_.words[letter - 'A']; }
  Eigen::Vector3d target(std::array<bool, 3>& programmed) const;
  // Workpiece frame <-> program coordinates (mm): the work offsets and a G68 rotation.
  Eigen::Vector3d to_program(const Eigen::Vector3d& w) const;
  Eigen::Vector3d to_workpiece(const Eigen::Vector3d& p) const;
  // The XY rotation in force: Fanuc's G68 about its centre, or LinuxCNC's coordinate system
  // rotation (G10 L2 R) about the system's origin before G92, the centre -G92 in program
  // coordinates (the two are never on together).
  bool rotated() const { return state_.rotation_rad != 0.0 || state_.system_rotation_rad != 0.0; }
  double rotation_angle() const {
    return state_.rotation_rad != 0.0 ? state_.rotation_rad : state_.system_rotation_rad;
  }
  Eigen::Vector2d rotation_center() const {
    return state_.rotation_rad != 0.0 ? state_.rotation_center_mm : Eigen::Vector2d(-state_.g92_mm.head<2>());
  }
  Eigen::Vector2d polar_point(const Eigen::Vector2d& from) const;
  void straight(MotionKind kind, int column);
  // Fanuc ,R / ,C: the corner between the line just emitted and the next one.
  struct PendingCorner {
    bool round = false;  // ,R (else ,C)
    double size_mm = 0.0;
    size_t block = 0;  // the first line, in Program::blocks
    int column = 0;
  };
  std::optional<PendingCorner> corner_;
  void corner_to(Block& second, int column);
  void synchronized(int column);
  void spline(int column);
  void nurbs_point(int column, bool first);
  void nurbs_end(int column);
  void arc(int column);
  void cycle(int column, bool new_series);
  void set_offsets(const Code& g);
  void home_return(const Code& g);
  void probe(int column, int code);
  // G68.2 / G69 / G53.1 / G53.6 (GcodeState::twp). Blocks from twp_first_block_ on are in the
  // feature frame until twp_emit() moves them to the workpiece frame.
  void twp_begin(const Code& g);
  void twp_end();
  void twp_emit();
  void twp_emit_before(size_t end);
  void seal_blocks();
  void twp_turn(const Code& g);
  // Rotaries standing turned outside G68.2 (GcodeState::twp without twp_feature).
  bool turns_hold_linear() const {
    return options_.tip_after_turn && !state_.rotary_program && state_.tcp == GcodeState::Tcp::Off &&
           (state_.twp_used || state_.length_comp);
  }
  // machine_mm: the machine's X Y Z where the tip stands, when known exactly (else from the tip).
  void turned_frame(const Eigen::Vector3d& tip_mm, const Eigen::Vector3d* machine_mm = nullptr);
  // A point of the tilted or turned frame on the workpiece (as blocks are emitted).
  Eigen::Vector3d twp_out(const Eigen::Vector3d& p) const {
    return state_.twp_rotation * p + state_.twp_translation_mm;
  }
  void end_turned_frame();
  void joint_move(const Block& block, const kinematics::RotaryWords& to, int column);
  size_t twp_first_block_ = 0;
  bool in_swing_ = false;  // append() is emitting the steps of a rotary turn
  // The tip's offset from the spindle's gauge point with the tool in the spindle (mm).
  Eigen::Vector3d tip_offset() const {
    if (state_.dynamic_length_mm) return -*state_.dynamic_length_mm;  // G43.1: the control's offset
    const auto it = options_.tool_length_mm.find(state_.tool);
    return it == options_.tool_length_mm.end() ? Eigen::Vector3d::Zero()
                                               : Eigen::Vector3d(-it->second * options_.spindle_axis);
  }
  void append(Block block, const std::array<bool, 3>& programmed, const kinematics::RotaryWords* rotary_end = nullptr,
              const kinematics::ExtraAxes* extra_end = nullptr);
  // U V W: the line's words on the current values (G90/G91, G53, the offsets), and a refusal
  // of them where they do not move. extra_word_: which of U V W the line gives as axes (not
  // Fanuc's dwell U); extra_column_: the first of them, 0 when none.
  kinematics::ExtraAxes extra_target() const;
  void no_extra(const std::string& where) const;
  int extra_column_ = 0;
  std::array<bool, 3> extra_word_{};
  std::array<double, 3> extra_program() const {  // U V W in program coordinates (mm)
    std::array<double, 3> p{};
    for (size_t e = 0; e < 3; ++e) p[e] = state_.extra.value_mm[e] - state_.g5x_extra_mm[e] - state_.g92_extra_mm[e];
    return p;
  }

  // Cutter radius compensation (GcodeState::CutterComp).
  using Comp = GcodeState::CutterComp;
  bool compensating() const { return state_.comp.side != Comp::Side::Off && state_.comp.radius_mm > 0.0; }
  // Where end points not named (and G91 increments) count from: the programmed point while
  // compensation follows a path, else the tool's position.
  Eigen::Vector3d base_point() const;
  void plane_axes(int& a, int& b, int& c) const;
  void comp_on(const Code& g);
  void comp_off(int column);
  void comp_stop(bool program_end, int column);
  // The compensation's geometry (cutter_comp.h), on this reader's position and blocks.
  detail::Compensator compensator() { return detail::Compensator(state_.comp, *this); }
  void comp_straight(Block& block, const std::array<bool, 3>& programmed, int column) {
    require_comp_position(programmed, column);
    compensator().straight(block, programmed, column);
  }
  void comp_arc(Block& block, const std::array<bool, 3>& programmed, int turn, int column) {
    require_comp_position(programmed, column);
    compensator().arc(block, programmed, turn, column);
  }
  // Compensation offsets from where the tool is: the plane's axes must be known before the
  // move, and the third axis by its end (a held block cannot wait for a later value).
  void require_comp_position(const std::array<bool, 3>& programmed, int column) const {
    int a = 0, b = 1, c = 2;
    plane_axes(a, b, c);
    for (int axis : {a, b, c}) {
      if (state_.known[static_cast<size_t>(axis)] || (axis == c && programmed[static_cast<size_t>(axis)])) continue;
      fail(column, std::string("cutter compensation while the ") + kAxisLetter[axis] +
                       " position is unknown is not supported: vcut assumes no start position (expected a move that "
                       "sets it first)");
    }
  }
  void comp_move_end_and_flush(const Eigen::Vector2d& x, int column) { compensator().move_end_and_flush(x, column); }
  void comp_flush() { compensator().flush(); }
  // CompHost.
  Eigen::Vector3d& tool_position() override { return state_.position_mm; }
  void comp_plane(int& a, int& b, int& c) const override { plane_axes(a, b, c); }
  double comp_unit() const override { return unit(); }
  void comp_append(Block block, const std::array<bool, 3>& programmed, bool held, const Eigen::Vector2d& direction,
                   double sweep_rad) override {
    hold_ = held;
    hold_direction_ = direction;
    hold_sweep_rad_ = sweep_rad;
    append(block, programmed);
    hold_ = false;
  }
  kinematics::BlockList& comp_blocks() override { return program_.blocks; }
  [[noreturn]] void comp_fail(int column, const std::string& message) const override { fail(column, message); }
  bool hold_ = false;  // append() holds the block for compensation instead of emitting it
  Eigen::Vector2d hold_direction_ = Eigen::Vector2d::Zero();
  double hold_sweep_rad_ = 0.0;
  void forget_axes(bool all);
  void select_system(int index, int column = 1);
  double feed_of_line(int column) const;

  const GcodeOptions& options_;
  Program& program_;
  GcodeState& state_;
  std::vector<std::unique_ptr<Source>> sources_;
  Source* current_ = nullptr;
  std::vector<Frame> frames_;
  std::map<std::string, SubDefinition> subs_;
  std::map<long long, Mark> programs_;  // Fanuc O<number>: the line after its O line
  bool axis_words_ = false;             // a line with axis words has run
  int end_line_ = 0;                    // the main file's closing '%' or M99 line, where reading stopped (0: neither)
  std::map<std::pair<const Source*, long long>, Mark> sequences_;  // N<number> lines found
  long long lines_read_ = 0;
  // The steps of a rotary turn (joint_move, twp_turn) beyond the line's own block: each is a
  // block as a line's is, and counts toward max_lines with the lines read.
  void count_steps(int steps, int column) {
    lines_read_ += steps - 1;
    if (lines_read_ > options_.max_lines)
      fail(column, "read " + std::to_string(options_.max_lines) +
                       " lines and rotary steps without reaching the end (a loop that never ends? the limit is "
                       "the job's program.max_lines)");
  }
  Line line_words_;
  std::vector<Assignment> assignments_;
  std::array<bool, 26> used_{};                           // words consumed by some code on this line
  bool lenient_ = false;                                  // an ignored unsupported code may consume any word
  bool exact_stop_line_ = false;                          // G9 on this line
  bool machine_coordinates_ = false;                      // G53 on this line
  Eigen::Vector3d line_axis_ = Eigen::Vector3d::UnitZ();  // G43.5: this line's tool axis
  int tcp_m_code_ = -1;                                   // a job-mapped TCP M code on this line: 1 on, 0 off
  std::optional<ModalState> saved_modes_;                 // M70

  ModalState save_modes() const {
    const GcodeState& g = state_;
    return {g.inches,      g.incremental, g.arc_center_absolute, g.inverse_time,    g.exact_stop,  g.retract_to_r,
            g.plane,       g.tcp,         g.blend_tolerance_mm,  g.feed_mm_per_min, g.spindle_rpm, g.spindle,
            g.work_offset, g.g92_mm,      g.g92_extra_mm,        g.parameters[5210]};
  }
  void restore_modes(const ModalState& m) {
    GcodeState& g = state_;
    g.inches = m.inches, g.incremental = m.incremental, g.arc_center_absolute = m.arc_center_absolute;
    g.inverse_time = m.inverse_time, g.exact_stop = m.exact_stop, g.retract_to_r = m.retract_to_r;
    g.plane = m.plane, g.tcp = m.tcp, g.blend_tolerance_mm = m.blend_tolerance_mm;
    g.feed_mm_per_min = m.feed_mm_per_min, g.spindle_rpm = m.spindle_rpm, g.spindle = m.spindle;
    // The coordinate system comes back with its offsets as they are now (#5221..): LinuxCNC's
    // M72 restores which system is active, not the values it had at M70 (as its interpreter
    // gives it: G10 L2 P1 X5 between M70 and M72 in G54 puts X1 at 6).
    g.work_offset = m.work_offset;
    g.g92_mm = m.g92_mm, g.g92_extra_mm = m.g92_extra_mm, g.parameters[5210] = m.g92_on;
    for (size_t a = 0; a < 3; ++a) {
      g.parameters[static_cast<size_t>(kG92Parameter) + a] = m.g92_mm[static_cast<Eigen::Index>(a)];
      g.parameters[static_cast<size_t>(kG92Parameter + 6) + a] = m.g92_extra_mm[a];
    }
    select_system(system_index(static_cast<int>(std::lround(std::stod(m.work_offset.substr(1)) * 10))));
  }
  int o_column_ = 0;  // column of a Fanuc program number on this line
};

const char* const kSystemNames[9] = {"G54", "G55", "G56", "G57", "G58", "G59", "G59.1", "G59.2", "G59.3"};
// An R arc's |R| may fall short of half its chord by LinuxCNC's RADIUS_TOLERANCE, 0.00005 in.
constexpr double kRadiusShortMm = 0.00005 * kMmPerInch;
// Splines (G5, G5.1) become straight moves no farther than this from the curve (mm).
constexpr double kSplineChordMm = 0.001;
constexpr size_t kG28Parameter = 5161;    // X of the G28 reference (mm, gauge point), Y Z A B C (deg) follow
constexpr size_t kG30Parameter = 5181;    // X of the G30 reference
constexpr int kPositionParameter = 5420;  // X of the current position (program coordinates)

double Reader::numbered_parameter(int number, int column) {
  if (fanuc_macros()) {
    if (number == 0) return detail::kVacant;
    if (added_common(number)) {
      const auto it = state_.added_commons.find(number);
      return it == state_.added_commons.end() ? detail::kVacant : it->second;
    }
    if ((number >= 3000 && number < 5000) || (number >= 5001 && number <= 5106) || number > 5601) {
      return fanuc_system_variable(number, column);
    }
    return state_.parameters[static_cast<size_t>(number)];
  }
  if (number == 5220)
    return 1.0 + system_index(static_cast<int>(std::lround(std::stod(state_.work_offset.substr(1)) * 10)));
  if (number == 5400) return state_.tool;
  if (number >= kPositionParameter && number < kPositionParameter + 9) {
    const int a = number - kPositionParameter;
    if (a < 3) return to_program(state_.position_mm)[a] / unit();
    if (a < 6) return state_.rotary.angle_rad[static_cast<size_t>(a - 3)] * 180.0 / M_PI;
    return extra_program()[static_cast<size_t>(a - 6)] / unit();
  }
  return state_.parameters[static_cast<size_t>(number)];
}

double Reader::named_parameter(const std::string& name, int column) {
  if (name.size() > 1 && name[0] == '_') {
    static const char* const kAxes[] = {"_x", "_y", "_z", "_a", "_b", "_c", "_u", "_v", "_w"};
    for (int a = 0; a < 9; ++a) {
      if (name == kAxes[a]) return numbered_parameter(kPositionParameter + a, column);
    }
    if (name == "_feed") return state_.feed_mm_per_min / unit();
    if (name == "_rpm") return state_.spindle_rpm;
    if (name == "_current_tool") return state_.tool;
    if (name == "_selected_tool") return state_.selected_tool;
    if (name == "_metric") return state_.inches ? 0.0 : 1.0;
    if (name == "_imperial") return state_.inches ? 1.0 : 0.0;
    if (name == "_absolute") return state_.incremental ? 0.0 : 1.0;
    if (name == "_incremental") return state_.incremental ? 1.0 : 0.0;
    if (name == "_inverse_time") return state_.inverse_time ? 1.0 : 0.0;
    if (name == "_units_per_minute") return state_.inverse_time ? 0.0 : 1.0;
    if (name == "_line") return current_->line;
    if (name == "_value" || name == "_value_returned") {
      const auto it = state_.globals.find(name);
      return it == state_.globals.end() ? 0.0 : it->second;
    }
    // An unset global reads as 0 (LinuxCNC's rs274 does so; an unset local is an error).
    const auto it = state_.globals.find(name);
    return it != state_.globals.end() ? it->second : 0.0;
  } else {
    const auto it = state_.locals.find(name);
    if (it != state_.locals.end()) return it->second;
  }
  fail(column, "#<" + name + "> is not defined (expected it to be set before it is read)");
}

bool Reader::named_parameter_exists(const std::string& name) {
  if (name.size() > 1 && name[0] == '_') return state_.globals.count(name) > 0;
  return state_.locals.count(name) > 0;
}

// --- Lines and jumps.

bool Reader::next_line(std::string& text) {
  Source& src = *current_;
  bool newline = false;  // a '\n' ends this piece
  if (!src.after_cr.empty()) {
    text.swap(src.after_cr);
    src.after_cr.clear();
    newline = src.after_cr_newline;
  } else {
    if (!std::getline(*src.in, text)) return false;
    newline = !src.in->eof();
  }
  // A CR that is not the last character of the line ends a line of its own (CRLF's CR is
  // stripped in line()).
  if (const void* cr = text.size() > 1 ? std::memchr(text.data(), '\r', text.size() - 1) : nullptr) {
    const size_t at = static_cast<size_t>(static_cast<const char*>(cr) - text.data());
    src.after_cr.assign(text, at + 1, std::string::npos);
    src.after_cr_newline = newline;
    text.resize(at);
    newline = true;  // the CR, one byte like a '\n'
  }
  if (++lines_read_ > options_.max_lines) {
    throw InputError(src.name, src.line + 1, 0,
                     "read " + std::to_string(options_.max_lines) +
                         " lines without reaching the end (a loop that never ends? the limit is "
                         "the job's program.max_lines)" +
                         call_chain());
  }
  if (src.line == INT_MAX) throw InputError(src.name, src.line, 0, "too many lines");
  ++src.line;
  src.line_start = src.offset;
  src.offset += static_cast<std::streamoff>(text.size()) + (newline ? 1 : 0);
  return true;
}

void Reader::jump(const Mark& mark) {
  Source& src = *mark.source;
  if (!src.seekable) {
    throw InputError(src.name, src.line, 0,
                     "loops and subroutines need to read lines again, and this input cannot seek "
                     "(expected a regular file)");
  }
  src.in->clear();
  src.in->seekg(mark.offset);
  src.after_cr.clear();
  if (!*src.in) throw InputError(src.name, src.line, 0, "read error going back in the file");
  src.offset = mark.offset;
  src.line = mark.line;
  current_ = &src;
}

std::string Reader::call_chain() const {
  std::string chain;
  for (size_t f = frames_.size(); f-- > 1;) {
    chain += (chain.empty() ? " (in o<" : ", in o<") + frames_[f].sub + "> called at " + frames_[f].call_where;
  }
  return chain.empty() ? chain : chain + ")";
}

void Reader::run(std::istream& in, const std::string& name) {
  auto main = std::make_unique<Source>();
  main->in = &in;
  main->name = name;
  main->file_index = static_cast<int>(program_.files.size());
  program_.files.push_back(name);
  const std::streampos start = in.tellg();
  main->seekable = start != std::streampos(-1);
  main->offset = main->seekable ? static_cast<std::streamoff>(start) : 0;
  main->begin = main->offset;
  current_ = main.get();
  sources_.push_back(std::move(main));
  frames_.emplace_back();
  if (state_.parameters.empty()) {
    state_.parameters.assign(5602, 0.0);
    if (options_.initial_tool > 0) state_.tool = state_.selected_tool = options_.initial_tool;
    for (const auto& [key, offset] : options_.work_offsets_mm) {
      for (int k = 0; k < 9; ++k) {
        if (key != kSystemNames[k]) continue;
        for (int a = 0; a < 3; ++a) state_.parameters[static_cast<size_t>(kG5xParameter + 20 * k + a)] = offset[a];
      }
    }
    select_system(0);
    // Power-on canned-cycle return: rs274ngc's is G99 (the R plane), Fanuc's G98.
    state_.retract_to_r = options_.flavor != GcodeOptions::Flavor::Fanuc;
    if (fanuc_macros()) {  // locals and commons start vacant
      for (size_t k = 1; k <= 33; ++k) state_.parameters[k] = detail::kVacant;
      for (size_t k = 100; k <= 999; ++k) state_.parameters[k] = detail::kVacant;
    }
    // The machine is at its start position; G28 / G30 references in #5161.. / #5181.. (mm, deg).
    if (options_.start_mm) {
      state_.position_mm = *options_.start_mm + tip_offset();
      state_.known = {true, true, true};
    }
    for (int k = 0; k < 2; ++k) {
      const size_t base = k == 0 ? kG28Parameter : kG30Parameter;
      for (int a = 0; a < 3; ++a)
        state_.parameters[base + static_cast<size_t>(a)] = options_.reference_mm[static_cast<size_t>(k)][a];
      for (int r = 0; r < 3; ++r)
        state_.parameters[base + 3 + static_cast<size_t>(r)] =
            options_.reference_rotary_deg[static_cast<size_t>(k)][static_cast<size_t>(r)];
    }
  }
  twp_first_block_ = program_.blocks.size();
  std::string text;
  try {
    while (true) {
      seal_blocks();
      if (!next_line(text)) {
        if (frames_.size() > 1) {
          fail(0, "the file ends inside o<" + frame().sub + "> (expected o<" + frame().sub + "> endsub)");
        }
        if (!frame().loops.empty()) {
          fail(0, "the file ends inside the loop o" + frame().loops.back().label + " opened at " +
                      frame().loops.back().where);
        }
        if (!frame().ifs.empty()) {
          fail(0, "the file ends inside o" + frame().ifs.back().first + " if, opened at " + frame().ifs.back().second +
                      " (expected endif)");
        }
        break;
      }
      if (!line(text)) break;
    }
  } catch (const std::bad_alloc&) {
    fail(0, "out of memory (a line too long, or too many moves)");
  } catch (const std::length_error&) {
    fail(0, "out of memory (a line too long, or too many moves)");
  } catch (const std::ios_base::failure&) {
    fail(0, "read error (expected a readable text file)");
  }
  if (current_->in->bad()) fail(0, "read error (expected a readable text file)");
  if (end_line_ != 0) check_after_end();
  // A file of subroutine definitions alone (LinuxCNC keeps each in a file of its own name):
  // nothing runs, which the warning says where the cause is not plain.
  if (program_.blocks.empty() && !axis_words_) {
    for (const auto& [label, sub] : subs_) {
      if (sub.called || sub.body.source != sources_.front().get()) continue;
      program_.warnings.push_back(sub.where + ": o" + label +
                                  " sub is defined but never called: the program makes no "
                                  "motion (expected a call, or the file that calls it)");
      break;
    }
  }
  // A file that ends (with '%' or without M2) while a compensated move is held: the machine
  // runs it, ending at its offset point (LinuxCNC's rs274 drops it).
  comp_stop(false, 1);
  if (corner_) {
    program_.warnings.push_back(program_.where(program_.blocks[corner_->block].source) + ": " +
                                (corner_->round ? ",R" : ",C") + " on the last line: no next line, no corner");
    corner_.reset();
  }
  if (state_.twp) twp_emit();  // the next file goes on in the tilted plane
}

bool Reader::line(std::string& text) {
  Source& src = *current_;
  if (!text.empty() && text.back() == '\r') text.pop_back();  // CRLF files
  // A UTF-8 byte order mark before the first line (Windows editors write one).
  if (src.line == 1 && text.compare(0, 3, "\xEF\xBB\xBF") == 0) text.replace(0, 3, 3, ' ');
  // Fanuc's ':' program number (ISO tapes) is an O number.
  if (const size_t k = skip_blanks(text, 0);
      k < text.size() && text[k] == ':' && k + 1 < text.size() && is_digit(text[k + 1])) {
    text[k] = 'O';
  }
  const size_t i = skip_blanks(text, 0);
  if (i == text.size()) return true;
  if (text[i] == '%') {
    // rs274ngc: a '%' on the first line opens the program and the next '%' line ends it.
    // Senders (bCNC) take "% text" lines as their own directives: outside LinuxCNC's flavour
    // such a line inside the program is skipped with a warning.
    if (const size_t k = skip_blanks(text, i + 1);
        options_.flavor != GcodeOptions::Flavor::LinuxCnc && src.seen_content && k < text.size()) {
      warn(column_at(i), "'%' line with text inside the program (a sender's directive): skipped");
      return true;
    }
    line_words_.clear();
    assignments_.clear();
    lex(text, i + 1);
    if (!line_words_.g.empty() || !line_words_.m.empty() || o_column_ != 0 || !assignments_.empty() ||
        std::any_of(line_words_.words.begin(), line_words_.words.end(), [](const Word& w) { return w.present; })) {
      fail(column_at(i), "words after '%' (expected '%' alone on its line)");
    }
    if (!src.seen_content) {
      src.seen_content = src.opened_with_percent = true;
      return true;
    }
    if (!src.opened_with_percent) {
      fail(column_at(i), "closing '%' in a program that did not open with '%' on its first line");
    }
    if (&src == sources_.front().get() && frames_.size() == 1) end_line_ = src.line;
    return false;
  }
  src.seen_content = true;
  // Block delete: rs274ngc skips a line starting with '/' when the block-delete switch is on
  // (GcodeOptions::block_delete); off, the line runs.
  if (text[i] == '/') {
    if (options_.block_delete) return true;
    text[i] = ' ';
  }
  if (options_.flavor != GcodeOptions::Flavor::LinuxCnc) {
    const int statement = macro_statement(text, skip_blanks(text, 0));
    if (statement == 1) return true;
  }
  OLine o;
  if (o_line(text, o) && !o.keyword.empty()) return o_word(text, o);
  line_words_.clear();
  assignments_.clear();
  lex(text, i);
  // rs274ngc: every value on the line is read before any parameter is set.
  for (const Assignment& a : assignments_) {
    if (a.target.name.empty()) {
      set_variable(a.target.number, a.value, a.column, text);
    } else if (a.target.name[0] == '_') {
      state_.globals[a.target.name] = a.value;
    } else {
      state_.locals[a.target.name] = a.value;
    }
  }
  return execute();
}

// --- o-words.

bool Reader::o_line(const std::string& s, OLine& o) {
  size_t i = skip_blanks(s, 0);
  if (i < s.size() && (s[i] == 'N' || s[i] == 'n')) {  // a line number before the o-word
    size_t j = skip_blanks(s, i + 1);
    if (j >= s.size() || !is_digit(s[j])) return false;
    while (j < s.size() && (is_digit(s[j]) || is_blank(s[j]))) ++j;
    i = j;
  }
  if (i >= s.size() || (s[i] != 'O' && s[i] != 'o')) return false;
  o.column = column_at(i);
  i = skip_blanks(s, i + 1);
  if (i < s.size() && s[i] == '<') {
    const size_t close = s.find('>', i + 1);
    if (close == std::string::npos) return false;  // lex reports it
    o.label.clear();
    for (size_t k = i + 1; k < close; ++k) {
      if (is_blank(s[k])) continue;
      o.label += (s[k] >= 'A' && s[k] <= 'Z') ? static_cast<char>(s[k] - 'A' + 'a') : s[k];
    }
    o.label = "<" + o.label + ">";
    i = close + 1;
  } else {
    if (i >= s.size() || !is_digit(s[i])) return false;
    std::string digits;
    while (i < s.size() && (is_digit(s[i]) || is_blank(s[i]))) {
      if (is_digit(s[i]) && !(digits.empty() && s[i] == '0')) digits += s[i];
      ++i;
    }
    o.label = digits.empty() ? "0" : digits;
  }
  i = skip_blanks(s, i);
  o.keyword.clear();
  while (i < s.size() && is_letter(s[i]))
    o.keyword += static_cast<char>(std::tolower(static_cast<unsigned char>(s[i++])));
  o.rest = i;
  return true;
}

double Reader::condition(const std::string& s, const OLine& o) {
  size_t i = skip_blanks(s, o.rest);
  if (i >= s.size() || s[i] != '[') {
    fail(column_at(std::min(i, s.size())),
         "o" + o.label + " " + o.keyword + " without its condition (expected [expression])");
  }
  const double v = detail::read_expression(s, i, *this);
  i = skip_blanks(s, i);
  if (i < s.size() && s[i] == '(') i = skip_blanks(s, skip_comment(s, i));
  if (i < s.size() && s[i] != ';') fail(column_at(i), "unexpected " + describe(s[i]) + " after the condition");
  return v;
}

OLine Reader::skip_to(const std::string& label, std::initializer_list<const char*> ends, const std::string& opened,
                      std::string& text) {
  OLine o;
  while (next_line(text)) {
    if (!text.empty() && text.back() == '\r') text.pop_back();
    if (!o_line(text, o) || o.label != label) continue;
    for (const char* e : ends) {
      if (o.keyword == e) return o;
    }
  }
  std::string expected;
  for (const char* e : ends) expected += (expected.empty() ? "" : " or ") + std::string("o") + label + " " + e;
  throw InputError(current_->name, current_->line, 0,
                   "the file ends before " + expected + " (opened at " + opened + ")" + call_chain());
}

// Reads on in the current file (not executing) to "o<name> sub" and defines it there.
bool Reader::read_to_sub(const std::string& name) {
  std::string text;
  OLine o;
  while (next_line(text)) {
    if (!text.empty() && text.back() == '\r') text.pop_back();
    if (o_line(text, o) && o.label == name && o.keyword == "sub") {
      subs_[name] = SubDefinition{mark_after(), here()};
      return true;
    }
  }
  return false;
}

// A subroutine or subprogram file, opened as a source of lines (program_.files names it).
Source* Reader::open_file(const std::filesystem::path& path, int column, const char* what) {
  auto src = std::make_unique<Source>();
  src->owned = std::make_unique<std::ifstream>(path, std::ios::binary);
  if (!*src->owned) fail(column, std::string("cannot open the ") + what + " file " + path.string());
  src->in = src->owned.get();
  src->name = path.string();
  src->file_index = static_cast<int>(program_.files.size());
  src->seekable = true;
  program_.files.push_back(src->name);
  sources_.push_back(std::move(src));
  return sources_.back().get();
}

SubDefinition* Reader::find_sub(const std::string& name, int column) {
  if (const auto it = subs_.find(name); it != subs_.end()) return &it->second;
  // Defined further down the calling file (after M2, say): read ahead for it, as rs274 does.
  if (current_->seekable) {
    const Mark back = mark_after();
    const bool found = read_to_sub(name);
    jump(back);
    if (found) return &subs_[name];
  }
  if (name.front() != '<') return nullptr;
  // A subroutine file: <name>.ngc holding "o<name> sub", in the calling program's folder or
  // on the search path.
  const std::string file = name.substr(1, name.size() - 2) + ".ngc";
  std::vector<std::filesystem::path> folders;
  folders.push_back(std::filesystem::path(sources_.front()->name).parent_path());
  for (const std::string& p : options_.subroutine_path) folders.emplace_back(p);
  for (const auto& folder : folders) {
    const std::filesystem::path path = folder / file;
    std::error_code ec;
    if (!std::filesystem::is_regular_file(path, ec)) continue;
    Source* caller = current_;
    current_ = open_file(path, column, "subroutine");
    const bool found = read_to_sub(name);
    const std::string where = current_->name;
    current_ = caller;
    if (found) return &subs_[name];
    fail(column, where + " does not define o" + name + " sub");
  }
  return nullptr;
}

void Reader::call(const std::string& s, const OLine& o) {
  SubDefinition* sub = find_sub(o.label, o.column);
  if (sub == nullptr) {
    std::string folders = std::filesystem::path(sources_.front()->name).parent_path().string();
    for (const std::string& p : options_.subroutine_path) folders += ", " + p;
    fail(o.column, "o" + o.label + " call: no such subroutine (expected o" + o.label + " sub earlier in the program" +
                       (o.label.front() == '<' ? ", or the file " + o.label.substr(1, o.label.size() - 2) + ".ngc in " +
                                                     (folders.empty() ? std::string(".") : folders)
                                               : std::string()) +
                       ")");
  }
  sub->called = true;
  if (frames_.size() > 64) fail(o.column, "subroutine calls nested more than 64 deep (a call that never returns?)");
  // Arguments: bracketed expressions, to #1..#30 of the call.
  std::vector<double> args;
  size_t i = skip_blanks(s, o.rest);
  while (i < s.size()) {
    if (s[i] == '(') {
      i = skip_blanks(s, skip_comment(s, i));
      continue;
    }
    if (s[i] == ';') break;
    if (s[i] != '[') fail(column_at(i), "unexpected " + describe(s[i]) + " in the call (expected arguments in [ ])");
    if (args.size() == 30) fail(column_at(i), "more than 30 arguments (expected at most 30)");
    args.push_back(detail::read_expression(s, i, *this));
    i = skip_blanks(s, i);
  }
  Frame f;
  f.sub = o.label.front() == '<' ? o.label.substr(1, o.label.size() - 2) : o.label;
  f.call_where = here();
  f.return_to = mark_after();
  for (size_t k = 0; k < 30; ++k) {
    f.saved_numbered[k] = state_.parameters[k + 1];
    state_.parameters[k + 1] = k < args.size() ? args[k] : 0.0;
  }
  f.saved_locals.swap(state_.locals);
  const Mark body = sub->body;
  frames_.push_back(std::move(f));
  jump(body);
}

void Reader::leave_sub(const std::string& s, const OLine& o) {
  if (frames_.size() <= 1) {
    fail(o.column, "o" + o.label + " " + o.keyword + " outside a subroutine call");
  }
  size_t i = skip_blanks(s, o.rest);
  bool returned = false;
  double value = 0.0;
  if (i < s.size() && s[i] == '[') {
    value = detail::read_expression(s, i, *this);
    returned = true;
  }
  Frame& f = frame();
  if (f.autorestore) restore_modes(*f.autorestore);
  for (size_t k = 0; k < 30; ++k) state_.parameters[k + 1] = f.saved_numbered[k];
  state_.locals.swap(f.saved_locals);
  state_.globals["_value"] = value;
  state_.globals["_value_returned"] = returned ? 1.0 : 0.0;
  const Mark back = f.return_to;
  frames_.pop_back();
  jump(back);
}

bool Reader::o_word(const std::string& s, const OLine& o) {
  const std::string& k = o.keyword;
  const std::string& label = o.label;
  Frame& f = frame();
  auto only_comment_after = [&](size_t i) {
    i = skip_blanks(s, i);
    while (i < s.size() && s[i] == '(') i = skip_blanks(s, skip_comment(s, i));
    if (i < s.size() && s[i] != ';') fail(column_at(i), "unexpected " + describe(s[i]) + " after o" + label + " " + k);
  };
  auto find_loop = [&]() -> Loop& {
    for (size_t n = f.loops.size(); n-- > 0;) {
      if (f.loops[n].label == label) {
        if (n + 1 != f.loops.size()) {
          fail(o.column, "o" + label + " " + k + " while the inner loop o" + f.loops.back().label + " is open");
        }
        return f.loops[n];
      }
    }
    fail(o.column, "o" + label + " " + k + " outside a loop o" + label);
  };
  std::string text;
  if (k == "sub") {
    if (frames_.size() > 1)
      fail(o.column,
           "o" + label + " sub inside the subroutine o<" + f.sub + "> (expected definitions at the top level)");
    only_comment_after(o.rest);
    subs_[label] = SubDefinition{mark_after(), here()};
    skip_to(label, {"endsub"}, here(), text);
    return true;
  }
  if (k == "endsub" || k == "return") {
    leave_sub(s, o);
    return true;
  }
  if (k == "call") {
    call(s, o);
    return true;
  }
  if (k == "if") {
    const std::string opened = here();
    f.ifs.emplace_back(label, opened);
    if (condition(s, o) != 0.0) return true;
    // Read on to the branch to run, or to endif.
    while (true) {
      const OLine next = skip_to(label, {"elseif", "else", "endif"}, opened, text);
      if (next.keyword == "endif") {
        f.ifs.pop_back();
        return true;
      }
      if (next.keyword == "else" || condition(text, next) != 0.0) return true;
    }
  }
  if (k == "elseif" || k == "else") {
    // The branch that ran ends here.
    if (f.ifs.empty() || f.ifs.back().first != label)
      fail(o.column, "o" + label + " " + k + " without o" + label + " if");
    const std::string opened = f.ifs.back().second;
    skip_to(label, {"endif"}, opened, text);
    f.ifs.pop_back();
    return true;
  }
  if (k == "endif") {
    if (f.ifs.empty() || f.ifs.back().first != label) fail(o.column, "o" + label + " endif without o" + label + " if");
    only_comment_after(o.rest);
    f.ifs.pop_back();
    return true;
  }
  if (k == "do") {
    only_comment_after(o.rest);
    f.loops.push_back(Loop{Loop::Kind::Do, label, mark_after(), 0.0, f.ifs.size(), here()});
    return true;
  }
  if (k == "while") {
    if (!f.loops.empty() && f.loops.back().label == label && f.loops.back().kind == Loop::Kind::Do) {
      // The end of a do loop.
      if (condition(s, o) != 0.0) {
        jump(f.loops.back().start);
      } else {
        f.loops.pop_back();
      }
      return true;
    }
    const bool again = !f.loops.empty() && f.loops.back().label == label && f.loops.back().kind == Loop::Kind::While;
    if (!again) f.loops.push_back(Loop{Loop::Kind::While, label, mark_this(), 0.0, f.ifs.size(), here()});
    if (condition(s, o) != 0.0) return true;
    const std::string opened = f.loops.back().where;
    f.loops.pop_back();
    skip_to(label, {"endwhile"}, opened, text);
    return true;
  }
  if (k == "endwhile") {
    Loop& loop = find_loop();
    if (loop.kind != Loop::Kind::While) fail(o.column, "o" + label + " endwhile ends a loop that is not a while loop");
    jump(loop.start);
    return true;
  }
  if (k == "repeat") {
    const double n = condition(s, o);
    if (n >= 1.0) {
      f.loops.push_back(Loop{Loop::Kind::Repeat, label, mark_after(), std::floor(n), f.ifs.size(), here()});
    } else {
      skip_to(label, {"endrepeat"}, here(), text);
    }
    return true;
  }
  if (k == "endrepeat") {
    Loop& loop = find_loop();
    if (loop.kind != Loop::Kind::Repeat) fail(o.column, "o" + label + " endrepeat ends a loop that is not a repeat");
    if (--loop.remaining >= 1.0) {
      jump(loop.start);
    } else {
      f.loops.pop_back();
    }
    return true;
  }
  if (k == "break" || k == "continue") {
    Loop& loop = find_loop();
    f.ifs.resize(loop.if_depth);
    const std::string opened = loop.where;
    const char* end = loop.kind == Loop::Kind::While    ? "endwhile"
                      : loop.kind == Loop::Kind::Repeat ? "endrepeat"
                                                        : "while";
    if (k == "break") {
      f.loops.pop_back();
      skip_to(label, {end}, opened, text);
      return true;
    }
    // continue: on to the loop's test.
    if (loop.kind == Loop::Kind::While) {
      jump(loop.start);
      return true;
    }
    const OLine test = skip_to(label, {end}, opened, text);
    return o_word(text, test);
  }
  fail(o.column, "unknown o-word keyword '" + k +
                     "' (expected sub, endsub, call, return, if, elseif, else, endif, "
                     "while, endwhile, do, break, continue, repeat or endrepeat)");
}

size_t Reader::skip_comment(const std::string& s, size_t i) {
  // rs274ngc rejects nested comments (NCE_NESTED_COMMENT_FOUND); CAM posts write them
  // ("(DRILL 4.5MM (R))") and Fanuc and the senders read them, so they nest here. LinuxCNC's
  // programs get a warning. Unbalanced, the comment ends at the first ')' (unnested reading).
  int depth = 1;
  size_t first_close = std::string::npos;
  for (size_t j = i + 1; j < s.size(); ++j) {
    if (s[j] == ')' && first_close == std::string::npos) first_close = j;
    if (s[j] == ')' && --depth == 0) return j + 1;
    if (s[j] != '(') continue;
    ++depth;
    if (options_.flavor == GcodeOptions::Flavor::LinuxCnc) {
      program_.warnings.push_back(where(column_at(j)) +
                                  ": '(' inside a comment (rs274 refuses it; read as a nested comment)");
    }
  }
  if (first_close != std::string::npos) return first_close + 1;
  fail(column_at(i), "unterminated comment: '(' without ')'");
}

// A word's value: a plain number (the fast path) or any rs274ngc real value. Errors about
// the value's start point at the word's letter.
double Reader::word_value(const std::string& s, size_t& i, char letter, std::string& text) {
  const int column = column_at(i - 1);
  size_t j = skip_blanks(s, i);
  if (j < s.size() && (s[j] == '+' || s[j] == '-')) j = skip_blanks(s, j + 1);
  if (j < s.size() && (is_digit(s[j]) || s[j] == '.')) {
    return detail::read_plain_number(s, i, letter, *this, text, column);
  }
  if (j >= s.size() || !(s[j] == '#' || s[j] == '[' || detail::function_at(s, j))) {
    fail(column, std::string("expected a number after '") + letter + "', found " +
                     (j < s.size() ? describe(s[j]) : std::string("end of line")));
  }
  const double value = detail::read_real_value(s, i, letter, *this);
  if (detail::is_vacant(value)) {
    fail(column,
         std::string("vacant value in the ") + letter + " word (a variable never set, or #0; expected a value)");
  }
  text = num(value);
  return value;
}

void Reader::lex(const std::string& s, size_t i) {
  const size_t n = s.size();
  bool first_word = true;
  o_column_ = 0;
  while (true) {
    i = skip_blanks(s, i);
    if (i >= n) return;
    const char c = s[i];
    const int column = column_at(i);
    if (c == '(') {
      i = skip_comment(s, i);
      continue;
    }
    if (c == ',' && options_.flavor != GcodeOptions::Flavor::LinuxCnc) {
      // Fanuc ,R<radius> / ,C<length>: round or chamfer the corner to the next line.
      const size_t j = skip_blanks(s, i + 1);
      if (j < n && (upper(s[j]) == 'R' || upper(s[j]) == 'C')) {
        const char kind = upper(s[j]);
        i = j + 1;
        std::string text;
        const double value = word_value(s, i, kind, text);
        Word& w = kind == 'R' ? line_words_.round : line_words_.chamfer;
        if (w.present) fail(column, std::string("second ,") + kind + " on the line (expected at most one)");
        if (!(value > 0.0) || value > kMaxMagnitude)
          fail(column, std::string(",") + kind + " " + text + " (expected a length > 0)");
        w = Word{true, value, column};
        first_word = false;
        continue;
      }
    }
    if (c == ';') return;  // LinuxCNC: the rest of the line is a comment
    if (c == '#') {
      // A parameter setting: #n = value or #<name> = value (set once the line is read).
      if (o_column_ != 0) fail(o_column_, "a program number O<digits> with more on its line (expected it alone)");
      ++i;
      const detail::ParameterRef ref = detail::read_parameter_ref(s, i, *this);
      i = skip_blanks(s, i);
      if (i >= n || s[i] != '=') {
        fail(column_at(i), "expected '=' after the parameter, found " +
                               (i >= n ? std::string("end of line") : describe(s[i])) +
                               " (a parameter is set with #n = value, or read as a word's value)");
      }
      ++i;
      // rs274ngc: one value ([...] for an expression); Fanuc and the others: an expression.
      const double value = options_.flavor == GcodeOptions::Flavor::LinuxCnc
                               ? detail::read_real_value(s, i, 0, *this)
                               : detail::read_open_expression(s, i, *this);
      assignments_.push_back({ref, value, column});
      first_word = false;
      continue;
    }
    if (!is_letter(c)) {
      if (c == '[') fail(column, "expression without its word (expected a letter before '[')");
      if (c == '@' || c == '^') {
        ++i;
        std::string text;
        const double value = word_value(s, i, c, text);
        if (std::abs(value) > kMaxMagnitude) fail(column, std::string(1, c) + " value " + text + " is out of range");
        Word& w = c == '@' ? line_words_.radius : line_words_.angle;
        if (w.present) fail(column, std::string("second ") + c + " word on the line (expected at most one)");
        w = Word{true, value, column};
        first_word = false;
        continue;
      }
      fail(column, "unexpected " + describe(c) + " (expected a word: a letter and a number)");
    }
    const char letter = upper(c);
    ++i;
    if (o_column_ != 0) {
      fail(o_column_,
           "o-word without a keyword (expected o<name> or o<number> followed by sub, call, if, "
           "while, ..., or a program number O<digits> alone on its line)");
    }
    if (letter == 'O') {
      // A Fanuc program number ("O1234" alone on a line) is accepted and ignored.
      const size_t j = skip_blanks(s, i);
      if (!first_word || j >= n || !is_digit(s[j])) {
        fail(column,
             "o-word not at the start of its line, or without a keyword (expected o<name> or "
             "o<number> followed by sub, call, if, while, ...)");
      }
      std::string text;
      detail::read_plain_number(s, i, letter, *this, text, column);
      o_column_ = column;
      first_word = false;
      continue;
    }

    std::string text;
    const double value =
        letter == 'N' ? detail::read_plain_number(s, i, letter, *this, text, column) : word_value(s, i, letter, text);
    if (letter != 'N' && letter != 'F' && std::abs(value) > kMaxMagnitude) {
      fail(column, std::string(1, letter) + " value " + text + " is out of range (expected |value| <= 1000000)");
    }
    if ((letter == 'G' || letter == 'M') &&
        (letter == 'G' ? line_words_.g : line_words_.m).size() >= kMaxCodesPerLine) {
      // Only so many modal groups exist; this bounds the memory a garbage line can take.
      fail(column, std::string("more than ") + std::to_string(kMaxCodesPerLine) + " " + letter +
                       " words on one line (expected at most one per modal group)");
    }
    if (letter == 'G') {
      Code code{-1, column, "G" + text};
      const double tenths = value * 10.0;
      if (value >= 0.0 && std::abs(tenths - std::round(tenths)) < 1e-6) {
        code.number = static_cast<int>(std::lround(tenths));
        code.text = "G" + std::to_string(code.number / 10);
        if (code.number % 10 != 0) code.text += "." + std::to_string(code.number % 10);
      }
      line_words_.g.push_back(code);
    } else if (letter == 'M') {
      Code code{-1, column, "M" + text};
      if (value >= 0.0 && is_whole(value)) {
        code.number = static_cast<int>(value);
        code.text = "M" + std::to_string(code.number);
      }
      line_words_.m.push_back(code);
    } else if (letter == 'N') {
      // rs274ngc: the line number comes first (after a block delete '/').
      if (!first_word) fail(column, "N word not at the start of the line (expected it first)");
      if (value < 0.0 || !is_whole(value)) {
        fail(column, "N value " + text + " (expected a whole number >= 0)");
      }
    } else {
      Word& w = line_words_.words[letter - 'A'];
      if (w.present) {
        fail(column, std::string("second ") + letter + " word on the line (expected at most one)");
      }
      w = Word{true, value, column};
    }
    first_word = false;
  }
}

// The end point of this line's motion in the workpiece frame; `programmed` says which axes
// the line names.
Eigen::Vector3d Reader::to_program(const Eigen::Vector3d& w) const {
  Eigen::Vector3d p = w - state_.g5x_mm - state_.g92_mm;
  if (rotated()) {
    const Eigen::Vector2d c = rotation_center();
    p.head<2>() = c + Eigen::Rotation2Dd(-rotation_angle()) * (p.head<2>() - c);
  }
  return p;
}

Eigen::Vector3d Reader::to_workpiece(const Eigen::Vector3d& p) const {
  Eigen::Vector3d w = p;
  if (rotated()) {
    const Eigen::Vector2d c = rotation_center();
    w.head<2>() = c + Eigen::Rotation2Dd(rotation_angle()) * (p.head<2>() - c);
  }
  return w + state_.g5x_mm + state_.g92_mm;
}

Eigen::Vector3d Reader::target(std::array<bool, 3>& programmed) const {
  const Eigen::Vector3d base = base_point();
  if (rotated() && !machine_coordinates_) {
    // G68: the words name a point of the rotated program coordinates (G91: an increment
    // along them); polar words turn about the program origin there too.
    Eigen::Vector3d p = to_program(base);
    if (line_words_.radius.present || line_words_.angle.present) {
      for (char letter : {'X', 'Y'}) {
        if (word(letter).present)
          fail(word(letter).column, std::string(1, letter) + " word with polar @/^ (expected one or the other)");
      }
      p.head<2>() = polar_point(p.head<2>());
      programmed[0] = programmed[1] = true;
    }
    for (int a = 0; a < 3; ++a) {
      const Word& w = word(kAxisLetter[a]);
      if (!(a < 2 && (line_words_.radius.present || line_words_.angle.present))) programmed[a] = w.present;
      if (!w.present) continue;
      const double v = w.value * unit();
      p[a] = state_.incremental ? p[a] + v : v;
    }
    const Eigen::Vector3d end = to_workpiece(p);
    for (int a = 0; a < 3; ++a) {
      if (!(std::abs(end[a]) <= kMaxMagnitude)) {
        fail(word(kAxisLetter[a]).present ? word(kAxisLetter[a]).column : 1,
             std::string(1, kAxisLetter[a]) + " position " + num(end[a]) +
                 " mm is out of range (expected within +-1e6 mm)");
      }
    }
    return end;
  }
  Eigen::Vector3d end = base;
  const Eigen::Vector3d offset = state_.g5x_mm + state_.g92_mm;
  const Word& radius = line_words_.radius;
  const Word& angle = line_words_.angle;
  if (radius.present || angle.present) {
    // Polar X Y (LinuxCNC): about the program origin, the distance @ and the angle ^ (deg);
    // one not given keeps the current point's; in G91 both add to the current point's.
    const int column = radius.present ? radius.column : angle.column;
    for (char letter : {'X', 'Y'}) {
      if (word(letter).present)
        fail(word(letter).column, std::string(1, letter) + " word with polar @/^ (expected one or the other)");
    }
    if (machine_coordinates_) fail(column, "polar @/^ with G53 (expected X Y)");
    if (!state_.known[0] || !state_.known[1]) {
      fail(column,
           "polar @/^ while the X or Y position is unknown is not supported: vcut assumes no start position "
           "(expected an X Y move first)");
    }
    const Eigen::Vector2d p = polar_point((base - offset).head<2>());
    end.x() = p.x() + offset.x();
    end.y() = p.y() + offset.y();
    programmed[0] = programmed[1] = true;
    for (int a = 0; a < 2; ++a) {
      if (!(std::abs(end[a]) <= kMaxMagnitude)) {
        fail(column, std::string(1, kAxisLetter[a]) + " position " + num(end[a]) +
                         " mm from polar @/^ is out of range (expected within +-1e6 mm)");
      }
    }
  }
  for (int a = 0; a < 3; ++a) {
    const Word& w = word(kAxisLetter[a]);
    if (!(a < 2 && (radius.present || angle.present))) programmed[a] = w.present;
    if (!w.present) continue;
    const double v = w.value * unit();
    if (machine_coordinates_) {
      if (state_.incremental) fail(w.column, "G53 in incremental mode G91 (expected G90)");
      // Machine coordinates, no work offsets, from the gauge point at all-zero axes. LinuxCNC
      // applies the tool length (G43) there: the tip goes to the point; Fanuc and Haas move the
      // spindle's gauge point there (their posts' G53 G0 Z0 with G43 on is the tool change
      // height), as LinuxCNC does under G49: the tip a tool length below it.
      const bool tip_there = options_.flavor == GcodeOptions::Flavor::LinuxCnc && state_.length_comp;
      end[a] = options_.machine_zero_mm[a] + v + (tip_there ? 0.0 : tip_offset()[a]);
    } else if (state_.incremental) {
      if (!state_.known[a]) {
        fail(w.column, std::string("incremental (G91) ") + kAxisLetter[a] + " move while the " + kAxisLetter[a] +
                           " position is unknown is not supported: vcut assumes no start "
                           "position (expected an absolute " +
                           kAxisLetter[a] + " move first)");
      }
      end[a] = base[a] + v;
    } else {
      end[a] = v + offset[a];
    }
    if (!(std::abs(end[a]) <= kMaxMagnitude)) {
      fail(w.column, std::string(1, kAxisLetter[a]) + " position " + num(end[a]) +
                         " mm is out of range (expected within +-1e6 mm)");
    }
  }
  return end;
}

// The point the line's polar words @ ^ name, from `from` (program coordinates, mm): its
// distance from the program origin and its angle, replaced (G90) or added to (G91).
Eigen::Vector2d Reader::polar_point(const Eigen::Vector2d& from) const {
  const Word& radius = line_words_.radius;
  const Word& angle = line_words_.angle;
  double r = from.norm() / unit(), t = std::atan2(from.y(), from.x()) * 180.0 / M_PI;
  if (state_.incremental && from.norm() <= 1e-9) {
    fail(radius.present ? radius.column : angle.column,
         "incremental (G91) polar @/^ at the program origin: the angle it adds to is undefined (expected G90 "
         "there, as LinuxCNC requires)");
  }
  if (state_.incremental) {
    r += radius.present ? radius.value : 0.0;
    t += angle.present ? angle.value : 0.0;
  } else {
    if (radius.present) r = radius.value;
    if (angle.present) t = angle.value;
  }
  return Eigen::Vector2d(std::cos(t * M_PI / 180.0), std::sin(t * M_PI / 180.0)) * (r * unit());
}

// Appends a block (unless it does not move) and brings the position and the unknown axes up
// to date. Blocks made while an axis is unknown hold that axis still; when the axis is first
// programmed they take its value, so that the first move only moves the programmed axes.
kinematics::ExtraAxes Reader::extra_target() const {
  kinematics::ExtraAxes extra = state_.extra;
  for (size_t e = 0; e < 3; ++e) {
    const char letter = "UVW"[e];
    const Word& w = word(letter);
    if (!extra_word_[e]) continue;
    const double v = w.value * unit();
    if (machine_coordinates_) {
      if (state_.incremental) fail(w.column, "G53 in incremental mode G91 (expected G90)");
      extra.value_mm[e] = v;  // machine coordinates: no work offsets
    } else {
      extra.value_mm[e] =
          state_.incremental ? extra.value_mm[e] + v : v + state_.g5x_extra_mm[e] + state_.g92_extra_mm[e];
    }
    extra.given[e] = true;
    if (!(std::abs(extra.value_mm[e]) <= kMaxMagnitude)) {
      fail(w.column, std::string(1, letter) + " position " + num(extra.value_mm[e]) +
                         " mm is out of range (expected within +-1e6 mm)");
    }
  }
  return extra;
}

void Reader::no_extra(const std::string& where) const {
  if (extra_column_ == 0) return;
  fail(extra_column_, "U V W words on a " + where +
                          " line are not supported (U V W move with G0, G1, G2, G3, G28 and G30, or set offsets with "
                          "G10 and G92)");
}

void Reader::append(Block block, const std::array<bool, 3>& programmed, const kinematics::RotaryWords* rotary_end,
                    const kinematics::ExtraAxes* extra_end) {
  // Rotary words (degrees, G90/G91 like the linear axes; G20 does not apply).
  kinematics::RotaryWords rotary = rotary_end != nullptr ? *rotary_end : state_.rotary;
  const bool holds_linear = !in_swing_ && turns_hold_linear();
  int rotary_column = 1;
  for (int r = 0; r < 3 && rotary_end == nullptr; ++r) {
    const Word& w = word(static_cast<char>('A' + r));
    if (!w.present) continue;
    if (rotary_column == 1) rotary_column = w.column;
    if (state_.twp && state_.twp_feature) {
      fail(w.column, std::string(1, static_cast<char>('A' + r)) +
                         " word with a tilted work plane on (G53.1 or G53.6 turn the rotaries; expected G69 first)");
    }
    const double v = w.value * M_PI / 180.0;
    rotary.angle_rad[static_cast<size_t>(r)] = state_.incremental ? rotary.angle_rad[static_cast<size_t>(r)] + v : v;
    rotary.given[static_cast<size_t>(r)] = true;
    // A rotary word that turns nothing (A0 at A0, as posts write on their first positioning
    // line) does not make an axis program of a tool-tip one.
    if (!holds_linear && rotary.angle_rad[static_cast<size_t>(r)] != state_.rotary.angle_rad[static_cast<size_t>(r)]) {
      state_.rotary_program = true;
    }
  }
  // U V W: the line's words (or the G28/G30 reference), linear with the move like A B C.
  kinematics::ExtraAxes extra = state_.extra;
  if (extra_end != nullptr) {
    extra = *extra_end;
  } else if (rotary_end == nullptr && extra_column_ != 0) {
    if (hold_ || compensating()) no_extra("cutter compensation (G41/G42)");
    if (state_.twp || in_swing_) no_extra("tilted work plane (G68.2) or turned rotaries'");
    extra = extra_target();
  }
  if (holds_linear && rotary.angle_rad != state_.rotary.angle_rad) {
    no_extra("rotary turn's");
    joint_move(block, rotary, rotary_column);
    return;
  }
  // A tilted plane's (or turned table's) frame can carry a point in range out of it.
  if (state_.twp || in_swing_) {
    const Eigen::Vector3d end =
        state_.twp ? Eigen::Vector3d(state_.twp_rotation * block.end_mm + state_.twp_translation_mm) : block.end_mm;
    for (int a = 0; a < 3; ++a) {
      if (!(std::abs(end[a]) <= kMaxMagnitude)) {
        fail(1, std::string(1, kAxisLetter[a]) + " position " + num(end[a]) +
                    " mm on the part is out of range (expected within +-1e6 mm)");
      }
    }
  }
  block.start_rotary = state_.rotary;
  block.end_rotary = rotary;
  block.start_extra = state_.extra;
  block.end_extra = extra;
  const bool extra_moves = extra.value_mm != state_.extra.value_mm;
  state_.extra = extra;
  // Under TCP the block is a tool pose: the tip, and the tool axis from the rotary words
  // (G43.4: the machine's axes at those values) or from I J K (G43.5).
  block.tool_pose = state_.tcp != GcodeState::Tcp::Off || !state_.rotary_program || state_.twp;
  bool reorients = false;
  if (state_.tcp == GcodeState::Tcp::Angles || state_.twp) {
    block.orientation = kinematics::OrientationMode::Axes;
  } else if (state_.tcp == GcodeState::Tcp::Vector) {
    block.start_axis = state_.tool_axis;
    block.end_axis = line_axis_;
    reorients = line_axis_ != state_.tool_axis;
    state_.tool_axis = line_axis_;
  }
  block.exact_stop = state_.exact_stop || exact_stop_line_;
  block.blend_tolerance_mm = state_.blend_tolerance_mm;
  const bool turns = rotary.angle_rad != state_.rotary.angle_rad;
  state_.rotary = rotary;
  // In a tilted or turned frame a move that is a few ulps long there may be none on the part.
  const bool moves = block.kind == MotionKind::Arc || turns || reorients || extra_moves ||
                     (state_.twp ? twp_out(block.start_mm) != twp_out(block.end_mm) : block.start_mm != block.end_mm);
  if (moves) {
    block.feed_mode = state_.inverse_time && block.kind != MotionKind::Rapid ? kinematics::FeedMode::InverseTime
                                                                             : kinematics::FeedMode::UnitsPerMinute;
    block.tool = state_.tool;
    block.spindle = state_.spindle;
    block.spindle_rpm = state_.spindle_rpm;
    block.source = kinematics::SourceRef{current_->file_index, current_->line};
    if (hold_) {
      state_.comp.held.push_back({block, hold_direction_, hold_sweep_rad_});
    } else {
      program_.blocks.push_back(block);
    }
    for (int a = 0; a < 3; ++a) {
      if (!state_.known[a] && !programmed[a]) {
        state_.pending[a].push_back(program_.blocks.size() - 1);
      }
    }
  }
  for (int a = 0; a < 3; ++a) {
    if (!programmed[a] || state_.known[a]) continue;
    state_.known[a] = true;
    auto& pending = state_.pending[a];
    if (pending.empty()) continue;
    const double value = block.end_mm[a];
    size_t patched = 0;
    std::string first;
    for (size_t index : pending) {
      if (index >= program_.blocks.size()) continue;  // a different Program was passed in
      Block& b = program_.blocks.edit(index);
      if (first.empty() && b.source.file >= 0 && static_cast<size_t>(b.source.file) < program_.files.size()) {
        first = program_.where(b.source);
      }
      b.start_mm[a] = b.end_mm[a] = value;
      if (b.kind == MotionKind::Arc) b.center_mm[a] = value;  // only the normal axis is ever pending
      ++patched;
    }
    pending.clear();
    if (patched > 0) {
      warn(word(kAxisLetter[a]).column, std::to_string(patched) + " earlier move(s) (first at " + first +
                                            ") ran while " + kAxisLetter[a] + " was unknown; they hold " +
                                            kAxisLetter[a] + " at " + num(value) + " mm, its first programmed value");
    }
  }
  state_.position_mm = block.end_mm;
}

// After an ignored code that moved axes we cannot follow (G28, G53, a canned cycle...).
void Reader::forget_axes(bool all) {
  bool any = false;
  for (int a = 0; a < 3; ++a) {
    if (word(kAxisLetter[a]).present) {
      state_.known[a] = false;
      any = true;
    }
  }
  if (all && !any) state_.known = {false, false, false};
}

void Reader::straight(MotionKind kind, int column) {
  const double feed = kind == MotionKind::Rapid ? 0.0 : feed_of_line(column);
  std::array<bool, 3> programmed{};
  Block block;
  block.kind = kind;
  block.end_mm = target(programmed);
  block.start_mm = state_.position_mm;
  for (int a = 0; a < 3; ++a) {
    if (!state_.known[a]) block.start_mm[a] = block.end_mm[a];
  }
  block.feed_mm_per_min = feed;
  state_.comp.arc_not_allowed = false;
  state_.spline_control_mm.reset();
  if (compensating()) {
    comp_straight(block, programmed, column);
    return;
  }
  if (state_.comp.machine_mm) {  // the exit move after G40: from where the tool is
    block.start_mm = *state_.comp.machine_mm;
    state_.comp.machine_mm.reset();
  }
  const Word& round = line_words_.round;
  const Word& chamfer = line_words_.chamfer;
  if (corner_ || round.present || chamfer.present) no_extra("corner (,R ,C)");
  if (corner_) corner_to(block, column);
  if (round.present || chamfer.present) {
    const Word& w = round.present ? round : chamfer;
    if (round.present && chamfer.present) fail(chamfer.column, ",R and ,C on one line (expected one of them)");
    if (kind != MotionKind::Linear)
      fail(w.column, std::string(round.present ? ",R" : ",C") + " on a rapid (expected G1)");
    if (compensating())
      fail(w.column, std::string(round.present ? ",R" : ",C") + " with cutter compensation on (not supported yet)");
    const size_t before = program_.blocks.size();
    append(block, programmed);
    if (program_.blocks.size() == before)
      fail(w.column, std::string(round.present ? ",R" : ",C") + " on a line that does not move");
    corner_ = PendingCorner{round.present, w.value * unit(), program_.blocks.size() - 1, w.column};
    return;
  }
  append(block, programmed);
}

// The corner between the held first line and `second` (its start is the corner): the first
// line ends t before the corner, then an arc of radius R tangent to both (t = R tan(phi / 2),
// phi the turn) or a straight chamfer to t after it (t = C), and `second` starts there.
void Reader::corner_to(Block& second, int column) {
  const PendingCorner c = *corner_;
  corner_.reset();
  const char* what = c.round ? ",R" : ",C";
  Block& first = program_.blocks.edit(c.block);
  const Eigen::Vector3d corner = first.end_mm;
  const Eigen::Vector3d in = corner - first.start_mm, out = second.end_mm - corner;
  const double in_length = in.norm(), out_length = out.norm();
  if (!(out_length > 0.0))
    fail(column, std::string(what) + ": the next line does not move (expected the corner's second line)");
  const Eigen::Vector3d d1 = in / in_length, d2 = out / out_length;
  const double turn = std::acos(std::clamp(d1.dot(d2), -1.0, 1.0));
  if (turn < 1e-9) return;  // straight on: no corner
  if (turn > M_PI - 1e-9)
    fail(column, std::string(what) + ": the next line turns back on the first (expected a corner)");
  const double t = c.round ? c.size_mm * std::tan(turn / 2.0) : c.size_mm;
  if (t > in_length + 1e-9 || t > out_length + 1e-9) {
    fail(column, std::string(what) + " " + num(c.size_mm) + " mm needs " + num(t) +
                     " mm of each line, and the lines are " + num(in_length) + " and " + num(out_length) +
                     " mm long (expected a smaller corner)");
  }
  const Eigen::Vector3d t1 = corner - t * d1, t2 = corner + t * d2;
  first.end_mm = t1;
  Block join = first;
  join.start_mm = t1;
  join.end_mm = t2;
  join.start_rotary = join.end_rotary = first.end_rotary;
  if (c.round) {
    const Eigen::Vector3d normal = d1.cross(d2).normalized();
    int a, b, n;
    plane_axes(a, b, n);
    if (std::abs(std::abs(normal[n]) - 1.0) > 1e-9)
      fail(column, ",R between lines not in the active plane (expected both lines in it)");
    const Eigen::Vector3d toward = (d2 - d2.dot(d1) * d1).normalized();
    join.kind = MotionKind::Arc;
    join.center_mm = t1 + c.size_mm * toward;
    join.normal = Eigen::Vector3d::Zero();
    join.normal[n] = normal[n] > 0.0 ? 1.0 : -1.0;
    join.turns = 1;
  }
  program_.blocks.push_back(join);
  second.start_mm = t2;
}

// G33 X Y Z K: a straight feed at K (length per spindle revolution) times the spindle speed.
// G33.1 Z K: rigid tapping, a feed down to Z and the same feed back up to where it started
// (the spindle reverses at the bottom), as LinuxCNC's canon RIGID_TAP runs it.
void Reader::synchronized(int column) {
  const bool tap = state_.motion == Motion::RigidTap;
  const char* code = tap ? "G33.1" : "G33";
  const Word& k = word('K');
  if (!k.present || !(k.value > 0.0))
    fail(k.present ? k.column : column,
         std::string(code) + " without K > 0 (expected K, the length per spindle revolution)");
  if (!(state_.spindle_rpm > 0.0) || state_.spindle == SpindleState::Off) {
    fail(column, std::string(code) + " with the spindle stopped (expected S and M3 or M4 before it)");
  }
  if (compensating()) fail(column, std::string(code) + " with cutter compensation on (expected G40 first)");
  if (tap && (word('X').present || word('Y').present)) {
    fail(word('X').present ? word('X').column : word('Y').column,
         "G33.1 with X or Y (expected Z only: the tap goes down where the tool is)");
  }
  std::array<bool, 3> programmed{};
  Block block;
  block.kind = MotionKind::Linear;
  block.start_mm = state_.position_mm;
  block.end_mm = target(programmed);
  block.feed_mm_per_min = k.value * unit() * state_.spindle_rpm;
  if (block.feed_mm_per_min > kMaxFeed_mm_per_min)
    fail(k.column, std::string(code) + " feed K x S is out of range (expected <= 1e9 mm/min)");
  const bool inverse = state_.inverse_time;
  state_.inverse_time = false;  // a synchronized feed is not inverse time
  const Eigen::Vector3d top = state_.position_mm;
  append(block, programmed);
  if (tap) {
    Block back = block;
    back.start_mm = state_.position_mm;
    back.end_mm = top;
    append(back, {true, true, true});
  }
  state_.inverse_time = inverse;
}

// G5 X Y I J P Q (cubic: I J from the start to the first control point, P Q from the end to the
// second; without I J after a G5, the mirror of the last second control point) and G5.1 X Y I
// J (quadratic: I J from the start to the control point), in G17 as LinuxCNC reads them: the
// curve as straight moves no farther than kSplineChordMm from it (a chord over a parameter
// step h of a curve with second derivative B'' deviates at most h^2 |B''| / 8).
void Reader::spline(int column) {
  const bool cubic = state_.motion == Motion::CubicSpline;
  const char* code = cubic ? "G5" : "G5.1";
  if (state_.plane != Plane::XY) fail(column, std::string(code) + " outside G17 (expected the XY plane)");
  if (compensating()) fail(column, std::string(code) + " with cutter compensation on (expected G40 first)");
  if (word('Z').present || word('A').present || word('B').present || word('C').present) {
    const char z = word('Z').present ? 'Z' : word('A').present ? 'A' : word('B').present ? 'B' : 'C';
    fail(word(z).column, std::string(code) + " with " + z + " (expected X Y only: the spline lies in the XY plane)");
  }
  const double feed = feed_of_line(column);
  std::array<bool, 3> programmed{};
  const Eigen::Vector3d start3 = state_.position_mm;
  const Eigen::Vector3d end3 = target(programmed);
  const Eigen::Vector2d p0 = start3.head<2>(), p3 = end3.head<2>();
  const bool ij = word('I').present || word('J').present;
  Eigen::Vector2d p1;
  if (ij) {
    p1 = p0 + Eigen::Vector2d(word('I').value, word('J').value) * unit();
  } else if (cubic && state_.spline_control_mm) {
    p1 = p0 + (p0 - *state_.spline_control_mm);
  } else {
    fail(column, std::string(code) + " without I J (expected I J" +
                     (cubic ? std::string(", or a G5 just before it") : std::string()) + ")");
  }
  std::vector<Eigen::Vector2d> control = {p0, p1};
  if (cubic) {
    if (!word('P').present || !word('Q').present)
      fail(column, "G5 without P and Q (expected P Q, from the end to the second control point)");
    const Eigen::Vector2d p2 = p3 + Eigen::Vector2d(word('P').value, word('Q').value) * unit();
    control.push_back(p2);
    state_.spline_control_mm = p2;
  } else if (word('P').present || word('Q').present) {
    fail(word('P').present ? word('P').column : word('Q').column, "G5.1 with P or Q (expected X Y I J)");
  }
  control.push_back(p3);
  // De Casteljau.
  auto at = [&](double t) {
    std::vector<Eigen::Vector2d> q = control;
    for (size_t n = q.size(); n > 1; --n) {
      for (size_t i = 0; i + 1 < n; ++i) q[i] = (1.0 - t) * q[i] + t * q[i + 1];
    }
    return q[0];
  };
  // The largest |B''| over the curve: at the ends for a cubic (B'' is linear in t).
  const double degree = static_cast<double>(control.size() - 1);
  double second = 0.0;
  for (size_t i = 0; i + 2 < control.size(); ++i) {
    second = std::max(second, degree * (degree - 1.0) * (control[i] - 2.0 * control[i + 1] + control[i + 2]).norm());
  }
  const int steps = static_cast<int>(std::clamp(std::ceil(std::sqrt(second / (8.0 * kSplineChordMm))), 1.0, 100000.0));
  if (!state_.known[0] || !state_.known[1])
    fail(column, std::string(code) + " from an unknown X or Y position (expected a move that sets them first)");
  for (int s = 1; s <= steps; ++s) {
    Block block;
    block.kind = MotionKind::Linear;
    block.start_mm = state_.position_mm;
    block.end_mm = end3;
    if (s < steps) block.end_mm.head<2>() = at(static_cast<double>(s) / steps);
    block.feed_mm_per_min = feed;
    append(block, programmed);
  }
  if (!cubic) state_.spline_control_mm.reset();
}

// G5.2 X Y P L starts a NURBS (LinuxCNC): the current point is its first control point
// (weight 1), each line up to G5.3 gives the next, X and Y both, with its weight P > 0 (P is
// optional on the G5.2 line, 1); L, the order, on the G5.2 line (default 3, quadratic).
void Reader::nurbs_point(int column, bool first) {
  if (first) {
    if (state_.nurbs) fail(column, "G5.2 inside a G5.2 NURBS block (expected G5.3 first)");
    if (state_.plane != Plane::XY) fail(column, "G5.2 outside G17 (expected the XY plane)");
    if (state_.comp.side != Comp::Side::Off) fail(column, "G5.2 with cutter compensation on (expected G40 first)");
    if (!state_.known[0] || !state_.known[1])
      fail(column, "G5.2 from an unknown X or Y position (expected a move that sets them first)");
    GcodeState::Nurbs n;
    n.feed_mm_per_min = feed_of_line(column);
    if (const Word& l = word('L'); l.present) {
      if (l.value < 2.0 || !is_whole(l.value) || l.value > 20.0)
        fail(l.column, "G5.2 L" + num(l.value) + " (expected the order, a whole number 2..20)");
      n.order = static_cast<int>(l.value);
    }
    n.points.emplace_back(state_.position_mm.x(), state_.position_mm.y(), 1.0);
    state_.nurbs = n;
  } else if (word('L').present) {
    fail(word('L').column, "L on a NURBS control point (expected the order on the G5.2 line)");
  }
  for (char letter : {'Z', 'A', 'B', 'C'}) {
    if (word(letter).present)
      fail(word(letter).column,
           std::string(1, letter) + " in a G5.2 NURBS block (expected X Y P: the curve lies in the XY plane)");
  }
  if (!word('X').present || !word('Y').present)
    fail(column, "a NURBS control point without both X and Y (expected X and Y)");
  const Word& p = word('P');
  if (!p.present && !first) fail(column, "a NURBS control point without P (expected its weight P > 0)");
  if (p.present && !(p.value > 0.0)) fail(p.column, "NURBS weight P " + num(p.value) + " (expected P > 0)");
  std::array<bool, 3> programmed{};
  const Eigen::Vector3d at = target(programmed);
  state_.nurbs->points.emplace_back(at.x(), at.y(), p.present ? p.value : 1.0);
  if (state_.nurbs->points.size() > 100000) fail(column, "a NURBS of more than 100000 control points (expected G5.3)");
}

// G5.3: the NURBS as straight moves within kSplineChordMm of it. The knots are LinuxCNC's
// (knot_vector_creator): clamped and uniform, 0 (order times), 1, 2, .., n - k + 2 (order
// times), so the curve starts and ends on the first and last control points. Each knot span
// is halved until the points at its quarters lie within the tolerance of the chord.
void Reader::nurbs_end(int column) {
  if (!state_.nurbs) fail(column, "G5.3 without a G5.2 NURBS block (expected G5.2 first)");
  for (char letter : {'X', 'Y', 'Z', 'A', 'B', 'C'}) {
    if (word(letter).present)
      fail(word(letter).column, "G5.3 with axis words (expected G5.3 alone: it ends the NURBS)");
  }
  const GcodeState::Nurbs nurbs = *state_.nurbs;
  state_.nurbs.reset();
  state_.motion = Motion::None;
  const int k = nurbs.order;
  const int n = static_cast<int>(nurbs.points.size()) - 1;
  if (n + 1 < k) {
    fail(column, "G5.3: a NURBS of order " + std::to_string(k) + " needs at least " + std::to_string(k) +
                     " control points, it has " + std::to_string(n + 1));
  }
  std::vector<double> knots;
  for (int i = 0; i <= n + k; ++i) knots.push_back(i < k ? 0.0 : i <= n ? i - k + 1.0 : n - k + 2.0);
  // De Boor on the homogeneous points (w x, w y, w).
  auto point = [&](double u) {
    int span = k - 1;
    while (span < n && u >= knots[static_cast<size_t>(span + 1)]) ++span;
    std::vector<Eigen::Vector3d> d;
    for (int j = 0; j < k; ++j) {
      const Eigen::Vector3d& c = nurbs.points[static_cast<size_t>(span - k + 1 + j)];
      d.emplace_back(c.x() * c.z(), c.y() * c.z(), c.z());
    }
    for (int r = 1; r < k; ++r) {
      for (int j = k - 1; j >= r; --j) {
        const int i = span - k + 1 + j;
        const double left = knots[static_cast<size_t>(i)], right = knots[static_cast<size_t>(i + k - r)];
        const double alpha = right > left ? (u - left) / (right - left) : 0.0;
        d[static_cast<size_t>(j)] = (1.0 - alpha) * d[static_cast<size_t>(j - 1)] + alpha * d[static_cast<size_t>(j)];
      }
    }
    const Eigen::Vector3d& h = d[static_cast<size_t>(k - 1)];
    return Eigen::Vector2d(h.x() / h.z(), h.y() / h.z());
  };
  auto distance_to_segment = [](const Eigen::Vector2d& q, const Eigen::Vector2d& a, const Eigen::Vector2d& b) {
    const Eigen::Vector2d ab = b - a;
    const double t = ab.squaredNorm() > 0.0 ? std::clamp((q - a).dot(ab) / ab.squaredNorm(), 0.0, 1.0) : 0.0;
    return (q - a - t * ab).norm();
  };
  std::vector<double> breaks;  // the parameters the moves end at
  std::function<void(double, double, const Eigen::Vector2d&, const Eigen::Vector2d&, int)> flatten =
      [&](double a, double b, const Eigen::Vector2d& pa, const Eigen::Vector2d& pb, int depth) {
        double off = 0.0;
        for (double t : {0.25, 0.5, 0.75}) {
          off = std::max(off, distance_to_segment(point(a + t * (b - a)), pa, pb));
        }
        if (off <= kSplineChordMm || depth >= 17) {  // at most 2^17 moves a span
          breaks.push_back(b);
          return;
        }
        const double m = 0.5 * (a + b);
        const Eigen::Vector2d pm = point(m);
        flatten(a, m, pa, pm, depth + 1);
        flatten(m, b, pm, pb, depth + 1);
      };
  const double umax = n - k + 2.0;
  for (int s = 0; s < n - k + 2; ++s)
    flatten(s, s + 1.0, point(s), s + 1 == n - k + 2 ? nurbs.points.back().head<2>() : point(s + 1.0), 0);
  for (double u : breaks) {
    Block block;
    block.kind = MotionKind::Linear;
    block.start_mm = state_.position_mm;
    block.end_mm = state_.position_mm;
    block.end_mm.head<2>() = u >= umax ? Eigen::Vector2d(nurbs.points.back().head<2>()) : point(u);
    block.feed_mm_per_min = nurbs.feed_mm_per_min;
    append(block, {true, true, false});
  }
}

void Reader::arc(int column) {
  const bool clockwise = state_.motion == Motion::ArcClockwise;
  const char* code = clockwise ? "G2" : "G3";
  if (rotated() && state_.plane != Plane::XY) {
    fail(column,
         std::string(code) + " outside G17 with the XY rotation on is not supported (G68 or G10 L2 R; expected G17)");
  }
  // The plane's first and second axes and its normal, as rs274ngc's convert_arc passes them
  // to convert_arc2: G17 (X, Y; Z), G18 (Z, X; Y), G19 (Y, Z; X). rs274ngc's turn is +1 for
  // G3, counterclockwise from the first axis toward the second, i.e. a right-hand rotation
  // about first x second = +Z, +Y, +X; G2 turns about the opposite. So in G18 the plane is
  // ZX and G3 turns about +Y: counterclockwise as seen from +Y looking toward the origin
  // (Z to the right, X up), the same "looking down the positive normal" rule as G17.
  int a = 0, b = 1, c = 2;
  const char* plane_name = "XY";
  if (state_.plane == Plane::ZX) {
    a = 2, b = 0, c = 1;
    plane_name = "ZX";
  } else if (state_.plane == Plane::YZ) {
    a = 1, b = 2, c = 0;
    plane_name = "YZ";
  }
  const Word& r = word('R');
  const bool ijk = word('I').present || word('J').present || word('K').present;
  if (!r.present && !ijk) {
    fail(column, std::string(code) + " arc without I/J/K or R (expected the centre or a radius)");
  }
  if (r.present && ijk) {
    fail(r.column, std::string(code) + " arc with both R and I/J/K (expected one or the other)");
  }
  const double feed = feed_of_line(column);
  for (int axis : {a, b}) {
    if (!state_.known[axis]) {
      fail(column, std::string(code) + " arc from an unknown " + kAxisLetter[axis] +
                       " position (expected a move that sets " + kAxisLetter[axis] + " before the first arc)");
    }
  }
  int turns = 1;
  const Word& p = word('P');
  if (p.present) {
    if (p.value < 1.0 || !is_whole(p.value)) {
      fail(p.column, "P (turns) " + num(p.value) + " (expected a whole number >= 1)");
    }
    turns = static_cast<int>(p.value);
  }

  if (state_.comp.arc_not_allowed) {
    fail(column,
         std::string(code) + " arc just after G40 (expected a straight move: the exit from cutter compensation)");
  }
  std::array<bool, 3> programmed{};
  Eigen::Vector3d end = target(programmed);
  // The centre counts from the programmed start (with compensation on, not the tool's).
  Eigen::Vector3d start = base_point();
  if (!state_.known[c]) start[c] = end[c];
  const Eigen::Vector2d s(start[a], start[b]);
  const Eigen::Vector2d e(end[a], end[b]);
  Eigen::Vector2d center;
  if (ijk) {
    const Word& normal_word = word(kCenterLetter[c]);
    // CAM posts for Fanuc, Haas and the senders write a zero K in G17 arcs; the controls ignore it.
    const bool zero_ok = options_.flavor != GcodeOptions::Flavor::LinuxCnc && normal_word.value == 0.0;
    if (normal_word.present && !zero_ok) {
      fail(normal_word.column, std::string(1, kCenterLetter[c]) + " word in a " + plane_name + "-plane arc (expected " +
                                   kCenterLetter[a] + " and " + kCenterLetter[b] + ")");
    }
    const Eigen::Vector3d offset = state_.g5x_mm + state_.g92_mm;
    for (int k = 0; k < 2; ++k) {
      const int axis = k == 0 ? a : b;
      const Word& w = word(kCenterLetter[axis]);
      double v = 0.0;  // rs274ngc: a missing incremental offset is 0
      if (w.present) {
        v = w.value * unit();
      } else if (state_.arc_center_absolute) {
        fail(column, std::string(1, kCenterLetter[axis]) + " word missing in an absolute-centre (G90.1) arc");
      }
      center[k] = state_.arc_center_absolute ? v + offset[axis] : start[axis] + v;
    }
    if (rotated()) {  // G17 only: I J are along the rotated axes
      const Eigen::Vector2d ij(word('I').value * unit(), word('J').value * unit());
      center = state_.arc_center_absolute
                   ? Eigen::Vector2d(to_workpiece(Eigen::Vector3d(ij.x(), ij.y(), 0.0)).head<2>())
                   : Eigen::Vector2d(Eigen::Vector2d(start[a], start[b]) + Eigen::Rotation2Dd(rotation_angle()) * ij);
    }
    if (const std::string error = detail::centre_arc_error(s, e, center, arc_tolerance(), code); !error.empty()) {
      fail(column, error);
    }
    // A full circle: make start and end coincide exactly so that the sweep is 2*pi, not ~0.
    if ((e - s).norm() <= kSamePointMm) {
      end[a] = start[a];
      end[b] = start[b];
    }
  } else {
    // rs274ngc arc_data_r.
    if (const std::string error =
            detail::radius_arc_centre(s, e, r.value * unit(), clockwise, code, "R", "I/J/K", center, kRadiusShortMm);
        !error.empty()) {
      fail(r.column, error);
    }
  }

  Block block;
  block.kind = MotionKind::Arc;
  block.start_mm = start;
  block.end_mm = end;
  block.center_mm = start;
  block.center_mm[a] = center[0];
  block.center_mm[b] = center[1];
  block.normal = Eigen::Vector3d::Zero();
  block.normal[c] = clockwise ? -1.0 : 1.0;
  block.turns = turns;
  block.feed_mm_per_min = feed;
  if (compensating()) {
    comp_arc(block, programmed, clockwise ? -turns : turns, column);
    return;
  }
  append(block, programmed);
}

// --- Fanuc custom macro B (dialect fanuc, or a file that reads like one).
//
// Variables: #0 vacant; #1..#33 local to a G65 call (vacant at the call, then its arguments:
// A #1, B #2, C #3, I #4, J #5, K #6, D #7, E #8, F #9, H #11, M #13, Q #17, R #18, S #19,
// T #20, U #21, V #22, W #23, X #24, Y #25, Z #26); #100..#199 and #500..#999 common, vacant at
// the start; system variables #3000 (alarm: an error with its message), #3006 (stop: a
// warning), #4001..#4130 (modal codes and words of the last block), #5001..#5106 (positions);
// the work offsets #5201..#5400 as LinuxCNC keeps them (#5221 = G54 X, 20 per system).
// Statements: IF [c] GOTO n, IF [c] THEN #i = e, WHILE [c] DOm .. ENDm, GOTO n. GOTO n runs
// the block N n, searched forward from here, then from the top of the file. Calls: G65 P L
// (macro, own locals), M98 P L (subprogram, the caller's locals; Fanuc writes the count in P:
// P30012 runs O0012 three times), M97 P (Haas: the block N P of this program), M99 (return; M99
// P n returns to the block N n). A program O1234 is found in the calling file, or as
// O1234.nc, 1234.nc or O1234 (or any file whose first line is O1234) in the program's folder
// and on program.subroutine_path.

double Reader::fanuc_system_variable(int number, int column) {
  const GcodeState& g = state_;
  if (number >= 3000 && number < 4000) return state_.parameters[static_cast<size_t>(number)];
  if (number >= 4001 && number <= 4022) {
    switch (number) {
      case 4001:
        switch (g.motion) {
          case Motion::Rapid:
            return 0;
          case Motion::Linear:
            return 1;
          case Motion::ArcClockwise:
            return 2;
          case Motion::ArcCounterClockwise:
            return 3;
          case Motion::Cycle:
            return g.cycle / 10.0;
          default:
            return 80;
        }
      case 4002:
        return g.plane == Plane::XY ? 17 : g.plane == Plane::ZX ? 18 : 19;
      case 4003:
        return g.incremental ? 91 : 90;
      case 4005:
        return g.inverse_time ? 93 : 94;
      case 4006:
        return g.inches ? 20 : 21;
      case 4007:
        return g.comp.side == GcodeState::CutterComp::Side::Off    ? 40
               : g.comp.side == GcodeState::CutterComp::Side::Left ? 41
                                                                   : 42;
      case 4008:
        return g.tcp == GcodeState::Tcp::Off ? 49 : 43;
      case 4009:
        return g.motion == Motion::Cycle ? g.cycle / 10.0 : 80;
      case 4010:
        return g.retract_to_r ? 99 : 98;
      case 4014:
        return std::stod(g.work_offset.substr(1));
      case 4015:
        return g.exact_stop ? 61 : 64;
      default:
        return 0;
    }
  }
  if (number >= 4101 && number <= 4130) {
    if (number == 4109) return g.feed_mm_per_min / unit();
    if (number == 4119) return g.spindle_rpm;
    if (number == 4120) return g.selected_tool >= 0 ? g.selected_tool : 0;
    return 0;
  }
  if (number >= 5001 && number <= 5106) {
    const int base = (number - 5001) / 20 * 20 + 5001, axis = number - base;
    if (base == 5061 && axis <= 5) return state_.parameters[static_cast<size_t>(number)];  // skip (probe) position
    if (base > 5041 || axis > 5) return 0;  // tool offsets, servo errors: none
    if (axis >= 3) return state_.rotary.angle_rad[static_cast<size_t>(axis - 3)] * 180.0 / M_PI;
    // #5001: the last block's end, #5041 the current position (work coordinates); #5021
    // machine coordinates.
    const double machine = state_.position_mm[axis];
    return (base == 5021 ? machine : to_program(state_.position_mm)[axis]) / unit();
  }
  fail(column, "system variable #" + std::to_string(number) +
                   " is not one vcut knows (expected #1..#33, #100..#999, #3000..#3999, #4001..#4130, #5001..#5106, "
                   "#5201..#5601, #98000..#98499 or #100000..#199999)");
}

void Reader::set_variable(int number, double value, int column, const std::string& text) {
  if (!fanuc_macros()) {
    if (number >= 5000 && number != 5220 &&
        (number == 5400 || (number >= kPositionParameter && number < kPositionParameter + 9))) {
      fail(column, "#" + std::to_string(number) + " is read-only");
    }
    state_.parameters[static_cast<size_t>(number)] = value;
    return;
  }
  // The line's first comment: the message of an alarm or a stop.
  std::string message;
  if (const size_t open = text.find('('); open != std::string::npos) {
    const size_t close = text.find(')', open);
    message = text.substr(open + 1, close == std::string::npos ? std::string::npos : close - open - 1);
  }
  if (number == 0) fail(column, "#0 is the vacant value and cannot be set");
  if (number == 3000) {
    fail(column, "alarm #3000 = " + (detail::is_vacant(value) ? std::string("vacant") : num(value)) +
                     (message.empty() ? std::string() : ": " + message) + " (the program stops the machine here)");
  }
  if (number == 3006) {
    warn(column, "stop #3006" + (message.empty() ? std::string() : ": " + message) +
                     " (the control waits for cycle start; the simulation goes on)");
    return;
  }
  if (added_common(number)) {
    state_.added_commons[number] = value;
    return;
  }
  if ((number >= 4000 && number < 5000) || (number >= 5001 && number <= 5106) || number > 5601) {
    fail(column, "#" + std::to_string(number) + " is a system variable the program cannot set");
  }
  state_.parameters[static_cast<size_t>(number)] = value;
  // Fanuc: a work offset written takes effect at once when its system is active.
  if (number >= kG5xParameter && number < kG5xParameter + 20 * 9) {
    const int active = static_cast<int>(std::lround(state_.parameters[5220])) - 1;
    if ((number - kG5xParameter) / 20 == active) select_system(active);
  }
}

// A line N n (after blanks and a block delete) in the current file: forward from here, then
// from the top (Fanuc's search for GOTO and M97). `found` is that line, to be read next.
bool Reader::find_sequence(long long number, Mark& found) {
  Source* const src = current_;
  if (const auto it = sequences_.find({src, number}); it != sequences_.end()) {
    found = it->second;
    return true;
  }
  if (!src->seekable)
    fail(0, "GOTO and M97 need to read the file again, and this input cannot seek (expected a regular file)");
  const Mark back = mark_after();
  const int stop_line = src->line;
  auto matches = [&](const std::string& s) {
    size_t i = skip_blanks(s, 0);
    if (i < s.size() && s[i] == '/') i = skip_blanks(s, i + 1);
    if (i >= s.size() || (s[i] != 'N' && s[i] != 'n')) return false;
    i = skip_blanks(s, i + 1);
    long long n = 0;
    bool any = false;
    for (; i < s.size() && (is_digit(s[i]) || is_blank(s[i])); ++i) {
      if (!is_digit(s[i])) continue;
      if (n > 1'000'000'000) return false;
      n = n * 10 + (s[i] - '0');
      any = true;
    }
    return any && n == number && (i >= s.size() || s[i] != '.');
  };
  std::string text;
  for (int pass = 0; pass < 2; ++pass) {
    if (pass == 1) jump(Mark{src, src->begin, 0});
    while (next_line(text)) {
      if (pass == 1 && src->line > stop_line) break;
      if (matches(text)) {
        found = mark_this();
        sequences_[{src, number}] = found;
        jump(back);
        return true;
      }
    }
  }
  jump(back);
  return false;
}

void Reader::go_to_sequence(double value, int column) {
  if (detail::is_vacant(value) || value < 0.0 || value != std::floor(value) || value > 99999999.0) {
    fail(column, "GOTO " + (detail::is_vacant(value) ? std::string("vacant") : num(value)) +
                     " (expected a sequence number, a whole number >= 0)");
  }
  Mark target;
  if (!find_sequence(static_cast<long long>(value), target)) {
    fail(column, "GOTO " + num(value) + ": no block N" + num(value) + " in " + current_->name);
  }
  jump(target);
}

// After the main file's closing '%' (a control reads a tape up to it) or its M99 (read once):
// the reader reads on only to find subprograms there. A program there that nothing called, or
// blocks outside any program, are not run: a warning names the first (a file holding a
// subprogram ending in M99, then its main program, runs the subprogram alone).
void Reader::check_after_end() {
  const int closing = end_line_;
  end_line_ = 0;
  Source& src = *current_;
  if (!src.seekable) return;
  const Mark back = mark_after();
  std::string text;
  bool in_program = false;  // after an O line of a program that was called
  constexpr int kScanLines = 100000;
  for (int k = 0; k < kScanLines && lines_read_ < options_.max_lines && next_line(text); ++k) {
    if (!text.empty() && text.back() == '\r') text.pop_back();
    const size_t i = skip_blanks(text, 0);
    if (i == text.size() || text[i] == '%' || text[i] == '(' || text[i] == ';') continue;
    std::string t = text;
    if (t[i] == ':') t[i] = 'O';
    OLine o;
    if (o_line(t, o) && o.keyword.empty() && !o.label.empty() &&
        std::all_of(o.label.begin(), o.label.end(), [](char c) { return is_digit(c); })) {
      if (o.label.size() > 12 || programs_.count(std::stoll(o.label)) == 0) {
        std::string written = "O";  // as the file writes it (O0001)
        for (size_t j = i + 1; j < t.size() && is_digit(t[j]); ++j) written += t[j];
        warn(1, "program " + (written.size() > 1 ? written : "O" + o.label) + " after the main program's end on line " +
                    std::to_string(closing) +
                    " is not run (expected the main program first, or this one in a file of its own)");
        break;
      }
      in_program = true;
      continue;
    }
    if (!in_program) {
      warn(1, "this line and those after it follow the main program's end on line " + std::to_string(closing) +
                  ": not run");
      break;
    }
  }
  jump(back);  // where reading stopped, for the messages that follow
}

// The body of program O<number>: the line after its O line.
Mark Reader::find_program(long long number, int column, const std::string& caller) {
  if (const auto it = programs_.find(number); it != programs_.end()) return it->second;
  const Mark body = locate_program(number, column, caller);
  programs_[number] = body;
  return body;
}

Mark Reader::locate_program(long long number, int column, const std::string& caller) {
  auto header = [&](const std::string& s) {
    OLine o;
    std::string t = s;
    if (!t.empty() && t.back() == '\r') t.pop_back();
    const size_t k = skip_blanks(t, 0);
    if (k < t.size() && t[k] == ':') t[k] = 'O';
    return o_line(t, o) && o.keyword.empty() && o.label == std::to_string(number);
  };
  // In the calling file: forward, then from the top.
  Source* const src = current_;
  if (src->seekable) {
    const Mark back = mark_after();
    const int stop_line = src->line;
    std::string text;
    for (int pass = 0; pass < 2; ++pass) {
      if (pass == 1) jump(Mark{src, src->begin, 0});
      while (next_line(text)) {
        if (pass == 1 && src->line > stop_line) break;
        if (header(text)) {
          const Mark body = mark_after();
          jump(back);
          return body;
        }
      }
    }
    jump(back);
  }
  // A file of its own.
  std::vector<std::filesystem::path> folders;
  folders.push_back(std::filesystem::path(sources_.front()->name).parent_path());
  for (const std::string& p : options_.subroutine_path) folders.emplace_back(p);
  const std::string digits4 = fmt::format("{:04}", number), digits = fmt::format("{}", number);
  std::vector<std::string> names;
  for (const std::string& stem : {std::string("O") + digits4, std::string("O") + digits, std::string(digits4),
                                  std::string(digits), std::string("o") + digits4, std::string("o") + digits}) {
    for (const char* ext : {"", ".nc", ".NC", ".ngc", ".tap", ".txt", ".min", ".eia"}) names.push_back(stem + ext);
  }
  auto open_source = [&](const std::filesystem::path& path) { return open_file(path, column, "subprogram"); };
  // The file's body: after its O line if it has one among its first lines, else from its start.
  auto body_of = [&](Source* file) {
    Source* caller_source = current_;
    current_ = file;
    std::string text;
    Mark body{file, 0, 0};
    for (int k = 0; k < 8 && next_line(text); ++k) {
      if (header(text)) {
        body = mark_after();
        break;
      }
    }
    current_ = caller_source;
    return body;
  };
  std::error_code ec;
  for (const auto& folder : folders) {
    for (const std::string& name : names) {
      const std::filesystem::path path = folder / name;
      if (std::filesystem::is_regular_file(path, ec)) return body_of(open_source(path));
    }
  }
  // Any file whose first line (after '%' and blank lines) is O<number>.
  for (const auto& folder : folders) {
    std::filesystem::directory_iterator it(folder.empty() ? "." : folder, ec), end;
    for (int files = 0; !ec && it != end && files < 2000; it.increment(ec), ++files) {
      if (!it->is_regular_file(ec) || it->file_size(ec) > (64u << 20)) continue;
      std::ifstream in(it->path(), std::ios::binary);
      std::string first;
      for (int k = 0; k < 4 && std::getline(in, first);) {
        const size_t j = skip_blanks(first, 0);
        if (j >= first.size() || first[j] == '%' || first[j] == '\r') continue;
        ++k;
        if (header(first)) return body_of(open_source(it->path()));
        break;
      }
    }
  }
  std::string searched;
  for (const auto& folder : folders)
    searched += (searched.empty() ? "" : ", ") + (folder.empty() ? std::string(".") : folder.string());
  fail(column, caller + ": program O" + digits4 + " found nowhere (searched " + current_->name + " and, in " +
                   searched + ", the files O" + digits4 + ".nc, " + digits + ".nc, O" + digits4 +
                   " and any whose first line is O" + digits4 + ")");
}

void Reader::fanuc_call(Frame::Kind kind, long long program, long long repeats, int column, const std::string& what,
                        const std::vector<std::pair<int, double>>& arguments, bool modal) {
  if (frames_.size() > 64) fail(column, what + ": calls nested more than 64 deep (a call that never returns?)");
  if (repeats <= 0) return;  // L0: no call
  Mark body;
  if (kind == Frame::Kind::Subprogram && program < 0) {  // M97: a block of this program
    if (!find_sequence(-program, body))
      fail(column, what + ": no block N" + std::to_string(-program) + " in " + current_->name);
  } else {
    body = find_program(program, column, what);
  }
  Frame f;
  f.kind = kind;
  f.sub = program < 0 ? "N" + std::to_string(-program) : "O" + std::to_string(program);
  f.call_where = here();
  f.return_to = mark_after();
  f.body = body;
  f.repeats_left = repeats - 1;
  f.modal = modal;
  if (kind == Frame::Kind::Macro) {
    for (size_t k = 0; k < 33; ++k) {
      f.saved_numbered[k] = state_.parameters[k + 1];
      state_.parameters[k + 1] = detail::kVacant;
    }
    for (const auto& [number, value] : arguments) state_.parameters[static_cast<size_t>(number)] = value;
  }
  frames_.push_back(std::move(f));
  jump(body);
}

// M99: the next pass of a repeated call, or back to the caller (and to its block N P).
bool Reader::fanuc_return() {
  if (frames_.size() <= 1 || frame().kind == Frame::Kind::OWord) return false;
  Frame& f = frame();
  if (f.repeats_left > 0) {
    --f.repeats_left;
    f.do_loops.clear();
    jump(f.body);
    return true;
  }
  if (f.kind == Frame::Kind::Macro) {
    for (size_t k = 0; k < 33; ++k) state_.parameters[k + 1] = f.saved_numbered[k];
  }
  const Mark back = f.return_to;
  frames_.pop_back();
  const Word& p = word('P');
  jump(back);
  if (p.present) go_to_sequence(p.value, p.column);
  return true;
}

// 0: not a statement; 1: done; 2: IF [..] THEN: the rest of the line (blanked before) runs.
int Reader::macro_statement(std::string& s, size_t i) {
  size_t k = i;
  if (k < s.size() && (s[k] == 'N' || s[k] == 'n')) {  // a sequence number first
    size_t j = skip_blanks(s, k + 1);
    if (j >= s.size() || !is_digit(s[j])) return 0;
    while (j < s.size() && is_digit(s[j])) ++j;
    k = skip_blanks(s, j);
  }
  std::string key;
  size_t after = k;
  while (after < s.size() && is_letter(s[after]) && key.size() < 6) key += upper(s[after++]);
  const int column = column_at(k);
  auto condition = [&](size_t& j, const char* statement) {
    j = skip_blanks(s, j);
    if (j >= s.size() || s[j] != '[')
      fail(column_at(j), std::string(statement) + " without its condition (expected " + statement + " [...])");
    const double c = detail::read_expression(s, j, *this);
    return !detail::is_vacant(c) && c != 0.0;
  };
  auto rest_is_comment = [&](size_t j) {
    j = skip_blanks(s, j);
    if (j < s.size() && s[j] == '(') j = skip_blanks(s, skip_comment(s, j));
    if (j < s.size() && s[j] != ';') fail(column_at(j), "unexpected " + describe(s[j]) + " after the statement");
  };
  auto loop_number = [&](size_t& j, const char* word) {
    j = skip_blanks(s, j);
    std::string text;
    const double m = detail::read_plain_number(s, j, 0, *this, text, column_at(j));
    if (m < 1.0 || m > 99.0 || m != std::floor(m))
      fail(column_at(j), std::string(word) + text + " (expected " + word + "1.." + word + "99)");
    return static_cast<int>(m);
  };
  if (key.rfind("IF", 0) == 0 && skip_blanks(s, k + 2) < s.size() && s[skip_blanks(s, k + 2)] == '[') {
    size_t j = k + 2;
    const bool yes = condition(j, "IF");
    j = skip_blanks(s, j);
    std::string then;
    const size_t word_at = j;
    while (j < s.size() && is_letter(s[j]) && then.size() < 5) then += upper(s[j++]);
    if (then == "GOTO") {
      const double target = detail::read_real_value(s, j, 0, *this);
      rest_is_comment(j);
      if (yes) go_to_sequence(target, column_at(word_at));
      return 1;
    }
    if (then == "THEN") {
      if (!yes) return 1;
      for (size_t b = 0; b < j; ++b) s[b] = ' ';
      return 2;
    }
    fail(column_at(word_at),
         "IF [...] without GOTO or THEN (expected IF [condition] GOTO n or IF [condition] THEN #i = ...)");
  }
  if (key == "WHILE") {
    size_t j = after;
    const bool yes = condition(j, "WHILE");
    j = skip_blanks(s, j);
    if (j + 1 >= s.size() || upper(s[j]) != 'D' || upper(s[j + 1]) != 'O')
      fail(column_at(j), "WHILE [...] without DO (expected WHILE [condition] DOm)");
    j += 2;
    const int m = loop_number(j, "DO");
    rest_is_comment(j);
    auto& loops = frame().do_loops;
    for (size_t l = 0; l < loops.size(); ++l) {
      if (loops[l].first == m) {
        loops.resize(l);
        break;
      }
    }
    if (yes) {
      loops.emplace_back(m, mark_this());
      return 1;
    }
    // Skip to the line END m (loops of one number do not nest).
    const std::string opened = here();
    std::string text;
    while (next_line(text)) {
      size_t q = skip_blanks(text, 0);
      if (q < text.size() && (text[q] == 'N' || text[q] == 'n')) {
        size_t d = skip_blanks(text, q + 1);
        if (d < text.size() && is_digit(text[d])) {
          while (d < text.size() && is_digit(text[d])) ++d;
          q = skip_blanks(text, d);
        }
      }
      if (q + 3 < text.size() && upper(text[q]) == 'E' && upper(text[q + 1]) == 'N' && upper(text[q + 2]) == 'D' &&
          is_digit(text[q + 3]) && std::atoi(text.c_str() + q + 3) == m) {
        return 1;
      }
    }
    fail(1, "the file ends inside WHILE [...] DO" + std::to_string(m) + " opened at " + opened + " (expected END" +
                std::to_string(m) + ")");
  }
  if (key == "END" && after < s.size() && is_digit(s[after])) {
    size_t j = after;
    const int m = loop_number(j, "END");
    rest_is_comment(j);
    auto& loops = frame().do_loops;
    for (size_t l = loops.size(); l-- > 0;) {
      if (loops[l].first != m) continue;
      const Mark again = loops[l].second;
      loops.resize(l);  // the WHILE line opens it again
      jump(again);
      return 1;
    }
    fail(column, "END" + std::to_string(m) + " without WHILE [...] DO" + std::to_string(m));
  }
  if (key == "GOTO") {
    size_t j = k + 4;
    const double target = detail::read_real_value(s, j, 0, *this);
    rest_is_comment(j);
    go_to_sequence(target, column);
    return 1;
  }
  return 0;
}

// --- Cutter radius compensation, as LinuxCNC's rs274ngc interpreter does it.
//
// In the plane's coordinates (u, v) = (X, Y) in G17, (Z, X) in G18: O is the last programmed
// end point, C the tool's (O offset by the radius r to the side), P the new programmed end.
// The entry move goes straight (or along its arc) to P offset by r, perpendicular to the move.
// Each later move is held until the next decides its end: at a concave corner the held move
// ends where the two offset paths meet; at a convex corner (turning more than 0.05 rad) an
// arc of radius r about the programmed corner joins them (a straight traverse for G0). A
// held move that would have to run backwards to the meeting point, an arc too small for the
// tool, and corners the tool cannot fit in are errors, as in LinuxCNC. G40 ends the held
// move at C, and the next move (straight) goes from there to its programmed end.
void Reader::plane_axes(int& a, int& b, int& c) const {
  a = 0, b = 1, c = 2;
  if (state_.plane == Plane::ZX) a = 2, b = 0, c = 1;
  if (state_.plane == Plane::YZ) a = 1, b = 2, c = 0;
}

Eigen::Vector3d Reader::base_point() const {
  Eigen::Vector3d base = state_.position_mm;
  if (compensating() && !state_.comp.first_move) {
    int a, b, c;
    plane_axes(a, b, c);
    base[a] = state_.comp.program_mm[a];
    base[b] = state_.comp.program_mm[b];
  }
  return base;
}

// G41 / G42 [D] (the radius of tool D, or of the tool in the spindle) and G41.1 / G42.1 D (a
// diameter in program units). A negative radius swaps the side.
void Reader::comp_on(const Code& g) {
  Comp& comp = state_.comp;
  if (state_.plane == Plane::YZ)
    fail(g.column, g.text + " in G19 (expected G17 or G18: compensation works in XY and ZX)");
  if (state_.plane != Plane::XY && rotated()) fail(g.column, g.text + " in G18 with the XY rotation on (expected G17)");
  if (comp.side != Comp::Side::Off) fail(g.column, g.text + " with compensation already on (expected G40 first)");
  // Fanuc 0M and others name the radius register with H when no D is given.
  const Word& d = !word('D').present && word('H').present && options_.flavor != GcodeOptions::Flavor::LinuxCnc
                      ? word('H')
                      : word('D');
  used_['D' - 'A'] = true;
  if (&d == &word('H')) used_['H' - 'A'] = true;
  double radius = 0.0;
  if (g.number == 411 || g.number == 421) {
    if (!d.present) fail(g.column, g.text + " without D (expected D, the tool's diameter)");
    if (word('L').present) {
      unsupported(word('L').column, g.text + "L", g.text + " L (a lathe tool orientation) is not supported");
      used_['L' - 'A'] = true;
    }
    radius = d.value * unit() / 2.0;
  } else {
    int tool = state_.tool;
    if (d.present) {
      const double n = std::floor(d.value + 0.5);
      if (std::abs(d.value - n) > 1e-4 || n < 0.0)
        fail(d.column, g.text + " D " + num(d.value) + " (expected a whole tool number >= 0)");
      if (n > 0.0) tool = static_cast<int>(n);
    }
    const auto it = options_.tool_radius_mm.find(tool);
    if (it == options_.tool_radius_mm.end()) {
      fail(d.present ? d.column : g.column, g.text + ": tool " + std::to_string(tool) +
                                                (tool == 0 ? " (none in the spindle)" : "") +
                                                " has no radius in the tool library (expected a tool the job's tools "
                                                "file lists, or G41.1/G42.1 D with a diameter)");
    }
    radius = it->second;
  }
  comp.side = g.number / 10 == 41 ? Comp::Side::Left : Comp::Side::Right;
  if (radius < 0.0) comp.side = comp.side == Comp::Side::Left ? Comp::Side::Right : Comp::Side::Left;
  comp.radius_mm = std::abs(radius);
  comp.max_radius_mm = std::max(comp.max_radius_mm, comp.radius_mm);
  comp.first_move = true;
  comp.held.clear();
  comp.endpoint_valid = false;
}

// G40: the held move ends at C; the next move, which must be straight, starts there and ends
// at its programmed point.
void Reader::comp_off(int column) {
  Comp& comp = state_.comp;
  if (compensating() && !comp.first_move) {
    int a, b, c;
    plane_axes(a, b, c);
    comp_move_end_and_flush({state_.position_mm[a], state_.position_mm[b]}, column);
    comp_flush();
    comp.machine_mm = state_.position_mm;
    state_.position_mm = comp.program_mm;
    comp.arc_not_allowed = true;
  }
  comp.side = Comp::Side::Off;
  comp.first_move = true;
}

// M0, M1, M60 and the program's end send the held move (ending at C); M2/M30 end compensation.
void Reader::comp_stop(bool program_end, int column) {
  Comp& comp = state_.comp;
  if (!comp.held.empty()) {
    int a, b, c;
    plane_axes(a, b, c);
    comp_move_end_and_flush({state_.position_mm[a], state_.position_mm[b]}, column);
    comp_flush();
  }
  if (program_end) {
    comp.side = Comp::Side::Off;
    comp.first_move = true;
  }
}

void Reader::select_system(int index, int column) {
  // The tilted plane's frame was made from the offsets at G68.2: G54..G59.3, G10 L2/L20 and
  // G92 are refused there by execute(); a parameter (#5221..) that moves the active offset too.
  if (state_.twp_feature) fail(column, "a work offset change with a tilted work plane on (expected G69 first)");
  for (int a = 0; a < 3; ++a) {
    state_.g5x_mm[a] = state_.parameters[static_cast<size_t>(kG5xParameter + 20 * index + a)];
    state_.g5x_extra_mm[static_cast<size_t>(a)] =
        state_.parameters[static_cast<size_t>(kG5xParameter + 20 * index + 6 + a)];
  }
  const double rotation_deg = state_.parameters[static_cast<size_t>(kG5xParameter + 20 * index + 9)];
  if (rotation_deg != 0.0 && state_.rotation_rad != 0.0)
    fail(1, "a rotated coordinate system with G68 on (expected G69 first)");
  if (rotation_deg != 0.0 && state_.twp)
    fail(1, "a rotated coordinate system with a tilted work plane on (expected G69 first)");
  state_.system_rotation_rad = rotation_deg * M_PI / 180.0;
  state_.parameters[5220] = index + 1;
}

double Reader::feed_of_line(int column) const {
  if (state_.inverse_time) {
    const Word& f = word('F');
    if (!f.present) {
      fail(column, "feed move in inverse-time mode G93 without F (expected an F word on every G1/G2/G3 line)");
    }
    return f.value;  // 1 / minutes
  }
  if (state_.feed_mm_per_min <= 0.0) {
    fail(column, "feed move without F (expected an F word on this line or before it)");
  }
  return state_.feed_mm_per_min;
}

// G10 L2/L20 (coordinate system offsets), L1/L10/L11 (the tool table: no effect on the tip's
// path here) and G92, G92.1, G92.2, G92.3, as LinuxCNC documents them; offsets in mm.
void Reader::set_offsets(const Code& g) {
  for (char letter : {'A', 'B', 'C'}) {
    const Word& w = word(letter);
    if (w.present && w.value != 0.0) {
      unsupported(w.column, g.text + std::string(1, letter),
                  g.text + " with a rotary offset " + letter + " (this reader offsets X Y Z only)");
    }
    used_[letter - 'A'] = true;
  }
  if (g.number == 100) {
    const Word& l = word('L');
    const Word& p = word('P');
    used_['L' - 'A'] = used_['P' - 'A'] = used_['R' - 'A'] = true;
    for (char letter : {'I', 'J', 'K', 'Q'}) used_[letter - 'A'] = true;  // tool-table words
    if (!l.present) fail(g.column, "G10 without L (expected L2 or L20 for a coordinate system, L1/L10/L11 for a tool)");
    if (l.value == 1.0 || l.value == 10.0 || l.value == 11.0) return;
    if (l.value != 2.0 && l.value != 20.0) {
      fail(l.column, "G10 L" + num(l.value) + " (expected L1, L2, L10, L11 or L20)");
    }
    if (!p.present || p.value < 0.0 || p.value > 9.0 || !is_whole(p.value)) {
      fail(p.present ? p.column : l.column,
           "G10 L" + num(l.value) + " needs P0..P9 (the coordinate system, 0 = active)");
    }
    const int active = static_cast<int>(std::lround(state_.parameters[5220])) - 1;
    const int k = p.value == 0.0 ? active : static_cast<int>(p.value) - 1;
    const size_t rotation_parameter = static_cast<size_t>(kG5xParameter + 20 * k + 9);
    if (const Word& r = word('R'); r.present) {
      // LinuxCNC: L2 R turns the system about Z (deg); L20 takes no R.
      if (l.value == 20.0) fail(r.column, "G10 L20 with R (expected R with G10 L2)");
      state_.parameters[rotation_parameter] = r.value;
    }
    // L2: the named values. L20: the offset that puts the current point at them, w - Rz (point
    // + G92), `point` the program point with the named axes replaced; in a turned system
    // (LinuxCNC) X and Y both change when either is named (rs274 prints X11.6603 Y9 for G10 L20
    // P1 X0 at X10 Y5 under X3 Y4 R30).
    const double turn_rad = state_.parameters[rotation_parameter] * M_PI / 180.0;
    Eigen::Vector3d offset = Eigen::Vector3d::Zero();
    std::array<bool, 3> set{};
    Eigen::Vector3d point = l.value == 20.0 ? to_program(state_.position_mm) : Eigen::Vector3d::Zero();
    for (int a = 0; a < 3; ++a) {
      const Word& w = word(kAxisLetter[a]);
      if (!w.present) continue;
      if (l.value == 20.0 && !state_.known[a]) {
        fail(w.column,
             std::string("G10 L20 while the ") + kAxisLetter[a] +
                 " position is unknown is not supported: vcut assumes no start position (expected a move first)");
      }
      point[a] = w.value * unit();
      set[static_cast<size_t>(a)] = true;
    }
    if (l.value == 2.0) {
      offset = point;
    } else if (turn_rad == 0.0) {
      offset = state_.position_mm - state_.g92_mm - point;
    } else {
      if (state_.rotation_rad != 0.0) fail(l.column, "G10 L20 with G68 on (expected G69 first)");
      Eigen::Vector3d q = point + state_.g92_mm;
      q.head<2>() = Eigen::Rotation2Dd(turn_rad) * Eigen::Vector2d(q.head<2>());
      offset = state_.position_mm - q;
      set[0] = set[1] = set[0] || set[1];
    }
    for (int a = 0; a < 3; ++a)
      if (set[static_cast<size_t>(a)]) state_.parameters[static_cast<size_t>(kG5xParameter + 20 * k + a)] = offset[a];
    for (size_t e = 0; e < 3; ++e) {  // U V W (L20: the current position takes the value)
      if (!extra_word_[e]) continue;
      double offset = word("UVW"[e]).value * unit();
      if (l.value == 20.0) offset = state_.extra.value_mm[e] - state_.g92_extra_mm[e] - offset;
      state_.parameters[static_cast<size_t>(kG5xParameter + 20 * k + 6) + e] = offset;
    }
    if (k == active) select_system(k);
    return;
  }
  if ((g.number == 920 || g.number == 520) && state_.rotation_rad != 0.0)
    fail(g.column, g.text + " with G68 on (expected " + g.text + " before it, or G69)");
  if (g.number == 520) {
    // G52 (LinuxCNC, Fanuc): the local origin at the named axes' values from the work zero;
    // LinuxCNC keeps it in the G92 offsets (#5211..), the axes not named keep theirs, and G52
    // X0 Y0 ends it (as its rs274 prints SET_G92_OFFSET).
    for (int a = 0; a < 3; ++a)
      if (const Word& w = word(kAxisLetter[a]); w.present) state_.g92_mm[a] = w.value * unit();
    for (size_t e = 0; e < 3; ++e)
      if (extra_word_[e]) state_.g92_extra_mm[e] = word("UVW"[e]).value * unit();
  } else if (g.number == 920) {
    // In a turned system (G10 L2 R) the offset is counted in its axes: w = Rz (p + G92) + G5x.
    Eigen::Vector3d turned = state_.position_mm - state_.g5x_mm;
    turned.head<2>() = Eigen::Rotation2Dd(-state_.system_rotation_rad) * Eigen::Vector2d(turned.head<2>());
    for (int a = 0; a < 3; ++a) {
      const Word& w = word(kAxisLetter[a]);
      if (!w.present) continue;
      if (!state_.known[a]) {
        fail(w.column,
             std::string("G92 while the ") + kAxisLetter[a] +
                 " position is unknown is not supported: vcut assumes no start position (expected a move first)");
      }
      state_.g92_mm[a] = turned[a] - w.value * unit();
    }
    for (size_t e = 0; e < 3; ++e) {
      if (extra_word_[e])
        state_.g92_extra_mm[e] = state_.extra.value_mm[e] - state_.g5x_extra_mm[e] - word("UVW"[e]).value * unit();
    }
  } else if (g.number == 921 || g.number == 922) {
    state_.g92_mm.setZero();
    state_.g92_extra_mm = {0.0, 0.0, 0.0};
  } else {  // G92.3: back to the offset kept in the parameters
    for (int a = 0; a < 3; ++a) state_.g92_mm[a] = state_.parameters[static_cast<size_t>(kG92Parameter + a)];
    for (size_t e = 0; e < 3; ++e)
      state_.g92_extra_mm[e] = state_.parameters[static_cast<size_t>(kG92Parameter + 6) + e];
  }
  if (g.number != 922) {
    for (size_t e = 0; e < 3; ++e)
      state_.parameters[static_cast<size_t>(kG92Parameter + 6) + e] = state_.g92_extra_mm[e];
    for (int a = 0; a < 3; ++a) state_.parameters[static_cast<size_t>(kG92Parameter + a)] = state_.g92_mm[a];
    state_.parameters[5210] = g.number == 920 || g.number == 923 || g.number == 520 ? 1.0 : 0.0;
  }
}

constexpr double kProbeBackoffMm = 0.254;

// G38.2 / G38.3 / G31: a straight feed toward the point that stops where the probe's tip
// touches the stock (GcodeOptions::probe_contact: the job's stock as it was before the
// program, the tip a point), with the tip's position then in #5061..#5066 (program
// coordinates) and #5070 = 1 (0: no contact), as LinuxCNC keeps them (Fanuc: #5061..; Mach3's
// G31: #2000..#2002 too). G38.2 without contact is an error, as on the control.
void Reader::probe(int column, int code) {
  const std::string name = code == 310 ? "G31" : "G38." + std::to_string(code - 380);
  const bool away = code == 384 || code == 385, needs_change = code == 382 || code == 384;
  if (state_.twp) fail(column, name + " with a tilted work plane or turned rotaries (expected them upright first)");
  if (state_.comp.side != Comp::Side::Off) fail(column, name + " with cutter compensation on (expected G40 first)");
  if (state_.inverse_time) fail(column, name + " in inverse-time mode G93 (expected G94)");
  for (char letter : {'A', 'B', 'C'}) {
    if (word(letter).present)
      fail(word(letter).column, std::string(1, letter) + " word on a probe move (expected X Y Z only)");
  }
  for (int a = 0; a < 3; ++a) {
    if (!state_.known[a])
      fail(column, name + " while the " + kAxisLetter[a] + " position is unknown (expected a move that sets it first)");
  }
  std::array<bool, 3> programmed{};
  const Eigen::Vector3d end = target(programmed);
  const Eigen::Vector3d start = state_.position_mm;
  if (needs_change && (end - start).norm() < 1e-7) {
    fail(column, name + " to where the probe is (expected a move; the control refuses one of zero length)");
  }
  const double feed = feed_of_line(column);
  double s = 1.0;
  bool contact = true;
  if (options_.probe_contact) {
    const std::optional<double> hit = options_.probe_contact(start, end);
    const bool touching = hit && *hit <= 0.0;
    if (!away) {
      if (touching)
        fail(column,
             name + ": the probe touches the stock where it starts (the control: the probe is already tripped)");
      contact = hit.has_value();
      if (hit) s = *hit;
    } else {
      if (!touching)
        fail(column,
             name + ": the probe does not touch the stock where it starts (the control: the probe is not tripped)");
      // The stock is convex (a box or a cylinder): it lets go where the move, run backwards
      // from its end, first touches it.
      const std::optional<double> back = options_.probe_contact(end, start);
      contact = back && *back > 0.0;
      if (contact) s = 1.0 - *back;
    }
    if (!contact && needs_change) {
      fail(column,
           name + " ends without " + (away ? "leaving" : "touching") +
               " the stock (the control stops with an error; expected the stock's surface in the probe's way, or G38." +
               (away ? "5" : "3") + ")");
    }
  } else {
    // No stock: the probe trips 0.254 mm (0.01 in) before its end, where LinuxCNC's
    // standalone interpreter puts it (behind the start on a shorter move; no move at all on
    // one of zero length).
    const double length_mm = (end - start).norm();
    s = length_mm > 0.0 ? 1.0 - kProbeBackoffMm / length_mm : 0.0;
    contact = false;  // #5070 = 0, as there
    if (state_.warned.insert("probe").second) {
      warn(column, name +
                       " with no stock to touch (vcut program reads none): the probe trips 0.254 mm before its end "
                       "point, as LinuxCNC's rs274 has it; a job probes its stock");
    }
  }
  Block block;
  block.kind = MotionKind::Linear;
  block.start_mm = start;
  block.end_mm = start + s * (end - start);
  block.feed_mm_per_min = feed;
  append(block, {true, true, true});
  const Eigen::Vector3d at = to_program(state_.position_mm) / unit();
  for (int a = 0; a < 3; ++a) {
    state_.parameters[static_cast<size_t>(5061 + a)] = at[a];
    state_.parameters[static_cast<size_t>(5064 + a)] = state_.rotary.angle_rad[static_cast<size_t>(a)] * 180.0 / M_PI;
    if (code == 310 && options_.flavor != GcodeOptions::Flavor::Fanuc)
      state_.parameters[static_cast<size_t>(2000 + a)] = at[a];
  }
  state_.parameters[5070] = contact ? 1.0 : 0.0;
}

// --- Tilted work plane, as Fanuc 30i and Haas NGC run it: G68.2 X Y Z (the feature frame's
// origin, absolute program coordinates) I J K (Euler angles, deg, Z then the new X then the
// new Z; P1: I J K about the fixed X, Y and Z, in that order); G53.1 turns the rotary axes,
// the linear axes held, so that the tool lies along the feature frame's +Z (the solution
// with the least rotary motion); G53.6 does the same keeping the tip where it is (tool centre
// point retention); G69 ends it. In between, X Y Z (arcs, cycles and compensation included)
// are in the feature frame and each block is a tool pose with the rotaries' values.
void Reader::twp_begin(const Code& g) {
  if (state_.twp && !state_.twp_feature) end_turned_frame();
  if (state_.twp) fail(g.column, "G68.2 with a tilted work plane on (expected G69 first)");
  if (rotated()) fail(g.column, "G68.2 with a G68 rotation on (expected G69 first)");
  for (int a = 0; a < 3; ++a) {
    if (!state_.known[a]) {
      fail(g.column, std::string("G68.2 while the ") + kAxisLetter[a] +
                         " position is unknown (expected a move that sets it first)");
    }
  }
  const Word& p = word('P');
  if (p.present && p.value != 0.0 && p.value != 1.0) {
    fail(p.column, "G68.2 P" + num(p.value) +
                       " (expected P0, Euler angles, or P1, roll-pitch-yaw; vcut does not read P2 three points, "
                       "P3 two vectors or P4 projection angles)");
  }
  const Word& q = word('Q');
  if (q.present && !(p.present && p.value == 1.0 && q.value == 123.0)) {
    fail(q.column, "G68.2 Q" + num(q.value) + " (expected no Q, or Q123 with P1: vcut turns about X, then Y, then Z)");
  }
  for (char letter : {'P', 'Q', 'I', 'J', 'K'}) used_[letter - 'A'] = true;
  auto angle = [&](char letter) { return word(letter).present ? word(letter).value * M_PI / 180.0 : 0.0; };
  using Turn = Eigen::AngleAxisd;
  const double i = angle('I'), j = angle('J'), k = angle('K');
  const Eigen::Matrix3d r =
      p.present && p.value == 1.0
          ? Eigen::Matrix3d(Turn(k, Eigen::Vector3d::UnitZ()) * Turn(j, Eigen::Vector3d::UnitY()) *
                            Turn(i, Eigen::Vector3d::UnitX()))
          : Eigen::Matrix3d(Turn(i, Eigen::Vector3d::UnitZ()) * Turn(j, Eigen::Vector3d::UnitX()) *
                            Turn(k, Eigen::Vector3d::UnitZ()));
  Eigen::Vector3d origin = Eigen::Vector3d::Zero();
  for (int a = 0; a < 3; ++a) {
    if (word(kAxisLetter[a]).present) origin[a] = word(kAxisLetter[a]).value * unit();
  }
  // The reader's coordinates q = feature point + offsets; workpiece = offsets + origin +
  // R * feature point = R * q + (offsets + origin - R * offsets).
  const Eigen::Vector3d offsets = state_.g5x_mm + state_.g92_mm;
  state_.twp_rotation = r;
  state_.twp_translation_mm = offsets + origin - r * offsets;
  state_.twp = state_.twp_feature = state_.twp_used = true;
  twp_first_block_ = program_.blocks.size();
  state_.position_mm = r.transpose() * (state_.position_mm - state_.twp_translation_mm);
  if (state_.comp.machine_mm)
    *state_.comp.machine_mm = r.transpose() * (*state_.comp.machine_mm - state_.twp_translation_mm);
  state_.spline_control_mm.reset();
}

// The blocks made in the tilted plane, from the feature frame to the workpiece frame.
void Reader::twp_emit() { twp_emit_before(program_.blocks.size()); }

// Those before block `end` only (the later ones may still change in the plane's frame).
void Reader::twp_emit_before(size_t end) {
  const Eigen::Matrix3d& r = state_.twp_rotation;
  for (size_t n = twp_first_block_; n < end; ++n) {
    Block& b = program_.blocks.edit(n);
    b.start_mm = twp_out(b.start_mm);
    b.end_mm = twp_out(b.end_mm);
    b.center_mm = twp_out(b.center_mm);
    b.normal = r * b.normal;
  }
  twp_first_block_ = std::max(twp_first_block_, end);
}

// Hands the blocks that cannot change any more to the program's compact store (block_list.h):
// all but those an axis not yet known, a corner to round or a tilted plane may still change
// (the plane's finished blocks go to the workpiece frame first).
void Reader::seal_blocks() {
  kinematics::BlockList& blocks = program_.blocks;
  if (blocks.open() < 2 * kinematics::BlockList::kChunk) return;
  size_t first_open = blocks.size();
  for (const auto& pending : state_.pending)
    if (!pending.empty()) first_open = std::min(first_open, pending.front());
  if (corner_) first_open = std::min(first_open, corner_->block);
  if (state_.twp) twp_emit_before(first_open);
  blocks.seal_before(first_open);
}

void Reader::twp_end() {
  end_turned_frame();
  // After G69 the rotaries stay where G53.1 turned them: X Y Z are the machine's again.
  if (turns_hold_linear()) turned_frame(state_.position_mm);
}

// Emits the transformed blocks and goes back to workpiece coordinates.
void Reader::end_turned_frame() {
  twp_emit();
  const Eigen::Matrix3d& r = state_.twp_rotation;
  const Eigen::Vector3d& t = state_.twp_translation_mm;
  state_.position_mm = r * state_.position_mm + t;
  if (state_.comp.machine_mm) *state_.comp.machine_mm = r * *state_.comp.machine_mm + t;
  state_.spline_control_mm.reset();
  state_.twp = state_.twp_feature = false;
  state_.twp_rotation.setIdentity();
  state_.twp_translation_mm.setZero();
}

// The rotaries stand at state_.rotary (twp off): from here X Y Z are the machine's, the tip's
// point with the rotaries at zero, taken to the workpiece by the turn (a rigid motion: its
// rotation and translation from the images of the origin and the unit points).
void Reader::turned_frame(const Eigen::Vector3d& tip_mm, const Eigen::Vector3d* machine_mm) {
  state_.position_mm = tip_mm;
  const auto& angles = state_.rotary.angle_rad;
  if (!options_.tip_after_turn || (angles[0] == 0.0 && angles[1] == 0.0 && angles[2] == 0.0)) return;
  const auto [r, t] = detail::turn_from_zero(options_.tip_after_turn, state_.tool, state_.rotary);
  state_.twp = true;
  state_.twp_feature = false;
  state_.twp_rotation = r;
  state_.twp_translation_mm = t;
  twp_first_block_ = program_.blocks.size();
  state_.position_mm = machine_mm != nullptr ? *machine_mm : Eigen::Vector3d(r.transpose() * (tip_mm - t));
  if (state_.comp.machine_mm) *state_.comp.machine_mm = r.transpose() * (*state_.comp.machine_mm - t);
}

// A move of the rotaries (and X Y Z) without TCP in a G43 / G68.2 program: the axes move
// together, linearly, from where they are; the tip's path on the part goes out as tool-pose
// steps of at most 1 deg of rotary motion each.
void Reader::joint_move(const Block& block, const kinematics::RotaryWords& to, int column) {
  if (block.kind == MotionKind::Arc) fail(column, "rotary words on an arc (expected them on a G0 or G1 line)");
  if (hold_ || state_.comp.side != Comp::Side::Off)
    fail(column, "rotary words with cutter compensation on (expected G40 first)");
  for (int a = 0; a < 3; ++a) {
    if (!state_.known[a])
      fail(column, std::string("a rotary move while the ") + kAxisLetter[a] +
                       " position is unknown (expected a move that sets it first)");
  }
  const kinematics::RotaryWords from = state_.rotary;
  kinematics::RotaryWords zero = from;
  zero.angle_rad = {0.0, 0.0, 0.0};
  const Eigen::Vector3d q0 = block.start_mm, q1 = block.end_mm;  // the machine's X Y Z
  if (const std::string why = detail::rotary_turn_refused(from, to); !why.empty()) fail(column, why);
  if (state_.twp) end_turned_frame();
  const int steps = rotary_steps(from, to);
  count_steps(steps, column);
  const bool inverse_time = block.kind != MotionKind::Rapid && state_.inverse_time;
  state_.position_mm = options_.tip_after_turn(state_.tool, q0, zero, from);
  in_swing_ = true;
  for (int n = 1; n <= steps; ++n) {
    const kinematics::RotaryWords step = rotary_step(from, to, n, steps);
    Block b = block;
    b.start_mm = state_.position_mm;
    b.end_mm = options_.tip_after_turn(state_.tool, q0 + (q1 - q0) * n / steps, zero, step);
    b.orientation = kinematics::OrientationMode::Axes;
    if (inverse_time) b.feed_mm_per_min = block.feed_mm_per_min * steps;  // each step 1/steps of the time
    append(b, {true, true, true}, &step);
  }
  in_swing_ = false;
  turned_frame(state_.position_mm, &q1);
}

// G53.1 / G53.6: the rotaries turn the tool to the feature frame's +Z, in the G0 / G1 mode.
// G53.1 holds the linear axes, so the tip swings with the table (or the head): its path goes
// out as straight tool-pose moves of at most 1 deg of rotary motion each (off the swing by at
// most r (1 - cos 0.5 deg) = 0.004 % of the tip's distance from the rotary axis).
void Reader::twp_turn(const Code& g) {
  if (!state_.twp || !state_.twp_feature)
    fail(g.column, g.text + " without a tilted work plane (expected G68.2 first)");
  if (!options_.orient || !options_.tip_after_turn) {
    fail(g.column, g.text + " needs the machine's rotary axes (expected a job, or vcut program --machine)");
  }
  if (state_.comp.side != Comp::Side::Off) fail(g.column, g.text + " with cutter compensation on (expected G40 first)");
  const Eigen::Matrix3d& r = state_.twp_rotation;
  const Eigen::Vector3d& t = state_.twp_translation_mm;
  const Eigen::Vector3d tip = r * state_.position_mm + t;
  const Eigen::Vector3d axis = r.col(2);
  const kinematics::RotaryWords from = state_.rotary;
  kinematics::RotaryWords to;
  // P (LinuxCNC's TWP remap): 0 the least rotary motion, 1 the tilting axis positive, 2 negative.
  int tilt_sign = 0;
  if (const Word& p = word('P'); p.present) {
    if (p.value != 0.0 && p.value != 1.0 && p.value != 2.0) {
      fail(p.column, g.text + " P" + num(p.value) +
                         " (expected P0 the least rotary motion, P1 the tilting axis positive, P2 negative)");
    }
    tilt_sign = p.value == 1.0 ? 1 : p.value == 2.0 ? -1 : 0;
  }
  if (const std::string why = options_.orient(state_.tool, tip, axis, from, tilt_sign, to); !why.empty()) {
    fail(g.column, g.text + ": the machine cannot turn the tool to the tilted plane's Z (" + num(axis.x()) + ", " +
                       num(axis.y()) + ", " + num(axis.z()) + "): " + why);
  }
  const bool feed = state_.motion == Motion::Linear && !state_.inverse_time && state_.feed_mm_per_min > 0.0;
  if (const std::string why = detail::rotary_turn_refused(from, to); g.number != 536 && !why.empty())
    fail(g.column, g.text + ": " + why);
  const int steps = g.number == 536 ? 1 : rotary_steps(from, to);
  count_steps(steps, g.column);
  in_swing_ = true;
  for (int n = 1; n <= steps; ++n) {
    const kinematics::RotaryWords step = rotary_step(from, to, n, steps);
    const Eigen::Vector3d end = g.number == 536 ? tip : options_.tip_after_turn(state_.tool, tip, from, step);
    Block block;
    block.kind = feed ? MotionKind::Linear : MotionKind::Rapid;
    block.feed_mm_per_min = feed ? state_.feed_mm_per_min : 0.0;
    block.start_mm = state_.position_mm;
    block.end_mm = r.transpose() * (end - t);
    append(block, {true, true, true}, &step);
  }
  in_swing_ = false;
}

// G28 / G30 (LinuxCNC, Fanuc, Haas): a rapid to the point the line's axis words name (in the
// active coordinate system and distance mode; the current point when none is named), then a
// rapid of the named axes (every axis when none is named) to the reference position kept in
// #5161.. / #5181.. (G53 coordinates of the gauge point, so the tip stops a tool length below
// it). G28.1 / G30.1 store the current position there.
void Reader::home_return(const Code& g) {
  const size_t base = g.number == 280 || g.number == 281 ? kG28Parameter : kG30Parameter;
  if (g.number == 281 || g.number == 301) {
    const Eigen::Vector3d gauge = state_.position_mm - tip_offset();
    for (int a = 0; a < 3; ++a) state_.parameters[base + static_cast<size_t>(a)] = gauge[a];
    for (int r = 0; r < 3; ++r) {
      state_.parameters[base + 3 + static_cast<size_t>(r)] =
          state_.rotary.angle_rad[static_cast<size_t>(r)] * 180.0 / M_PI;
    }
    for (size_t e = 0; e < 3; ++e) state_.parameters[base + 6 + e] = state_.extra.value_mm[e];
    return;
  }
  std::array<bool, 3> named{};
  Block via;
  via.kind = MotionKind::Rapid;
  via.start_mm = state_.position_mm;
  via.end_mm = target(named);
  for (int a = 0; a < 3; ++a) {
    if (!state_.known[a] && !named[a]) via.start_mm[a] = via.end_mm[a] = state_.position_mm[a];
  }
  append(via, named);
  std::array<bool, 3> rotary_named{};
  bool any = false;
  for (int a = 0; a < 3; ++a) any = any || named[a];
  for (int r = 0; r < 3; ++r) {
    rotary_named[static_cast<size_t>(r)] = word(static_cast<char>('A' + r)).present;
    any = any || rotary_named[static_cast<size_t>(r)];
  }
  std::array<bool, 3> extra_named{};
  for (size_t e = 0; e < 3; ++e) {
    extra_named[e] = extra_word_[e];
    any = any || extra_named[e];
  }
  Block home;
  home.kind = MotionKind::Rapid;
  home.start_mm = state_.position_mm;
  home.end_mm = state_.position_mm;
  std::array<bool, 3> moved{};
  const Eigen::Vector3d tip =
      Eigen::Vector3d(state_.parameters[base], state_.parameters[base + 1], state_.parameters[base + 2]) + tip_offset();
  // In a coordinate system LinuxCNC has turned (G10 L2 R), its interpreter turns the home
  // point into program coordinates and moves only the named axes there, the others keeping
  // their program values: the machine then ends at that turned point, not at each axis's
  // home (rs274 prints G28 Y2 at X10 Y5 under G10 L2 P1 X3 Y10 R30 as X10 Y-7.1603).
  const bool turned_system = state_.system_rotation_rad != 0.0 && state_.rotation_rad == 0.0;
  Eigen::Vector3d program = to_program(state_.position_mm);
  const Eigen::Vector3d home_program = to_program(tip);
  for (int a = 0; a < 3; ++a) {
    if (any && !named[a]) continue;
    if (!(std::abs(tip[a]) <= kMaxMagnitude)) {
      fail(g.column, g.text + ": the tip's " + kAxisLetter[a] + " there, " + num(tip[a]) +
                         " mm, is out of range (expected within +-1e6 mm)");
    }
    home.end_mm[a] = tip[a];
    program[a] = home_program[a];
    moved[a] = true;
  }
  if (turned_system) home.end_mm = to_workpiece(program);
  kinematics::RotaryWords rotary = state_.rotary;
  for (int r = 0; r < 3; ++r) {
    const auto k = static_cast<size_t>(r);
    // A machine's rotary axes go home too when no axis is named, as soon as the program uses them.
    if (any ? !rotary_named[k] : !state_.rotary.given[k]) continue;
    rotary.angle_rad[k] = state_.parameters[base + 3 + k] * M_PI / 180.0;
    rotary.given[k] = true;
  }
  // U V W (machine coordinates, mm) likewise; with no axis named, those the program moved or
  // whose reference is not 0 (LinuxCNC sends every axis home; the others stay at 0).
  kinematics::ExtraAxes extra = state_.extra;
  for (size_t e = 0; e < 3; ++e) {
    const double reference = state_.parameters[base + 6 + e];
    if (any ? !extra_named[e] : !(state_.extra.given[e] || reference != 0.0)) continue;
    if (options_.extra_axes.find("UVW"[e]) == std::string::npos) continue;
    if (!(std::abs(reference) <= kMaxMagnitude)) {
      fail(g.column, std::string(1, "UVW"[e]) + " reference #" + std::to_string(base + 6 + e) + " = " + num(reference) +
                         " mm is out of range (expected within +-1e6 mm)");
    }
    extra.value_mm[e] = reference;
    extra.given[e] = true;
  }
  append(home, moved, &rotary, &extra);
}

// Canned cycles G73 G81 G82 G83 G85 G89 in the XY plane, as LinuxCNC documents them: an
// optional first move up to the R plane, then for each of the L holes a rapid in X Y at the
// current height, a rapid down to R, the cycle's own in-and-out, and the retract to R (G99)
// or to the height the line started at (G98). Heights in program coordinates.
void Reader::cycle(int column, bool new_series) {
  const char* name = state_.cycle == 730   ? "G73"
                     : state_.cycle == 810 ? "G81"
                     : state_.cycle == 820 ? "G82"
                     : state_.cycle == 830 ? "G83"
                     : state_.cycle == 850 ? "G85"
                                           : "G89";
  if (state_.plane != Plane::XY) {
    unsupported(column, std::string(name) + "plane",
                std::string(name) + " outside the XY plane (this reader drills along Z, G17)");
    forget_axes(true);
    return;
  }
  if (state_.inverse_time) fail(column, std::string(name) + " in inverse-time mode G93 (expected G94)");
  const double feed = feed_of_line(column);
  for (int a = 0; a < 3; ++a) {
    if (!state_.known[a]) {
      fail(column, std::string(name) + " from an unknown " + kAxisLetter[a] + " position (expected a move first)");
    }
  }
  const Word& r_word = word('R');
  const Word& z_word = word('Z');
  const Word& q_word = word('Q');
  const Word& p_word = word('P');
  const Word& l_word = word('L');
  if (r_word.present) state_.cycle_r = r_word.value;
  if (z_word.present) state_.cycle_z = z_word.value;
  if (q_word.present) state_.cycle_q = q_word.value;
  if (p_word.present) state_.cycle_p = p_word.value;
  if (new_series && !r_word.present)
    fail(column, std::string(name) + " without R (expected the retract plane R on the cycle's first line)");
  if (new_series && !z_word.present)
    fail(column, std::string(name) + " without Z (expected the hole bottom Z on the cycle's first line)");
  const bool pecks = state_.cycle == 730 || state_.cycle == 830;
  if (pecks && !(state_.cycle_q > 0.0)) {
    fail(q_word.present ? q_word.column : column, std::string(name) + " needs Q > 0 (the peck depth)");
  }
  if ((state_.cycle == 820 || state_.cycle == 890) && state_.cycle_p < 0.0) {
    fail(p_word.present ? p_word.column : column,
         std::string(name) + " P " + num(state_.cycle_p) + " (expected a dwell >= 0 s)");
  }
  int repeats = 1;
  if (l_word.present) {
    if (l_word.value < 0.0 || !is_whole(l_word.value) || l_word.value > 1e5) {
      fail(l_word.column, "L " + num(l_word.value) + " (expected a whole number of repeats 0..100000)");
    }
    repeats = static_cast<int>(l_word.value);
  }
  Eigen::Vector3d at = to_program(state_.position_mm);  // program coordinates, mm
  const double u = unit();
  double r = state_.cycle_r * u, bottom = state_.cycle_z * u;
  Eigen::Vector2d hole = at.head<2>(), step = Eigen::Vector2d::Zero();
  if (new_series) state_.cycle_initial_z_mm = at.z();
  if (state_.incremental) {
    // As LinuxCNC's rs274 does: R from the height the series started at (not from this
    // line's), Z from R.
    r = state_.cycle_initial_z_mm + r;
    bottom = r + bottom;
    for (int a = 0; a < 2; ++a) {
      if (word(kAxisLetter[a]).present) step[a] = word(kAxisLetter[a]).value * u;
    }
  } else {
    for (int a = 0; a < 2; ++a) {
      if (word(kAxisLetter[a]).present) hole[a] = word(kAxisLetter[a]).value * u;
    }
  }
  if (bottom > r) {
    fail(z_word.present ? z_word.column : column,
         std::string(name) + " with the bottom Z " + num(bottom / u) + " above R " + num(r / u) + " (expected Z <= R)");
  }
  const std::array<bool, 3> all = {true, true, true};
  auto move = [&](MotionKind kind, double x, double y, double z) {
    Block block;
    block.kind = kind;
    block.start_mm = state_.position_mm;
    block.end_mm = to_workpiece(Eigen::Vector3d(x, y, z));
    if (!(block.end_mm.cwiseAbs().maxCoeff() <= kMaxMagnitude)) {
      fail(column, std::string(name) + " moves to " + num(block.end_mm.x()) + ", " + num(block.end_mm.y()) + ", " +
                       num(block.end_mm.z()) + " mm, out of range (expected within +-1e6 mm)");
    }
    block.feed_mm_per_min = kind == MotionKind::Rapid ? 0.0 : feed;
    append(block, all);
    at = Eigen::Vector3d(x, y, z);
  };
  if (new_series && at.z() < r) move(MotionKind::Rapid, at.x(), at.y(), r);
  // G98: back to the height the series started at, but never below R.
  const double clear = state_.retract_to_r ? r : std::max(state_.cycle_initial_z_mm, r);
  const double rapid_delta = 0.254;  // mm: LinuxCNC's 0.010 inch back-off before the next peck
  double height = at.z();
  const bool polar = line_words_.radius.present || line_words_.angle.present;
  if (polar && (word('X').present || word('Y').present)) {
    fail(column, std::string(name) + " with both X/Y and polar @/^ (expected one or the other)");
  }
  for (int n = 0; n < repeats; ++n) {
    if (polar) {
      hole = polar_point(hole);  // G91: each repeat turns and stretches from the last hole
    } else if (state_.incremental) {
      hole += step;
    }
    const double x = hole.x(), y = hole.y();
    move(MotionKind::Rapid, x, y, height);
    if (height != r) move(MotionKind::Rapid, x, y, r);
    switch (state_.cycle) {
      case 730:
      case 830: {
        const double delta = state_.cycle_q * u;
        for (double depth = r - delta; depth > bottom; depth -= delta) {
          move(MotionKind::Linear, x, y, depth);
          move(MotionKind::Rapid, x, y, state_.cycle == 830 ? r : depth + rapid_delta);
          if (state_.cycle == 830) move(MotionKind::Rapid, x, y, depth + rapid_delta);
        }
        move(MotionKind::Linear, x, y, bottom);
        move(MotionKind::Rapid, x, y, clear);
        break;
      }
      case 850:  // out at the feed to R, then a rapid to the G98 height
        move(MotionKind::Linear, x, y, bottom);
        move(MotionKind::Linear, x, y, r);
        if (clear != r) move(MotionKind::Rapid, x, y, clear);
        break;
      case 890:  // out at the feed all the way to the clear height (rs274ngc's G89, unlike G85)
        move(MotionKind::Linear, x, y, bottom);
        move(MotionKind::Linear, x, y, clear);
        break;
      default:  // G81, G82
        move(MotionKind::Linear, x, y, bottom);
        move(MotionKind::Rapid, x, y, clear);
        break;
    }
    height = clear;
  }
}

// Fanuc G67, G65 and G66 (macro calls): true when the line was a call, its other words the
// macro's arguments.
bool Reader::macro_call() {
  Line& ln = line_words_;
  // Fanuc G67: the end of a G66 modal call (the line's other codes go on).
  if (options_.flavor != GcodeOptions::Flavor::LinuxCnc) {
    const auto g67 = std::find_if(ln.g.begin(), ln.g.end(), [](const Code& g) { return g.number == 670; });
    if (g67 != ln.g.end()) {
      if (!modal_call_) warn(g67->column, "G67 without a G66 modal call on; nothing to end");
      modal_call_.reset();
      ln.g.erase(g67);
    }
  }
  // Fanuc G65 P<program> L<count> <arguments>: a macro call; the other words are its arguments.
  // G66 takes the same words and calls the macro after each later line that moves an axis.
  for (const Code& g : ln.g) {
    if ((g.number != 650 && g.number != 660) || options_.flavor == GcodeOptions::Flavor::LinuxCnc) continue;
    const std::string code = g.number == 650 ? "G65" : "G66";
    if (ln.g.size() > 1)
      fail(ln.g[&g == &ln.g[0] ? 1 : 0].column,
           code + " with another G code (expected " + code + " alone: its words are arguments)");
    const Word& p = word('P');
    if (!p.present || p.value < 0.0 || p.value != std::floor(p.value))
      fail(p.present ? p.column : g.column,
           code + " without P, the macro's program number (expected " + code + " P<number>)");
    const Word& l = word('L');
    if (l.present && (l.value < 0.0 || l.value != std::floor(l.value)))
      fail(l.column, code + " L " + num(l.value) + " (expected a whole number of calls)");
    static const struct {
      char letter;
      int number;
    } kArguments[] = {{'A', 1},  {'B', 2},  {'C', 3},  {'I', 4},  {'J', 5},  {'K', 6},  {'D', 7},
                      {'E', 8},  {'F', 9},  {'H', 11}, {'Q', 17}, {'R', 18}, {'S', 19}, {'T', 20},
                      {'U', 21}, {'V', 22}, {'W', 23}, {'X', 24}, {'Y', 25}, {'Z', 26}};
    std::vector<std::pair<int, double>> arguments;
    for (const auto& a : kArguments) {
      if (word(a.letter).present) arguments.emplace_back(a.number, word(a.letter).value);
    }
    if (ln.radius.present || ln.angle.present)
      fail(ln.radius.present ? ln.radius.column : ln.angle.column,
           "polar @/^ on a " + code + " line (expected letter arguments)");
    if (ln.m.size() > 1) fail(ln.m[1].column, "two M arguments on a " + code + " line (expected at most one, #13)");
    if (ln.m.size() == 1) arguments.emplace_back(13, std::stod(ln.m[0].text.substr(1)));
    const long long repeats = l.present ? static_cast<long long>(l.value) : 1;
    if (g.number == 660) {
      if (modal_call_) fail(g.column, "G66 while a modal call is on (expected G67 first)");
      // The macro must exist: look for it now, as the control does when the first move calls it.
      find_program(static_cast<long long>(p.value), p.column, "G66 P" + num(p.value));
      modal_call_ = ModalCall{static_cast<long long>(p.value), repeats, "G66 P" + num(p.value), arguments};
      return true;
    }
    fanuc_call(Frame::Kind::Macro, static_cast<long long>(p.value), repeats, g.column, "G65 P" + num(p.value),
               arguments);
    return true;
  }
  return false;
}

// The line's G codes by modal group, each supported or reported, and the pairs that cannot
// share a line.
Reader::LineCodes Reader::codes_of_line() {
  const Line& ln = line_words_;
  LineCodes c;
  // --- G codes: one per modal group, supported or reported.
  // Fanuc: G80 is the canned-cycle cancel (group 9), so "G0 G80" is a rapid that ends the
  // cycle; rs274ngc has G80 in the motion group and refuses the pair.
  const bool g80_apart =
      options_.flavor != GcodeOptions::Flavor::LinuxCnc &&
      std::count_if(ln.g.begin(), ln.g.end(), [](const Code& g) { return g_info(g.number).group == kMotion; }) > 1;
  for (const Code& g : ln.g) {
    if (g80_apart && g.number == 800) continue;
    const GInfo info = g_info(g.number);
    if (info.group >= 0) {
      const Code*& slot = c.g[static_cast<size_t>(info.group)];
      if (slot != nullptr) {
        fail(g.column, "two G codes of the " + std::string(group_name(info.group)) + " group on one line, " +
                           slot->text + " and " + g.text + " (expected at most one)");
      }
      slot = &g;
    }
    if (info.supported) continue;
    std::string message =
        info.group < 0 ? "unknown G code " + g.text : "unsupported G code " + g.text + " (" + info.what + ")";
    // Mach3 and older controls write G70 / G71 for inch / mm (a real Mach3 file: G71G91.1).
    if (g.number == 700 || g.number == 710)
      message += "; if it means " + std::string(g.number == 700 ? "inch" : "mm") + " units, as on Mach3, write " +
                 (g.number == 700 ? "G20" : "G21");
    unsupported(g.column, g.text, message);
    lenient_ = true;  // warning mode: the code and the words it would use are ignored
    if (info.group == kNonModal && info.uses_axes) {
      c.axis_user = &g;
      c.axis_user_all = info.all_axes;
    }
  }
  // rs274ngc: two codes that both use the axis words cannot share a line (G53 modifies the
  // motion instead, so it goes with G0/G1).
  if (c.axis_user != nullptr && c.axis_user->number != 530 && c.g[kMotion] != nullptr && c.g[kMotion]->number != 800) {
    const Code* later = c.axis_user->column > c.g[kMotion]->column ? c.axis_user : c.g[kMotion];
    fail(later->column, c.axis_user->text + " and " + c.g[kMotion]->text +
                            " both use the axis words (expected them on separate lines)");
  }
  c.non_modal = c.g[kNonModal];
  c.homes = c.non_modal != nullptr && (c.non_modal->number == 280 || c.non_modal->number == 300);
  c.stores_home = c.non_modal != nullptr && (c.non_modal->number == 281 || c.non_modal->number == 301);
  // Fanuc G68 X Y R: X Y are the rotation's centre, not a move.
  c.rotation = c.g[kRotation];
  if (c.rotation != nullptr && c.rotation->number == 680 && options_.flavor == GcodeOptions::Flavor::LinuxCnc) {
    fail(c.rotation->column, "unknown G code " + c.rotation->text +
                                 " (LinuxCNC rotates with G10 L2 R; expected dialect fanuc or gcode for G68)");
  }
  c.rotates = c.rotation != nullptr && c.rotation->number != 690;  // G68 / G68.2 take X Y Z
  c.sets_offsets = c.non_modal != nullptr &&
                   (c.non_modal->number == 100 || c.non_modal->number == 920 || c.non_modal->number == 520 || c.homes);
  if (c.rotates && c.g[kMotion] != nullptr && c.g[kMotion]->number != 800) {
    const Code* later = c.rotation->column > c.g[kMotion]->column ? c.rotation : c.g[kMotion];
    fail(later->column, c.rotation->text + " and " + c.g[kMotion]->text +
                            " both use the axis words (expected them on separate lines)");
  }
  if (c.sets_offsets && c.g[kMotion] != nullptr && c.g[kMotion]->number != 800) {
    const Code* later = c.non_modal->column > c.g[kMotion]->column ? c.non_modal : c.g[kMotion];
    fail(later->column, c.non_modal->text + " and " + c.g[kMotion]->text +
                            " both use the axis words (expected them on separate lines)");
  }
  machine_coordinates_ = c.non_modal != nullptr && c.non_modal->number == 530;
  c.length_axes = c.g[kToolLength] != nullptr && (c.g[kToolLength]->number == 431 || c.g[kToolLength]->number == 432)
                      ? c.g[kToolLength]
                      : nullptr;
  if (c.length_axes != nullptr && c.g[kMotion] != nullptr && c.g[kMotion]->number != 800) {
    const Code* later = c.length_axes->column > c.g[kMotion]->column ? c.length_axes : c.g[kMotion];
    fail(later->column, c.length_axes->text + " and " + c.g[kMotion]->text +
                            " both use the axis words (expected them on separate lines)");
  }
  return c;
}

// The line's M codes by group: supported, calls and returns, TCP switches, or the
// machine's own.
void Reader::read_m_codes(LineCodes& c) {
  const Line& ln = line_words_;
  // --- M codes.
  for (const Code& m : ln.m) {
    const int group = m.number >= 0 ? m_group(m.number) : -1;
    if (group >= 0) {
      const Code*& slot = c.m[static_cast<size_t>(group)];
      // LinuxCNC's rs274 refuses two M codes of one group on a line, M7 with M8 included.
      if (slot != nullptr) {
        fail(m.column, "two M codes of one modal group on one line, " + slot->text + " and " + m.text +
                           " (expected at most one)");
      }
      slot = &m;
    }
    if (const auto tcp = options_.tcp_m_codes.find(m.number); m.number >= 0 && tcp != options_.tcp_m_codes.end()) {
      tcp_m_code_ = tcp->second ? 1 : 0;
      continue;
    }
    if (m.number >= 0 && m_supported(m.number)) {
      if (m.number == 2 || m.number == 30) {
        c.program_end = true;
      } else {
        c.m_code[static_cast<size_t>(m.number)] = true;
      }
      continue;
    }
    if (m.number == 97 || m.number == 98 || m.number == 99) {  // calls and returns, after the motion
      if (c.flow != nullptr)
        fail(m.column,
             "two call or return M codes on one line, " + c.flow->text + " and " + m.text + " (expected one)");
      c.flow = &m;
      continue;
    }
    lenient_ = true;  // the words of an ignored code are not checked
    if (m.number < 0 || options_.unsupported_as_warning) {
      unsupported(m.column, m.text, "unknown M code " + m.text);
      continue;
    }
    // A machine's own M code (Haas M31 part counter, M101 ...): the control runs it and the
    // motion goes on, so it is a warning unless the job asks for an error.
    if (options_.m_codes_ignored.count(m.number) > 0) continue;
    if (options_.unknown_m_code_as_error) {
      fail(m.column, "unknown M code " + m.text +
                         " (expected one the machine file declares under m_codes, or program.unsupported: warn)");
    }
    if (state_.warned.insert(m.text).second) {
      warn(m.column, "M code " + m.text + " is not one the machine file declares; ignored, the motion goes on");
    }
  }
}

// Letters this reader does not move, and rotary words out of range.
void Reader::check_letters(LineCodes& c) {
  // Fanuc: G4 X (or U) is the dwell time in seconds, not an axis.
  c.dwell_axis = options_.flavor != GcodeOptions::Flavor::LinuxCnc && c.non_modal != nullptr &&
                 c.non_modal->number == 40 && !word('P').present && (word('X').present || word('U').present);
  // --- U V W: the extra linear axes the machine has (LinuxCNC's axis mask).
  extra_column_ = 0;
  extra_word_ = {false, false, false};
  for (char letter : {'U', 'V', 'W'}) {
    const Word& w = word(letter);
    if (!w.present || (c.dwell_axis && letter == 'U')) continue;
    if (options_.extra_axes.find(letter) == std::string::npos) {
      fail(w.column, std::string(1, letter) + " word: the machine has no " + letter +
                         " axis (a job's machines move X Y Z and their rotary axes; `vcut program` lists U V W)");
    }
    extra_word_[static_cast<size_t>(letter - 'U')] = true;
    if (extra_column_ == 0 || w.column < extra_column_) extra_column_ = w.column;
  }
  for (char letter : {'A', 'B', 'C'}) {
    const Word& w = word(letter);
    if (w.present && !(std::abs(w.value) <= kMaxMagnitude))
      fail(w.column, std::string(1, letter) + " " + num(w.value) + " deg is out of range (expected within +-1e6 deg)");
  }
}

// Units, feed, spindle and tool, and the M codes that set modes, in rs274ngc's order.
void Reader::set_feed_speed_tool(LineCodes& c) {
  // --- Modes, in rs274ngc's order of execution within a line: F is set before G20/G21, so an
  // F on a G20/G21 line is in the units before it (as LinuxCNC's rs274 reads it); the
  // lengths of the line are in the new units.
  const double feed_unit = unit();
  if (const Code* g = c.g[kUnits]) state_.inches = g->number == 200;

  // Lengths beyond 1e6 mm after conversion are as absurd as before it.
  for (char letter : {'X', 'Y', 'Z', 'I', 'J', 'K', 'R'}) {
    const Word& w = word(letter);
    if (w.present && std::abs(w.value * unit()) > kMaxMagnitude) {
      fail(w.column, std::string(1, letter) + " " + num(w.value) + " in = " + num(w.value * unit()) +
                         " mm is out of range (expected within +-1e6 mm)");
    }
  }
  if (const Code* g = c.g[kFeedMode]) state_.inverse_time = g->number == 930;
  if (const Word& f = word('F'); f.present && state_.inverse_time) {
    // G93: F is the inverse of the move's time in minutes, on every feed move's line.
    if (!(f.value > 0.0)) fail(f.column, "F " + num(f.value) + " (expected an inverse time > 0, 1/min)");
    if (f.value > kMaxFeed_mm_per_min) fail(f.column, "F " + num(f.value) + " is out of range (expected <= 1e9 1/min)");
  } else if (f.present) {
    const double feed = f.value * feed_unit;
    if (!(feed > 0.0)) fail(f.column, "F " + num(f.value) + " (expected a feed > 0)");
    if (feed > kMaxFeed_mm_per_min) {
      fail(f.column, "F " + num(feed) + " mm/min is out of range (expected <= 1e9 mm/min)");
    }
    state_.feed_mm_per_min = feed;
  }
  if (const Word& s = word('S'); s.present) {
    if (s.value < 0.0) fail(s.column, "S " + num(s.value) + " (expected a spindle speed >= 0)");
    state_.spindle_rpm = s.value;
  }
  if (const Word& t = word('T'); t.present) {
    if (t.value < 0.0 || !is_whole(t.value)) {
      fail(t.column, "T " + num(t.value) + " (expected a tool number, a whole number >= 0)");
    }
    state_.selected_tool = static_cast<int>(t.value);
  }
  // M6 loads the tool selected by the last T (on this line or before); T alone only
  // selects. Without any T, M6 changes nothing (rs274ngc loads the prepared tool).
  if (c.m_code[6] && state_.selected_tool >= 0) {
    // The control takes its position from the machine after a tool change (rs274ngc re-reads
    // it): after G40 that is the last compensated point, not the programmed one.
    if (state_.comp.machine_mm) {
      state_.position_mm = *state_.comp.machine_mm;
      state_.comp.machine_mm.reset();
    }
    // The spindle stays where it is: the new tool's tip is its gauge length below it.
    const Eigen::Vector3d before = tip_offset();
    state_.tool = state_.selected_tool;
    state_.position_mm += tip_offset() - before;
  }
  if (c.m_code[3]) state_.spindle = SpindleState::Clockwise;
  if (c.m_code[4]) state_.spindle = SpindleState::CounterClockwise;
  if (c.m_code[5]) state_.spindle = SpindleState::Off;
  // M0/M1 (pauses), M7/M8/M9 (coolant), M48..M53 (overrides) do not change the path; nor
  // do M62..M68 (I/O), which take P, E, L and Q.
  for (int m = 62; m <= 68; ++m) {
    if (c.m_code[m]) {
      for (char letter : {'P', 'E', 'L', 'Q'}) used_[letter - 'A'] = true;
    }
  }
  if (c.m_code[61]) {  // M61 Q: the tool in the spindle is Q, without a change
    const Word& q = word('Q');
    if (!q.present || q.value < 0.0 || !is_whole(q.value)) {
      fail(q.present ? q.column : c.m[6]->column, "M61 needs Q, the tool number (a whole number >= 0)");
    }
    state_.tool = state_.selected_tool = static_cast<int>(q.value);
    used_['Q' - 'A'] = true;
  }
  // M70 saves the modal state, M71 forgets it, M72 restores it, M73 saves it to be restored
  // when the current subroutine returns.
  if (c.m_code[70] || c.m_code[73]) {
    ModalState saved = save_modes();
    if (c.m_code[70]) {
      saved_modes_ = saved;
    } else {
      if (frames_.size() <= 1) fail(c.m[10]->column, "M73 outside a subroutine (expected it in a called o-word sub)");
      frame().autorestore = saved;
    }
  }
  if (c.m_code[71]) saved_modes_.reset();
  if (c.m_code[72]) {
    if (!saved_modes_) fail(c.m[10]->column, "M72 without a state saved by M70");
    restore_modes(*saved_modes_);
  }
}

// The P word taken by `code`; two codes may not share it.
void Reader::use_p(LineCodes& c, const std::string& code) {
  if (!c.p_user.empty()) {
    fail(word('P').column, "P word used by both " + c.p_user + " and " + code + " (expected them on separate lines)");
  }
  c.p_user = code;
  used_['P' - 'A'] = true;
}

// Dwell, the plane, and rotations and tilted planes, with what compensation or a tilted
// plane refuses.
void Reader::set_plane_and_frames(LineCodes& c) {
  const Line& ln = line_words_;
  const Word& p = word('P');
  if (const Code* g = c.g[kNonModal]; g != nullptr && g->number == 40 && c.dwell_axis) {
    // Fanuc: G4 X<seconds> or U<seconds> (P in ms): no motion.
    const Word& t = word('X').present ? word('X') : word('U');
    if (t.value < 0.0)
      fail(t.column,
           "G4 " + std::string(word('X').present ? "X" : "U") + " " + num(t.value) + " (expected seconds >= 0)");
  } else if (const Code* g = c.g[kNonModal]; g != nullptr && g->number == 40) {  // G4 dwell
    if (!p.present) fail(g->column, "G4 dwell without P (expected P seconds)");
    if (p.value < 0.0) fail(p.column, "G4 P " + num(p.value) + " (expected seconds >= 0)");
    use_p(c, g->text);
  }
  if (state_.comp.side != Comp::Side::Off) {
    // What LinuxCNC refuses while cutter compensation is on.
    auto refuse = [&](const Code* g, const char* what) {
      if (g != nullptr) fail(g->column, g->text + " with cutter compensation on (" + what + "; expected G40 first)");
    };
    const Plane plane = state_.plane;
    if (const Code* g = c.g[kPlane]; g != nullptr && (g->number == 170   ? Plane::XY
                                                      : g->number == 180 ? Plane::ZX
                                                                         : Plane::YZ) != plane) {
      refuse(g, "a plane change");
    }
    refuse(c.g[kCoordinateSystem], "a coordinate system change");
    refuse(c.g[kToolLength], "a tool length change");
    if (c.non_modal != nullptr && (c.homes || c.stores_home || c.non_modal->number == 520 ||
                                   (c.non_modal->number >= 920 && c.non_modal->number <= 923))) {
      refuse(c.non_modal, "a move home or an axis offset");
    }
    if (state_.motion == Motion::Cycle ||
        (c.g[kMotion] != nullptr && c.g[kMotion]->number >= 730 && c.g[kMotion]->number != 800)) {
      refuse(c.g[kMotion] != nullptr ? c.g[kMotion] : &ln.g.front(), "a canned cycle");
    }
    if (c.m_code[6]) refuse(c.m[6], "a tool change");
  }
  if (const Code* g = c.g[kPlane]; g != nullptr && g_info(g->number).supported) {
    state_.plane = g->number == 170 ? Plane::XY : g->number == 180 ? Plane::ZX : Plane::YZ;
  }
  if (c.rotation != nullptr) {
    if (state_.comp.side != Comp::Side::Off)
      fail(c.rotation->column, c.rotation->text + " with cutter compensation on (expected G40 first)");
    if (corner_) {
      fail(c.rotation->column,
           std::string(corner_->round ? ",R" : ",C") + " at " + program_.where(program_.blocks[corner_->block].source) +
               " needs a G1 line next (expected the corner's second line before " + c.rotation->text + ")");
    }
    if (c.rotation->number == 690) {
      state_.rotation_rad = 0.0;
      if (state_.twp && state_.twp_feature) twp_end();
    } else if (c.rotation->number == 682) {
      twp_begin(*c.rotation);
    } else {
      if (state_.twp && state_.twp_feature)
        fail(c.rotation->column, "G68 with a tilted work plane on (expected G69 first)");
      if (state_.plane != Plane::XY) fail(c.rotation->column, "G68 outside G17 (this reader rotates in the XY plane)");
      const Word& r = word('R');
      if (!r.present) fail(c.rotation->column, "G68 without R (expected R, the rotation in degrees)");
      used_['R' - 'A'] = true;
      // The centre: X Y in absolute program coordinates, the current point for those not given.
      const Eigen::Vector3d here_program = to_program(state_.position_mm);
      Eigen::Vector2d center = here_program.head<2>();
      if (word('X').present) center.x() = word('X').value * unit();
      if (word('Y').present) center.y() = word('Y').value * unit();
      // Nested G68 (a rotation while one is on): Fanuc composes them; vcut asks for G69 first.
      if (rotated()) fail(c.rotation->column, "G68 while a rotation is on (expected G69 first)");
      state_.rotation_center_mm = center;
      state_.rotation_rad = r.value * M_PI / 180.0;
    }
  }
  if (state_.twp && state_.twp_feature) {
    // What a control refuses in its tilted-plane mode (or vcut does not follow there).
    auto refuse = [&](const Code* g, const char* what) {
      if (g != nullptr) fail(g->column, g->text + " with a tilted work plane on (" + what + "; expected G69 first)");
    };
    if (machine_coordinates_) refuse(c.non_modal, "machine coordinates");
    if (c.homes || c.stores_home) refuse(c.non_modal, "a reference position");
    if (c.sets_offsets || (c.non_modal != nullptr && c.non_modal->number >= 920 && c.non_modal->number <= 923))
      refuse(c.non_modal, "an offset change");
    refuse(c.g[kCoordinateSystem], "a coordinate system change");
    if (c.g[kToolLength] != nullptr && c.g[kToolLength]->number == 435) refuse(c.g[kToolLength], "a tool axis vector");
    if (c.m_code[6]) refuse(c.m[6], "a tool change");
  }
}

// Compensation, tool length, coordinate systems, path control, distance modes, offsets
// and the motion mode.
void Reader::set_modes(LineCodes& c) {
  const Word& p = word('P');
  if (const Code* g = c.g[kCutterComp]) {
    if (g->number == 400) {
      comp_off(g->column);
    } else {
      comp_on(*g);
    }
  }
  if (const Code* g = c.g[kToolLength]) {
    state_.tcp = g->number == 434   ? GcodeState::Tcp::Angles
                 : g->number == 435 ? GcodeState::Tcp::Vector
                                    : GcodeState::Tcp::Off;
    state_.length_comp = g->number == 430 || g->number == 431 || g->number == 432;
    if (g->number == 431 || (g->number == 432 && state_.dynamic_length_mm)) {
      // G43.1: the line's X Y Z; G43.2: added to a G43.1 offset (after G43 H it adds to the
      // tool table's length, which the tip already is: nothing to track).
      Eigen::Vector3d offset = g->number == 432 ? *state_.dynamic_length_mm : Eigen::Vector3d::Zero();
      for (int a = 0; a < 3; ++a)
        if (word(kAxisLetter[a]).present) offset[a] += word(kAxisLetter[a]).value * unit();
      if (!(offset.cwiseAbs().maxCoeff() <= kMaxMagnitude))
        fail(g->column, g->text + " tool length offset out of range (expected within +-1e6 mm)");
      state_.dynamic_length_mm = offset;
    } else if (g->number != 432) {
      state_.dynamic_length_mm.reset();
    }
  }
  if (tcp_m_code_ >= 0) state_.tcp = tcp_m_code_ ? GcodeState::Tcp::Angles : GcodeState::Tcp::Off;
  // TCP takes X Y Z as the tip on the part again.
  if (state_.tcp != GcodeState::Tcp::Off && state_.twp && !state_.twp_feature) end_turned_frame();
  if (const Code* g = c.g[kToolLength]; g != nullptr && g->number != 490) {
    const Word& h = word('H');
    if (h.present && (h.value < 0.0 || !is_whole(h.value))) {
      fail(h.column, "H " + num(h.value) + " (expected a tool number, a whole number >= 0)");
    }
    used_['H' - 'A'] = true;
  }
  if (const Code* g = c.g[kCoordinateSystem]; g != nullptr) {
    state_.work_offset = g->text;
    select_system(system_index(g->number), g->column);
  }
  exact_stop_line_ = c.g[kNonModal] != nullptr && c.g[kNonModal]->number == 90;
  if (const Code* g = c.g[kPathControl]; g != nullptr && g->number != 640) {
    state_.exact_stop = true;  // G61, G61.1
  }
  if (const Code* g = c.g[kPathControl]; g != nullptr && g->number == 640) {
    // G64 P (blending tolerance) and Q (naive CAM tolerance, not used): lengths >= 0.
    for (char letter : {'P', 'Q'}) {
      const Word& w = word(letter);
      if (w.present && w.value < 0.0) {
        fail(w.column, std::string("G64 ") + letter + " " + num(w.value) + " (expected a tolerance >= 0)");
      }
    }
    state_.exact_stop = false;
    state_.blend_tolerance_mm = p.present ? p.value * unit() : -1.0;
    if (p.present) use_p(c, g->text);
    used_['Q' - 'A'] = true;
  }
  if (const Code* g = c.g[kDistance]) state_.incremental = g->number == 910;
  if (const Code* g = c.g[kArcDistance]) state_.arc_center_absolute = g->number == 901;
  if (const Code* g = c.g[kReturnMode]) state_.retract_to_r = g->number == 990;
  if (c.non_modal != nullptr && (c.non_modal->number == 100 || c.non_modal->number == 520 ||
                                 (c.non_modal->number >= 920 && c.non_modal->number <= 923))) {
    set_offsets(*c.non_modal);
  }
  c.was_cycle = state_.motion == Motion::Cycle;
  c.previous_cycle = state_.cycle;
  if (state_.nurbs && (c.g[kMotion] == nullptr || c.g[kMotion]->number != 53)) {
    if (const Code* g = c.g[kMotion]) fail(g->column, g->text + " inside a G5.2 NURBS block (expected G5.3 first)");
  }
  if (const Code* g = c.g[kMotion]; g != nullptr && g->number == 53) {
    nurbs_end(g->column);
  } else if (const Code* g = c.g[kMotion]) {
    static const std::pair<int, Motion> kMotions[] = {{0, Motion::Rapid},
                                                      {10, Motion::Linear},
                                                      {20, Motion::ArcClockwise},
                                                      {30, Motion::ArcCounterClockwise},
                                                      {800, Motion::None},
                                                      {330, Motion::SpindleSync},
                                                      {331, Motion::RigidTap},
                                                      {50, Motion::CubicSpline},
                                                      {51, Motion::QuadraticSpline},
                                                      {730, Motion::Cycle},
                                                      {810, Motion::Cycle},
                                                      {820, Motion::Cycle},
                                                      {830, Motion::Cycle},
                                                      {850, Motion::Cycle},
                                                      {890, Motion::Cycle},
                                                      {382, Motion::Probe},
                                                      {383, Motion::Probe},
                                                      {384, Motion::Probe},
                                                      {385, Motion::Probe},
                                                      {52, Motion::Nurbs}};
    state_.motion = Motion::Unsupported;
    for (const auto& [code, motion] : kMotions) {
      if (code == g->number) state_.motion = motion;
    }
    if (state_.motion == Motion::Cycle) state_.cycle = g->number;
    if (state_.motion == Motion::Probe) state_.probe = g->number;
  }
}

// The line's motion: home returns, probes, turned frames, or a move in the motion mode;
// true when an axis move ran (G66 calls its macro after it).
bool Reader::run_motion(LineCodes& c) {
  const Line& ln = line_words_;
  const Word& p = word('P');
  bool line_moves = false;
  const bool has_axis = word('X').present || word('Y').present || word('Z').present || word('A').present ||
                        word('B').present || word('C').present || ln.radius.present || ln.angle.present ||
                        extra_column_ != 0;
  if ((ln.radius.present || ln.angle.present) && state_.plane != Plane::XY) {
    fail(ln.radius.present ? ln.radius.column : ln.angle.column,
         "polar @/^ outside G17 (expected G17: polar coordinates are in the XY plane only, as in LinuxCNC)");
  }
  const Code* motion_code = c.g[kMotion];
  const bool explicit_motion = motion_code != nullptr && motion_code->number <= 30;
  c.axis_column = INT_MAX;
  for (char letter : {'X', 'Y', 'Z', 'A', 'B', 'C'}) {
    if (word(letter).present) c.axis_column = std::min(c.axis_column, word(letter).column);
  }
  if (extra_column_ != 0) c.axis_column = std::min(c.axis_column, extra_column_);
  // Motion errors point at the G0..G3 word, or at the first axis word of a modal motion.
  const int column = explicit_motion ? motion_code->column : c.axis_column;
  if (machine_coordinates_ && !(has_axis && (state_.motion == Motion::Rapid || state_.motion == Motion::Linear))) {
    fail(c.non_modal->column, "G53 without a G0 or G1 move on its line (expected G53 G0/G1 with axis words)");
  }
  if (corner_ && (has_axis || explicit_motion || c.homes) &&
      (state_.motion != Motion::Linear || c.homes || c.sets_offsets)) {
    fail(explicit_motion ? motion_code->column : c.axis_column,
         std::string(corner_->round ? ",R" : ",C") + " at " + program_.where(program_.blocks[corner_->block].source) +
             " needs a G1 line next (expected the corner's second line)");
  }
  if (motion_code != nullptr && motion_code->number == 52 && !has_axis) {
    fail(motion_code->column, "G5.2 without X and Y (expected the first control point on its line)");
  }
  if (c.homes || c.stores_home) {
    if (c.stores_home && has_axis)
      fail(c.axis_column, c.non_modal->text + " with axis words (expected " + c.non_modal->text +
                              " alone: it stores the current position)");
    home_return(*c.non_modal);
  } else if (c.non_modal != nullptr && c.non_modal->number == 310) {
    no_extra("G31");
    if (!has_axis) fail(c.non_modal->column, "G31 without axis words (expected the point the probe moves toward)");
    probe(c.non_modal->column, 310);
  } else if (c.non_modal != nullptr && (c.non_modal->number == 531 || c.non_modal->number == 536)) {
    if (has_axis)
      fail(c.axis_column,
           c.non_modal->text + " with axis words (expected " + c.non_modal->text + " alone: it turns the rotary axes)");
    used_['P' - 'A'] = true;
    twp_turn(*c.non_modal);
  } else if (c.axis_user != nullptr) {
    forget_axes(c.axis_user_all);
  } else if (c.sets_offsets || c.rotates || c.length_axes != nullptr || c.dwell_axis ||
             (c.non_modal != nullptr && c.non_modal->number >= 920 && c.non_modal->number <= 923)) {
    // G10, G92 and G43.1/G43.2 took the axis words (G10 and G92 U V W too).
    if (c.rotates) no_extra(c.rotation != nullptr ? c.rotation->text : "G68");
    if (c.length_axes != nullptr) no_extra(c.length_axes->text);
  } else if (has_axis || explicit_motion ||
             (state_.tcp == GcodeState::Tcp::Vector && (word('I').present || word('J').present || word('K').present))) {
    line_moves = has_axis && state_.motion != Motion::None;
    switch (state_.motion) {
      case Motion::None:
        if (has_axis) {
          fail(c.axis_column,
               "axis word with no motion mode (expected G0, G1, G2 or G3 on this line "
               "or an earlier one)");
        }
        break;
      case Motion::Unsupported:
        forget_axes(false);
        lenient_ = true;
        break;
      case Motion::SpindleSync:
      case Motion::RigidTap:
        no_extra(state_.motion == Motion::SpindleSync ? "G33" : "G33.1");
        used_['K' - 'A'] = true;
        synchronized(column);
        break;
      case Motion::Nurbs:
        no_extra("G5.2");
        used_['P' - 'A'] = used_['L' - 'A'] = true;
        if (p.present) c.p_user = "G5.2";
        nurbs_point(column, motion_code != nullptr);
        break;
      case Motion::Probe:
        no_extra("G38");
        probe(motion_code != nullptr ? motion_code->column : column, state_.probe);
        break;
      case Motion::CubicSpline:
      case Motion::QuadraticSpline:
        no_extra(state_.motion == Motion::CubicSpline ? "G5" : "G5.1");
        for (char letter : {'I', 'J', 'P', 'Q'}) used_[letter - 'A'] = true;
        if (p.present) c.p_user = "G5";
        spline(column);
        break;
      case Motion::Rapid:
      case Motion::Linear:
        line_axis_ = state_.tool_axis;
        if (state_.tcp == GcodeState::Tcp::Vector) {
          for (char letter : {'A', 'B', 'C'}) {
            if (word(letter).present) {
              fail(word(letter).column,
                   std::string(1, letter) + " word in G43.5 (the tool axis is I J K; expected G43.4 for rotary words)");
            }
          }
          const bool ijk = word('I').present || word('J').present || word('K').present;
          if (ijk) {
            // Fanuc: the components not given are 0.
            const Eigen::Vector3d v(word('I').value, word('J').value, word('K').value);
            if (!(v.norm() > 1e-9))
              fail(word('I').present   ? word('I').column
                   : word('J').present ? word('J').column
                                       : word('K').column,
                   "G43.5 tool axis I J K of zero length (expected a direction)");
            line_axis_ = v.normalized();
            for (char letter : {'I', 'J', 'K'}) used_[letter - 'A'] = true;
          }
          if (ijk && !has_axis) {
            straight(state_.motion == Motion::Rapid ? MotionKind::Rapid : MotionKind::Linear, column);
            break;
          }
        }
        if (has_axis) {
          straight(state_.motion == Motion::Rapid ? MotionKind::Rapid : MotionKind::Linear, column);
        }
        break;
      case Motion::Cycle:
        no_extra("canned cycle");
        for (char letter : {'R', 'Q', 'L'}) used_[letter - 'A'] = true;
        if (p.present) use_p(c, motion_code != nullptr ? motion_code->text : "the canned cycle");
        cycle(column, !(c.was_cycle && c.previous_cycle == state_.cycle));
        break;
      case Motion::ArcClockwise:
      case Motion::ArcCounterClockwise:
        for (char letter : {'I', 'J', 'K', 'R'}) used_[letter - 'A'] = true;
        if (p.present) use_p(c, state_.motion == Motion::ArcClockwise ? "G2" : "G3");
        arc(column);
        break;
    }
  }
  return line_moves;
}

// M97, M98 or M99 after the line's motion: false when the program ends here.
bool Reader::call_or_return(const LineCodes& c) {
  const Word& pw = word('P');
  const Word& lw = word('L');
  used_['P' - 'A'] = used_['L' - 'A'] = true;
  if (lw.present && (lw.value < 0.0 || lw.value != std::floor(lw.value)))
    fail(lw.column, c.flow->text + " L " + num(lw.value) + " (expected a whole number of passes)");
  if (pw.present && (pw.value < 0.0 || pw.value != std::floor(pw.value) || pw.value > 99999999.0)) {
    fail(pw.column, c.flow->text + " P " + num(pw.value) + " (expected a whole number)");
  }
  if (c.flow->number == 99) {
    if (!fanuc_return()) {
      // M99 in the main program: the control starts it again, endlessly; read once.
      warn(c.flow->column, "M99 in the main program (the control runs it again from the top, endlessly); read once");
      if (current_ == sources_.front().get()) end_line_ = current_->line;
      return false;
    }
    return true;
  }
  if (!pw.present) fail(c.flow->column, c.flow->text + " without P (expected " + c.flow->text + " P<number>)");
  long long program = static_cast<long long>(pw.value), repeats = lw.present ? static_cast<long long>(lw.value) : 1;
  if (c.flow->number == 98 && !lw.present && options_.flavor == GcodeOptions::Flavor::Fanuc && program > 9999) {
    repeats = program / 10000;  // Fanuc: M98 P30012 runs O0012 three times
    program %= 10000;
  }
  fanuc_call(Frame::Kind::Subprogram, c.flow->number == 97 ? -program : program, repeats, c.flow->column,
             c.flow->text + " P" + num(pw.value));
  return true;
}

// Words no code on the line used (rs274ngc: "X word with no G code that uses it").
void Reader::check_unused_words() {
  for (char letter : {'I', 'J', 'K', 'R', 'P', 'Q', 'H', 'D', 'L', 'E'}) {
    const Word& w = word(letter);
    if (!w.present || used_[letter - 'A']) continue;
    // Fanuc and Haas keep an H or D (offset number) given without G43 or G41/G42, as in
    // "G53 G0 H0 Z0" or "G43 H13 D13"; it does not move the tip here, where tool lengths and
    // radii come from the tool library.
    if ((letter == 'H' || letter == 'D') && options_.flavor != GcodeOptions::Flavor::LinuxCnc && w.value >= 0.0 &&
        is_whole(w.value)) {
      continue;
    }
    std::string users = "a G code";
    if (letter == 'E') fail(w.column, "word letter 'E' with no M66, M67 or M68 to use it");
    switch (letter) {
      case 'I':
      case 'J':
      case 'K':
      case 'R':
        users = "G2/G3 arc, G10 or a canned cycle";
        break;
      case 'P':
        users = "G4, G2/G3, G10, G64 or a canned cycle";
        break;
      case 'Q':
        users = "G64 or G73/G83";
        break;
      case 'L':
        users = "G10 or a canned cycle";
        break;
      case 'E':
        users = "M66, M67 or M68";
        break;
      case 'H':
        users = "G43";
        break;
      default:
        break;
    }
    fail(w.column, std::string(1, letter) + " word with no " + users + " to use it");
  }
}

bool Reader::execute() {
  Line& ln = line_words_;
  used_.fill(false);
  lenient_ = false;
  tcp_m_code_ = -1;
  if (o_column_ != 0) {  // a Fanuc program number alone on its line
    if (options_.flavor == GcodeOptions::Flavor::LinuxCnc || !current_->executed) return true;
    // The next program's number after this program's blocks: this one ends (no M30 before it).
    if (frames_.size() > 1)
      fail(o_column_, "a program number inside a called program (expected M99 before the next program)");
    warn(o_column_, "the program ends at the next program number (no M30 or M2 before it)");
    return false;
  }
  if (!axis_words_)
    for (const char axis : {'X', 'Y', 'Z', 'A', 'B', 'C', 'U', 'V', 'W'})
      axis_words_ = axis_words_ || ln.words[static_cast<size_t>(axis - 'A')].present;
  if (!current_->executed) {  // a block with words (not a comment line) has run
    current_->executed = !ln.g.empty() || !ln.m.empty() || !assignments_.empty() ||
                         std::any_of(ln.words.begin(), ln.words.end(), [](const Word& w) { return w.present; });
  }

  if (macro_call()) return true;
  LineCodes c = codes_of_line();
  read_m_codes(c);
  check_letters(c);
  set_feed_speed_tool(c);
  set_plane_and_frames(c);
  set_modes(c);
  const bool line_moves = run_motion(c);

  // Fanuc G66: the modal macro after a line that moves an axis (never from inside one).
  const bool modal_call =
      modal_call_ && line_moves && std::none_of(frames_.begin(), frames_.end(), [](const Frame& f) { return f.modal; });
  if (modal_call && c.flow != nullptr) {
    fail(c.flow->column, c.flow->text + " on a line that calls the G66 macro (expected it on a line of its own)");
  }
  if (c.flow != nullptr) return call_or_return(c);
  if (!lenient_) check_unused_words();

  // M0, M1, M60 and the program's end send a held compensated move.
  if (c.m_code[0] || c.m_code[1] || c.m_code[60] || c.program_end) {
    comp_stop(c.program_end, ln.m.empty() ? 1 : ln.m.front().column);
  }
  if (c.program_end) {
    // LinuxCNC M2/M30: G54, G17, G90, G94, G40, M5, M9 and motion mode G1; units, tool,
    // feed and position stay. Nothing after this line is read. A control's reset also ends a
    // tilted work plane (G69).
    if (state_.twp && state_.twp_feature) twp_end();
    modal_call_.reset();  // G67
    state_.work_offset = "G54";
    state_.plane = Plane::XY;
    state_.incremental = false;
    state_.spindle = SpindleState::Off;
    state_.motion = Motion::Linear;
    return false;
  }
  if (modal_call) {
    fanuc_call(Frame::Kind::Macro, modal_call_->program, modal_call_->repeats, c.axis_column, modal_call_->what,
               modal_call_->arguments, true);
  }
  return true;
}

}  // namespace

void read_gcode(std::istream& in, const std::string& name, const GcodeOptions& options, kinematics::Program& program,
                GcodeState& state) {
  validate_options(name, options);
  Reader reader(options, program, state);
  try {
    reader.run(in, name);
  } catch (const InputError&) {
    reader.emit_frames();
    throw;
  }
  detail::warn_unprogrammed_axes(state.pending, name, program);
}

kinematics::Program read_gcode(const std::string& path, const GcodeOptions& options) {
  std::ifstream in = detail::open_program_file(path, "a G-code file", "the G-code file");
  kinematics::Program program;
  GcodeState state;
  read_gcode(in, path, options, program, state);
  return program;
}

}  // namespace vcut::io
