// Reads RS274/NGC as LinuxCNC's interpreter does (src/emc/rs274ngc: interp_read.cc for the
// words, interp_convert.cc for the order of execution within a line, interp_arc.cc for arcs)
// for the three-axis subset named in gcode_reader.h. Where this reader differs on purpose it
// says so next to the code. Memory: one line at a time, plus the Blocks.
#include <vcut/io/gcode_reader.h>
#include <vcut/io/input_error.h>

#include <algorithm>
#include <charconv>
#include <climits>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <istream>
#include <new>
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

constexpr double kMmPerInch = 25.4;  // exact, by the 1959 definition of the inch
// Any number beyond this (mm, mm/min, rpm, s, turns, tool numbers) is a typo or garbage:
// a 1 km stroke or a 1000 m/min feed exists on no milling machine.
constexpr double kMaxMagnitude = 1e6;
// Points closer than this coincide (full circles, zero radius): far below any machine's
// resolution, far above the rounding of mm values up to kMaxMagnitude (~1e-10).
constexpr double kSamePointMm = 1e-9;
// R arcs: |R| may fall short of half the chord by this times max(1, |R|) before it is an
// error; this only absorbs rounding of the printed values (the brief's 1e-9).
constexpr double kRadiusRoundingRelative = 1e-9;
// I J K arcs: a radius mismatch up to this times r is allowed on top of arc_tolerance_mm,
// so that large radii printed with few decimals are not rejected (LinuxCNC's
// SPIRAL_RELATIVE_TOLERANCE plays the same role).
constexpr double kArcRelativeTolerance = 1e-6;

// rs274ngc has 15 G and 5 M modal groups: a line with more codes than this is garbage.
constexpr size_t kMaxCodesPerLine = 32;

constexpr char kAxisLetter[3] = {'X', 'Y', 'Z'};
constexpr char kCenterLetter[3] = {'I', 'J', 'K'};

