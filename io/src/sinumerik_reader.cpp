// Reads the SINUMERIK 840D subset described in sinumerik_reader.h. The semantics follow the
// SINUMERIK 840D sl programming manuals (Fundamentals; Job planning §"Transformations" for
// TRAORI and the orientation modes); where this reader picks one reading it says so here.
// Memory: one line at a time, plus the Blocks.
#include <vcut/io/input_error.h>
#include <vcut/io/sinumerik_reader.h>

#include "line_source.h"
#include "plane_arc.h"
#include "reader_util.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <charconv>
#include <cerrno>
#include <climits>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <optional>
#include <filesystem>
#include <fstream>
#include <functional>
#include <map>
#include <istream>
#include <new>
#include <stdexcept>
#include <system_error>
#include <vector>

namespace vcut::io {
namespace {

using kinematics::Block;
using kinematics::MotionKind;
using kinematics::OrientationMode;
using kinematics::SpindleState;
using Motion = SinumerikState::Motion;
using Plane = SinumerikState::Plane;

using detail::kMmPerInch;
// Any length (mm), feed (mm/min), speed (rpm) or angle (deg) beyond this is a typo or garbage:
// a 1 km stroke or a 1000 m/min feed exists on no milling machine.
constexpr double kMaxMagnitude = 1e6;
using detail::kSamePointMm;
// A tool or cone vector shorter than this has no direction (CAM prints 4 to 9 decimals).
constexpr double kMinVectorNorm = 1e-6;
// Two tool vectors this close to opposite (cosine) have no single great circle between them.
constexpr double kOppositeAxisCosine = -1.0 + 1e-12;
// Cone interpolation: start and end vectors must make the same angle with the cone axis within
// this (rad): 1e-4 rad is a vector printed with 4 decimals.
constexpr double kConeAngleToleranceRad = 1e-4;
// ORICONIO / ORICONTO: orientations closer than this (chord on the unit sphere, about rad) do not
// fix a circle; 1e-4 is a vector printed with 4 decimals, as above.
constexpr double kMinConeChord = 1e-4;
constexpr int kMaxExpressionDepth = 64;  // nesting of ( ) and unary signs
constexpr int kMaxCallDepth = 16;        // subprograms within subprograms
constexpr int kRParameters = 1000;       // R0..R999
constexpr int kMaxToolNumber = 99999;    // as the tool library
constexpr double kDegToRad = M_PI / 180.0;

constexpr char kAxisLetter[3] = {'X', 'Y', 'Z'};
constexpr char kCenterLetter[3] = {'I', 'J', 'K'};

bool is_blank(char c) { return c == ' ' || c == '\t' || c == '\f' || c == '\v'; }
using detail::describe;
using detail::is_digit;
using detail::num;
using detail::upper;

bool is_upper(char c) { return (c >= 'A' && c <= 'Z') || c == '_'; }
int clamp_int(std::size_t v) { return v >= static_cast<std::size_t>(INT_MAX) ? INT_MAX : static_cast<int>(v); }

// One programmed value of a block.
struct Value {
  bool present = false;
  double value = 0.0;
  int column = 0;
  enum class Mode { Modal, Absolute, Incremental } mode = Mode::Modal;  // AC( / IC(
};

// The words of one block, as read (program units, degrees), before they are executed.
struct Line {
  Value axis[3];    // X Y Z
  Value rotary[3];  // A B C
  Value center[3];  // I J K
  Value vector[3];  // A3 B3 C3
  Value cone[3];    // A6 B6 C6
  Value middle[3];  // A7 B7 C7 (ORICONIO's intermediate orientation)
  Value cr, f, s, t, d, adis, adispos, turn;
  int motion = -1, motion_column = 0;  // G0..G3 in this block
  int dwell_column = 0;                // G4
  bool exact_stop = false;             // G9
  bool m6 = false, end = false;
  int m6_column = 0;
  int spindle = -1, spindle_column = 0;  // M3 M4 M5
  int first_column = 0;                  // of the block's first word
  // A frame statement (its X Y Z are its values, not a move) and RPL=.
  enum class Frame { None, Trans, ATrans, Rot, ARot, Scale, AScale, Mirror, AMirror } frame = Frame::None;
  int frame_column = 0;
  std::string frame_name;
  Value rpl;
  // A drilling cycle called in this block (CYCLE81(...)), or MCALL (modal call / its end).
  std::string cycle;
  std::vector<std::optional<double>> cycle_args;
  std::vector<std::string> cycle_texts;  // "..." parameters by position (CYCLE800's _TC), else ""
  int cycle_column = 0;
  bool mcall = false;
  // A subprogram called (L123, CALL "NAME", NAME(args)), P times.
  std::string call;
  std::vector<double> call_args;
  int call_column = 0;
  Value p;
  // SUPA / G53 / G153: this block's X Y Z in machine coordinates (no offset, no frame).
  int machine_column = 0;
  // G74 / G75 (74, 75): the named axes (X1= or X) to the reference or fixed point FP=.
  int home = 0, home_column = 0;
  Value fp;
  bool machine_axis[3] = {false, false, false};  // X1= Y1= Z1=
  int machine_axis_column = 0;
};

class Reader {
 public:
  Reader(const std::string& name, const SinumerikOptions& options, kinematics::Program& program, SinumerikState& state,
         int file_index, int depth = 0)
      : name_(name), options_(options), program_(program), state_(state), file_index_(file_index), depth_(depth) {}
  // A subprogram's parameters (PROC NAME(REAL A, INT B)), bound from its call's values.
  std::vector<double> arguments;

  // The file's lines are kept (jumps and loops go back), then run from the first.
  void run(std::istream& in) {
    detail::LineSource source(in);
    std::string text;
    int number = 0;
    while (true) {
      const detail::LineSource::Result r = source.next(text);
      if (r == detail::LineSource::kEnd) break;
      seal_blocks();
      if (number == INT_MAX) fail_at(number, 0, "too many lines");
      ++number;
      line_ = number;
      if (r == detail::LineSource::kTooLong) fail(0, "line longer than 1 MiB (expected a text file of NC blocks)");
      lines_.push_back(text);
    }
    if (in.bad()) fail_at(number + 1, 0, "read error (expected a readable text file)");
    prescan();
    long long executed = 0;
    for (std::size_t pc = 0; pc < lines_.size();) {
      line_ = static_cast<int>(pc + 1);
      if (++executed > options_.max_lines) {
        fail(0, "more than " + std::to_string(options_.max_lines) +
                    " blocks run (a loop that never ends? expected program.max_lines to be larger)");
      }
      std::size_t next = pc + 1;
      prepare(lines_[pc]);
      if (flow(pc, next)) {
        pc = next;
        continue;
      }
      if (!block()) break;
      pc = next;
    }
  }

 private:
  [[noreturn]] void fail_at(int line, int column, const std::string& message) const {
    throw InputError(name_, line, column, message);
  }
  [[noreturn]] void fail(int column, const std::string& message) const { fail_at(line_, column, message); }
  [[noreturn]] void fail_here(const std::string& message) const { fail(column(i_), message); }
  int column(std::size_t i) const { return clamp_int(i + 1); }
  std::string where(int column) const { return name_ + ":" + std::to_string(line_) + ":" + std::to_string(column); }
  void warn(int column, const std::string& message) { program_.warnings.push_back(where(column) + ": " + message); }

  // An unsupported word: an error, or one warning per distinct word (then ignored).
  void unsupported(const std::string& word, int column, const std::string& why = {}) {
    const std::string text = word + " is not supported" + (why.empty() ? "" : " (" + why + ")");
    if (!options_.unsupported_as_warning) fail(column, text);
    if (state_.warned.insert(word).second) {
      warn(column, text + "; ignored (and so is every later " + word + ")");
    }
  }

  void prepare(const std::string& text);  // s_ from a line: upper case, checked
  bool block();                           // s_ read and run; false after M30
  // Program flow: the structures' partners, labels and block numbers of every line.
  void prescan();
  bool flow(std::size_t pc, std::size_t& next);  // a flow statement run (true), else false
  std::size_t jump_target(std::size_t pc, const std::string& how, int column);
  bool condition(int depth);
  double relation(int depth);
  void define();
  void call(const std::string& name, const std::vector<double>& args, int repeat, int column);
  void proc();                                                 // PROC NAME(type name, ...): the parameters bound
  std::string subprogram_file(const std::string& name) const;  // "" when not found
  std::string searched_for(const std::string& name) const {    // "NAME.SPF or .MPF in folders"
    std::string searched;
    for (const std::string& f : subprogram_folders()) searched += (searched.empty() ? "" : ", ") + f;
    return name + ".SPF or .MPF in " + searched;
  }
  std::vector<std::string> subprogram_folders() const;
  std::size_t body(std::string* label, long long* number);  // after N and a label: the first word
  void word();
  // (value, value, ...) after a subprogram's name, into Line::call_args; nothing without '('.
  void call_arguments(const std::string& name) {
    if (!at('(')) return;
    ++i_;
    while (!at(')')) {
      l_.call_args.push_back(expression(1));
      if (at(')')) break;
      expect(',', name + "( with values not separated by ',' (expected NAME(value, value, ...))");
    }
    ++i_;
  }
  void assignment(const std::string& address, int column);
  void skip_argument();
  void code(char letter, int column);
  void keyword(const std::string& name, int column);
  void set(Value& v, const char* name, double value, int column, Value::Mode mode = Value::Mode::Modal);
  double literal();
  double expression(int depth);
  double term(int depth);
  double factor(int depth);
  double primary(int depth);
  double function(const std::string& name, int column, int depth);
  double finite(double v, int column, const char* what) const;
  void skip_blanks() {
    while (i_ < s_.size() && is_blank(s_[i_])) ++i_;
  }
  bool at(char c) {
    skip_blanks();
    return i_ < s_.size() && s_[i_] == c;
  }
  void expect(char c, const std::string& message) {
    if (!at(c)) fail_here(message);
    ++i_;
  }
  std::string letters() {
    const std::size_t start = i_;
    while (i_ < s_.size() && is_upper(s_[i_])) ++i_;
    return s_.substr(start, i_ - start);
  }

  void execute();
  static int first_column(const Value (&v)[3]) {
    for (const Value& w : v)
      if (w.present) return w.column;
    return 0;
  }
  void motion();
  void apply_frame();
  void cycle(const std::string& name, const std::vector<std::optional<double>>& args, int column);
  // feed_mm_per_min > 0: that feed, else F times feed_factor.
  void cycle_move(const Eigen::Vector3d& frame_point, bool rapid, double feed_factor, int column,
                  double feed_mm_per_min = 0.0);
  double coarse_pitch_mm(double size, const std::string& name, int column) const;
  void swivel(const std::vector<std::optional<double>>& args, const std::vector<std::string>& texts, int column);
  Eigen::Matrix3d swivel_turn(int mode, double a_deg, double b_deg, double c_deg, int column) const;
  // The rigid motion that turning the rotary axes from zero to `rotary` gives a point held by
  // the linear axes (identity without the machine or with the rotaries at zero): the tip of
  // machine-coordinate point p lies at turned.first * p + turned.second.
  std::pair<Eigen::Matrix3d, Eigen::Vector3d> turned(const kinematics::RotaryWords& rotary) const {
    return detail::turn_from_zero(options_.tip_after_turn, state_.tool, rotary);
  }
  // From the machine's axes to where X Y Z are kept: the turn, or none in an axis program
  // (X Y Z are the machine's there already).
  std::pair<Eigen::Matrix3d, Eigen::Vector3d> machine_turn() const {
    if (state_.rotary_program) return {Eigen::Matrix3d::Identity(), Eigen::Vector3d::Zero()};
    return turned(state_.rotary);
  }
  // A straight move of the tip to `end` (workpiece frame) made by a cycle or a machine word,
  // at `feed_mm_per_min` (0: a rapid), with the tool as it stands; an exact stop at its end.
  // `what` names it in the range error; axes not `programmed` and still unknown hold still.
  void straight(const Eigen::Vector3d& end, double feed_mm_per_min, const char* what, int column,
                const std::array<bool, 3>& programmed = {true, true, true});
  void straight_to(const Eigen::Vector3d& to, int column) { straight(to, 0.0, "a move", column); }
  void retract(double fr, double fr_i_mm, int column);  // CYCLE800's _FR
  void home();                                          // G74 / G75
  void finish_block();                                  // the block's call and end
  // The rotaries turn from where they stand to `to`, the linear axes held, in steps of 1 deg.
  void turn_rotaries(const kinematics::RotaryWords& to, int column);
  // The spindle's direction (tip -> spindle) in the frame of X Y Z: the tool axis, or in an axis
  // program (X Y Z the machine's, at zero rotaries) the machine's spindle axis.
  Eigen::Vector3d spindle() const { return state_.rotary_program ? options_.spindle_axis : state_.tool_axis; }
  double tool_length_mm() const {
    const auto it = options_.tool_length_mm.find(state_.tool);
    return it == options_.tool_length_mm.end() ? 0.0 : it->second;
  }
  // The whole frame, swivel (CYCLE800) and programmable: a programmed point p lies at
  // frame_origin() + frame_linear() * p in the workpiece frame.
  Eigen::Matrix3d frame_linear() const { return state_.swivel_rotation * state_.frame_linear; }
  Eigen::Vector3d frame_origin() const {
    return offset() + state_.swivel_translation_mm + state_.swivel_rotation * state_.frame_translation_mm;
  }
  bool frame_turns() const { return !frame_linear().isIdentity(0.0); }
  Eigen::Vector3d placed(const Eigen::Vector3d& frame_point) const {
    return frame_origin() + frame_linear() * frame_point;
  }
  Eigen::Vector3d in_frame(const Eigen::Vector3d& workpiece_point) const {
    return frame_linear().inverse() * (workpiece_point - frame_origin());
  }
  void arc_in_plane(Block& block, bool clockwise, const Eigen::Vector3d& centre_origin);
  double length_mm(const Value& v) const { return v.value * (state_.inch ? kMmPerInch : 1.0); }
  // The work offset, and under D0 the tool's length: X Y Z then place the gauge point.
  Eigen::Vector3d offset() const {
    const auto it = options_.work_offsets_mm.find(state_.work_offset);
    const Eigen::Vector3d work =
        state_.work_offset == "G500" || it == options_.work_offsets_mm.end() ? Eigen::Vector3d::Zero() : it->second;
    return state_.tool_offset_off ? Eigen::Vector3d(work - tool_length_mm() * spindle()) : work;
  }
  Eigen::Vector3d target(std::array<bool, 3>& programmed) const;
  bool orient(Block& block);
  void arc(Block& block, bool clockwise);
  void append(Block block, const std::array<bool, 3>& programmed, bool reorients);
  // Hands the blocks before the first one an axis not yet known may still change to the
  // program's compact store (block_list.h).
  void seal_blocks() {
    kinematics::BlockList& blocks = program_.blocks;
    if (blocks.open() < 2 * kinematics::BlockList::kChunk) return;
    std::size_t first_open = blocks.size();
    for (const auto& pending : state_.pending)
      if (!pending.empty()) first_open = std::min(first_open, pending.front());
    blocks.seal_before(first_open);
  }