bool is_blank(char c) { return c == ' ' || c == '\t'; }
bool is_digit(char c) { return c >= '0' && c <= '9'; }
bool is_letter(char c) { return (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z'); }
char upper(char c) { return (c >= 'a' && c <= 'z') ? static_cast<char>(c - 'a' + 'A') : c; }

size_t skip_blanks(const std::string& s, size_t i) {
  while (i < s.size() && is_blank(s[i])) ++i;
  return i;
}

int column_of(size_t i) {
  return i >= static_cast<size_t>(INT_MAX) ? INT_MAX : static_cast<int>(i) + 1;
}

std::string describe(char c) {
  const auto u = static_cast<unsigned char>(c);
  char buf[16];
  if (u >= 32 && u < 127) {
    std::snprintf(buf, sizeof buf, "'%c'", c);
  } else {
    std::snprintf(buf, sizeof buf, "byte 0x%02X", u);
  }
  return buf;
}

std::string num(double v) {
  char buf[40];
  std::snprintf(buf, sizeof buf, "%.10g", v);
  return buf;
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
  std::vector<Code> g;
  std::vector<Code> m;
  void clear() {
    words.fill(Word{});
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
  kGroupCount = 16
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
    {400, {kCutterComp, true}},
    // G43/G49: accepted without effect. Blocks are tool-tip positions and the programmed
    // point is taken to be the tip, which is what a CAM post with G43 H means; tool lengths
    // are the machine model's business.
    {430, {kToolLength, true}}, {490, {kToolLength, true}},
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
    {980, {kReturnMode, true}}, {990, {kReturnMode, true}},  // no effect without cycles

    {50, {kMotion, false, true, false, "spline/NURBS"}},
    {51, {kMotion, false, true, false, "spline/NURBS"}},
    {52, {kMotion, false, true, false, "spline/NURBS"}},
    {53, {kMotion, false, true, false, "spline/NURBS"}},
    {330, {kMotion, false, true, false, "spindle-synchronized motion"}},
    {331, {kMotion, false, true, false, "spindle-synchronized motion"}},
    {382, {kMotion, false, true, false, "probing"}}, {383, {kMotion, false, true, false, "probing"}},
    {384, {kMotion, false, true, false, "probing"}}, {385, {kMotion, false, true, false, "probing"}},
    {730, {kMotion, false, true, false, "canned cycle"}},
    {740, {kMotion, false, true, false, "canned cycle"}},
    {760, {kMotion, false, true, false, "canned cycle"}},
    {810, {kMotion, false, true, false, "canned cycle"}},
    {820, {kMotion, false, true, false, "canned cycle"}},
    {830, {kMotion, false, true, false, "canned cycle"}},
    {840, {kMotion, false, true, false, "canned cycle"}},
    {850, {kMotion, false, true, false, "canned cycle"}},
    {860, {kMotion, false, true, false, "canned cycle"}},
    {870, {kMotion, false, true, false, "canned cycle"}},
    {880, {kMotion, false, true, false, "canned cycle"}},
    {890, {kMotion, false, true, false, "canned cycle"}},
    {100, {kNonModal, false, true, false, "setting offsets"}},
    {280, {kNonModal, false, true, true, "move to a stored position"}},
    {300, {kNonModal, false, true, true, "move to a stored position"}},
    {281, {kNonModal, false, false, false, "store a position"}},
    {301, {kNonModal, false, false, false, "store a position"}},
    {520, {kNonModal, false, true, true, "local coordinate offset"}},
    {530, {kNonModal, false, true, false, "move in machine coordinates"}},
    {920, {kNonModal, false, true, true, "coordinate system offset"}},
    {921, {kNonModal, false, true, true, "coordinate system offset"}},
    {922, {kNonModal, false, true, true, "coordinate system offset"}},
    {923, {kNonModal, false, true, true, "coordinate system offset"}},
    {171, {kPlane, false, false, false, "UVW plane"}},
    {181, {kPlane, false, false, false, "UVW plane"}},
    {191, {kPlane, false, false, false, "UVW plane"}},
    {410, {kCutterComp, false, false, false, "cutter radius compensation"}},
    {411, {kCutterComp, false, false, false, "cutter radius compensation"}},
    {420, {kCutterComp, false, false, false, "cutter radius compensation"}},
    {421, {kCutterComp, false, false, false, "cutter radius compensation"}},
    {431, {kToolLength, false, false, false, "dynamic tool length offset"}},
    {432, {kToolLength, false, false, false, "dynamic tool length offset"}},
    {930, {kFeedMode, false, false, false, "inverse-time feed"}},
    {950, {kFeedMode, false, false, false, "feed per revolution"}},
    {960, {kSpindleMode, false, false, false, "constant surface speed"}},
    {70, {kLatheMode, false, false, false, "lathe diameter/radius mode"}},
    {80, {kLatheMode, false, false, false, "lathe diameter/radius mode"}},
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
    case 6: return 6;
    case 3: case 4: case 5: return 7;
    case 7: case 8: case 9: return 8;
    case 48: case 49: case 50: case 51: case 52: case 53: return 9;
    default: return -1;
  }
}
// clang-format on

bool m_supported(int m) { return (m >= 0 && m <= 9) || m == 30; }

bool valid_offset_name(const std::string& name) {
  static const char* const kNames[] = {"G54", "G55",   "G56",   "G57",  "G58",
                                       "G59", "G59.1", "G59.2", "G59.3"};
  for (const char* n : kNames) {
    if (name == n) return true;
  }
  return false;
}

void validate_options(const std::string& name, const GcodeOptions& options) {
  if (!std::isfinite(options.arc_tolerance_mm) || options.arc_tolerance_mm < 0.0) {
    throw InputError(name, 0, 0,
                     "arc tolerance " + num(options.arc_tolerance_mm) +
                         " mm in the options (expected a finite value >= 0)");
  }
  for (const auto& [key, offset] : options.work_offsets_mm) {
    if (!valid_offset_name(key)) {
      throw InputError(
          name, 0, 0,
          "work offset '" + key + "' in the options (expected one of G54..G59, G59.1..G59.3)");
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

class Reader {
 public:
  Reader(const std::string& name, const GcodeOptions& options, Program& program, GcodeState& state,
         int file_index)
      : name_(name), options_(options), program_(program), state_(state), file_index_(file_index) {}

  // One line without its '\n'. Returns false once the program has ended (M2, M30, a
  // closing '%'): LinuxCNC reads nothing after that either.
  bool line(std::string& text, int number);

 private:
  [[noreturn]] void fail(int column, const std::string& message) const {
    throw InputError(name_, line_, column, message);
  }
  std::string where(int column) const {
    return name_ + ":" + std::to_string(line_) + ":" + std::to_string(column);
  }
  void warn(int column, const std::string& message) {
    program_.warnings.push_back(where(column) + ": " + message);
  }
  // An unsupported word: an error, or (unsupported_as_warning) one warning per distinct key.
  void unsupported(int column, const std::string& key, const std::string& message) {
    if (!options_.unsupported_as_warning) fail(column, message);
    if (state_.warned.insert(key).second) warn(column, message + "; ignored");
  }

  void lex(const std::string& s, size_t i);
  double read_number(const std::string& s, size_t& i, char letter, int column,
                     std::string& text) const;
  size_t skip_comment(const std::string& s, size_t i) const;
  bool execute();

  Eigen::Vector3d work_offset() const {
    const auto it = options_.work_offsets_mm.find(state_.work_offset);
    return it == options_.work_offsets_mm.end() ? Eigen::Vector3d::Zero() : it->second;
  }
  double unit() const { return state_.inches ? kMmPerInch : 1.0; }
  const Word& word(char letter) const { return line_words_.words[letter - 'A']; }
  Eigen::Vector3d target(std::array<bool, 3>& programmed) const;
  void straight(MotionKind kind, int column);
  void arc(int column);
  void append(Block block, const std::array<bool, 3>& programmed);
  void forget_axes(bool all);

  const std::string& name_;
  const GcodeOptions& options_;
  Program& program_;
  GcodeState& state_;
  const int file_index_;
  int line_ = 0;
  bool seen_content_ = false;  // a non-blank line has been read (the opening '%' is the first)
  bool opened_with_percent_ = false;
  Line line_words_;
  std::array<bool, 26> used_{};  // words consumed by some code on this line
  bool lenient_ = false;         // an ignored unsupported code may consume any word
  bool exact_stop_line_ = false;  // G9 on this line
  int o_column_ = 0;             // column of a Fanuc program number on this line
};

bool Reader::line(std::string& text, int number) {
  line_ = number;
  if (!text.empty() && text.back() == '\r') text.pop_back();  // CRLF files
  const size_t i = skip_blanks(text, 0);
  if (i == text.size()) return true;
  if (text[i] == '%') {
    // rs274ngc: a '%' on the first line opens the program and the next '%' line ends it.
    line_words_.clear();
    lex(text, i + 1);
    if (!line_words_.g.empty() || !line_words_.m.empty() || o_column_ != 0 ||
        std::any_of(line_words_.words.begin(), line_words_.words.end(),
                    [](const Word& w) { return w.present; })) {
      fail(column_of(i), "words after '%' (expected '%' alone on its line)");
    }
    if (!seen_content_) {
      seen_content_ = opened_with_percent_ = true;
      return true;
    }
    if (!opened_with_percent_) {
      fail(column_of(i), "closing '%' in a program that did not open with '%' on its first line");
    }
    return false;
  }
  seen_content_ = true;
  // Block delete: rs274ngc skips a line starting with '/' when the block-delete switch is on;
  // this reader always has it on.
  if (text[i] == '/') return true;
  line_words_.clear();
  lex(text, i);
  return execute();
}

size_t Reader::skip_comment(const std::string& s, size_t i) const {
  for (size_t j = i + 1; j < s.size(); ++j) {
    if (s[j] == ')') return j + 1;
    // rs274ngc rejects nested comments (NCE_NESTED_COMMENT_FOUND).
    if (s[j] == '(') fail(column_of(j), "'(' inside a comment (expected ')' first)");
  }
  fail(column_of(i), "unterminated comment: '(' without ')'");
}

// rs274ngc's real_value without expressions: [+|-] digits [. [digits]] | [+|-] . digits.
// Blanks may sit anywhere in it: LinuxCNC removes them before parsing, so "X 1 0.5" is X10.5.
// There is no exponent, and no nan or inf.
double Reader::read_number(const std::string& s, size_t& i, char letter, int column,
                           std::string& text) const {
  const size_t n = s.size();
  size_t j = skip_blanks(s, i);
  bool negative = false;
  if (j < n && (s[j] == '+' || s[j] == '-')) {
    negative = s[j] == '-';
    j = skip_blanks(s, j + 1);
  }
  std::string digits;
  bool point = false;
  bool any_digit = false;
  bool integer_part_nonzero = false;
  for (; j < n; ++j) {
    const char c = s[j];
    if (is_digit(c)) {
      digits += c;
      any_digit = true;
      if (!point && c != '0') integer_part_nonzero = true;
    } else if (c == '.' && !point) {
      digits += c;
      point = true;
    } else if (!is_blank(c)) {
      break;
    }
  }
  if (!any_digit) {
    fail(column, std::string("expected a number after '") + letter + "', found " +
                     (j < n ? describe(s[j]) : std::string("end of line")));
  }
  // "X1e5": an exponent. ("X1 E5" reads as an E word, an unknown letter.)
  if (j < n && (s[j] == 'e' || s[j] == 'E') && !is_blank(s[j - 1])) {
    fail(column, std::string("exponent in the ") + letter +
                     " number (rs274 numbers have none; expected digits with an optional '.')");
  }
  i = j;
  text = (negative ? "-" : "") + (digits.size() > 24 ? digits.substr(0, 24) + "..." : digits);
  double value = 0.0;
  const char* first = digits.data();
  const char* last = digits.data() + digits.size();
  const auto [end, ec] = std::from_chars(first, last, value, std::chars_format::fixed);
  if (ec == std::errc::result_out_of_range) {
    if (integer_part_nonzero) {
      fail(column, std::string(1, letter) + " value " + text +
                       " is out of range (expected |value| <= 1000000)");
    }
    value = 0.0;  // underflow: smaller than any length or speed that matters
  } else if (ec != std::errc() || end != last) {
    fail(column, std::string("malformed ") + letter + " number " + text);
  }
  return negative ? -value : value;
}

void Reader::lex(const std::string& s, size_t i) {
  const size_t n = s.size();
  bool first_word = true;
  o_column_ = 0;
  while (true) {
    i = skip_blanks(s, i);
    if (i >= n) return;
    const char c = s[i];
    const int column = column_of(i);
    if (c == '(') {
      i = skip_comment(s, i);
      continue;
    }
    if (c == ';') return;  // LinuxCNC: the rest of the line is a comment
    if (!is_letter(c)) {
      if (c == '#') fail(column, "parameters (#) are not supported (expected a word)");
      if (c == '[') fail(column, "expressions ([ ]) are not supported (expected a number)");
      if (c == '\r')
        fail(column, "carriage return inside a line (expected \\n or \\r\\n line ends)");
      fail(column, "unexpected " + describe(c) + " (expected a word: a letter and a number)");
    }
    const char letter = upper(c);
    ++i;
    if (o_column_ != 0) {
      fail(o_column_,
           "O-words (subroutines, loops, conditionals) are not supported "
           "(expected a program number O<digits> alone on its line)");
    }
    if (letter == 'O') {
      // A Fanuc program number ("O1234" alone on a line) is accepted and ignored.
      const size_t j = skip_blanks(s, i);
      if (!first_word || j >= n || !is_digit(s[j])) {
        fail(column, "O-words (subroutines, loops, conditionals) are not supported");
      }
      std::string text;
      read_number(s, i, letter, column, text);
      o_column_ = column;
      first_word = false;
      continue;
    }
    if (letter == 'E') {
      fail(column, "unknown word letter 'E' (expected one of A-D, F-N, P-Z)");
    }
    std::string text;
    const double value = read_number(s, i, letter, column, text);
    if (letter != 'N' && std::abs(value) > kMaxMagnitude) {
      fail(column, std::string(1, letter) + " value " + text +
                       " is out of range (expected |value| <= 1000000)");
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
Eigen::Vector3d Reader::target(std::array<bool, 3>& programmed) const {
  Eigen::Vector3d end = state_.position_mm;
  const Eigen::Vector3d offset = work_offset();
  for (int a = 0; a < 3; ++a) {
    const Word& w = word(kAxisLetter[a]);
    programmed[a] = w.present;
    if (!w.present) continue;
    const double v = w.value * unit();
    if (state_.incremental) {
      if (!state_.known[a]) {
        fail(w.column, std::string("incremental (G91) ") + kAxisLetter[a] + " move while the " +
                           kAxisLetter[a] + " position is unknown (expected an absolute " +
                           kAxisLetter[a] + " move first)");
      }
      end[a] = state_.position_mm[a] + v;
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

// Appends a block (unless it does not move) and brings the position and the unknown axes up
// to date. Blocks made while an axis is unknown hold that axis still; when the axis is first
// programmed they take its value, so that the first move only moves the programmed axes.
void Reader::append(Block block, const std::array<bool, 3>& programmed) {
  // Rotary words (degrees, G90/G91 like the linear axes; G20 does not apply).
  kinematics::RotaryWords rotary = state_.rotary;
  for (int r = 0; r < 3; ++r) {
    const Word& w = word(static_cast<char>('A' + r));
    if (!w.present) continue;
    const double v = w.value * M_PI / 180.0;
    rotary.angle_rad[static_cast<size_t>(r)] = state_.incremental ? rotary.angle_rad[static_cast<size_t>(r)] + v : v;
    rotary.given[static_cast<size_t>(r)] = true;
    state_.rotary_program = true;
  }
  block.start_rotary = state_.rotary;
  block.end_rotary = rotary;
  block.tool_pose = !state_.rotary_program;
  block.exact_stop = state_.exact_stop || exact_stop_line_;
  block.blend_tolerance_mm = state_.blend_tolerance_mm;
  const bool turns = rotary.angle_rad != state_.rotary.angle_rad;
  state_.rotary = rotary;
  const bool moves = block.kind == MotionKind::Arc || block.start_mm != block.end_mm || turns;
  if (moves) {
    block.feed_mode = kinematics::FeedMode::UnitsPerMinute;
    block.tool = state_.tool;
    block.spindle = state_.spindle;
    block.spindle_rpm = state_.spindle_rpm;
    block.source = kinematics::SourceRef{file_index_, line_};
    program_.blocks.push_back(block);
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
      Block& b = program_.blocks[index];
      if (first.empty() && b.source.file >= 0 &&
          static_cast<size_t>(b.source.file) < program_.files.size()) {
        first = program_.where(b.source);
      }
      b.start_mm[a] = b.end_mm[a] = value;
      if (b.kind == MotionKind::Arc)
        b.center_mm[a] = value;  // only the normal axis is ever pending
      ++patched;
    }
    pending.clear();
    if (patched > 0) {
      warn(word(kAxisLetter[a]).column, std::to_string(patched) + " earlier move(s) (first at " +
                                            first + ") ran while " + kAxisLetter[a] +
                                            " was unknown; they hold " + kAxisLetter[a] + " at " +
                                            num(value) + " mm, its first programmed value");
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
  if (kind == MotionKind::Linear && state_.feed_mm_per_min <= 0.0) {
    fail(column, "feed move without F (expected an F word on this line or before it)");
  }
  std::array<bool, 3> programmed{};
  Block block;
  block.kind = kind;
  block.end_mm = target(programmed);
  block.start_mm = state_.position_mm;
  for (int a = 0; a < 3; ++a) {
    if (!state_.known[a]) block.start_mm[a] = block.end_mm[a];
  }
  block.feed_mm_per_min = kind == MotionKind::Rapid ? 0.0 : state_.feed_mm_per_min;
  append(block, programmed);
}

void Reader::arc(int column) {
  const bool clockwise = state_.motion == Motion::ArcClockwise;
  const char* code = clockwise ? "G2" : "G3";
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
  if (state_.feed_mm_per_min <= 0.0) {
    fail(column, "feed move without F (expected an F word on this line or before it)");
  }
  for (int axis : {a, b}) {
    if (!state_.known[axis]) {
      fail(column, std::string(code) + " arc from an unknown " + kAxisLetter[axis] +
                       " position (expected a move that sets " + kAxisLetter[axis] +
                       " before the first arc)");
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

  std::array<bool, 3> programmed{};
  Eigen::Vector3d end = target(programmed);
  Eigen::Vector3d start = state_.position_mm;
  if (!state_.known[c]) start[c] = end[c];
  const Eigen::Vector2d s(start[a], start[b]);
  const Eigen::Vector2d e(end[a], end[b]);
  Eigen::Vector2d center;
  if (ijk) {
    const Word& normal_word = word(kCenterLetter[c]);
    if (normal_word.present) {
      fail(normal_word.column, std::string(1, kCenterLetter[c]) + " word in a " + plane_name +
                                   "-plane arc (expected " + kCenterLetter[a] + " and " +
                                   kCenterLetter[b] + ")");
    }
    const Eigen::Vector3d offset = work_offset();
    for (int k = 0; k < 2; ++k) {
      const int axis = k == 0 ? a : b;
      const Word& w = word(kCenterLetter[axis]);
      double v = 0.0;  // rs274ngc: a missing incremental offset is 0
      if (w.present) {
        v = w.value * unit();
      } else if (state_.arc_center_absolute) {
        fail(column, std::string(1, kCenterLetter[axis]) +
                         " word missing in an absolute-centre (G90.1) arc");
      }
      center[k] = state_.arc_center_absolute ? v + offset[axis] : start[axis] + v;
    }
    const double r_start = (s - center).norm();
    const double r_end = (e - center).norm();
    if (r_start <= kSamePointMm || r_end <= kSamePointMm) {
      fail(column, std::string("zero-radius ") + code +
                       " arc (expected the centre away from the start and the end)");
    }
    const double allowed =
        std::max(options_.arc_tolerance_mm, kArcRelativeTolerance * std::max(r_start, r_end));
    if (std::abs(r_end - r_start) > allowed) {
      fail(column, std::string(code) + " arc end is not on its circle: radius " + num(r_start) +
                       " mm at the start, " + num(r_end) +
                       " mm at the end (expected equal within " + num(allowed) + " mm)");
    }
    // A full circle: make start and end coincide exactly so that the sweep is 2*pi, not ~0.
    if ((e - s).norm() <= kSamePointMm) {
      end[a] = start[a];
      end[b] = start[b];
    }
  } else {
    // rs274ngc arc_data_r: the centre lies on the chord's perpendicular bisector, to the
    // right of start->end for G2 with R > 0 or G3 with R < 0 (negative R: the long arc).
    const double radius = r.value * unit();
    const Eigen::Vector2d d = e - s;
    const double chord = d.norm();
    if (chord <= kSamePointMm) {
      fail(r.column, std::string(code) +
                         " R arc that ends where it starts (expected I/J/K for a full circle)");
    }
    const double abs_r = std::abs(radius);
    double half = chord / 2.0;
    if (half - abs_r > kRadiusRoundingRelative * std::max(1.0, abs_r)) {
      fail(r.column, "arc radius |R| = " + num(abs_r) + " mm is less than half the chord, " +
                         num(half) + " mm (expected |R| >= " + num(half) + " mm)");
    }
    half = std::min(half, abs_r);
    const double to_center = std::sqrt((abs_r - half) * (abs_r + half));
    const Eigen::Vector2d left = Eigen::Vector2d(-d.y(), d.x()) / chord;
    const bool right = (clockwise && radius > 0.0) || (!clockwise && radius < 0.0);
    center = (s + e) / 2.0 + (right ? -to_center : to_center) * left;
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
  block.feed_mm_per_min = state_.feed_mm_per_min;
  append(block, programmed);
}

bool Reader::execute() {
  Line& ln = line_words_;
  used_.fill(false);
  lenient_ = false;
  if (o_column_ != 0) return true;  // a Fanuc program number alone on its line

  // --- G codes: one per modal group, supported or reported.
  std::array<const Code*, kGroupCount> by_group{};
  const Code* axis_user = nullptr;  // an ignored code that takes the axis words
  bool axis_user_all = false;
  for (const Code& g : ln.g) {
    const GInfo info = g_info(g.number);
    if (info.group >= 0) {
      const Code*& slot = by_group[static_cast<size_t>(info.group)];
      if (slot != nullptr) {
        fail(g.column, "two G codes of the " + std::string(group_name(info.group)) +
                           " group on one line, " + slot->text + " and " + g.text +
                           " (expected at most one)");
      }
      slot = &g;
    }
    if (info.supported) continue;
    const std::string message = info.group < 0
                                    ? "unknown G code " + g.text
                                    : "unsupported G code " + g.text + " (" + info.what + ")";
    unsupported(g.column, g.text, message);
    lenient_ = true;  // warning mode: the code and the words it would use are ignored
    if (info.group == kNonModal && info.uses_axes) {
      axis_user = &g;
      axis_user_all = info.all_axes;
    }
  }
  // rs274ngc: two codes that both use the axis words cannot share a line (G53 modifies the
  // motion instead, so it goes with G0/G1).
  if (axis_user != nullptr && axis_user->number != 530 && by_group[kMotion] != nullptr &&
      by_group[kMotion]->number != 800) {
    const Code* later =
        axis_user->column > by_group[kMotion]->column ? axis_user : by_group[kMotion];
    fail(later->column, axis_user->text + " and " + by_group[kMotion]->text +
                            " both use the axis words (expected them on separate lines)");
  }

  // --- M codes.
  std::array<const Code*, 10> m_by_group{};
  bool m_code[10] = {};  // supported M codes present, by number (all are < 10 but M30)
  bool program_end = false;
  for (const Code& m : ln.m) {
    const int group = m.number >= 0 ? m_group(m.number) : -1;
    if (group >= 0) {
      const Code*& slot = m_by_group[static_cast<size_t>(group)];
      // rs274ngc lets M7 and M8 share a line; every other pair of one group is an error.
      const bool coolant_pair = group == 8 && slot != nullptr && slot->number != 9 &&
                                m.number != 9 && slot->number != m.number;
      if (slot != nullptr && !coolant_pair) {
        fail(m.column, "two M codes of one modal group on one line, " + slot->text + " and " +
                           m.text + " (expected at most one)");
      }
      slot = &m;
    }
    if (m.number >= 0 && m_supported(m.number)) {
      if (m.number == 2 || m.number == 30) {
        program_end = true;
      } else {
        m_code[m.number] = true;
      }
      continue;
    }
    unsupported(m.column, m.text, (group < 0 ? "unknown M code " : "unsupported M code ") + m.text);
    lenient_ = true;
  }

  // --- Letters this reader does not move.
  for (char letter : {'U', 'V', 'W'}) {
    const Word& w = word(letter);
    if (w.present) {
      unsupported(w.column, std::string(1, letter),
                  std::string(1, letter) + " words (extra linear axes) are not supported: this reader moves X Y Z A B C");
    }
  }
  for (char letter : {'A', 'B', 'C'}) {
    const Word& w = word(letter);
    if (w.present && !(std::abs(w.value) <= kMaxMagnitude))
      fail(w.column, std::string(1, letter) + " " + num(w.value) + " deg is out of range (expected within +-1e6 deg)");
  }

  // --- Modes, in rs274ngc's order of execution within a line, except that G20/G21 apply
  // to every number of their line, F included (LinuxCNC would read an F on the G20 line in
  // the previous units; nobody writes "G20 F10" meaning mm/min).
  if (const Code* g = by_group[kUnits]) state_.inches = g->number == 200;

  // Lengths beyond 1e6 mm after conversion are as absurd as before it.
  for (char letter : {'X', 'Y', 'Z', 'I', 'J', 'K', 'R'}) {
    const Word& w = word(letter);
    if (w.present && std::abs(w.value * unit()) > kMaxMagnitude) {
      fail(w.column, std::string(1, letter) + " " + num(w.value) + " in = " +
                         num(w.value * unit()) + " mm is out of range (expected within +-1e6 mm)");
    }
  }
  if (const Word& f = word('F'); f.present) {
    const double feed = f.value * unit();
    if (!(feed > 0.0)) fail(f.column, "F " + num(f.value) + " (expected a feed > 0)");
    if (feed > kMaxMagnitude) {
      fail(f.column, "F " + num(feed) + " mm/min is out of range (expected <= 1e6 mm/min)");
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
  if (m_code[6] && state_.selected_tool >= 0) state_.tool = state_.selected_tool;
  if (m_code[3]) state_.spindle = SpindleState::Clockwise;
  if (m_code[4]) state_.spindle = SpindleState::CounterClockwise;
  if (m_code[5]) state_.spindle = SpindleState::Off;
  // M0/M1 (pauses) and M7/M8/M9 (coolant) do not change the path.

  const Word& p = word('P');
  std::string p_user;  // the code that took the P word
  auto use_p = [&](const std::string& code) {
    if (!p_user.empty()) {
      fail(p.column,
           "P word used by both " + p_user + " and " + code + " (expected them on separate lines)");
    }
    p_user = code;
    used_['P' - 'A'] = true;
  };
  if (const Code* g = by_group[kNonModal]; g != nullptr && g->number == 40) {  // G4 dwell
    if (!p.present) fail(g->column, "G4 dwell without P (expected P seconds)");
    if (p.value < 0.0) fail(p.column, "G4 P " + num(p.value) + " (expected seconds >= 0)");
    use_p(g->text);
  }
  if (const Code* g = by_group[kPlane]; g != nullptr && g_info(g->number).supported) {
    state_.plane = g->number == 170 ? Plane::XY : g->number == 180 ? Plane::ZX : Plane::YZ;
  }
  if (const Code* g = by_group[kToolLength]; g != nullptr && g->number == 430) {
    const Word& h = word('H');
    if (h.present && (h.value < 0.0 || !is_whole(h.value))) {
      fail(h.column, "H " + num(h.value) + " (expected a tool number, a whole number >= 0)");
    }
    used_['H' - 'A'] = true;
  }
  if (const Code* g = by_group[kCoordinateSystem]; g != nullptr) state_.work_offset = g->text;
  exact_stop_line_ = by_group[kNonModal] != nullptr && by_group[kNonModal]->number == 90;
  if (const Code* g = by_group[kPathControl]; g != nullptr && g->number != 640) {
    state_.exact_stop = true;  // G61, G61.1
  }
  if (const Code* g = by_group[kPathControl]; g != nullptr && g->number == 640) {
    // G64 P (blending tolerance) and Q (naive CAM tolerance, not used): lengths >= 0.
    for (char letter : {'P', 'Q'}) {
      const Word& w = word(letter);
      if (w.present && w.value < 0.0) {
        fail(w.column,
             std::string("G64 ") + letter + " " + num(w.value) + " (expected a tolerance >= 0)");
      }
    }
    state_.exact_stop = false;
    state_.blend_tolerance_mm = p.present ? p.value * unit() : -1.0;
    if (p.present) use_p(g->text);
    used_['Q' - 'A'] = true;
  }
  if (const Code* g = by_group[kDistance]) state_.incremental = g->number == 910;
  if (const Code* g = by_group[kArcDistance]) state_.arc_center_absolute = g->number == 901;
  if (const Code* g = by_group[kMotion]) {
    switch (g->number) {
      case 0:
        state_.motion = Motion::Rapid;
        break;
      case 10:
        state_.motion = Motion::Linear;
        break;
      case 20:
        state_.motion = Motion::ArcClockwise;
        break;
      case 30:
        state_.motion = Motion::ArcCounterClockwise;
        break;
      case 800:
        state_.motion = Motion::None;
        break;
      default:
        state_.motion = Motion::Unsupported;
        break;
    }
  }

  // --- Motion.
  const bool has_axis = word('X').present || word('Y').present || word('Z').present || word('A').present ||
                        word('B').present || word('C').present;
  const Code* motion_code = by_group[kMotion];
  const bool explicit_motion = motion_code != nullptr && motion_code->number <= 30;
  int axis_column = INT_MAX;  // the first axis word
  for (char letter : {'X', 'Y', 'Z', 'A', 'B', 'C'}) {
    if (word(letter).present) axis_column = std::min(axis_column, word(letter).column);
  }
  // Motion errors point at the G0..G3 word, or at the first axis word of a modal motion.
  const int column = explicit_motion ? motion_code->column : axis_column;
  if (axis_user != nullptr) {
    forget_axes(axis_user_all);
  } else if (has_axis || explicit_motion) {
    switch (state_.motion) {
      case Motion::None:
        if (has_axis) {
          fail(axis_column,
               "axis word with no motion mode (expected G0, G1, G2 or G3 on this line "
               "or an earlier one)");
        }
        break;
      case Motion::Unsupported:
        forget_axes(false);
        lenient_ = true;
        break;
      case Motion::Rapid:
      case Motion::Linear:
        if (has_axis) {
          straight(state_.motion == Motion::Rapid ? MotionKind::Rapid : MotionKind::Linear, column);
        }
        break;
      case Motion::ArcClockwise:
      case Motion::ArcCounterClockwise:
        for (char letter : {'I', 'J', 'K', 'R'}) used_[letter - 'A'] = true;
        if (p.present) use_p(state_.motion == Motion::ArcClockwise ? "G2" : "G3");
        arc(column);
        break;
    }
  }

  // --- Words no code on the line used (rs274ngc: "X word with no G code that uses it").
  if (!lenient_) {
    for (char letter : {'I', 'J', 'K', 'R', 'P', 'Q', 'H', 'D', 'L'}) {
      const Word& w = word(letter);
      if (!w.present || used_[letter - 'A']) continue;
      std::string users = "a G code that uses it";
      switch (letter) {
        case 'I':
        case 'J':
        case 'K':
        case 'R':
          users = "G2/G3 arc";
          break;
        case 'P':
          users = "G4, G2/G3 or G64";
          break;
        case 'Q':
          users = "G64";
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

  if (program_end) {
    // LinuxCNC M2/M30: G54, G17, G90, G94, G40, M5, M9 and motion mode G1; units, tool,
    // feed and position stay. Nothing after this line is read.
    state_.work_offset = "G54";
    state_.plane = Plane::XY;
    state_.incremental = false;
    state_.spindle = SpindleState::Off;
    state_.motion = Motion::Linear;
    return false;
  }
  return true;
}

}  // namespace

void read_gcode(std::istream& in, const std::string& name, const GcodeOptions& options,
                kinematics::Program& program, GcodeState& state) {
  validate_options(name, options);
  const int file_index = static_cast<int>(program.files.size());
  program.files.push_back(name);
  Reader reader(name, options, program, state, file_index);
  std::string text;
  int number = 0;
  try {
    while (std::getline(in, text)) {
      if (number == INT_MAX) throw InputError(name, number, 0, "too many lines");
      ++number;
      if (!reader.line(text, number)) break;
    }
  } catch (const std::bad_alloc&) {
    throw InputError(name, number + 1, 0, "out of memory (a line too long, or too many moves)");
  } catch (const std::length_error&) {
    throw InputError(name, number + 1, 0, "out of memory (a line too long, or too many moves)");
  } catch (const std::ios_base::failure&) {
    throw InputError(name, number + 1, 0, "read error (expected a readable text file)");
  }
  if (in.bad()) throw InputError(name, number + 1, 0, "read error (expected a readable text file)");
  for (int a = 0; a < 3; ++a) {
    if (state.pending[a].empty()) continue;
    program.warnings.push_back(name + ": " + kAxisLetter[a] +
                               " has not been programmed by the end of this file; " +
                               std::to_string(state.pending[a].size()) +
                               " move(s) hold it at 0 unless a later file sets it");
  }
}

kinematics::Program read_gcode(const std::string& path, const GcodeOptions& options) {
  std::error_code ec;
  if (std::filesystem::is_directory(path, ec)) {
    throw InputError(path, 0, 0, "is a directory (expected a G-code file)");
  }
  std::ifstream in(path, std::ios::binary);
  if (!in) {
    throw InputError(path, 0, 0,
                     std::string("cannot open the G-code file: ") + std::strerror(errno));
  }
  kinematics::Program program;
  GcodeState state;
  read_gcode(in, path, options, program, state);
  return program;
}

}  // namespace vcut::io