  const std::string& name_;
  const SinumerikOptions& options_;
  kinematics::Program& program_;
  SinumerikState& state_;
  int file_index_;
  int depth_;  // subprogram nesting
  int line_ = 0;
  std::string s_;  // the block, upper case outside strings
  std::size_t i_ = 0;
  std::size_t begin_ = 0;               // after a byte order mark
  std::vector<std::string> lines_;      // the file
  std::vector<long> partner_;           // IF -> ELSE/ENDIF, ELSE -> ENDIF, WHILE <-> ENDWHILE, ... (-1: none)
  std::vector<std::string> label_;      // "NAME" of "NAME:" on each line
  std::vector<long long> number_;       // its N number, -1: none
  std::map<std::string, double> vars_;  // DEF REAL/INT/BOOL variables
  mutable std::map<std::string, std::string> found_;           // subprogram name -> its file ("" none)
  std::map<std::size_t, std::pair<std::string, double>> for_;  // FOR line -> variable, end value
  Line l_;
};

// ---------------------------------------------------------------------------------------------
// Parsing

void Reader::prepare(const std::string& text) {
  std::size_t n = text.size();
  if (n > 0 && text[n - 1] == '\r') --n;  // CRLF files
  std::size_t begin = 0;
  if (line_ == 1 && n >= 3 && std::memcmp(text.data(), "\xEF\xBB\xBF", 3) == 0) begin = 3;  // BOM
  s_.assign(text, 0, n);
  bool quoted = false;
  for (std::size_t k = begin; k < n; ++k) {
    const char c = s_[k];
    const auto u = static_cast<unsigned char>(c);
    if (u < 0x20 || u == 0x7F) {
      if (c == '\t' || c == '\f' || c == '\v') continue;
      if (c == '\r') fail(column(k), "carriage return inside a line (expected \\n or \\r\\n line ends)");
      fail(column(k), "not a text file: control byte " + describe(c) + " (expected an NC program)");
    }
    if (c == '"') quoted = !quoted;
    if (!quoted) s_[k] = upper(c);
  }
  i_ = begin;
  begin_ = begin;
}

bool Reader::block() {
  const std::size_t n = s_.size();
  i_ = begin_;
  skip_blanks();
  if (i_ < n && s_[i_] == '%') return true;  // %_N_NAME_MPF, %MPF100: a header
  i_ = body(nullptr, nullptr);               // past N and a label
  l_ = Line{};
  while (true) {
    skip_blanks();
    if (i_ >= n || s_[i_] == ';') break;
    if (l_.first_column == 0) l_.first_column = column(i_);
    word();
  }
  execute();
  return !l_.end;
}

// ---------------------------------------------------------------------------------------------
// Program flow (Siemens, Programming Manual Job Planning, "Flexible NC programming"): labels
// NAME: and block numbers as jump targets; GOTOF (forward), GOTOB (backward), GOTO (forward,
// then backward), GOTOC (GOTO that goes on when the target is missing); IF cond GOTOx target;
// IF cond / ELSE / ENDIF; WHILE cond / ENDWHILE; FOR var = a TO b / ENDFOR; REPEAT / UNTIL
// cond; LOOP / ENDLOOP; DEF REAL | INT | BOOL name[=value], ... Conditions: == <> < > <= >=,
// AND OR XOR NOT, TRUE FALSE. A loop that runs more than SinumerikOptions::max_lines blocks
// is an error.

std::size_t Reader::body(std::string* label, long long* number) {
  std::size_t i = begin_;
  auto blanks = [&] {
    while (i < s_.size() && is_blank(s_[i])) ++i;
  };
  auto block_number = [&] {
    if (i < s_.size() && s_[i] == 'N' && i + 1 < s_.size() && is_digit(s_[i + 1])) {
      std::size_t k = i + 1;
      while (k < s_.size() && is_digit(s_[k])) ++k;
      if (k < s_.size() && (s_[k] == '.' || is_upper(s_[k]))) return;  // not a plain N number
      if (number && k - i - 1 <= 15) *number = std::stoll(s_.substr(i + 1, k - i - 1));
      i = k;
      blanks();
    }
  };
  blanks();
  block_number();
  // A label: a name of letters, digits and _ starting with a letter or _, then ':'.
  if (i < s_.size() && is_upper(s_[i])) {
    std::size_t k = i;
    while (k < s_.size() && (is_upper(s_[k]) || is_digit(s_[k]))) ++k;
    std::size_t c = k;
    while (c < s_.size() && is_blank(s_[c])) ++c;
    if (c < s_.size() && s_[c] == ':' && k - i >= 2) {
      if (label) *label = s_.substr(i, k - i);
      i = c + 1;
      blanks();
      block_number();
    }
  }
  return i;
}

void Reader::prescan() {
  const std::size_t n = lines_.size();
  partner_.assign(n, -1);
  label_.assign(n, std::string());
  number_.assign(n, -1);
  struct Open {
    std::string word;
    std::size_t line;
    int column;
  };
  std::vector<Open> open;
  const int saved = line_;
  for (std::size_t k = 0; k < n; ++k) {
    line_ = static_cast<int>(k + 1);
    // Only the block's start matters here (N, a label, the first word): its first 80 bytes,
    // in upper case (the whole line is checked when it runs); an IF line whole, for its GOTO.
    const std::string& raw = lines_[k];
    begin_ = k == 0 && raw.compare(0, 3, "\xEF\xBB\xBF") == 0 ? 3 : 0;
    auto take = [&](std::size_t bytes) {
      s_.assign(raw, 0, bytes);
      for (char& ch : s_) ch = upper(ch);
      i_ = body(&label_[k], &number_[k]);
    };
    take(std::min<std::size_t>(raw.size(), begin_ + 80));
    // The whole line where blanks, N or a label fill the window up to where the first word may
    // be cut (the fuzzer put an ENDFOR after 170 form feeds), or for an IF.
    if (s_.size() < raw.size() && (i_ + 16 > s_.size() || s_.compare(i_, 2, "IF") == 0)) take(raw.size());
    const std::size_t start = i_;
    const std::string word = letters();
    const int col = column(start);
    auto close = [&](const char* opener, const char* alt) {
      if (open.empty() || (open.back().word != opener && (alt == nullptr || open.back().word != alt)))
        fail(col,
             word + " without its " + opener + (open.empty() ? "" : " (the open one is " + open.back().word + ")"));
      return open.back().line;
    };
    if (word == "IF") {
      if (s_.find("GOTO", i_) == std::string::npos) open.push_back({word, k, col});  // IF cond GOTOx: one line
    } else if (word == "ELSE") {
      const std::size_t at = close("IF", nullptr);
      partner_[at] = static_cast<long>(k);
      open.back() = {"ELSE", k, col};
    } else if (word == "ENDIF") {
      const std::size_t at = close("IF", "ELSE");
      partner_[at] = static_cast<long>(k);
      open.pop_back();
    } else if (word == "WHILE" || word == "FOR" || word == "REPEAT" || word == "LOOP") {
      open.push_back({word, k, col});
    } else if (word == "ENDWHILE" || word == "ENDFOR" || word == "UNTIL" || word == "ENDLOOP") {
      const char* opener = word == "ENDWHILE" ? "WHILE"
                           : word == "ENDFOR" ? "FOR"
                           : word == "UNTIL"  ? "REPEAT"
                                              : "LOOP";
      const std::size_t at = close(opener, nullptr);
      partner_[at] = static_cast<long>(k);
      partner_[k] = static_cast<long>(at);
      open.pop_back();
    }
  }
  if (!open.empty()) {
    line_ = static_cast<int>(open.back().line + 1);
    const std::string& w = open.back().word;
    fail(open.back().column, w + " without its " +
                                 (w == "IF" || w == "ELSE" ? "ENDIF"
                                  : w == "WHILE"           ? "ENDWHILE"
                                  : w == "FOR"             ? "ENDFOR"
                                  : w == "REPEAT"          ? "UNTIL"
                                                           : "ENDLOOP") +
                                 " before the end of the file");
  }
  line_ = saved;
}

std::size_t Reader::jump_target(std::size_t pc, const std::string& how, int how_column) {
  skip_blanks();
  const std::size_t start = i_;
  std::string target;
  while (i_ < s_.size() && (is_upper(s_[i_]) || is_digit(s_[i_]))) target.push_back(s_[i_++]);
  if (target.empty()) fail(how_column, how + " without its target (expected a label or a block number N..)");
  long long number = -1;
  if (target.size() > 1 && target[0] == 'N' && std::all_of(target.begin() + 1, target.end(), is_digit) &&
      target.size() <= 16)
    number = std::stoll(target.substr(1));
  auto matches = [&](std::size_t k) { return label_[k] == target || (number >= 0 && number_[k] == number); };
  const bool forward = how != "GOTOB", backward = how != "GOTOF";
  if (forward)
    for (std::size_t k = pc + 1; k < lines_.size(); ++k)
      if (matches(k)) return k;
  if (backward)
    for (std::size_t k = pc + 1; k-- > 0;)
      if (matches(k)) return k;
  if (how == "GOTOC") return pc + 1;
  fail(column(start), how + " " + target + ": no such label or block number " +
                          (forward && backward ? "in the program"
                           : forward           ? "after this line"
                                               : "before this line"));
}

// A condition: OR of AND of [NOT] relations (a relation: an expression, or two compared).
bool Reader::condition(int depth) {
  if (depth > kMaxExpressionDepth) fail_here("condition nested more than 64 deep");
  auto word_is = [&](const char* w) {
    skip_blanks();
    const std::size_t n = std::strlen(w);
    if (s_.compare(i_, n, w) != 0) return false;
    if (i_ + n < s_.size() && (is_upper(s_[i_ + n]) || is_digit(s_[i_ + n]))) return false;
    i_ += n;
    return true;
  };
  std::function<bool(int)> unary = [&](int d) -> bool {
    if (word_is("NOT")) return !unary(d + 1);
    skip_blanks();
    if (at('(')) {
      // A condition in parentheses, IF (A <= B) AND (C > 0); unless an operator follows the
      // ')', when the parentheses were an expression's: (R1 + 2) > 3.
      const std::size_t open = i_++;
      const bool inner = condition(d + 1);
      skip_blanks();
      if (at(')')) {
        ++i_;
        skip_blanks();
        if (i_ >= s_.size() || std::strchr("+-*/<>=", s_[i_]) == nullptr) return inner;
      }
      i_ = open;
    }
    return relation(d) != 0.0;
  };
  auto conjunction = [&](int d) {
    bool v = unary(d);
    while (word_is("AND")) v = unary(d) && v;
    return v;
  };
  bool v = conjunction(depth);
  while (true) {
    if (word_is("OR")) {
      v = conjunction(depth) || v;
    } else if (word_is("XOR")) {
      v = conjunction(depth) != v;
    } else {
      return v;
    }
  }
}

double Reader::relation(int depth) {
  const double a = expression(depth);
  skip_blanks();
  static const char* const kOps[] = {"==", "<>", "<=", ">=", "<", ">"};
  for (const char* op : kOps) {
    const std::size_t n = std::strlen(op);
    if (s_.compare(i_, n, op) != 0) continue;
    i_ += n;
    const double b = expression(depth);
    const std::string o(op);
    return (o == "=="   ? a == b
            : o == "<>" ? a != b
            : o == "<=" ? a <= b
            : o == ">=" ? a >= b
            : o == "<"  ? a < b
                        : a > b)
               ? 1.0
               : 0.0;
  }
  return a;
}

// DEF REAL | INT | BOOL name[=value][, name[=value] ...]: variables of this program, 0 at first.
void Reader::define() {
  const int col = column(i_);
  skip_blanks();
  const std::string type = letters();
  if (type != "REAL" && type != "INT" && type != "BOOL")
    fail(col, "DEF " + type + " is not supported (expected DEF REAL, INT or BOOL)");
  while (true) {
    skip_blanks();
    const std::size_t start = i_;
    std::string name;
    while (i_ < s_.size() && (is_upper(s_[i_]) || is_digit(s_[i_]))) name.push_back(s_[i_++]);
    if (name.empty()) fail(column(start), "DEF " + type + " without a name");
    if (name.size() < 2 || (name[0] == 'R' && std::all_of(name.begin() + 1, name.end(), is_digit)))
      fail(column(start), "DEF " + name + " (expected a name of 2 or more characters, not an address or R parameter)");
    double value = 0.0;
    if (at('=')) {
      ++i_;
      value = expression(0);
    }
    if (type == "INT") value = std::round(value);
    if (type == "BOOL") value = value != 0.0 ? 1.0 : 0.0;
    vars_[name] = value;
    if (!at(',')) break;
    ++i_;
  }
  skip_blanks();
  if (i_ < s_.size() && s_[i_] != ';')
    fail_here("unexpected text after DEF (expected a comment or the end of the block)");
}

bool Reader::flow(std::size_t pc, std::size_t& next) {
  i_ = body(nullptr, nullptr);
  const std::size_t start = i_;
  const std::string word = letters();
  if (word.size() < 2) return false;  // an address (X10, G1, N...): most blocks, no flow word
  const int col = column(start);
  auto finish = [&] {
    skip_blanks();
    if (i_ < s_.size() && s_[i_] != ';')
      fail_here("unexpected text after " + word + " (expected the end of the block)");
  };
  const long partner = partner_[pc];
  // A loop or branch word whose partner prescan() did not pair is refused, not followed (the
  // fuzzer found an ENDFOR that the scan had missed, followed to line -1).
  static const std::map<std::string, std::string> kPartner = {
      {"ELSE", "ENDIF"}, {"WHILE", "ENDWHILE"}, {"ENDWHILE", "WHILE"}, {"FOR", "ENDFOR"},
      {"ENDFOR", "FOR"}, {"UNTIL", "REPEAT"},   {"ENDLOOP", "LOOP"}};
  if (partner < 0)
    if (const auto it = kPartner.find(word); it != kPartner.end()) fail(col, word + " without its " + it->second);
  if (word == "PROC") {
    proc();
  } else if (word == "RET") {
    next = lines_.size();  // back to the caller
  } else if (word == "DEF") {
    define();
  } else if (word == "GOTOF" || word == "GOTOB" || word == "GOTO" || word == "GOTOC") {
    next = jump_target(pc, word, col);
    finish();
  } else if (word == "IF") {
    const bool holds = condition(0);
    skip_blanks();
    const std::size_t jump_at = i_;
    const std::string go = letters();
    if (go == "GOTOF" || go == "GOTOB" || go == "GOTO" || go == "GOTOC") {
      const std::size_t to = jump_target(pc, go, column(jump_at));
      if (holds) next = to;
    } else {
      if (!go.empty())
        fail(column(jump_at),
             "unexpected " + go + " after IF's condition (expected GOTOF, GOTOB, GOTO or the end of the block)");
      // (The scan took an IF whose comment says GOTO for a one-line IF: no ENDIF is known.)
      if (partner < 0)
        fail(col, "IF without GOTO and without its ENDIF (expected IF cond GOTOF label, or IF ... ENDIF)");
      if (!holds) next = static_cast<std::size_t>(partner) + 1;  // after ELSE, or after ENDIF
    }
    finish();
  } else if (word == "CASE") {
    // CASE (expr) OF c1 GOTOF l1 c2 GOTOB l2 ... [DEFAULT GOTOF ld]: the jump of the first
    // constant equal to the value, else DEFAULT's, else on to the next block. Every target is
    // checked, taken or not.
    expect('(', "CASE without '(' (expected CASE (expression) OF constant GOTOF label ...)");
    const double value = expression(1);
    expect(')', "CASE ( without its closing ')'");
    skip_blanks();
    if (letters() != "OF") fail_here("CASE without OF (expected CASE (expression) OF constant GOTOF label ...)");
    bool matched = false, any = false;
    while (true) {
      skip_blanks();
      if (i_ >= s_.size() || s_[i_] == ';') break;
      const std::size_t at_case = i_;
      const bool fallback = s_.compare(i_, 7, "DEFAULT") == 0;
      double constant = 0.0;
      if (fallback)
        i_ += 7;
      else
        constant = expression(1);
      skip_blanks();
      const std::size_t jump_at = i_;
      const std::string go = letters();
      if (go != "GOTOF" && go != "GOTOB" && go != "GOTO" && go != "GOTOC")
        fail(column(jump_at), "CASE's " + std::string(fallback ? "DEFAULT" : num(constant)) +
                                  " without its jump (expected GOTOF or GOTOB and a label)");
      const std::size_t to = jump_target(pc, go, column(jump_at));
      if (!matched && (fallback || constant == value)) {
        next = to;
        matched = true;
      }
      any = true;
      if (fallback) {
        skip_blanks();
        if (i_ < s_.size() && s_[i_] != ';')
          fail(column(at_case), "CASE's DEFAULT before another case (expected it last)");
      }
    }
    if (!any) fail(col, "CASE without a case (expected constant GOTOF label after OF)");
  } else if (word == "ELSE") {
    next = static_cast<std::size_t>(partner) + 1;  // the true branch ends here
  } else if (word == "ENDIF" || word == "REPEAT" || word == "LOOP") {
    finish();
  } else if (word == "WHILE") {
    if (!condition(0)) next = static_cast<std::size_t>(partner) + 1;
    finish();
  } else if (word == "ENDWHILE") {
    next = static_cast<std::size_t>(partner);
  } else if (word == "ENDLOOP") {
    next = static_cast<std::size_t>(partner) + 1;
  } else if (word == "UNTIL") {
    if (!condition(0)) next = static_cast<std::size_t>(partner) + 1;
    finish();
  } else if (word == "FOR") {
    skip_blanks();
    const std::size_t at_var = i_;
    std::string name;
    while (i_ < s_.size() && (is_upper(s_[i_]) || is_digit(s_[i_]))) name.push_back(s_[i_++]);
    const bool r =
        name.size() > 1 && name[0] == 'R' && std::all_of(name.begin() + 1, name.end(), is_digit) && name.size() <= 4;
    if (!r && !vars_.count(name))
      fail(column(at_var), "FOR " + name + " (expected an R parameter or a DEF INT variable)");
    expect('=', "FOR without '=' (expected FOR var = start TO end)");
    const double from = expression(0);
    skip_blanks();
    if (letters() != "TO") fail_here("FOR without TO (expected FOR var = start TO end)");
    const double to = expression(0);
    finish();
    (r ? state_.r[static_cast<std::size_t>(std::stoi(name.substr(1)))] : vars_[name]) = from;
    for_[pc] = {name, to};
    if (from > to) next = static_cast<std::size_t>(partner) + 1;
  } else if (word == "ENDFOR") {
    const std::size_t head = static_cast<std::size_t>(partner);
    const auto& [name, to] = for_.at(head);
    const bool r = name[0] == 'R' && vars_.count(name) == 0;
    double& v = r ? state_.r[static_cast<std::size_t>(std::stoi(name.substr(1)))] : vars_[name];
    v += 1.0;
    if (v <= to) next = head + 1;
  } else {
    return false;
  }
  return true;
}

// ---------------------------------------------------------------------------------------------
// Subprograms: L123, CALL "NAME", NAME or NAME(values), P times, from NAME.SPF (or .MPF) in the
// calling program's folder, then SinumerikOptions::subroutine_path. They share the modal state
// and the R parameters; PROC NAME(REAL A, INT B) binds the call's values; M17, RET, M2 or M30
// go back.

std::vector<std::string> Reader::subprogram_folders() const {
  std::vector<std::string> folders;
  const std::filesystem::path own = std::filesystem::path(name_).parent_path();
  folders.push_back(own.empty() ? std::string(".") : own.string());
  for (const std::string& f : options_.subroutine_path) folders.push_back(f);
  return folders;
}

std::string Reader::subprogram_file(const std::string& name) const {
  // Asked for every word the reader does not know: each name is looked up on disk once.
  if (const auto known = found_.find(name); known != found_.end()) return known->second;
  std::string& found = found_[name];
  std::string lower = name;
  for (char& ch : lower) ch = static_cast<char>(std::tolower(static_cast<unsigned char>(ch)));
  for (const std::string& folder : subprogram_folders()) {
    for (const std::string& base : {name, lower}) {
      for (const char* ext : {".SPF", ".spf", ".MPF", ".mpf"}) {
        const std::filesystem::path p = std::filesystem::path(folder) / (base + ext);
        std::error_code ec;
        if (std::filesystem::is_regular_file(p, ec)) return found = p.lexically_normal().string();
      }
    }
  }
  return found;
}

void Reader::call(const std::string& name, const std::vector<double>& args, int repeat, int column) {
  if (depth_ >= kMaxCallDepth)
    fail(column,
         name + ": subprograms nested more than " + std::to_string(kMaxCallDepth) + " deep (one calling itself?)");
  const std::string path = subprogram_file(name);
  if (path.empty()) fail(column, "subprogram " + name + " not found (expected " + searched_for(name) + ")");
  int index = -1;
  for (std::size_t k = 0; k < program_.files.size(); ++k)
    if (program_.files[k] == path) index = static_cast<int>(k);
  if (index < 0) {
    index = static_cast<int>(program_.files.size());
    program_.files.push_back(path);
  }
  for (int k = 0; k < repeat; ++k) {
    std::ifstream in(path, std::ios::binary);
    if (!in) fail(column, "subprogram " + path + " cannot be read");
    Reader sub(program_.files[static_cast<std::size_t>(index)], options_, program_, state_, index, depth_ + 1);
    sub.arguments = args;
    sub.run(in);
  }
}

void Reader::proc() {
  skip_blanks();
  const std::string name = letters();
  if (name.empty()) fail_here("PROC without its name");
  if (!at('(')) return;
  ++i_;
  std::size_t k = 0;
  while (!at(')')) {
    const int col = column(i_);
    const std::string type = letters();
    if (type != "REAL" && type != "INT" && type != "BOOL")
      fail(col, "PROC parameter of type " + (type.empty() ? std::string("?") : type) +
                    " (expected REAL, INT or BOOL; VAR and other types are not supported)");
    skip_blanks();
    std::string param;
    while (i_ < s_.size() && (is_upper(s_[i_]) || is_digit(s_[i_]))) param.push_back(s_[i_++]);
    if (param.size() < 2) fail(col, "PROC parameter without a name of 2 or more characters");
    double value = k < arguments.size() ? arguments[k] : 0.0;
    if (type == "INT") value = std::round(value);
    if (type == "BOOL") value = value != 0.0 ? 1.0 : 0.0;
    vars_[param] = value;
    ++k;
    if (at(')')) break;
    expect(',', "PROC parameters not separated by ','");
  }
  ++i_;
  if (arguments.size() > k)
    fail(column(i_), "PROC " + name + " takes " + std::to_string(k) + " parameter(s), the call gave " +
                         std::to_string(arguments.size()));
  // SAVE, DISPLOF, SBLOF and the like: how the control shows and restores it, not the path.
  skip_blanks();
  i_ = s_.size();
}

void Reader::word() {
  const std::size_t start = i_;
  const int col = column(start);
  const char c = s_[i_];
  if (c == '$') {
    ++i_;
    const std::string name = "$" + letters();
    unsupported(name, col, "system variables");
    skip_argument();
    return;
  }
  if (c == '/' && l_.first_column == col) {
    ++i_;
    unsupported("/", col, "block skip");
    return;
  }
  if (!is_upper(c)) fail(col, "unexpected " + describe(c) + " (expected a word: an address and its value)");
  const std::string name = letters();
  // An address with a numeric extension (R1, A3, CR...) is always followed by '='; a letter
  // followed by digits and no '=' is the letter and its value (X10, G1, A3 = A at 3 deg).
  std::size_t j = i_;
  while (j < s_.size() && is_digit(s_[j])) ++j;
  std::size_t k = j;
  while (k < s_.size() && is_blank(s_[k])) ++k;
  if (k < s_.size() && s_[k] == '=') {
    const std::string address = name + s_.substr(i_, j - i_);
    i_ = k + 1;
    assignment(address, col);
    return;
  }
  if (name.size() == 1) {
    code(name[0], col);
    return;
  }
  const std::string full = name + s_.substr(i_, j - i_);
  i_ = j;
  keyword(full, col);
}

void Reader::set(Value& v, const char* name, double value, int column, Value::Mode mode) {
  if (v.present) fail(column, std::string(name) + " programmed twice in one block");
  v.present = true;
  v.value = value;
  v.column = column;
  v.mode = mode;
}

// A number written after an address letter without '=': [sign] digits [. digits] [EX [sign]
// digits].
double Reader::literal() {
  skip_blanks();
  const std::size_t start = i_;
  std::string text;
  if (i_ < s_.size() && (s_[i_] == '+' || s_[i_] == '-')) text += s_[i_++];
  bool digits = false;
  while (i_ < s_.size() && is_digit(s_[i_])) text += s_[i_++], digits = true;
  if (i_ < s_.size() && s_[i_] == '.') {
    text += s_[i_++];
    while (i_ < s_.size() && is_digit(s_[i_])) text += s_[i_++], digits = true;
  }
  if (!digits) {
    i_ = start;
    fail_here(i_ < s_.size() ? "unexpected " + describe(s_[i_]) + " (expected a number)"
                             : std::string("end of the block (expected a number)"));
  }
  if (i_ + 1 < s_.size() && s_[i_] == 'E' && s_[i_ + 1] == 'X') {
    i_ += 2;
    text += 'e';
    if (i_ < s_.size() && (s_[i_] == '+' || s_[i_] == '-')) text += s_[i_++];
    bool exponent = false;
    while (i_ < s_.size() && is_digit(s_[i_])) text += s_[i_++], exponent = true;
    if (!exponent) fail_here("EX without its exponent (expected digits, as in 1.5EX3)");
  }
  if (text.size() > 400) fail(column(start), "number with more than 400 characters");
  // from_chars: exact like strtod, without its locale.
  double v = 0.0;
  const char* first = text.data() + (text[0] == '+' ? 1 : 0);
  const auto [end, ec] = std::from_chars(first, text.data() + text.size(), v);
  if (ec == std::errc::result_out_of_range) {
    // Underflow (1EX-400) is zero; overflow is an error.
    const auto e = text.find('e');
    if (e == std::string::npos || text[e + 1] != '-') {
      fail(column(start), "number " + text + " is out of range (expected a finite value)");
    }
    v = 0.0;
  } else if (ec != std::errc() || end != text.data() + text.size() || !std::isfinite(v)) {
    fail(column(start), "number " + text + " is out of range (expected a finite value)");
  }
  return v;
}

double Reader::finite(double v, int column, const char* what) const {
  if (!std::isfinite(v)) fail(column, std::string(what) + " is not a finite number");
  return v;
}

double Reader::expression(int depth) {
  if (depth > kMaxExpressionDepth) fail_here("expression nested more than 64 deep");
  double v = term(depth);
  while (true) {
    skip_blanks();
    if (i_ >= s_.size() || (s_[i_] != '+' && s_[i_] != '-')) return v;
    const char op = s_[i_];
    const int col = column(i_);
    ++i_;
    const double w = term(depth);
    v = finite(op == '+' ? v + w : v - w, col, "the result");
  }
}

double Reader::term(int depth) {
  double v = factor(depth);
  while (true) {
    skip_blanks();
    if (i_ >= s_.size() || (s_[i_] != '*' && s_[i_] != '/')) return v;
    const char op = s_[i_];
    const int col = column(i_);
    ++i_;
    const double w = factor(depth);
    if (op == '/' && w == 0.0) fail(col, "division by zero");
    v = finite(op == '*' ? v * w : v / w, col, "the result");
  }
}

double Reader::factor(int depth) {
  if (depth > kMaxExpressionDepth) fail_here("expression nested more than 64 deep");
  skip_blanks();
  if (i_ < s_.size() && (s_[i_] == '+' || s_[i_] == '-')) {
    const bool minus = s_[i_] == '-';
    ++i_;
    const double v = factor(depth + 1);
    return minus ? -v : v;
  }
  return primary(depth);
}

double Reader::primary(int depth) {
  skip_blanks();
  if (i_ >= s_.size() || s_[i_] == ';') fail_here("end of the block (expected a value)");
  const char c = s_[i_];
  const int col = column(i_);
  if (is_digit(c) || c == '.') return literal();
  if (c == '(') {
    ++i_;
    const double v = expression(depth + 1);
    expect(')', "'(' without its closing ')'");
    return v;
  }
  if (c == '$') fail(col, "system variables ($...) are not supported in expressions");
  if (!is_upper(c)) fail(col, "unexpected " + describe(c) + " (expected a value)");
  const std::size_t start = i_;
  while (i_ < s_.size() && (is_upper(s_[i_]) || is_digit(s_[i_]))) ++i_;
  const std::string name = s_.substr(start, i_ - start);
  if (name.size() > 1 && name[0] == 'R' &&
      std::all_of(name.begin() + 1, name.end(), [](char ch) { return is_digit(ch); })) {
    if (name.size() > 4) fail(col, name + " (expected R0..R999)");
    return state_.r[static_cast<std::size_t>(std::stoi(name.substr(1)))];
  }
  if (const auto var = vars_.find(name); var != vars_.end()) return var->second;
  if (name == "TRUE" || name == "FALSE") return name == "TRUE" ? 1.0 : 0.0;
  if (at('(')) {
    if (name == "AC" || name == "IC") {
      fail(col,
           name + "( inside an expression (expected it as the whole value of one coordinate, X=" + name + "(...))");
    }
    ++i_;
    return function(name, col, depth + 1);
  }
  fail(col, "unknown name " + name + " in an expression (expected a number, R0..R999, a DEF variable or a function)");
}

double Reader::function(const std::string& name, int col, int depth) {
  static const char* const kKnown[] = {"SIN",  "COS", "TAN", "ASIN",  "ACOS", "ATAN2",
                                       "SQRT", "ABS", "POT", "TRUNC", "ROUND"};
  if (std::none_of(std::begin(kKnown), std::end(kKnown), [&](const char* k) { return name == k; })) {
    fail(col, "unknown function " + name + "( (expected SIN COS TAN ASIN ACOS ATAN2 SQRT ABS POT TRUNC ROUND)");
  }
  const double x = expression(depth);
  double y = 0.0;
  if (name == "ATAN2") {
    expect(',', "ATAN2 with one argument (expected ATAN2(y, x))");
    y = expression(depth);
  }
  expect(')', name + "( without its closing ')'");
  double v = 0.0;
  if (name == "SIN") {
    v = std::sin(x * kDegToRad);
  } else if (name == "COS") {
    v = std::cos(x * kDegToRad);
  } else if (name == "TAN") {
    v = std::tan(x * kDegToRad);
  } else if (name == "ASIN" || name == "ACOS") {
    if (!(std::abs(x) <= 1.0)) fail(col, name + " of " + num(x) + " (expected a value in [-1, 1])");
    v = (name == "ASIN" ? std::asin(x) : std::acos(x)) / kDegToRad;
  } else if (name == "ATAN2") {
    if (x == 0.0 && y == 0.0) fail(col, "ATAN2(0, 0) has no angle");
    v = std::atan2(x, y) / kDegToRad;
  } else if (name == "SQRT") {
    if (x < 0.0) fail(col, "SQRT of " + num(x) + " (expected a value >= 0)");
    v = std::sqrt(x);
  } else if (name == "ABS") {
    v = std::abs(x);
  } else if (name == "POT") {
    v = x * x;  // POT: the square (Siemens)
  } else if (name == "TRUNC") {
    v = std::trunc(x);
  } else {
    v = std::round(x);
  }
  return finite(v, col, (name + "(...)").c_str());
}

// Skips an ignored word's value: `=` and what follows up to a blank outside ( ) and quotes, or
// a ( ) argument list.
void Reader::skip_argument() {
  skip_blanks();
  if (i_ < s_.size() && s_[i_] == '=') ++i_;
  int depth = 0;
  bool quoted = false;
  const std::size_t start = i_;
  while (i_ < s_.size()) {
    const char c = s_[i_];
    if (quoted) {
      quoted = c != '"';
    } else if (c == '"') {
      quoted = true;
    } else if (c == '(' || c == '[') {
      ++depth;
    } else if (c == ')' || c == ']') {
      --depth;
    } else if ((is_blank(c) || c == ';') && depth <= 0) {
      break;
    }
    ++i_;
  }
  if (quoted) fail(column(start), "string without its closing '\"'");
  if (depth > 0) fail(column(start), "'(' without its closing ')'");
}

// `address=value`.
void Reader::assignment(const std::string& address, int col) {
  skip_blanks();
  if (address.size() == 1) {
    const char a = address[0];
    const char* kCoordinates = "XYZABCIJK";
    if (std::strchr(kCoordinates, a) != nullptr) {
      // X=AC(..) / X=IC(..): absolute or incremental for this coordinate only.
      Value::Mode mode = Value::Mode::Modal;
      if (i_ + 2 < s_.size() && (s_.compare(i_, 2, "AC") == 0 || s_.compare(i_, 2, "IC") == 0)) {
        std::size_t k = i_ + 2;
        while (k < s_.size() && is_blank(s_[k])) ++k;
        if (k < s_.size() && s_[k] == '(') {
          mode = s_[i_] == 'A' ? Value::Mode::Absolute : Value::Mode::Incremental;
          const std::string fn = s_.substr(i_, 2);
          i_ = k + 1;
          const double v = expression(1);
          expect(')', fn + "( without its closing ')'");
          Value* slot = nullptr;
          if (a >= 'X')
            slot = &l_.axis[a - 'X'];
          else if (a >= 'I')
            slot = &l_.center[a - 'I'];
          else
            slot = &l_.rotary[a - 'A'];
          set(*slot, address.c_str(), v, col, mode);
          return;
        }
      }
      const double v = expression(0);
      Value* slot = a >= 'X' ? &l_.axis[a - 'X'] : a >= 'I' ? &l_.center[a - 'I'] : &l_.rotary[a - 'A'];
      set(*slot, address.c_str(), v, col);
      return;
    }
    if (a == 'T' && at('"')) {
      const std::size_t start = i_++;
      const std::size_t close = s_.find('"', i_);
      if (close == std::string::npos) fail(column(start), "string without its closing '\"'");
      const std::string text = s_.substr(i_, close - i_);
      i_ = close + 1;
      const bool numeric = !text.empty() && text.size() <= 5 &&
                           std::all_of(text.begin(), text.end(), [](char ch) { return is_digit(ch); });
      if (!numeric) {
        // A tool by its name: numbered in the order the program names them (the tool library
        // numbers its tools), with a note the first time.
        if (text.empty() || text.size() > 64)
          fail(col, "tool name T=\"" + text.substr(0, 64) + "\" (expected 1..64 characters)");
        auto [it, added] = state_.tool_names.emplace(text, static_cast<int>(state_.tool_names.size()) + 1);
        if (added)
          warn(col, "tool T=\"" + text + "\" taken as tool " + std::to_string(it->second) +
                        " (tools named in the program are numbered in the order they are named)");
        set(l_.t, "T", it->second, col);
        return;
      }
      set(l_.t, "T", std::stod(text), col);
      return;
    }
    if (a == 'F') return set(l_.f, "F", expression(0), col);
    if (a == 'S') return set(l_.s, "S", expression(0), col);
    if (a == 'T') return set(l_.t, "T", expression(0), col);
    if (a == 'D') return set(l_.d, "D", expression(0), col);
  }
  if (address[0] == 'R' && address.size() > 1 && is_digit(address[1])) {
    const std::string digits = address.substr(1);
    if (digits.size() > 3) fail(col, address + " (expected R0..R999)");
    const double v = expression(0);
    state_.r[static_cast<std::size_t>(std::stoi(digits))] = v;
    return;
  }
  if (const auto var = vars_.find(address); var != vars_.end()) {
    var->second = expression(0);  // a DEF variable
    return;
  }
  if (address == "CR") return set(l_.cr, "CR", expression(0), col);
  if (address == "TURN") return set(l_.turn, "TURN", expression(0), col);
  if (address == "FP") return set(l_.fp, "FP", expression(0), col);
  if (address == "X1" || address == "Y1" || address == "Z1") {
    // A machine axis by its name, in G74 / G75 (its value is not used).
    l_.machine_axis[address[0] - 'X'] = true;
    if (l_.machine_axis_column == 0) l_.machine_axis_column = col;
    expression(0);
    return;
  }
  if (address == "RPL") return set(l_.rpl, "RPL", expression(0), col);
  if (address == "ADIS") return set(l_.adis, "ADIS", expression(0), col);
  if (address == "ADISPOS") return set(l_.adispos, "ADISPOS", expression(0), col);
  static const char* const kVector[3] = {"A3", "B3", "C3"};
  static const char* const kCone[3] = {"A6", "B6", "C6"};
  static const char* const kMiddle[3] = {"A7", "B7", "C7"};
  for (int k = 0; k < 3; ++k) {
    if (address == kVector[k]) return set(l_.vector[k], kVector[k], expression(0), col);
    if (address == kCone[k]) return set(l_.cone[k], kCone[k], expression(0), col);
    if (address == kMiddle[k]) return set(l_.middle[k], kMiddle[k], expression(0), col);
  }
  if (address == "NUT") {
    // The manual gives NUT's range (0..180 deg) but not whether it is the full or the half
    // opening, nor which of the two cones of that opening through the start and the end it
    // selects; the reader would have to guess.
    fail(col,
         "NUT= (the cone's opening angle) is not supported: the manual does not fix which cone it "
         "selects (expected the cone by ORICONCW/ORICONCCW with its axis A6 B6 C6, by ORICONIO with "
         "A7 B7 C7, or by ORICONTO)");
  }
  unsupported(address + "=", col);
  skip_argument();
}

// A letter and its number: X10, G1, N7, M30, "X -1320". One case per address letter (and per
// G or M code within them): the control's table of addresses, kept as one table to read
// against the manual; most cases are a line or two.
void Reader::code(char letter, int col) {
  switch (letter) {
    case 'X':
    case 'Y':
    case 'Z':
      return set(l_.axis[letter - 'X'], std::string(1, letter).c_str(), literal(), col);
    case 'A':
    case 'B':
    case 'C':
      return set(l_.rotary[letter - 'A'], std::string(1, letter).c_str(), literal(), col);
    case 'I':
    case 'J':
    case 'K':
      return set(l_.center[letter - 'I'], std::string(1, letter).c_str(), literal(), col);
    case 'F':
      return set(l_.f, "F", literal(), col);
    case 'S':
      return set(l_.s, "S", literal(), col);
    case 'T':
      return set(l_.t, "T", literal(), col);
    case 'D':
      return set(l_.d, "D", literal(), col);
    case 'R':
      fail(col, "R parameter without '=' (expected an assignment such as R1=10)");
    case 'L': {
      // L123: the subprogram L123 (L123.SPF).
      const double v = literal();
      if (!(v >= 0.0 && v <= 99999999.0 && v == std::floor(v)))
        fail(col, "L" + num(v) + " (expected L and a whole number)");
      if (!l_.call.empty()) fail(col, "a second subprogram call in one block (expected one)");
      l_.call = "L" + std::to_string(static_cast<long long>(v));
      l_.call_column = col;
      skip_blanks();
      call_arguments(l_.call);  // L140(2): values for its PROC
      return;
    }
    case 'P':
      return set(l_.p, "P", literal(), col);
    case 'N': {
      const double v = literal();
      if (v < 0.0 || v != std::floor(v)) fail(col, "block number N" + num(v) + " (expected a whole number)");
      return;
    }
    default:
      break;
  }
  if (letter != 'G' && letter != 'M') {
    std::string word(1, letter);
    skip_blanks();
    if (i_ < s_.size() && (is_digit(s_[i_]) || s_[i_] == '.' || s_[i_] == '-' || s_[i_] == '+')) {
      literal();
    }
    unsupported(word, col);
    if (at('(')) skip_argument();
    return;
  }
  const double v = literal();
  if (!(v >= 0.0 && v <= 9999.0 && v == std::floor(v))) {
    fail(col, std::string(1, letter) + num(v) + " (expected a whole " + letter + " code)");
  }
  const int n = static_cast<int>(v);
  const std::string word = std::string(1, letter) + std::to_string(n);
  if (letter == 'M') {
    switch (n) {
      case 0:
      case 1:
      case 7:
      case 8:
      case 9:
        return;  // stops and coolant: no motion
      case 2:
      case 17:
      case 30:
        l_.end = true;
        return;
      case 3:
      case 4:
      case 5:
        if (l_.spindle >= 0) fail(col, "two spindle codes (M3 M4 M5) in one block");
        l_.spindle = n;
        l_.spindle_column = col;
        return;
      case 6:
        l_.m6 = true;
        l_.m6_column = col;
        return;
      default:
        skip_blanks();
        if (at('(')) skip_argument();  // a value for the machine's own code: M202(0.0024)
        // A machine's own M code (M50 a clamp, M200 a mode...): no path effect. A warning once
        // per code, as the G-code reader has it; none for the machine file's; an error when
        // the job asks.
        if (options_.m_codes_ignored.count(n) != 0) return;
        if (options_.unknown_m_code_as_error)
          fail(col, word + " is not an M code vcut knows (expected M0..M9, M17, M30)");
        if (state_.warned.insert(word).second)
          warn(col, word +
                        " is not an M code vcut knows: read as one that does not move the axes (the machine "
                        "file's m_codes lists its own)");
        return;
    }
  }
  switch (n) {
    case 0:
    case 1:
    case 2:
    case 3:
      if (l_.motion >= 0) fail(col, "two motion codes (G0 G1 G2 G3) in one block");
      l_.motion = n;
      l_.motion_column = col;
      return;
    case 4:
      l_.dwell_column = col;
      return;
    case 9:
      l_.exact_stop = true;
      return;
    case 17:
      state_.plane = Plane::XY;
      return;
    case 18:
      state_.plane = Plane::ZX;
      return;
    case 19:
      state_.plane = Plane::YZ;
      return;
    case 40:
    case 62:   // corner deceleration at inside corners (G41/G42): the speed, not the path
    case 621:  // corner deceleration at all corners
    case 601:
    case 602:
    case 603:
      return;  // no radius compensation; exact-stop windows (G601..G603) do not change the path
    case 54:
    case 55:
    case 56:
    case 57:
    case 500:
      state_.work_offset = word;
      return;
    case 53:
    case 153:
      l_.machine_column = col;
      return;
    case 74:
    case 75:
      if (l_.home != 0) fail(col, word + " after G" + std::to_string(l_.home) + " in one block (expected one)");
      l_.home = n;
      l_.home_column = col;
      return;
    case 60:
      state_.exact_stop = true;
      return;
    case 64:
    case 641:
    case 642:
    case 643:
    case 644:
    case 645:
      state_.exact_stop = false;
      return;
    case 70:
    case 700:
      state_.inch = true;
      state_.inch_feed = n == 700;
      return;
    case 71:
    case 710:
      state_.inch = false;
      state_.inch_feed = false;
      return;
    case 90:
      state_.incremental = false;
      return;
    case 91:
      state_.incremental = true;
      return;
    case 93:
      state_.inverse_time = true;
      return;
    case 94:
      state_.inverse_time = false;
      return;
    case 25:
    case 26:
    case 58:
    case 59:
    case 110:
    case 111:
    case 112:
      fail(col, word +
                    " is not supported: its axis words are not a motion to the programmed point "
                    "(expected G0 G1 G2 G3 moves in the workpiece frame)");
    case 33:
    case 34:
    case 35:
    case 331:
    case 332:
      fail(col, word + " (thread cutting) is not supported (expected G0 G1 G2 G3)");
    default:
      if (n >= 505 && n <= 599) {  // the settable offsets beyond G57 (SinumerikOptions::work_offsets_mm)
        state_.work_offset = word;
        return;
      }
      return unsupported(word, col);
  }
}

// One case per 840D word (frames, orientation modes, cycles' modal words, notes): a table, kept
// in one place to read against the manual; the work of each is in its own function.
void Reader::keyword(const std::string& name, int col) {
  // Flow statements start their block (Reader::flow); here they are inside one, or not read.
  static const char* const kFlow[] = {"IF",      "ELSE",   "ENDIF", "WHILE", "ENDWHILE", "FOR",    "ENDFOR", "LOOP",
                                      "ENDLOOP", "REPEAT", "UNTIL", "GOTO",  "GOTOF",    "GOTOB",  "GOTOC",  "CASE",
                                      "PROC",    "RET",    "DEF",   "PCALL", "EXTCALL",  "REPEATB"};
  for (const char* w : kFlow) {
    if (name == w) {
      fail(col, name +
                    " (program flow, calls and definitions) is not supported: skipping it would change "
                    "what the program does (expected a program of motion blocks)");
    }
  }
  // Frames and motion types whose axis words would otherwise be read as a plain move.
  static const char* const kNotMoves[] = {"ROTS",    "AROTS",   "CROTS",    "CIP",    "CT",
                                          "ASPLINE", "BSPLINE", "CSPLINE",  "POLY",   "INVCW",
                                          "INVCCW",  "TRACYL",  "TRANSMIT", "TRAANG", "OFFN"};
  for (const char* w : kNotMoves) {
    if (name == w) {
      fail(col, name +
                    " is not supported: it changes the frame or the kind of motion, so the "
                    "block's axis words cannot be read as a plain move (expected G0 G1 G2 G3 "
                    "in the workpiece frame)");
    }
  }
  // Programmable frames: the block's X Y Z are the frame's values (Line::frame).
  static const std::pair<const char*, Line::Frame> kFrames[] = {
      {"TRANS", Line::Frame::Trans},   {"ATRANS", Line::Frame::ATrans},  {"ROT", Line::Frame::Rot},
      {"AROT", Line::Frame::ARot},     {"SCALE", Line::Frame::Scale},    {"ASCALE", Line::Frame::AScale},
      {"MIRROR", Line::Frame::Mirror}, {"AMIRROR", Line::Frame::AMirror}};
  for (const auto& [word, op] : kFrames) {
    if (name != word) continue;
    if (l_.frame != Line::Frame::None)
      fail(col, name + " after " + l_.frame_name + " in one block (expected one frame statement per block)");
    l_.frame = op;
    l_.frame_column = col;
    l_.frame_name = name;
    return;
  }
  if (name == "CALL") {
    // CALL "NAME": the subprogram by its name in a string.
    skip_blanks();
    if (!at('"')) fail(col, "CALL without the subprogram's name (expected CALL \"NAME\")");
    const std::size_t open = i_++;
    const std::size_t close = s_.find('"', i_);
    if (close == std::string::npos) fail(column(open), "string without its closing '\"'");
    std::string called = s_.substr(i_, close - i_);
    for (char& ch : called) ch = upper(ch);
    i_ = close + 1;
    l_.call = called;
    l_.call_column = col;
    return;
  }
  if (name == "STOPRE") return;  // the look-ahead stops: the path is the same
  if (name == "EXTERN") {        // a subprogram's declaration: the call names the file
    i_ = s_.size();
    return;
  }
  if (name == "COMPOF" || name == "COMPON" || name == "COMPCAD" || name == "COMPCURV" || name == "COMPSURF" ||
      name == "WORKPIECE") {
    // The compressor (blocks joined within the control's tolerance: the path as programmed,
    // within it) and ShopMill's blank for the control's own simulation: one note each.
    if (state_.warned.insert(name).second)
      warn(col, name +
                    (name == "WORKPIECE" ? " (the blank, for the control's own display)"
                                         : " (the control's compressor, within its tolerance)") +
                    " read as a note: the path is the programmed one");
    skip_blanks();
    if (at('(')) skip_argument();
    return;
  }
  if (name == "CYCLE832") {
    // High-speed settings (tolerance, smoothing): the control's path within the tolerance,
    // not a different one. One note per program.
    if (state_.warned.insert("CYCLE832").second)
      warn(col,
           "CYCLE832 (high-speed settings) read as a note: its tolerance is the control's, the path is the programmed "
           "one");
    if (at('(')) skip_argument();
    return;
  }
  if (name == "SUPA") {
    l_.machine_column = col;
    return;
  }
  if (name == "FNORM") return;  // the feed as programmed over the block (FLIN and FCUB vary it)
  if (name == "SETMS") {        // the master spindle: one spindle here
    skip_blanks();
    if (at('(')) skip_argument();
    return;
  }
  if (name == "MCALL") {
    l_.mcall = true;  // alone: the modal call ends; with a cycle: it becomes the modal call
    return;
  }
  if (name == "CYCLE81" || name == "CYCLE82" || name == "CYCLE83" || name == "CYCLE84" || name == "CYCLE840" ||
      name == "CYCLE85" || name == "CYCLE86" || name == "CYCLE87" || name == "CYCLE88" || name == "CYCLE89" ||
      name == "CYCLE800") {
    if (!l_.cycle.empty()) fail(col, name + " after " + l_.cycle + " in one block (expected one cycle call)");
    l_.cycle = name;
    l_.cycle_column = col;
    expect('(',
           name + " without its parameters (expected " + name +
               (name == "CYCLE800" ? "(_FR, _TC, _ST, _MODE, ...) or CYCLE800()" : "(RTP, RFP, SDIS, DP, DPR, ...)") +
               ")");
    // Positional parameters; an empty one is left out (Siemens' default). CYCLE800() has none.
    skip_blanks();
    if (name == "CYCLE800" && at(')')) {
      ++i_;
      return;
    }
    while (true) {
      skip_blanks();
      l_.cycle_texts.emplace_back();
      if (at(',') || at(')')) {
        l_.cycle_args.emplace_back();
      } else if (at('"')) {
        if (name != "CYCLE800") fail(column(i_), name + " with a text parameter (expected numbers)");
        const std::size_t open = i_++;
        const std::size_t close = s_.find('"', i_);
        if (close == std::string::npos) fail(column(open), "string without its closing '\"'");
        l_.cycle_texts.back() = s_.substr(i_, close - i_);
        i_ = close + 1;
        l_.cycle_args.emplace_back();
        skip_blanks();
      } else {
        l_.cycle_args.emplace_back(expression(1));
      }
      if (at(')')) break;
      expect(',', name + "( with a parameter list that does not end with ')'");
      if (l_.cycle_args.size() > 32) fail(col, name + " with more than 32 parameters");
    }
    ++i_;
    return;
  }
  if (name == "TRAORI") {
    if (at('(')) {
      ++i_;
      if (!at(')')) {
        const double v = expression(1);
        if (v != 1.0) {
          fail(col, "TRAORI(" + num(v) + ") (expected TRAORI or TRAORI(1): the machine file has one transformation)");
        }
      }
      expect(')', "TRAORI( without its closing ')'");
    }
    state_.traori = true;
    return;
  }
  if (name == "TRAFOOF") {
    state_.traori = false;
    return;
  }
  if (name == "ORIWKS") {
    state_.orimks = false;
    return;
  }
  if (name == "ORIMKS") {
    state_.orimks = true;
    return;
  }
  if (name == "ORIVECT" || name == "ORIPLANE") {
    state_.orientation = OrientationMode::Vector;  // ORIPLANE is identical to ORIVECT (Siemens)
    state_.cone_by = SinumerikState::ConeBy::Axis;
    return;
  }
  if (name == "ORIAXES") {
    state_.orientation = OrientationMode::Axes;
    state_.cone_by = SinumerikState::ConeBy::Axis;
    return;
  }
  if (name == "ORICONCW" || name == "ORICONCCW") {
    // Siemens' "clockwise" is seen looking along the direction vector A6 B6 C6: a positive
    // (right-hand) turn about it, i.e. vcut's ConeCounterClockwise. The manual's example:
    // ORICONCW about (0,0,1) from (0,1,1)/sqrt2 to (1,0,1)/sqrt2 turns 270 deg.
    state_.orientation = name == "ORICONCW" ? OrientationMode::ConeCounterClockwise : OrientationMode::ConeClockwise;
    state_.cone_by = SinumerikState::ConeBy::Axis;
    return;
  }
  if (name == "ORICONIO" || name == "ORICONTO") {
    // The reader makes these cones counterclockwise about the axis it derives (see orient).
    state_.orientation = OrientationMode::ConeCounterClockwise;
    state_.cone_by = name == "ORICONIO" ? SinumerikState::ConeBy::Intermediate : SinumerikState::ConeBy::Tangent;
    return;
  }
  if (name == "MSG") {
    if (at('(')) skip_argument();
    return;
  }
  // A subprogram by its name, NAME or NAME(values), when one is found on the path.
  if (l_.call.empty() && (!subprogram_file(name).empty())) {
    l_.call = name;
    l_.call_column = col;
    call_arguments(name);
    return;
  }
  skip_blanks();
  // NAME(values): a call of a cycle vcut does not know, or of a subprogram not found.
  if (i_ < s_.size() && s_[i_] == '(')
    unsupported(name, col, "not a cycle vcut reads, and no subprogram: expected " + searched_for(name));
  else
    unsupported(name, col);
  if (i_ < s_.size() && (s_[i_] == '(' || s_[i_] == '=')) skip_argument();
}

// ---------------------------------------------------------------------------------------------
// Executing a block

// The order in which the control executes a block's parts (tool, spindle, feed, modes, frames,
// then the motion and the calls): in one function because that order is what it says.
void Reader::execute() {
  Line& l = l_;
  // Tool: T selects, M6 loads (Siemens' tool change with M6).
  if (l.t.present) {
    const double t = l.t.value;
    if (!(t >= 0.0 && t <= kMaxToolNumber && t == std::floor(t))) {
      fail(l.t.column, "tool number T" + num(t) + " (expected a whole number 0..99999)");
    }
    state_.selected_tool = static_cast<int>(t);
  }
  if (l.m6) {
    if (state_.selected_tool < 0) fail(l.m6_column, "M6 without a tool selected (expected a T word before or with it)");
    // The spindle stays where it is: the new tool's tip is its length below the gauge point.
    const double before = tool_length_mm();
    state_.tool = state_.selected_tool;
    state_.position_mm -= (tool_length_mm() - before) * spindle();
    if (!l.d.present) state_.tool_offset_off = false;  // M6 takes the new tool's first edge, D1
  }
  if (l.d.present) {
    const double d = l.d.value;
    if (!(d >= 0.0 && d <= kMaxToolNumber && d == std::floor(d))) {
      fail(l.d.column, "tool offset D" + num(d) + " (expected a whole number 0..99999)");
    }
    state_.tool_offset_off = d == 0.0;
  }
  if (l.s.present) {
    if (!(l.s.value >= 0.0 && l.s.value <= kMaxMagnitude)) {
      fail(l.s.column, "spindle speed S" + num(l.s.value) + " (expected 0..1e6 rpm)");
    }
    state_.spindle_rpm = l.s.value;
  }
  if (l.spindle >= 0) {
    state_.spindle = l.spindle == 3   ? SpindleState::Clockwise
                     : l.spindle == 4 ? SpindleState::CounterClockwise
                                      : SpindleState::Off;
  }
  const double unit = state_.inch ? kMmPerInch : 1.0;
  for (Value* v : {&l.adis, &l.adispos}) {
    if (!v->present) continue;
    if (!(v->value >= 0.0 && v->value * unit <= kMaxMagnitude)) {
      fail(v->column,
           std::string(v == &l.adis ? "ADIS" : "ADISPOS") + " " + num(v->value) + " (expected a distance 0..1e6 mm)");
    }
    (v == &l.adis ? state_.adis_mm : state_.adispos_mm) = v->value * unit;
  }
  if (l.motion >= 0) {
    state_.motion = l.motion == 0   ? Motion::Rapid
                    : l.motion == 1 ? Motion::Linear
                    : l.motion == 2 ? Motion::ArcClockwise
                                    : Motion::ArcCounterClockwise;
  }
  if (l.frame != Line::Frame::None) {
    apply_frame();  // its X Y Z are the frame's values: no move
    return;
  }
  if (l.machine_axis_column > 0 && l.home == 0)
    fail(l.machine_axis_column, "a machine axis X1= Y1= Z1= outside G74 / G75 (expected X Y Z)");
  if (l.fp.present && l.home != 75) fail(l.fp.column, "FP= without G75 (expected G75 FP=1 or FP=2)");
  if (l.home != 0) {
    home();
    finish_block();
    return;
  }
  bool moves = false;
  for (int k = 0; k < 3; ++k) moves = moves || l.axis[k].present || l.rotary[k].present || l.vector[k].present;
  if (l.dwell_column > 0) {
    // G4 F.. (s) or S.. (revolutions): a dwell. Its F and S are not the feed and speed.
    if (moves) fail(l.dwell_column, "G4 (dwell) with axis words in the same block (expected G4 alone)");
    return;
  }
  if (l.f.present) {
    const double f = l.f.value * (state_.inch_feed ? kMmPerInch : 1.0);
    if (!(f > 0.0 && f <= kMaxMagnitude)) {
      fail(l.f.column, "feed F" + num(l.f.value) + " (expected > 0 and at most 1e6 mm/min)");
    }
    if (!state_.inverse_time) state_.feed_mm_per_min = f;
  }
  for (int k = 0; k < 3; ++k) {
    if (l.cone[k].present) {
      if (state_.orimks) {
        fail(l.cone[k].column,
             "cone axis A6 B6 C6 under ORIMKS (machine-frame vectors) is not supported "
             "(expected ORIWKS)");
      }
      Eigen::Vector3d c(l.cone[0].value, l.cone[1].value, l.cone[2].value);  // missing: 0
      if (!c.allFinite() || c.norm() < kMinVectorNorm || c.cwiseAbs().maxCoeff() > kMaxMagnitude) {
        fail(l.cone[k].column, "cone axis A6 B6 C6 (" + num(c.x()) + ", " + num(c.y()) + ", " + num(c.z()) +
                                   ") (expected a vector of nonzero length)");
      }
      state_.cone_axis = (frame_linear() * c).normalized();
      break;
    }
  }
  // The cone modes' words: A6 B6 C6 belong to ORICONCW/CCW, A7 B7 C7 to an ORICONIO block with
  // its end vector.
  const bool cone_mode = state_.orientation == OrientationMode::ConeClockwise ||
                         state_.orientation == OrientationMode::ConeCounterClockwise;
  const int cone_column = first_column(l.cone);
  const int middle_column = first_column(l.middle);
  if (cone_column > 0 && cone_mode && state_.cone_by != SinumerikState::ConeBy::Axis) {
    fail(cone_column, std::string("cone axis A6 B6 C6 under ") +
                          (state_.cone_by == SinumerikState::ConeBy::Intermediate ? "ORICONIO" : "ORICONTO") +
                          ", whose cone is fixed by the intermediate orientation or the tangent (expected "
                          "ORICONCW or ORICONCCW for a cone by its axis)");
  }
  if (middle_column > 0) {
    if (!cone_mode || state_.cone_by != SinumerikState::ConeBy::Intermediate) {
      fail(middle_column,
           "intermediate orientation A7 B7 C7 outside ORICONIO (expected ORICONIO before or in "
           "this block)");
    }
    if (first_column(l.vector) == 0) {
      fail(middle_column,
           "intermediate orientation A7 B7 C7 without the end vector A3 B3 C3 (expected both in "
           "the ORICONIO block)");
    }
  }
  // A6 B6 C6 without an end vector under ORICONCW/CCW: a full turn on the cone (the manual's
  // example: "the tool orientation goes through a full revolution on the outside of the same
  // taper").
  if (cone_column > 0 && cone_mode && state_.traori) moves = true;
  const bool arc = state_.motion == Motion::ArcClockwise || state_.motion == Motion::ArcCounterClockwise;
  if (!arc) {
    for (int k = 0; k < 3; ++k) {
      if (l.center[k].present) {
        fail(l.center[k].column, std::string(1, kCenterLetter[k]) + " outside an arc (expected G2 or G3)");
      }
    }
    if (l.cr.present) fail(l.cr.column, "CR= outside an arc (expected G2 or G3)");
  }
  const bool centre = l.center[0].present || l.center[1].present || l.center[2].present;
  const bool positions = moves || (arc && (centre || l.cr.present));
  if (l.turn.present && !(positions && arc))
    fail(l.turn.column, "TURN= outside an arc (expected G2 or G3 with the arc's end or centre)");
  if (l.cycle == "CYCLE800") {
    if (positions) fail(l.cycle_column, "CYCLE800 with axis words in its block (expected it in a block of its own)");
    if (l.mcall) fail(l.cycle_column, "MCALL CYCLE800 (expected CYCLE800 called directly: it is not a modal cycle)");
    swivel(l.cycle_args, l.cycle_texts, l.cycle_column);
    l.cycle.clear();
  }
  if (positions) motion();
  if (l.mcall) {
    // MCALL CYCLE8x(...): every later positioning block ends with it; MCALL alone: no more.
    state_.modal_cycle = l.cycle;
    state_.modal_cycle_args = l.cycle_args;
  } else if (!l.cycle.empty()) {
    cycle(l.cycle, l.cycle_args, l.cycle_column);
  } else if (positions && !state_.modal_cycle.empty()) {
    cycle(state_.modal_cycle, state_.modal_cycle_args, l.first_column);
  }
  finish_block();
}

// What follows a block's motion: its subprogram call and the program's end.
void Reader::finish_block() {
  const Line& l = l_;
  if (l.p.present && l.call.empty()) fail(l.p.column, "P without a subprogram call (expected L.. P.. or NAME P..)");
  if (!l.call.empty()) {
    const double times = l.p.present ? l.p.value : 1.0;
    if (!(times >= 1.0 && times <= 9999.0 && times == std::floor(times)))
      fail(l.p.column, "P" + num(times) + " (expected the number of runs, 1..9999)");
    call(l.call, l.call_args, static_cast<int>(times), l.call_column);
  }
  if (l.end) {
    // M30/M2/M17: nothing after this line is read; the end resets G91 and the feed mode as
    // Siemens' reset values do (the tool and the position stay).
    state_.incremental = false;
  }
}

// The block's end point (workpiece frame, mm): programmed axes in G90/G91 or AC/IC, others stay.
Eigen::Vector3d Reader::target(std::array<bool, 3>& programmed) const {
  Eigen::Vector3d end = state_.position_mm;
  if (l_.machine_column > 0) {
    // SUPA / G53 / G153: machine coordinates count from the gauge point at all-zero axes; the
    // tool's length stays on (the tip is there), under D0 the gauge point is there. The point
    // is the tip with the rotaries at zero, turned with them.
    const auto [r, t] = machine_turn();
    Eigen::Vector3d axes = r.transpose() * (state_.position_mm - t);
    const Eigen::Vector3d shift =
        state_.tool_offset_off ? Eigen::Vector3d(tool_length_mm() * options_.spindle_axis) : Eigen::Vector3d::Zero();
    for (int a = 0; a < 3; ++a) {
      const Value& w = l_.axis[a];
      if (!w.present) continue;
      if (w.mode == Value::Mode::Incremental || (w.mode == Value::Mode::Modal && state_.incremental))
        fail(w.column, std::string("incremental ") + kAxisLetter[a] +
                           " in machine coordinates (SUPA, G53, G153) (expected absolute)");
      programmed[static_cast<std::size_t>(a)] = true;
      axes[a] = options_.machine_zero_mm[a] + length_mm(w) - shift[a];
      if (!(std::abs(axes[a]) <= kMaxMagnitude))
        fail(w.column, std::string(1, kAxisLetter[a]) + " position " + num(axes[a]) +
                           " mm is out of range (expected within +-1e6 mm)");
    }
    return r * axes + t;
  }
  if (frame_turns()) {
    // A turned, scaled or mirrored frame mixes the axes: the point in the frame, then placed.
    Eigen::Vector3d q = in_frame(state_.position_mm);
    for (int a = 0; a < 3; ++a) {
      const Value& w = l_.axis[a];
      if (!w.present) continue;
      for (int k = 0; k < 3; ++k) {
        if (!state_.known[static_cast<std::size_t>(k)]) {
          fail(w.column, std::string("a move in a turned, scaled or mirrored frame (ROT, SCALE, MIRROR) from an "
                                     "unknown ") +
                             kAxisLetter[k] + " position (expected X, Y and Z programmed before the frame)");
        }
      }
      programmed[static_cast<std::size_t>(a)] = true;
      const bool incremental =
          w.mode == Value::Mode::Incremental || (w.mode == Value::Mode::Modal && state_.incremental);
      q[a] = (incremental ? q[a] : 0.0) + length_mm(w);
    }
    end = placed(q);
    if (!(end.cwiseAbs().maxCoeff() <= kMaxMagnitude)) {
      fail(first_column(l_.axis), "position " + num(end.x()) + ", " + num(end.y()) + ", " + num(end.z()) +
                                      " mm in the workpiece frame is out of range (expected within +-1e6 mm)");
    }
    return end;
  }
  const Eigen::Vector3d off = frame_origin();
  for (int a = 0; a < 3; ++a) {
    const Value& w = l_.axis[a];
    if (!w.present) continue;
    programmed[static_cast<std::size_t>(a)] = true;
    const double v = length_mm(w);
    const bool incremental = w.mode == Value::Mode::Incremental || (w.mode == Value::Mode::Modal && state_.incremental);
    if (incremental) {
      if (!state_.known[static_cast<std::size_t>(a)]) {
        fail(w.column, std::string("incremental ") + kAxisLetter[a] + " from an unknown " + kAxisLetter[a] +
                           " position (expected an absolute " + kAxisLetter[a] + " first)");
      }
      end[a] = state_.position_mm[a] + v;
    } else {
      end[a] = v + off[a];
    }
    if (!(std::abs(end[a]) <= kMaxMagnitude)) {
      fail(w.column, std::string(1, kAxisLetter[a]) + " position " + num(end[a]) +
                         " mm is out of range (expected within +-1e6 mm)");
    }
  }
  return end;
}

// A cone block's tool vector at s = 1 moves along angle'(s) k x u (rotation about the unit k):
// k x end_axis for a counterclockwise turn, its negative for a clockwise one (unit).
Eigen::Vector3d cone_end_tangent(const Block& block) {
  const Eigen::Vector3d t = block.cone_axis.normalized().cross(block.end_axis).normalized();
  return block.orientation == OrientationMode::ConeClockwise ? Eigen::Vector3d(-t) : t;
}

// The block's orientation. Returns whether it changes the tool axis or the rotary axes. One
// function: the orientation modes (rotary axes, A3 B3 C3 vectors, ORICONE's cone words and
// intermediate vector) share the checks of which words a block may combine, made in order.
bool Reader::orient(Block& block) {
  const Line& l = l_;
  const bool vector = l.vector[0].present || l.vector[1].present || l.vector[2].present;
  const bool axes = l.rotary[0].present || l.rotary[1].present || l.rotary[2].present;
  const int vector_column = l.vector[0].present   ? l.vector[0].column
                            : l.vector[1].present ? l.vector[1].column
                                                  : l.vector[2].column;
  // Rotary words: degrees, G90/G91 or AC/IC as the linear axes (G70 does not apply).
  kinematics::RotaryWords rotary = state_.rotary;
  for (int r = 0; r < 3; ++r) {
    const Value& w = l.rotary[r];
    if (!w.present) continue;
    const auto k = static_cast<std::size_t>(r);
    const char letter = static_cast<char>('A' + r);
    if (!(std::abs(w.value) <= kMaxMagnitude)) {
      fail(w.column, std::string(1, letter) + " " + num(w.value) + " deg is out of range (expected within +-1e6)");
    }
    const bool incremental = w.mode == Value::Mode::Incremental || (w.mode == Value::Mode::Modal && state_.incremental);
    if (incremental && !rotary.given[k]) {
      fail(w.column, std::string("incremental ") + letter + " from an unknown " + letter +
                         " position (expected an absolute " + letter + " first)");
    }
    rotary.angle_rad[k] = (incremental ? rotary.angle_rad[k] : 0.0) + w.value * kDegToRad;
    rotary.given[k] = true;
  }
  block.start_rotary = state_.rotary;
  block.end_rotary = rotary;
  const bool turns = rotary.angle_rad != state_.rotary.angle_rad;
  if (!state_.traori) {
    if (vector) {
      fail(vector_column, "tool vector A3 B3 C3 without TRAORI (expected TRAORI before vector orientation)");
    }
    if (axes) state_.rotary_program = true;
    state_.rotary = rotary;
    block.tool_pose = !state_.rotary_program;
    if (!block.tool_pose) {
      block.orientation = OrientationMode::Axes;
      if (axes) state_.axis_set_by_rotary_line = line_;
      return turns;
    }
    block.start_axis = block.end_axis = state_.tool_axis;
    return false;
  }
  block.tool_pose = true;
  block.orientation = state_.orientation;
  const bool cone = state_.orientation == OrientationMode::ConeClockwise ||
                    state_.orientation == OrientationMode::ConeCounterClockwise;
  using ConeBy = SinumerikState::ConeBy;
  // A6 B6 C6 without an end vector under ORICONCW/CCW: a full turn (checked in execute).
  const bool full_turn = cone && state_.cone_by == ConeBy::Axis && !vector &&
                         (l.cone[0].present || l.cone[1].present || l.cone[2].present);
  const int cone_column = l.cone[0].present   ? l.cone[0].column
                          : l.cone[1].present ? l.cone[1].column
                                              : l.cone[2].column;
  // ORICONTO continues the previous motion block's turn; any other block sets it anew below.
  const Eigen::Vector3d tangent_in = state_.axis_tangent;
  state_.axis_tangent = Eigen::Vector3d::Zero();
  if (vector && axes) {
    fail(vector_column, "tool vector A3 B3 C3 and rotary axes A B C in one block (expected one or the other)");
  }
  if (axes) {
    // Direct rotary axis positions under TRAORI: the pose engine solves the tool axis.
    if (cone) {
      fail(l.rotary[0].present   ? l.rotary[0].column
           : l.rotary[1].present ? l.rotary[1].column
                                 : l.rotary[2].column,
           "rotary axes A B C under a cone mode (ORICONxx) (expected the end orientation as "
           "A3 B3 C3)");
    }
    state_.rotary = rotary;
    state_.axis_set_by_rotary_line = line_;
    return turns;
  }
  if (state_.axis_set_by_rotary_line > 0) {
    if (vector || full_turn) {
      fail(vector ? vector_column : cone_column,
           std::string(vector ? "tool vector A3 B3 C3" : "a full turn on the cone A6 B6 C6") +
               " after the orientation was set by rotary axes A B C (line " +
               std::to_string(state_.axis_set_by_rotary_line) +
               "): the reader cannot tell the vector those axes give without the machine (expected "
               "the orientation as A3 B3 C3 throughout, or as A B C throughout)");
    }
    // The rotary axes hold where they were programmed; the tip moves under TCP. A cone mode
    // selected meanwhile turns nothing in this block, so the block has no cone (and no cone axis).
    block.start_rotary = block.end_rotary = state_.rotary;
    if (cone) block.orientation = OrientationMode::Vector;
    return false;
  }
  if (full_turn) {
    const Eigen::Vector3d& k = state_.cone_axis;
    const double a0 = std::acos(std::clamp(state_.tool_axis.dot(k), -1.0, 1.0));
    if (a0 < kConeAngleToleranceRad || M_PI - a0 < kConeAngleToleranceRad) {
      fail(cone_column,
           "full turn on the cone A6 B6 C6 with the tool vector along its axis (expected a cone "
           "with an opening)");
    }
    // End = start: the pose engine turns a cone block whose end is its start by a full 360 deg.
    block.start_axis = block.end_axis = state_.tool_axis;
    block.cone_axis = k;
    state_.rotary.given = {false, false, false};
    state_.axis_tangent = cone_end_tangent(block);
    return true;
  }
  if (!vector) {
    block.start_axis = block.end_axis = state_.tool_axis;
    block.orientation = cone ? OrientationMode::Vector : state_.orientation;
    return false;
  }
  if (state_.orimks) {
    fail(vector_column,
         "tool vector A3 B3 C3 under ORIMKS (machine-frame vectors) is not supported "
         "(expected ORIWKS)");
  }
  // Components not programmed are 0 (Siemens: "vector components that have not been programmed
  // are set to zero"); the length does not matter.
  // In the workpiece frame: the programmable frame turns the vector too (ORIWKS).
  const Eigen::Vector3d v = frame_linear() * Eigen::Vector3d(l.vector[0].value, l.vector[1].value, l.vector[2].value);
  if (!v.allFinite() || v.cwiseAbs().maxCoeff() > kMaxMagnitude || v.norm() < kMinVectorNorm) {
    fail(vector_column, "tool vector A3 B3 C3 (" + num(v.x()) + ", " + num(v.y()) + ", " + num(v.z()) +
                            ") (expected a vector of nonzero length)");
  }
  const Eigen::Vector3d axis = v.normalized();
  block.start_axis = state_.tool_axis;
  block.end_axis = axis;
  state_.rotary.given = {false, false, false};  // the axes that give this vector are not known
  const bool through_middle = cone && state_.cone_by == ConeBy::Intermediate;
  const bool middle = l.middle[0].present || l.middle[1].present || l.middle[2].present;
  if (axis == state_.tool_axis && !middle) {
    // The same vector again (CAM repeats it in every block): no turn, also under a cone mode.
    block.orientation = cone ? OrientationMode::Vector : state_.orientation;
    return false;
  }
  const Eigen::Vector3d& a = block.start_axis;
  const Eigen::Vector3d& c = axis;
  if (cone && state_.cone_by == ConeBy::Axis) {
    if (state_.cone_axis.isZero()) {
      fail(vector_column, "ORICONCW/ORICONCCW without a cone axis (expected A6 B6 C6 in this block or before)");
    }
    const Eigen::Vector3d& k = state_.cone_axis;
    const double a0 = std::acos(std::clamp(block.start_axis.dot(k), -1.0, 1.0));
    const double a1 = std::acos(std::clamp(axis.dot(k), -1.0, 1.0));
    if (std::abs(a0 - a1) > kConeAngleToleranceRad) {
      fail(vector_column, "end vector at " + num(a1 / kDegToRad) + " deg from the cone axis but the start at " +
                              num(a0 / kDegToRad) +
                              " deg (expected both on one cone about A6 B6 C6, within 0.006 deg)");
    }
    if (a0 < kConeAngleToleranceRad || M_PI - a0 < kConeAngleToleranceRad) {
      fail(vector_column, "tool vector along the cone axis A6 B6 C6 (expected a cone with an opening)");
    }
    block.cone_axis = k;
  } else if (through_middle) {
    // ORICONIO: the circle through the tips of a, m, c lies in the plane with normal
    // n = (m - a) x (c - a); the triangle a, m, c runs counterclockwise about n, and so does
    // the circle through its vertices in the same order: counterclockwise about n from a, m
    // comes before c. Every point of that circle makes the same angle with n, so it is the
    // cone about n. Three distinct points of a sphere are never collinear; only nearly
    // coinciding ones leave the circle undetermined.
    if (!middle) {
      fail(vector_column,
           "ORICONIO end vector without the intermediate orientation A7 B7 C7 (expected A7 B7 C7 "
           "in the block with A3 B3 C3)");
    }
    const int column = l.middle[0].present   ? l.middle[0].column
                       : l.middle[1].present ? l.middle[1].column
                                             : l.middle[2].column;
    const Eigen::Vector3d w(l.middle[0].value, l.middle[1].value, l.middle[2].value);
    if (!w.allFinite() || w.cwiseAbs().maxCoeff() > kMaxMagnitude || w.norm() < kMinVectorNorm) {
      fail(column, "intermediate orientation A7 B7 C7 (" + num(w.x()) + ", " + num(w.y()) + ", " + num(w.z()) +
                       ") (expected a vector of nonzero length)");
    }
    const Eigen::Vector3d m = w.normalized();
    const double am = (m - a).norm(), mc = (c - m).norm(), ac = (c - a).norm();
    if (std::min({am, mc, ac}) < kMinConeChord) {
      const char* which = am < kMinConeChord   ? "the intermediate and the start"
                          : mc < kMinConeChord ? "the intermediate and the end"
                                               : "the end and the start";
      fail(column, std::string("ORICONIO orientations that (nearly) coincide: ") + which + " are " +
                       num(std::min({am, mc, ac})) +
                       " apart on the unit sphere, so no single circle runs through start, "
                       "intermediate and end (expected three orientations at least 1e-4 apart)");
    }
    block.cone_axis = (m - a).cross(c - a).normalized();
    block.orientation = OrientationMode::ConeCounterClockwise;
  } else if (cone) {
    // ORICONTO: the circle through a with tangent t there, through c, lies in the plane through
    // a spanned by t and c - a: normal n = t x (c - a). With a, t, b = a x t right-handed and
    // c - a = alpha a + beta t + gamma b, alpha = (a.c - 1) = -|c - a|^2 / 2 (a, c unit), so
    // n = -alpha b + gamma a and n x a = -alpha t: the counterclockwise turn about n leaves a
    // along +t whenever c != a. Hence always counterclockwise about n.
    const Eigen::Vector3d& t = tangent_in;
    if (t.isZero()) {
      fail(vector_column,
           "ORICONTO without a tangent: the previous motion block did not turn the tool vector "
           "(expected a block turning it under ORIVECT, ORIPLANE or a cone mode right before, "
           "with A3 B3 C3)");
    }
    const double ac = (c - a).norm();
    if (ac < kMinConeChord) {
      fail(vector_column, "ORICONTO end vector " + num(ac) +
                              " from the start on the unit sphere (expected at least 1e-4: the "
                              "circle is not fixed by so short a turn)");
    }
    block.cone_axis = t.cross(c - a).normalized();
    block.orientation = OrientationMode::ConeCounterClockwise;
  } else if (state_.orientation == OrientationMode::Vector && block.start_axis.dot(axis) <= kOppositeAxisCosine) {
    fail(vector_column,
         "tool vector opposite to the previous one (expected less than 180 deg of turn: "
         "no single great circle joins opposite vectors)");
  }
  if (cone) {
    state_.axis_tangent = cone_end_tangent(block);
  } else if (state_.orientation == OrientationMode::Vector) {
    // Great circle from a to c: at s = 1 the vector moves perpendicular to c, in the plane of
    // a and c, away from a: along (a x c) x c = -(a - (a.c) c).
    state_.axis_tangent = a.cross(c).cross(c).normalized();
  }
  state_.tool_axis = axis;
  return true;
}

void Reader::arc(Block& block, bool clockwise) {
  if (!frame_turns()) {
    arc_in_plane(block, clockwise, frame_origin());
    return;
  }
  // In a turned, scaled or mirrored frame: the arc in the frame's plane, then placed. A scale
  // that differs between the plane's two axes would make it an ellipse.
  const Eigen::Matrix3d m = frame_linear();
  const int a = state_.plane == Plane::XY ? 0 : state_.plane == Plane::ZX ? 2 : 1;
  const int b = state_.plane == Plane::XY ? 1 : state_.plane == Plane::ZX ? 0 : 2;
  const int c = 3 - a - b;
  const Eigen::Vector3d ca = m.col(a), cb = m.col(b), cc = m.col(c);
  const double tol = 1e-9 * ca.squaredNorm();
  if (!(std::abs(ca.squaredNorm() - cb.squaredNorm()) <= tol && std::abs(ca.dot(cb)) <= tol &&
        std::abs(ca.dot(cc)) <= tol && std::abs(cb.dot(cc)) <= tol)) {
    fail(l_.motion_column > 0 ? l_.motion_column : l_.first_column,
         std::string(clockwise ? "G2" : "G3") +
             " arc in a frame scaled differently along its axes (SCALE/ASCALE): an ellipse, not an arc (expected "
             "equal scale factors)");
  }
  Block local = block;
  local.start_mm = in_frame(block.start_mm);
  local.end_mm = in_frame(block.end_mm);
  arc_in_plane(local, clockwise, Eigen::Vector3d::Zero());
  block.kind = local.kind;
  block.end_mm = placed(local.end_mm);
  block.center_mm = placed(local.center_mm);
  // A mirror (det < 0) turns the arc the other way about the placed normal.
  block.normal = (m.determinant() < 0.0 ? -1.0 : 1.0) * (m * local.normal).normalized();
  block.turns = local.turns;
  // A scale > 1 scales the end's mismatch with the start's radius too: within the tolerance again.
  auto radius = [&](const Eigen::Vector3d& p) {
    const Eigen::Vector3d d = p - block.center_mm;
    return (d - block.normal * block.normal.dot(d)).norm();
  };
  const double r1 = radius(block.start_mm), r2 = radius(block.end_mm);
  if (!(std::abs(r1 - r2) <= std::max(options_.arc_tolerance_mm, 0.001 * std::max(r1, r2)))) {
    fail(l_.motion_column > 0 ? l_.motion_column : l_.first_column,
         "arc end " + num(std::abs(r1 - r2)) +
             " mm off its circle once the frame's SCALE is applied (expected within " +
             num(std::max(options_.arc_tolerance_mm, 0.001 * std::max(r1, r2))) + " mm)");
  }
}

void Reader::arc_in_plane(Block& block, bool clockwise, const Eigen::Vector3d& centre_origin) {
  const char* code = clockwise ? "G2" : "G3";
  int a = 0, b = 1, c = 2;  // the plane's first and second axes and its normal, as in G-code
  const char* plane_name = "XY";
  if (state_.plane == Plane::ZX) {
    a = 2, b = 0, c = 1;
    plane_name = "ZX";
  } else if (state_.plane == Plane::YZ) {
    a = 1, b = 2, c = 0;
    plane_name = "YZ";
  }
  const Value& cr = l_.cr;
  const bool ijk = l_.center[0].present || l_.center[1].present || l_.center[2].present;
  const int column = l_.motion_column > 0 ? l_.motion_column : l_.first_column;
  if (!cr.present && !ijk)
    fail(column, std::string(code) + " arc without I J K or CR= (expected the centre or the radius)");
  if (cr.present && ijk)
    fail(cr.column, std::string(code) + " arc with both CR= and I J K (expected one or the other)");
  for (int axis : {a, b}) {
    if (!state_.known[static_cast<std::size_t>(axis)]) {
      fail(column, std::string(code) + " arc from an unknown " + kAxisLetter[axis] +
                       " position (expected a move that sets " + kAxisLetter[axis] + " before the first arc)");
    }
  }
  const Eigen::Vector3d start = block.start_mm;
  Eigen::Vector3d& end = block.end_mm;
  const Eigen::Vector2d s(start[a], start[b]);
  const Eigen::Vector2d e(end[a], end[b]);
  Eigen::Vector2d center;
  if (ijk) {
    const Value& normal_word = l_.center[c];
    if (normal_word.present) {
      fail(normal_word.column, std::string(1, kCenterLetter[c]) + " in a " + plane_name + "-plane arc (expected " +
                                   kCenterLetter[a] + " and " + kCenterLetter[b] + ")");
    }
    const Eigen::Vector3d& off = centre_origin;
    for (int k = 0; k < 2; ++k) {
      const int axis = k == 0 ? a : b;
      const Value& w = l_.center[axis];
      // Missing: 0 relative to the start; I=AC(..) is the centre in the active frame.
      const double v = w.present ? length_mm(w) : 0.0;
      center[k] = w.present && w.mode == Value::Mode::Absolute ? v + off[axis] : start[axis] + v;
      if (!(std::abs(center[k]) <= kMaxMagnitude)) {
        fail(w.column, std::string(1, kCenterLetter[axis]) + " gives a centre out of range (expected within +-1e6 mm)");
      }
    }
    if (const std::string error =
            detail::centre_arc_error(s, e, center, {options_.arc_tolerance_mm, 0.001, kMaxMagnitude}, code);
        !error.empty()) {
      fail(column, error);
    }
    if ((e - s).norm() <= kSamePointMm) {  // a full circle: start and end coincide exactly
      end[a] = start[a];
      end[b] = start[b];
    }
  } else {
    const double radius = length_mm(cr);
    if (!(std::abs(radius) <= kMaxMagnitude) && (e - s).norm() > kSamePointMm) {
      fail(cr.column, "CR=" + num(cr.value) + " (expected |CR| <= 1e6 mm)");
    }
    if (const std::string error = detail::radius_arc_centre(s, e, radius, clockwise, code, "CR=", "I J K", center);
        !error.empty()) {
      fail(cr.column, error);
    }
  }
  block.kind = MotionKind::Arc;
  block.center_mm = start;
  block.center_mm[a] = center[0];
  block.center_mm[b] = center[1];
  block.normal = Eigen::Vector3d::Zero();
  block.normal[c] = clockwise ? -1.0 : 1.0;  // right-hand rule: G2 in G17 turns about -Z
  block.turns = 1;
}

void Reader::motion() {
  const Motion m = state_.motion;
  const int rotary_column = first_column(l_.rotary);
  if (rotary_column > 0 && !state_.traori && !state_.rotary_program) {
    // A B C words without TRAORI: from here X Y Z are the machine's axes (an axis program).
    if (state_.swivel_plane)
      fail(rotary_column, "rotary axis words with CYCLE800's plane on (expected CYCLE800() first, or TRAORI)");
    const auto [r, t] = turned(state_.rotary);
    state_.position_mm = r.transpose() * (state_.position_mm - t);
    state_.swivel_rotation.setIdentity();
    state_.swivel_translation_mm.setZero();
    state_.rotary_program = true;  // (orient() says so too): target() reads X Y Z as the axes
  }
  Block block;
  block.kind = m == Motion::Rapid ? MotionKind::Rapid : MotionKind::Linear;
  std::array<bool, 3> programmed{};
  block.end_mm = target(programmed);
  block.start_mm = state_.position_mm;
  for (int a = 0; a < 3; ++a) {
    if (!state_.known[static_cast<std::size_t>(a)]) block.start_mm[a] = block.end_mm[a];
  }
  const bool reorients = orient(block);
  if (m == Motion::ArcClockwise || m == Motion::ArcCounterClockwise) arc(block, m == Motion::ArcClockwise);
  if (l_.turn.present) {
    // TURN=n: n more full turns of a helix (or circle) before the programmed end.
    const double n = l_.turn.value;
    if (block.kind != MotionKind::Arc) fail(l_.turn.column, "TURN= outside an arc (expected G2 or G3)");
    if (!(n >= 0.0 && n <= 999.0 && n == std::floor(n)))
      fail(l_.turn.column, "TURN=" + num(n) + " (expected a whole number of extra turns, 0..999)");
    block.turns += static_cast<int>(n);
  }
  const int column = l_.motion_column > 0 ? l_.motion_column : l_.first_column;
  if (m != Motion::Rapid) {
    if (state_.inverse_time) {
      if (!l_.f.present) {
        fail(column,
             "G93 (inverse time) motion without F (expected F, 1 / minutes, in every G1 G2 G3 "
             "block)");
      }
      block.feed_mm_per_min = l_.f.value;
      block.feed_mode = kinematics::FeedMode::InverseTime;
    } else {
      if (!(state_.feed_mm_per_min > 0.0)) {
        fail(column,
             "feed motion without a feed (expected F in mm/min in this block or before; G1 is "
             "active from the start)");
      }
      block.feed_mm_per_min = state_.feed_mm_per_min;
    }
  }
  block.exact_stop = state_.exact_stop || l_.exact_stop;
  if (!state_.exact_stop) {
    block.blend_tolerance_mm = m == Motion::Rapid ? state_.adispos_mm : state_.adis_mm;
  }
  append(block, programmed, reorients);
}

// TRANS ATRANS ROT AROT SCALE ASCALE MIRROR AMIRROR (Siemens, Programming Manual Fundamentals,
// "Coordinate transformations (frames)"): the plain forms replace the whole programmable frame
// (TRANS alone clears it), the A-forms add to it in its current axes: ATRANS moves by L t,
// AROT turns by L R, ASCALE and AMIRROR scale and mirror by L S and L M. ROT X a Y b Z c turns
// about Z, then the new Y, then the new X (R = Rz(c) Ry(b) Rx(a), Siemens' default RPY
// order); ROT RPL=a turns in the active plane (about Z in G17, Y in G18, X in G19). MIRROR X0
// mirrors X (the value is not used); SCALE factors must be > 0.
void Reader::apply_frame() {
  const Line& l = l_;
  Eigen::Matrix3d& m = state_.frame_linear;
  Eigen::Vector3d& t = state_.frame_translation_mm;
  using F = Line::Frame;
  const bool additive = l.frame == F::ATrans || l.frame == F::ARot || l.frame == F::AScale || l.frame == F::AMirror;
  for (int k = 0; k < 3; ++k) {
    const Value& w = l.axis[k];
    if (w.present && (w.mode != Value::Mode::Modal || !(std::abs(w.value) <= kMaxMagnitude)))
      fail(w.column, l.frame_name + " " + kAxisLetter[k] + " " + num(w.value) +
                         " (expected a plain value within +-1e6, no AC or IC)");
  }
  if (l.rpl.present && l.frame != F::Rot && l.frame != F::ARot)
    fail(l.rpl.column, "RPL= with " + l.frame_name + " (expected ROT or AROT)");
  Eigen::Matrix3d change = Eigen::Matrix3d::Identity();
  Eigen::Vector3d move = Eigen::Vector3d::Zero();
  switch (l.frame) {
    case F::Trans:
    case F::ATrans:
      for (int k = 0; k < 3; ++k)
        if (l.axis[k].present) move[k] = length_mm(l.axis[k]);
      break;
    case F::Rot:
    case F::ARot: {
      auto deg = [&](int k) { return l.axis[k].present ? l.axis[k].value * kDegToRad : 0.0; };
      change =
          (Eigen::AngleAxisd(deg(2), Eigen::Vector3d::UnitZ()) * Eigen::AngleAxisd(deg(1), Eigen::Vector3d::UnitY()) *
           Eigen::AngleAxisd(deg(0), Eigen::Vector3d::UnitX()))
              .toRotationMatrix();
      if (l.rpl.present) {
        const Eigen::Vector3d normal = state_.plane == Plane::XY   ? Eigen::Vector3d::UnitZ()
                                       : state_.plane == Plane::ZX ? Eigen::Vector3d::UnitY()
                                                                   : Eigen::Vector3d::UnitX();
        change = change * Eigen::AngleAxisd(l.rpl.value * kDegToRad, normal).toRotationMatrix();
      }
      break;
    }
    case F::Scale:
    case F::AScale:
      for (int k = 0; k < 3; ++k) {
        if (!l.axis[k].present) continue;
        if (!(l.axis[k].value > 0.0 && l.axis[k].value <= 1000.0))
          fail(l.axis[k].column, l.frame_name + " factor " + num(l.axis[k].value) + " (expected > 0 and at most 1000)");
        change(k, k) = l.axis[k].value;
      }
      break;
    case F::Mirror:
    case F::AMirror:
      for (int k = 0; k < 3; ++k)
        if (l.axis[k].present) change(k, k) = -1.0;
      break;
    case F::None:
      return;
  }
  if (!additive) {
    m = Eigen::Matrix3d::Identity();
    t = Eigen::Vector3d::Zero();
  }
  t += m * move;
  m = m * change;
}

// A straight move of a drilling cycle to a point of the frame, as a G0 or G1 block would make it.
void Reader::cycle_move(const Eigen::Vector3d& frame_point, bool rapid, double feed_factor, int column,
                        double feed_mm_per_min) {
  if (!rapid && !(feed_mm_per_min > 0.0)) {
    if (!(state_.feed_mm_per_min > 0.0))
      fail(column, "drilling cycle without a feed (expected F in mm/min before the cycle)");
    if (state_.inverse_time) fail(column, "drilling cycle under G93 (expected G94: a feed in mm/min)");
    feed_mm_per_min = state_.feed_mm_per_min * feed_factor;
  }
  straight(placed(frame_point), rapid ? 0.0 : feed_mm_per_min, "a drilling cycle's move", column);
}

// The ISO metric coarse pitch (mm) of thread size M`size` (CYCLE84/CYCLE840 MPIT, 3..48; a
// negative size is a left-hand thread).
double Reader::coarse_pitch_mm(double size, const std::string& name, int column) const {
  static const std::pair<int, double> kCoarse[] = {{3, 0.5},   {4, 0.7},  {5, 0.8},  {6, 1.0},  {8, 1.25}, {10, 1.5},
                                                   {12, 1.75}, {14, 2.0}, {16, 2.0}, {18, 2.5}, {20, 2.5}, {22, 2.5},
                                                   {24, 3.0},  {27, 3.0}, {30, 3.5}, {33, 3.5}, {36, 4.0}, {39, 4.0},
                                                   {42, 4.5},  {45, 4.5}, {48, 5.0}};
  for (const auto& [m, pitch] : kCoarse)
    if (std::abs(size) == m) return pitch;
  fail(column, name + " MPIT " + num(size) + " (expected a metric coarse thread size M3..M48, or PIT)");
}

// CYCLE81(RTP, RFP, SDIS, DP, DPR) drilling, CYCLE82(..., DTB) with a dwell at the bottom,
// CYCLE83(RTP, RFP, SDIS, DP, DPR, FDEP, FDPR, DAM, DTB, DTS, FRF, VARI) deep-hole drilling
// (Siemens, Programming Manual Cycles), at the current X Y along the frame's Z (G17):
// rapid to RFP + SDIS, feed to the final depth (DPR below RFP when given, else DP), rapid to
// RTP. CYCLE83 pecks: the first to FDPR below RFP (else FDEP), each next one DAM less deep
// than the last but at least DAM (DAM 0: as deep as the first); VARI 1 (swarf removal) goes
// back to RFP + SDIS after each peck and rapid down again to where it stopped, VARI 0 (chip
// breaking) backs off 1 mm; the first peck's feed is F x FRF. Dwells (DTB, DTS) take no path.
// Tapping CYCLE84 (rigid) and CYCLE840 (compensating chuck), boring CYCLE85 and CYCLE89 feed
// back out to RFP + SDIS, then rapid to RTP; boring CYCLE86, CYCLE87, CYCLE88 stop the spindle
// at the depth and rapid out (CYCLE86's lift-off from the wall, RPA RPO, is a few tenths and
// not followed). A tap feeds at its pitch (PIT, or MPIT's coarse pitch) times the speed
// (CYCLE84's SST in and SST1 out, else S); CYCLE85 at FFR in and RFF out; the others at F.
void Reader::cycle(const std::string& name, const std::vector<std::optional<double>>& args, int column) {
  if (state_.plane != Plane::XY) fail(column, name + " outside G17 (expected G17: drilling along Z)");
  for (int k = 0; k < 3; ++k) {
    if (!state_.known[static_cast<std::size_t>(k)])
      fail(column,
           name + " from an unknown " + kAxisLetter[k] + " position (expected X, Y and Z programmed before it)");
  }
  auto arg = [&](std::size_t k) -> std::optional<double> {
    if (k >= args.size() || !args[k]) return std::nullopt;
    const double v = *args[k];
    if (!(std::abs(v) <= kMaxMagnitude)) fail(column, name + " parameter " + std::to_string(k + 1) + " out of range");
    return v;
  };
  const double unit = state_.inch ? kMmPerInch : 1.0;
  const auto rtp = arg(0), rfp = arg(1), dp = arg(3), dpr = arg(4);
  if (!rtp || !rfp) fail(column, name + " without RTP and RFP (expected " + name + "(RTP, RFP, SDIS, DP, DPR, ...))");
  const double sdis = std::abs(arg(2).value_or(0.0));
  if (!dp && !dpr) fail(column, name + " without its depth (expected DP or DPR)");
  const double top = *rfp * unit, clear = top + sdis * unit, retract = *rtp * unit;
  const double bottom = dpr ? top - std::abs(*dpr) * unit : *dp * unit;
  if (!(bottom < clear))
    fail(column, name + " depth at or above RFP + SDIS (expected the hole below the reference plane)");
  const Eigen::Vector3d here = in_frame(state_.position_mm);
  auto at_z = [&](double z) { return Eigen::Vector3d(here.x(), here.y(), z); };
  cycle_move(at_z(std::max(here.z(), clear)), true, 1.0, column);
  cycle_move(at_z(clear), true, 1.0, column);
  if (name != "CYCLE83") {
    double in_mm_per_min = 0.0, out_mm_per_min = 0.0;  // 0: F
    const double feed_unit = state_.inch_feed ? kMmPerInch : 1.0;
    if (name == "CYCLE84" || name == "CYCLE840") {
      // A tap advances its pitch per turn: PIT (or the metric coarse pitch of thread size
      // MPIT), times the speed (CYCLE84: SST in, SST1 out; else S).
      const bool rigid = name == "CYCLE84";
      const double mpit = arg(rigid ? 7 : 9).value_or(0.0), pit = arg(rigid ? 8 : 10).value_or(0.0);
      const double sst = rigid ? arg(10).value_or(0.0) : 0.0, sst1 = rigid ? arg(11).value_or(0.0) : 0.0;
      const double pitch = pit != 0.0 ? std::abs(pit) * unit : mpit != 0.0 ? coarse_pitch_mm(mpit, name, column) : 0.0;
      const double speed = sst > 0.0 ? sst : state_.spindle_rpm;
      const double back = sst1 > 0.0 ? sst1 : speed;
      if (pitch > 0.0 && speed > 0.0) {
        in_mm_per_min = pitch * speed;
        out_mm_per_min = pitch * back;
      } else if (!(state_.feed_mm_per_min > 0.0)) {
        fail(column, name + " without its pitch and speed (expected PIT or MPIT and S, or an F before it)");
      }
    } else if (name == "CYCLE85") {
      // FFR in, RFF out (mm/min).
      const auto ffr = arg(6), rff = arg(7);
      if (ffr && *ffr > 0.0) in_mm_per_min = *ffr * feed_unit;
      if (rff && *rff > 0.0) out_mm_per_min = *rff * feed_unit;
    }
    cycle_move(at_z(bottom), false, 1.0, column, in_mm_per_min);
    if (name == "CYCLE84" || name == "CYCLE840" || name == "CYCLE85" || name == "CYCLE89")
      cycle_move(at_z(clear), false, 1.0, column, out_mm_per_min);  // feed back out of the hole
  } else {
    const auto fdep = arg(5), fdpr = arg(6), dam = arg(7), frf = arg(10), vari = arg(11);
    double first = fdpr ? std::abs(*fdpr) * unit : fdep ? top - *fdep * unit : top - bottom;
    if (!(first > 0.0)) first = top - bottom;
    const double degression = std::abs(dam.value_or(0.0)) * unit;
    // Bounded work: a peck too small for its depth is a typo (and a million blocks per hole).
    const double smallest = degression > 0.0 ? std::min(first, degression) : first;
    if (top - bottom > 10000.0 * smallest)
      fail(column, "CYCLE83 pecks of " + num(smallest) + " mm for a hole " + num(top - bottom) +
                       " mm deep: more than 10000 pecks (expected a larger FDPR or DAM)");
    if (frf && !(*frf > 0.0 && *frf <= 1.0))
      fail(column, "CYCLE83 FRF " + num(*frf) + " (expected a feed factor over 0, at most 1)");
    const double factor = frf ? *frf : 1.0;
    const bool swarf = vari.value_or(1.0) != 0.0;
    double reached = top, peck = first;
    bool first_peck = true;
    while (reached > bottom) {
      const double next = std::max(bottom, reached - peck);
      if (!first_peck && swarf) cycle_move(at_z(reached), true, 1.0, column);
      cycle_move(at_z(next), false, first_peck ? factor : 1.0, column);
      reached = next;
      first_peck = false;
      peck = degression > 0.0 ? std::max(peck - degression, degression) : first;
      if (reached > bottom) cycle_move(at_z(swarf ? clear : reached + 1.0), true, 1.0, column);
    }
  }
  cycle_move(at_z(retract), true, 1.0, column);
}

// --- CYCLE800, swivelling (Siemens, Operating Manual "Swivel plane": parameters
// CYCLE800(_FR, _TC, _ST, _MODE, _X0, _Y0, _Z0, _A, _B, _C, _X1, _Y1, _Z1, _DIR, _FR_I, _DMODE)).
// The swivel frame S(p) = (X0 Y0 Z0) + R (p + (X1 Y1 Z1)): X0.. the reference point of the turn
// (before it), X1.. the zero point of the turned plane (after it), in the frame chain after the
// work offset and before TRANS / ROT (as $P_WPFRAME sits before $P_PFRAME). _ST's units digit:
// 0 a new plane (S replaces the swivel frame), 1 additive (S follows it). _MODE bits 7-6: 00
// axis by axis, bits 1-0, 3-2, 5-4 the axis of the 1st, 2nd, 3rd turn (01 X, 10 Y, 11 Z: 57 is
// X Y Z, 27 Z Y X), _A _B _C the angles in that order, each about the axes the previous turns
// left (R = R1(_A) R2(_B) R3(_C)); 10 (128) projection angles (Reader::swivel_turn: as ROTS
// defines them, _A _B about the first two axes, _C about the third); 11 (192) rotary axes
// direct: _A _B the positions of the
// machine's rotary axes 1 and 2 (SinumerikOptions::rotary_axes), R the turn they give the tool's
// frame on the workpiece (SinumerikOptions::frame_rotation). Solid angle (64) is refused: vcut
// has not verified its convention.
// _DIR -1 / +1: the rotaries turn the tool to R z, the solution whose tilting axis is <= 0 /
// >= 0 (the other where that one is out of reach, as the control does); 0: the frame only.
// _FR: 0 no retraction, 1 machine Z to the machine's home, 2 Z then X Y to it, 4 along the tool
// axis until Z is there, 5 _FR_I mm along the tool axis; the machine file has no swivel data
// record, so its home stands in for the record's retraction positions. The rotaries then turn
// with the linear axes held (the tip swings with them, in steps of 1 deg). CYCLE800() or _TC
// "0" deselects: the swivel frame goes; where the rotaries stay turned, X Y Z are the machine's
// axes again (the frame is the turn itself). Other _ST digits (direction optimisation, tool
// tracking) and _DMODE are not read.
void Reader::swivel(const std::vector<std::optional<double>>& args, const std::vector<std::string>& texts, int column) {
  auto arg = [&](std::size_t k) -> double {
    if (k >= args.size() || !args[k]) return 0.0;
    const double v = *args[k];
    if (!(std::abs(v) <= kMaxMagnitude))
      fail(column, "CYCLE800 parameter " + std::to_string(k + 1) + " " + num(v) + " (expected within +-1e6)");
    return v;
  };
  const bool deselect = args.empty() || (texts.size() > 1 && texts[1] == "0");
  if (deselect) {
    state_.swivel_plane = false;
    if (state_.rotary_program) {  // an axis program: X Y Z are the machine's already
      state_.swivel_rotation.setIdentity();
      state_.swivel_translation_mm.setZero();
      return;
    }
    const auto [r, t] = turned(state_.rotary);
    // X Y Z are the machine's: p + offset is the axes' point, M(p + o) = o + S(p).
    const Eigen::Vector3d o = offset();
    state_.swivel_rotation = r;
    state_.swivel_translation_mm = r * o + t - o;
    return;
  }
  const double fr = arg(0), st = arg(2), mode_value = arg(3), dir = arg(13);
  if (fr != 0.0 && fr != 1.0 && fr != 2.0 && fr != 4.0 && fr != 5.0)
    fail(column, "CYCLE800 _FR " + num(fr) +
                     " (expected 0 no retraction, 1 Z, 2 Z then X Y, 4 the most along the tool, 5 _FR_I along it)");
  if (!(st >= 0.0 && st == std::floor(st)) || (static_cast<long long>(st) % 10) > 1)
    fail(column, "CYCLE800 _ST " + num(st) + " (expected a whole number whose units digit is 0 new or 1 additive)");
  if (!(mode_value >= 0.0 && mode_value <= 255.0 && mode_value == std::floor(mode_value)))
    fail(column, "CYCLE800 _MODE " + num(mode_value) + " (expected 0..255: 57 X Y Z, 27 Z Y X, 192 rotary axes)");
  if (dir != -1.0 && dir != 0.0 && dir != 1.0)
    fail(column, "CYCLE800 _DIR " + num(dir) + " (expected -1 or +1, the direction, or 0: the frame only)");
  const double unit = state_.inch ? kMmPerInch : 1.0;
  const Eigen::Vector3d x0(arg(4) * unit, arg(5) * unit, arg(6) * unit);
  const Eigen::Vector3d x1(arg(10) * unit, arg(11) * unit, arg(12) * unit);
  const int mode = static_cast<int>(mode_value);
  kinematics::RotaryWords direct = state_.rotary;
  Eigen::Matrix3d turn;
  if ((mode >> 6) == 3) {
    if (options_.rotary_axes.empty() || !options_.frame_rotation)
      fail(column, "CYCLE800 _MODE " + num(mode_value) +
                       " (rotary axes direct) needs the machine's rotary axes (expected a job, or --machine)");
    if (static_cast<long long>(st) % 10 == 1)
      fail(column, "CYCLE800 _MODE 192 (rotary axes direct) with an additive plane (_ST 1; expected a new plane)");
    for (std::size_t k = 0; k < 2; ++k) {
      const double deg = arg(7 + k);
      if (k >= options_.rotary_axes.size()) {
        if (deg != 0.0)
          fail(column, "CYCLE800 _MODE 192: the machine has no rotary axis " + std::to_string(k + 1) + " for " +
                           num(deg) + " deg");
        continue;
      }
      // A swivel is within a turn or so (the machine's limits decide the rest, as its poses are checked).
      if (!(std::abs(deg) <= 720.0))
        fail(column, "CYCLE800 _MODE 192: rotary axis " + std::to_string(k + 1) + " at " + num(deg) +
                         " deg (expected within +-720 deg)");
      const auto r = static_cast<std::size_t>(options_.rotary_axes[k] - 'A');
      direct.angle_rad[r] = deg * kDegToRad;
      direct.given[r] = true;
    }
    turn = options_.frame_rotation(direct);
  } else {
    turn = swivel_turn(mode, arg(7), arg(8), arg(9), column);
  }
  const bool additive = static_cast<long long>(st) % 10 == 1;
  // The new plane in the frame before it: additive, after the present swivel frame.
  const Eigen::Matrix3d r0 = additive ? state_.swivel_rotation : Eigen::Matrix3d::Identity();
  const Eigen::Vector3d t0 = additive ? state_.swivel_translation_mm : Eigen::Vector3d::Zero();
  const Eigen::Matrix3d rotation = r0 * turn;
  const Eigen::Vector3d translation = t0 + r0 * (x0 + turn * x1);
  if (!(translation.cwiseAbs().maxCoeff() <= kMaxMagnitude))
    fail(column, "CYCLE800's frame moves the zero out of range (expected within +-1e6 mm)");
  if (fr != 0.0 || dir != 0.0) {
    for (int k = 0; k < 3; ++k) {
      if (!state_.known[static_cast<std::size_t>(k)])
        fail(column, std::string("CYCLE800 from an unknown ") + kAxisLetter[k] +
                         " position (expected X, Y and Z programmed before it, or the job's start: position: it "
                         "retracts and turns from there)");
    }
  }
  if (state_.rotary_program) {
    // After A B C words without TRAORI, X Y Z were the machine's axes: from here the tip again.
    const auto [r, t] = turned(state_.rotary);
    state_.position_mm = r * state_.position_mm + t;
    state_.rotary_program = false;
  }
  if (fr != 0.0) retract(fr, arg(14) * unit, column);
  if (dir != 0.0) {
    if (!options_.orient || !options_.tip_after_turn)
      fail(column,
           "CYCLE800 turns the rotary axes (_DIR " + num(dir) +
               "): it needs the machine (expected a job, or vcut program --machine; _DIR 0 for the frame only)");
    kinematics::RotaryWords to = direct;
    if ((mode >> 6) != 3) {
      const Eigen::Vector3d axis = rotation.col(2);
      const int sign = dir > 0.0 ? 1 : -1;
      std::string why = options_.orient(state_.tool, state_.position_mm, axis, state_.rotary, sign, to);
      if (!why.empty()) why = options_.orient(state_.tool, state_.position_mm, axis, state_.rotary, 0, to);
      if (!why.empty())
        fail(column, "CYCLE800: the machine cannot turn the tool to the plane's Z (" + num(axis.x()) + ", " +
                         num(axis.y()) + ", " + num(axis.z()) + "): " + why);
    }
    turn_rotaries(to, column);
    state_.tool_axis = rotation.col(2);
  }
  state_.swivel_rotation = rotation;
  state_.swivel_translation_mm = translation;
  // A new plane of no turn and no shift (NX's CYCLE800 with zero angles) is no plane.
  state_.swivel_plane = !(rotation.isIdentity(1e-12) && translation.isZero(0.0));
}

// CYCLE800's turn for _MODE axis by axis (bits 7-6 00).
Eigen::Matrix3d Reader::swivel_turn(int mode, double a_deg, double b_deg, double c_deg, int column) const {
  const int kind = mode >> 6;
  if (kind == 1) {
    fail(column, "CYCLE800 _MODE " + std::to_string(mode) +
                     " (solid angle) is not supported: vcut has not verified its convention (expected axis by axis, "
                     "such as 57 or 27, projection angles, or 192 rotary axes direct)");
  }
  const double angles[3] = {a_deg, b_deg, c_deg};
  const int axes[3] = {mode & 3, (mode >> 2) & 3, (mode >> 4) & 3};  // 1 X, 2 Y, 3 Z, 0 none
  auto turn = [](int axis, double deg) {
    return Eigen::AngleAxisd(deg * kDegToRad, Eigen::Vector3d::Unit(axis - 1)).toRotationMatrix();
  };
  const std::string where = "CYCLE800 _MODE " + std::to_string(mode);
  if (kind == 2) {
    // Projection angles, as ROTS defines them (Function Manual K2, "frame rotations with solid
    // angles"): the angles about the first two axes p and q are those of the plane's traces,
    // taken in cyclic order (p, q, r) = (X, Y, Z), (Y, Z, X) or (Z, X, Y): the new p axis lies in
    // the old r-p plane, turned by beta about q; the new q axis turned by alpha about p lies in
    // the plane. R = Rq(beta) Rp(alpha') with tan alpha' = tan alpha cos beta, then the third
    // angle about the new r axis.
    const int first = axes[0], second = axes[1];
    if (first == 0 || second == 0 || first == second || (axes[2] != 0 && axes[2] == first) ||
        (axes[2] != 0 && axes[2] == second))
      fail(column, where + " (projection angles) names the axes " + std::to_string(first) + ", " +
                       std::to_string(second) + ", " + std::to_string(axes[2]) +
                       " (expected two different axes, then the third)");
    const bool cyclic = second == first % 3 + 1;
    const int p = cyclic ? first : second, q = cyclic ? second : first, r = 6 - p - q;
    const double alpha = cyclic ? a_deg : b_deg, beta = cyclic ? b_deg : a_deg;
    if (!(std::abs(alpha) < 90.0 && std::abs(beta) < 90.0))
      fail(column, where + " projection angles " + num(a_deg) + ", " + num(b_deg) +
                       " deg (expected within -90..90: the plane's traces)");
    if (axes[2] == 0 && c_deg != 0.0)
      fail(column, where + " names no axis for the third turn but its angle is " + num(c_deg) + " deg");
    const double alpha_turned = std::atan(std::tan(alpha * kDegToRad) * std::cos(beta * kDegToRad)) / kDegToRad;
    return turn(q, beta) * turn(p, alpha_turned) * turn(r, c_deg);
  }
  // Axis by axis (kind 0); rotary axes direct (kind 3) do not come here.
  Eigen::Matrix3d r = Eigen::Matrix3d::Identity();
  for (int k = 0; k < 3; ++k) {
    if (axes[k] == 0) {
      if (angles[k] != 0.0)
        fail(column, where + " names no axis for turn " + std::to_string(k + 1) + " but its angle is " +
                         num(angles[k]) + " deg (expected 57 X Y Z, 27 Z Y X or another order)");
      continue;
    }
    r = r * turn(axes[k], angles[k]);
  }
  return r;
}

void Reader::straight(const Eigen::Vector3d& end, double feed_mm_per_min, const char* what, int column,
                      const std::array<bool, 3>& programmed) {
  if (!(end.cwiseAbs().maxCoeff() <= kMaxMagnitude))
    fail(column, std::string(what) + " out of range (expected within +-1e6 mm of the workpiece zero)");
  Block block;
  block.kind = feed_mm_per_min > 0.0 ? MotionKind::Linear : MotionKind::Rapid;
  block.feed_mm_per_min = feed_mm_per_min;
  block.start_mm = state_.position_mm;
  block.end_mm = end;
  for (std::size_t k = 0; k < 3; ++k) {
    if (!state_.known[k]) block.start_mm[static_cast<int>(k)] = end[static_cast<int>(k)];
  }
  block.tool_pose = !state_.rotary_program;
  block.orientation = state_.rotary_program ? OrientationMode::Axes : OrientationMode::Vector;
  block.start_axis = block.end_axis = state_.tool_axis;
  block.start_rotary = block.end_rotary = state_.rotary;
  block.exact_stop = true;
  append(block, programmed, false);
}

// CYCLE800's retraction (_FR 1, 2, 4, 5), in the machine's axes: the tip's point p with the
// rotaries at zero is where the linear axes stand (as in an axis program); the home's gauge
// point less the tool's length along the spindle is the retracted tip there.
void Reader::retract(double fr, double fr_i_mm, int column) {
  const Eigen::Vector3d tool = state_.tool_axis;
  if (fr == 5.0) {
    if (!(fr_i_mm >= 0.0)) fail(column, "CYCLE800 _FR 5 with _FR_I " + num(fr_i_mm) + " (expected a distance >= 0 mm)");
    straight_to(state_.position_mm + fr_i_mm * tool, column);
    return;
  }
  if (!options_.reference_mm)
    fail(column, "CYCLE800 _FR " + num(fr) +
                     " retracts to the machine's home: it needs the machine (expected a job, or --machine; _FR 0 or 5 "
                     "without one)");
  const auto [r, t] = turned(state_.rotary);
  const Eigen::Vector3d home = (*options_.reference_mm)[0] - tool_length_mm() * options_.spindle_axis;
  const Eigen::Vector3d axes = r.transpose() * (state_.position_mm - t);  // the linear axes' point
  if (fr == 4.0) {
    // Along the tool until the Z axis reaches its home: the tool direction in the axes' frame.
    const Eigen::Vector3d d = r.transpose() * tool;
    if (d.z() > 1e-6 && axes.z() < home.z()) {
      straight_to(state_.position_mm + (home.z() - axes.z()) / d.z() * tool, column);
      return;
    }
  }
  Eigen::Vector3d up = axes;
  up.z() = std::max(axes.z(), home.z());
  straight_to(r * up + t, column);
  if (fr == 2.0) straight_to(r * Eigen::Vector3d(home.x(), home.y(), up.z()) + t, column);
}

void Reader::turn_rotaries(const kinematics::RotaryWords& to, int column) {
  const kinematics::RotaryWords from = state_.rotary;
  if (const std::string why = detail::rotary_turn_refused(from, to); !why.empty()) fail(column, "CYCLE800: " + why);
  const Eigen::Vector3d tip = state_.position_mm;
  const int steps = detail::rotary_steps(from, to);
  for (int n = 1; n <= steps; ++n) {
    const kinematics::RotaryWords step = detail::rotary_step(from, to, n, steps);
    Block block;
    block.kind = MotionKind::Rapid;
    block.start_mm = state_.position_mm;
    block.end_mm = options_.tip_after_turn(state_.tool, tip, from, step);
    block.tool_pose = true;
    block.start_rotary = state_.rotary;
    block.end_rotary = step;
    block.start_axis = block.end_axis = state_.tool_axis;
    block.exact_stop = true;
    append(block, {true, true, true}, true);
    state_.rotary = step;
  }
  state_.rotary = to;
}

// G74 (reference point approach) and G75 FP=1 / FP=2 (fixed point 1, 2): the named axes (X1=
// Y1= Z1= as the manual writes them, or X Y Z; their values are not used) rapid to the
// machine's home or second home (SinumerikOptions::reference_mm), the others stay; the tip a
// tool's length below the gauge point.
void Reader::home() {
  const Line& l = l_;
  const std::string name = "G" + std::to_string(l.home);
  int fp = 1;
  if (l.home == 75) {
    if (!l.fp.present) fail(l.home_column, "G75 without FP= (expected FP=1 or FP=2, the fixed point)");
    if (l.fp.value != 1.0 && l.fp.value != 2.0)
      fail(l.fp.column, "G75 FP=" + num(l.fp.value) +
                            " (expected FP=1 or FP=2: the machine file has two fixed points, home and second home)");
    fp = static_cast<int>(l.fp.value);
  }
  for (int k = 0; k < 3; ++k) {
    if (l.rotary[k].present)
      fail(l.rotary[k].column, name + " with a rotary axis (expected X Y Z: vcut moves the linear axes there)");
  }
  std::array<bool, 3> named{};
  bool any = false;
  for (std::size_t k = 0; k < 3; ++k) {
    named[k] = l.machine_axis[k] || l.axis[k].present;
    any = any || named[k];
  }
  if (!any) fail(l.home_column, name + " without an axis (expected " + name + " X1=0 Y1=0 Z1=0 naming the axes)");
  if (!options_.reference_mm)
    fail(l.home_column, name + " goes to a point of the machine: it needs the machine (expected a job, or --machine)");
  const auto [r, t] = machine_turn();
  Eigen::Vector3d axes = r.transpose() * (state_.position_mm - t);
  const Eigen::Vector3d point =
      (*options_.reference_mm)[static_cast<std::size_t>(fp - 1)] - tool_length_mm() * options_.spindle_axis;
  for (int k = 0; k < 3; ++k)
    if (named[static_cast<std::size_t>(k)]) axes[k] = point[k];
  straight(r * axes + t, 0.0, (name + "'s move").c_str(), l.home_column, named);
}

// Appends a block (unless it does not move) and brings the position and the unknown axes up
// to date, as the G-code reader does: blocks made while an axis is unknown hold it still and
// take its value when it is first programmed.
void Reader::append(Block block, const std::array<bool, 3>& programmed, bool reorients) {
  const bool moves = block.kind == MotionKind::Arc || block.start_mm != block.end_mm || reorients;
  if (moves) {
    block.tool = state_.tool;
    block.spindle = state_.spindle;
    block.spindle_rpm = state_.spindle_rpm;
    block.source = kinematics::SourceRef{file_index_, line_};
    program_.blocks.push_back(block);
    for (std::size_t a = 0; a < 3; ++a) {
      if (!state_.known[a] && !programmed[a]) state_.pending[a].push_back(program_.blocks.size() - 1);
    }
  }
  for (std::size_t a = 0; a < 3; ++a) {
    if (!programmed[a] || state_.known[a]) continue;
    state_.known[a] = true;
    auto& pending = state_.pending[a];
    if (pending.empty()) continue;
    const double value = block.end_mm[static_cast<int>(a)];
    std::size_t patched = 0;
    std::string first;
    for (std::size_t index : pending) {
      if (index >= program_.blocks.size()) continue;  // a different Program was passed in
      Block& b = program_.blocks.edit(index);
      if (first.empty() && b.source.file >= 0 && static_cast<std::size_t>(b.source.file) < program_.files.size()) {
        first = program_.where(b.source);
      }
      b.start_mm[static_cast<int>(a)] = b.end_mm[static_cast<int>(a)] = value;
      if (b.kind == MotionKind::Arc) b.center_mm[static_cast<int>(a)] = value;  // only the normal axis
      ++patched;
    }
    pending.clear();
    if (patched > 0) {
      warn(l_.axis[a].column, std::to_string(patched) + " earlier move(s) (first at " + first + ") ran while " +
                                  kAxisLetter[a] + " was unknown; they hold " + kAxisLetter[a] + " at " + num(value) +
                                  " mm, its first programmed value");
    }
  }
  state_.position_mm = block.end_mm;
}

void validate(const std::string& name, const SinumerikOptions& options) {
  if (!std::isfinite(options.arc_tolerance_mm) || options.arc_tolerance_mm < 0.0) {
    throw InputError(
        name, 0, 0,
        "arc tolerance " + num(options.arc_tolerance_mm) + " mm in the options (expected a finite value >= 0)");
  }
  for (const auto& [key, offset] : options.work_offsets_mm) {
    if (!offset.allFinite() || offset.cwiseAbs().maxCoeff() > kMaxMagnitude) {
      throw InputError(name, 0, 0, "work offset " + key + " in the options (expected finite values within +-1e6 mm)");
    }
  }
}

}  // namespace

void read_sinumerik(std::istream& in, const std::string& name, const SinumerikOptions& options,
                    kinematics::Program& program, SinumerikState& state) {
  validate(name, options);
  if (state.r.size() != static_cast<std::size_t>(kRParameters)) state.r.assign(kRParameters, 0.0);
  const int file_index = static_cast<int>(program.files.size());
  if (file_index == 0 && options.initial_tool > 0) state.tool = state.selected_tool = options.initial_tool;
  if (file_index == 0 && options.start_mm) {
    // The machine is somewhere: its home's gauge point, the tip a tool length below it.
    const auto length = options.tool_length_mm.find(state.tool);
    const double l = length == options.tool_length_mm.end() ? 0.0 : length->second;
    state.position_mm = *options.start_mm - l * options.spindle_axis;
    state.known = {true, true, true};
  }
  program.files.push_back(name);
  Reader reader(name, options, program, state, file_index);
  detail::read_guarded(name, [&] { reader.run(in); });
  detail::warn_unprogrammed_axes(state.pending, name, program);
}

kinematics::Program read_sinumerik(const std::string& path, const SinumerikOptions& options) {
  std::ifstream in = detail::open_program_file(path, "a SINUMERIK program file", "the SINUMERIK program");
  kinematics::Program program;
  SinumerikState state;
  read_sinumerik(in, path, options, program, state);
  return program;
}

}  // namespace vcut::io
