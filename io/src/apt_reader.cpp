// Reads APT CL data in its text form as CAM systems print it (CATIA, NX "APT source",
// Mastercam/Fusion APT posts): one statement per line, `$` continuations, `$$` comments.
// The statement words and their parameters follow ISO 4343 (CLDATA) and the APT language
// (ISO 3592); where this reader picks one of several readings it says so next to the code.
// Memory: one line and one statement at a time, plus the Blocks and the cutters.
#include <vcut/io/apt_reader.h>
#include <vcut/io/input_error.h>

#include <algorithm>
#include <charconv>
#include <climits>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <initializer_list>
#include <istream>
#include <new>
#include <stdexcept>
#include <system_error>
#include <tuple>
#include <vector>

#include "block_room.h"
#include "cutter_comp.h"
#include "line_source.h"
#include "reader_util.h"

namespace vcut::io {
namespace {

using kinematics::Block;
using kinematics::MotionKind;
using kinematics::SpindleState;
using removal::Cutter;
using removal::CutterType;

constexpr double kMmPerInch = 25.4;  // exact, by the 1959 definition of the inch
// Any length beyond this (mm), feed (mm/min) or speed (rpm) is a typo or garbage: a 1 km
// stroke or a 1000 m/min feed exists on no milling machine.
constexpr double kMaxMagnitude = 1e6;
// Points closer than this coincide (full circles): far below any machine's resolution, far
// above the rounding of mm values up to kMaxMagnitude (~1e-10).
constexpr double kSamePointMm = 1e-9;
// A circle's start and end may be off its radius by this times r on top of the arc tolerance,
// so that large radii printed with few decimals are not rejected (as in the G-code reader).
constexpr double kArcRelativeTolerance = 1e-6;
// (i,j,k) shorter than this has no direction. CL files print unit vectors with 4 to 9 decimals.
constexpr double kMinAxisNorm = 1e-6;
// Two tool axes this close to opposite (cosine) have no single great circle between them.
constexpr double kOppositeAxisCosine = -1.0 + 1e-12;
// Bounded memory: no line or statement of a CL file comes near this.
constexpr std::size_t kMaxStatementBytes = std::size_t{1} << 20;
constexpr std::size_t kMaxParameters = 64;  // CIRCLE/ has 11 at most, the longest we read
// CUTTER/ consistency: e and f are printed with the file's few decimals (0.00005 in = 0.0013 mm).
constexpr double kCutterMatchMm = 0.002;
// Angles printed as 0.000000 are zero; anything beyond this is a real alpha or beta.
constexpr double kZeroAngleDeg = 1e-6;
// CUTTER/ without h: 4 diameters of flute, a common stub-to-regular end mill, and the height
// above which a real tool's shank would take over. Documented in apt_reader.h.
constexpr double kDefaultHeightPerDiameter = 4.0;
constexpr int kMaxToolNumber = 99999;  // as the tool library

bool is_blank(char c) { return c == ' ' || c == '\t' || c == '\f' || c == '\v'; }
using detail::describe;
using detail::is_digit;
using detail::is_letter;
using detail::num;
using detail::upper;

bool is_word_char(char c) { return is_letter(c) || is_digit(c) || c == '_' || c == '-'; }
size_t skip_blanks(const std::string& s, size_t i) {
  while (i < s.size() && is_blank(s[i])) ++i;
  return i;
}

int clamp_int(size_t v) { return v >= static_cast<size_t>(INT_MAX) ? INT_MAX : static_cast<int>(v); }

std::string point(const Eigen::Vector3d& p) { return "(" + num(p.x()) + ", " + num(p.y()) + ", " + num(p.z()) + ")"; }

bool same_cutter(const Cutter& a, const Cutter& b) {
  return a.type == b.type && a.diameter_mm == b.diameter_mm && a.corner_radius_mm == b.corner_radius_mm &&
         a.flute_length_mm == b.flute_length_mm && a.shank_diameter_mm == b.shank_diameter_mm &&
         a.length_mm == b.length_mm && a.gauge_length_mm == b.gauge_length_mm && a.tip_angle_deg == b.tip_angle_deg;
}

// One parameter after the '/': a number or a word (upper case).
struct Arg {
  bool is_number = false;
  double value = 0.0;
  std::string word;
  size_t pos = 0;  // offset in the statement
};

// Where the text of a statement came from: statement offset -> line and column.
struct Segment {
  size_t offset;
  int line;
  int column;  // of the byte at `offset`
};

enum class Word {
  kUnknown,
  kCutcom,
  kGoto,
  kFrom,
  kGodlta,
  kRapid,
  kFedrat,
  kCutter,
  kLoadtl,
  kLoad,
  kMultax,
  kTlaxis,
  kCircle,
  kSpindl,
  kUnits,
  kEnd,
  kFini,
};

Word lookup(const std::string& w) {
  switch (w.size()) {
    case 3:
      if (w == "END") return Word::kEnd;
      break;
    case 4:
      if (w == "GOTO") return Word::kGoto;
      if (w == "FROM") return Word::kFrom;
      if (w == "FINI") return Word::kFini;
      if (w == "LOAD") return Word::kLoad;
      break;
    case 5:
      if (w == "RAPID") return Word::kRapid;
      if (w == "UNITS") return Word::kUnits;
      break;
    case 6:
      if (w == "GODLTA") return Word::kGodlta;
      if (w == "FEDRAT") return Word::kFedrat;
      if (w == "CUTTER") return Word::kCutter;
      if (w == "LOADTL") return Word::kLoadtl;
      if (w == "MULTAX") return Word::kMultax;
      if (w == "TLAXIS") return Word::kTlaxis;
      if (w == "CIRCLE") return Word::kCircle;
      if (w == "SPINDL") return Word::kSpindl;
      if (w == "CUTCOM") return Word::kCutcom;
      break;
    default:
      break;
  }
  return Word::kUnknown;
}

// Statements whose remainder is free text: not parsed, no `$` continuation.
bool free_text(const char* w, size_t n, bool& silent) {
  auto is = [&](const char* k) { return std::strlen(k) == n && std::memcmp(w, k, n) == 0; };
  silent = is("PPRINT");
  return silent || is("PARTNO") || is("INSERT") || is("REMARK") || is("TPRINT");
}

class Reader : public detail::CompHost {
 public:
  Reader(const std::string& name, const AptOptions& options, AptProgram& out, AptState& state, int file_index)
      : name_(name), options_(options), out_(out), state_(state), file_index_(file_index) {}

  void run(std::istream& in);

 private:
  [[noreturn]] void fail_at(int line, int column, const std::string& message) const {
    throw InputError(name_, line, column, message);
  }
  [[noreturn]] void fail(size_t pos, const std::string& message) const {
    const auto [line, column] = locate(pos);
    fail_at(line, column, message);
  }
  std::pair<int, int> locate(size_t pos) const {
    for (size_t k = segments_.size(); k-- > 0;) {
      if (segments_[k].offset <= pos) {
        return {segments_[k].line, clamp_int(static_cast<size_t>(segments_[k].column) + (pos - segments_[k].offset))};
      }
    }
    return {line_, 0};
  }
  std::string where(size_t pos) const {
    const auto [line, column] = locate(pos);
    return name_ + ":" + std::to_string(line) + ":" + std::to_string(column);
  }
  std::string where_line() const { return name_ + ":" + std::to_string(statement_line_); }
  // One warning per word; the message is only built the first time (unknown statements can
  // be on every line).
  template <class Message>
  void warn_once(const std::string& word, Message&& message) {
    if (state_.warned.count(word) != 0) return;
    state_.warned.insert(word);
    out_.program.warnings.push_back(message());
  }

  bool line(std::string& text, int number);
  bool statement();
  void parse_args(size_t i);
  size_t parse_number(size_t i, Arg& arg) const;

  // Parameter helpers: the k-th parameter as a number, checked.
  double number(size_t k, const char* what) const;
  double length(size_t k, const char* what) const;  // converted to mm, within +-1e6
  void count(size_t low, size_t high, const char* form) const;
  void count_of(std::initializer_list<size_t> allowed, const char* form) const;
  Eigen::Vector3d unit_vector(size_t k, const char* what) const;
  double unit() const { return state_.inches ? kMmPerInch : 1.0; }

  void do_goto();
  void do_from();
  void do_godlta();
  void do_fedrat();
  void do_cutter();
  void do_loadtl(bool load_tool);
  void do_multax();
  void do_tlaxis();
  void do_circle();
  void do_spindl();
  void do_units();
  void do_cutcom();
  bool compensating() const { return state_.comp.side != Comp::Side::Off && state_.comp.radius_mm > 0.0; }
  void comp_end(size_t pos);  // sends the held moves to where the tool is
  // What the G-code reader refuses with G41/G42 on (a new position, a tool change, five axes).
  void no_cutcom(const char* what) const {
    if (state_.comp.side != GcodeState::CutterComp::Side::Off) {
      fail(major_pos_, std::string(what) + " with CUTCOM on (expected CUTCOM/OFF first)");
    }
  }
  // CompHost: the compensation's moves are this reader's.
  using Comp = GcodeState::CutterComp;
  Eigen::Vector3d& tool_position() override { return state_.position_mm; }
  void comp_plane(int& a, int& b, int& c) const override { a = 0, b = 1, c = 2; }
  double comp_unit() const override { return state_.inches ? kMmPerInch : 1.0; }
  void comp_append(Block block, const std::array<bool, 3>& programmed, bool held, const Eigen::Vector2d& direction,
                   double sweep_rad) override;
  std::vector<Block>& comp_blocks() override { return out_.program.blocks; }
  [[noreturn]] void comp_fail(int column, const std::string& message) const override {
    fail(static_cast<size_t>(column), message);
  }
  // Where the program is (CL points count from it): with compensation on, the last programmed
  // point in XY, not the tool's.
  Eigen::Vector3d programmed_point() const {
    Eigen::Vector3d p = state_.position_mm;
    if (compensating() && !state_.comp.first_move) p.head<2>() = state_.comp.program_mm.head<2>();
    return p;
  }
  void no_circle_pending(const char* what) const;

  void motion(MotionKind kind, const Eigen::Vector3d& end, const Eigen::Vector3d& end_axis);
  int motion_tool();

  const std::string& name_;
  const AptOptions& options_;
  AptProgram& out_;
  AptState& state_;
  const int file_index_;

  int line_ = 0;
  bool continuing_ = false;  // the last line ended in '$'
  std::string stmt_;         // the statement's text, continuation lines joined
  std::vector<Segment> segments_;
  int statement_line_ = 0;  // its first line
  std::string major_;
  size_t major_pos_ = 0;
  std::vector<Arg> args_;
  size_t nargs_ = 0;
  size_t args_pos_ = 0;  // just after the '/' (or after the word when there is none)
};

void Reader::run(std::istream& in) {
  detail::LineSource source(in);
  std::string text;
  int number = 0;
  bool finished = false;
  // Most lines of a CL file are motions: room for one Block per line, estimated from the first
  // 64 KiB, saves the vector's regrowth copies (half the reading time of a 10^6-line file).
  // Capacity that is never written stays virtual memory.
  const std::streamsize available = in.rdbuf() ? in.rdbuf()->in_avail() : 0;
  bool reserved = false;
  while (true) {
    const detail::LineSource::Result r = source.next(text);
    if (r == detail::LineSource::kEnd) break;
    if (!reserved) {
      reserved = true;
      detail::reserve_blocks(out_.program.blocks, source.estimate_lines(static_cast<double>(available)));
    }
    if (number == INT_MAX) fail_at(number, 0, "too many lines");
    ++number;
    if (r == detail::LineSource::kTooLong) {
      fail_at(number, 0, "line longer than 1 MiB (expected a text file of CL statements)");
    }
    if (!line(text, number)) {
      finished = true;
      break;
    }
  }
  if (in.bad()) fail_at(number + 1, 0, "read error (expected a readable text file)");
  if (continuing_) {
    const Segment& last = segments_.back();
    fail_at(last.line, 0,
            "'$' continuation at the end of the file (expected the statement to go on in the "
            "next line)");
  }
  // A file that ends while a compensated move is held: it runs to its offset point.
  if (!state_.comp.held.empty()) comp_end(0);
  if (!finished && state_.circle_pending) {
    state_.circle_pending = false;
    fail_at(state_.circle_line, state_.circle_column,
            "CIRCLE/ without the GOTO/ that ends its arc (expected a GOTO/ after it before the "
            "end of the file)");
  }
}

bool Reader::line(std::string& text, int number) {
  line_ = number;
  size_t n = text.size();
  if (n > 0 && text[n - 1] == '\r') --n;  // CRLF files
  size_t i = 0;
  if (number == 1 && n >= 3 && std::memcmp(text.data(), "\xEF\xBB\xBF", 3) == 0) i = 3;  // BOM
  for (size_t k = i; k < n; ++k) {
    const auto c = static_cast<unsigned char>(text[k]);
    if (c >= 0x20 && c != 0x7F) continue;
    if (c == '\t' || c == '\f' || c == '\v') continue;
    if (c == '\r') {
      fail_at(number, clamp_int(k + 1), "carriage return inside a line (expected \\n or \\r\\n line ends)");
    }
    fail_at(number, clamp_int(k + 1),
            "not a text file: control byte " + describe(text[k]) + " (expected an APT CL file of text statements)");
  }
  if (!continuing_) {
    while (i < n && is_blank(text[i])) ++i;
    if (i == n) return true;
    size_t j = i;
    while (j < n && is_word_char(text[j])) ++j;
    char word[8];
    bool silent = false;
    if (j - i <= sizeof word) {
      for (size_t k = i; k < j; ++k) word[k - i] = upper(text[k]);
      if (free_text(word, j - i, silent)) {
        if (!silent) {
          const std::string w(word, j - i);
          warn_once(w, [&] {
            return name_ + ":" + std::to_string(number) + ":" + std::to_string(i + 1) + ": statement " + w +
                   " is not supported; ignored (and so is every later " + w + ")";
          });
        }
        return true;
      }
    }
    stmt_.clear();
    segments_.clear();
    statement_line_ = number;
  }
  // `$$`: the rest of the line is a comment and the statement ends here. `$`: the statement
  // goes on in the next line and the rest of this one is a comment.
  const auto* dollar = static_cast<const char*>(std::memchr(text.data() + i, '$', n - i));
  const size_t end = dollar ? static_cast<size_t>(dollar - text.data()) : n;
  const bool continues = dollar && !(end + 1 < n && text[end + 1] == '$');
  if (stmt_.size() + (end - i) > kMaxStatementBytes) {
    fail_at(number, 0, "statement longer than 1 MiB (a '$' continuation that never ends?)");
  }
  segments_.push_back({stmt_.size(), number, clamp_int(i + 1)});
  stmt_.append(text, i, end - i);
  continuing_ = continues;
  if (continues) return true;
  return statement();
}

size_t Reader::parse_number(size_t i, Arg& arg) const {
  const std::string& s = stmt_;
  const size_t n = s.size();
  const size_t start = i;
  if (i < n && (s[i] == '+' || s[i] == '-')) ++i;
  const size_t digits_start = i;
  bool any_digit = false;
  bool integer_nonzero = false;
  while (i < n && is_digit(s[i])) {
    any_digit = true;
    if (s[i] != '0') integer_nonzero = true;
    ++i;
  }
  if (i < n && s[i] == '.') {
    ++i;
    while (i < n && is_digit(s[i])) {
      any_digit = true;
      ++i;
    }
  }
  if (!any_digit) fail(start, "malformed number (expected digits)");
  bool negative_exponent = false;
  if (i < n && (s[i] == 'e' || s[i] == 'E')) {
    size_t j = i + 1;
    if (j < n && (s[j] == '+' || s[j] == '-')) {
      negative_exponent = s[j] == '-';
      ++j;
    }
    if (j >= n || !is_digit(s[j])) fail(start, "malformed exponent in a number (expected digits)");
    while (j < n && is_digit(s[j])) ++j;
    i = j;
  }
  if (i < n && (is_letter(s[i]) || s[i] == '.' || s[i] == '_')) {
    fail(start, "malformed number (unexpected " + describe(s[i]) + ")");
  }
  const char* first = s.data() + (s[start] == '+' ? digits_start : start);
  const char* last = s.data() + i;
  double value = 0.0;
  const auto [ptr, ec] = std::from_chars(first, last, value);
  if (ec == std::errc::result_out_of_range) {
    if (negative_exponent || !integer_nonzero) {
      value = 0.0;  // underflow: smaller than any length or speed that matters
    } else {
      fail(start, "number out of range (expected |value| <= 1e6)");
    }
  } else if (ec != std::errc() || ptr != last) {
    fail(start, "malformed number");
  }
  arg.is_number = true;
  arg.value = value;
  arg.pos = start;
  return i;
}

void Reader::parse_args(size_t i) {
  const std::string& s = stmt_;
  const size_t n = s.size();
  nargs_ = 0;
  i = skip_blanks(s, i);
  if (i >= n) fail(i, "nothing after " + major_ + "/ (expected its parameters)");
  while (true) {
    i = skip_blanks(s, i);
    if (nargs_ == kMaxParameters) {
      fail(i, "more than " + std::to_string(kMaxParameters) + " parameters in " + major_ + "/");
    }
    if (nargs_ == args_.size()) args_.emplace_back();
    Arg& arg = args_[nargs_];
    if (i >= n || s[i] == ',') {
      fail(i, "empty parameter in " + major_ + "/ (expected a number or a word)");
    }
    const char c = s[i];
    if (is_digit(c) || c == '+' || c == '-' || c == '.') {
      i = parse_number(i, arg);
    } else if (is_letter(c)) {
      arg.is_number = false;
      arg.value = 0.0;
      arg.pos = i;
      arg.word.clear();
      while (i < n && (is_word_char(s[i]) || s[i] == '.')) arg.word.push_back(upper(s[i++]));
    } else {
      fail(i, "unexpected " + describe(c) + " in " + major_ + "/ (expected a number or a word)");
    }
    ++nargs_;
    i = skip_blanks(s, i);
    if (i >= n) return;
    if (s[i] != ',') {
      fail(i, "unexpected " + describe(s[i]) + " in " + major_ + "/ (expected ',' between parameters)");
    }
    ++i;
  }
}

bool Reader::statement() {
  const std::string& s = stmt_;
  const size_t n = s.size();
  size_t i = skip_blanks(s, 0);
  if (i >= n) return true;  // a comment or blanks only
  if (!is_letter(s[i])) {
    fail(i, "unexpected " + describe(s[i]) + " (expected a statement word such as GOTO/)");
  }
  major_.clear();
  major_pos_ = i;
  while (i < n && is_word_char(s[i])) major_.push_back(upper(s[i++]));
  Word word = lookup(major_);
  // A statement is WORD, or WORD/parameters. Unknown words may be several before the '/',
  // "TOOL PATH/..." (NX): joined with one blank. Anything else after the word ("G0 X1",
  // "P1=POINT/...") is not CL data: an error, not a warning.
  size_t j = skip_blanks(s, i);
  if (word == Word::kUnknown && j > i && j < n && is_letter(s[j])) {
    size_t k = j;
    std::string joined = major_;
    while (k < n && is_letter(s[k])) {
      joined.push_back(' ');
      while (k < n && is_word_char(s[k])) joined.push_back(upper(s[k++]));
      k = skip_blanks(s, k);
    }
    if (k < n && s[k] == '/') {
      major_ = joined;
      j = k;
    }
  }
  i = j;
  const bool slash = i < n && s[i] == '/';
  if (!slash && i < n) {
    fail(i, "unexpected " + describe(s[i]) + " after " + major_ +
                " (expected '/' and its parameters, or the end of the statement)");
  }
  if (word == Word::kUnknown) {
    warn_once(major_, [&] {
      return where(major_pos_) + ": statement " + major_ + " is not supported; ignored (and so is every later " +
             major_ + ")";
    });
    return true;
  }
  nargs_ = 0;
  args_pos_ = slash ? i + 1 : i;
  if (slash) parse_args(i + 1);

  switch (word) {
    case Word::kGoto:
      do_goto();
      break;
    case Word::kFrom:
      do_from();
      break;
    case Word::kGodlta:
      do_godlta();
      break;
    case Word::kRapid:
      if (nargs_ != 0) fail(args_pos_, "RAPID takes no parameters (expected RAPID alone)");
      no_circle_pending("RAPID");
      state_.rapid_next = true;
      break;
    case Word::kFedrat:
      do_fedrat();
      break;
    case Word::kCutter:
      do_cutter();
      break;
    case Word::kLoadtl:
      do_loadtl(false);
      break;
    case Word::kLoad:
      do_loadtl(true);
      break;
    case Word::kMultax:
      do_multax();
      break;
    case Word::kTlaxis:
      do_tlaxis();
      break;
    case Word::kCircle:
      do_circle();
      break;
    case Word::kSpindl:
      do_spindl();
      break;
    case Word::kUnits:
      do_units();
      break;
    case Word::kCutcom:
      do_cutcom();
      break;
    case Word::kEnd:
      // APT END: the end of a machining section (the machine stops); reading goes on.
      no_circle_pending("END");
      break;
    case Word::kFini:
      no_circle_pending("FINI");
      return false;  // the end of the part program: nothing after it is read
    case Word::kUnknown:
      break;
  }
  return true;
}

void Reader::count(size_t low, size_t high, const char* form) const {
  if (nargs_ >= low && nargs_ <= high) return;
  const size_t pos = nargs_ > high ? args_[high].pos : args_pos_;
  fail(pos, major_ + "/ with " + std::to_string(nargs_) + " parameter(s) (expected " + form + ")");
}

void Reader::count_of(std::initializer_list<size_t> allowed, const char* form) const {
  if (std::find(allowed.begin(), allowed.end(), nargs_) != allowed.end()) return;
  const size_t high = *std::max_element(allowed.begin(), allowed.end());
  const size_t pos = nargs_ > high ? args_[high].pos : args_pos_;
  fail(pos, major_ + "/ with " + std::to_string(nargs_) + " parameter(s) (expected " + form + ")");
}

double Reader::number(size_t k, const char* what) const {
  const Arg& a = args_[k];
  if (!a.is_number) {
    fail(a.pos, "expected a number for " + std::string(what) + " in " + major_ + "/, found '" + a.word + "'");
  }
  if (!std::isfinite(a.value)) fail(a.pos, "number out of range");
  return a.value;
}

double Reader::length(size_t k, const char* what) const {
  const double v = number(k, what) * unit();
  if (!(std::abs(v) <= kMaxMagnitude)) {
    fail(args_[k].pos, std::string(what) + " " + num(v) + " mm is out of range (expected within +-1e6 mm)");
  }
  return v;
}

Eigen::Vector3d Reader::unit_vector(size_t k, const char* what) const {
  Eigen::Vector3d v(number(k, what), number(k + 1, what), number(k + 2, what));
  if (!(v.cwiseAbs().maxCoeff() <= kMaxMagnitude)) {
    fail(args_[k].pos, std::string(what) + " " + point(v) + " is out of range");
  }
  const double norm = v.norm();
  if (!(norm >= kMinAxisNorm)) {
    fail(args_[k].pos,
         "zero " + std::string(what) + " " + point(v) + " (expected a direction i,j,k, normally a unit vector)");
  }
  return v / norm;
}

void Reader::no_circle_pending(const char* what) const {
  if (!state_.circle_pending) return;
  fail(major_pos_, std::string(what) + " after the CIRCLE/ at " + state_.circle_where +
                       " (expected the GOTO/ that ends its arc first)");
}

// The tool of a motion, giving the last CUTTER/ its tool number the first time it moves.
int Reader::motion_tool() {
  if (state_.has_cutter && !state_.cutter_bound) {
    auto& cutters = out_.cutters;
    const auto it = cutters.find(state_.tool);
    if (it != cutters.end() && !same_cutter(it->second, state_.cutter)) {
      if (state_.loadtl_seen) {
        fail(major_pos_, "tool " + std::to_string(state_.tool) + " has cut with another cutter than the CUTTER/ at " +
                             state_.cutter_where +
                             " (expected LOADTL/ with a new tool number before a different "
                             "CUTTER/)");
      }
      // No LOADTL/ in the program: each different cutter is its own tool, numbered in order.
      int number = cutters.rbegin()->first + 1;
      for (const auto& [t, c] : cutters) {
        if (same_cutter(c, state_.cutter)) number = t;
      }
      if (number > kMaxToolNumber) fail(major_pos_, "too many different cutters");
      state_.tool = number;
    }
    cutters.emplace(state_.tool, state_.cutter);
    state_.cutter_bound = true;
  }
  return state_.tool;
}

void Reader::motion(MotionKind kind, const Eigen::Vector3d& end, const Eigen::Vector3d& end_axis) {
  const bool rapid = kind == MotionKind::Rapid;
  if (!rapid && state_.feed_mm_per_min <= 0.0) {
    fail(major_pos_,
         "feed motion before any FEDRAT/ (expected FEDRAT/ before it, or RAPID for a rapid "
         "motion)");
  }
  const int tool = motion_tool();
  state_.rapid_next = false;
  if (!state_.known) {
    // The first motion without FROM/: where it starts is not known, so it only sets the point.
    state_.known = true;
    state_.position_mm = end;
    state_.pose_axis = state_.axis = end_axis;
    return;
  }
  if (!compensating() && kind != MotionKind::Arc && end == state_.position_mm && end_axis == state_.pose_axis) {
    return;  // no motion: no Block (as the G-code reader)
  }
  if (state_.pose_axis.dot(end_axis) < kOppositeAxisCosine) {
    fail(major_pos_, "the tool axis turns from " + point(state_.pose_axis) + " to its opposite " + point(end_axis) +
                         " in one motion (expected an intermediate axis: no single great circle "
                         "joins opposite axes)");
  }
  Block block;
  block.kind = kind;
  block.start_mm = state_.position_mm;
  block.end_mm = end;
  block.tool_pose = true;
  block.start_axis = state_.pose_axis;
  block.end_axis = end_axis;
  block.orientation = kinematics::OrientationMode::Vector;
  block.feed_mm_per_min = rapid ? 0.0 : state_.feed_mm_per_min;
  block.feed_mode = kinematics::FeedMode::UnitsPerMinute;
  block.tool = tool;
  block.spindle = state_.spindle;
  block.spindle_rpm = state_.spindle_rpm;
  block.source = kinematics::SourceRef{file_index_, statement_line_};
  if (kind == MotionKind::Arc) {
    const Eigen::Vector3d n = state_.circle_normal;
    block.normal = n;
    block.center_mm = state_.circle_center_mm + n * n.dot(block.start_mm - state_.circle_center_mm);
    block.turns = 1;
  }
  Comp& comp = state_.comp;
  if (compensating()) {
    if (!end_axis.isApprox(Eigen::Vector3d::UnitZ(), 1e-12) ||
        !state_.pose_axis.isApprox(Eigen::Vector3d::UnitZ(), 1e-12)) {
      fail(major_pos_, "a tool axis other than (0,0,1) with CUTCOM on (expected three-axis CL data)");
    }
    detail::Compensator compensator(comp, *this);
    const int column = static_cast<int>(major_pos_);
    if (kind == MotionKind::Arc) {
      if (std::abs(std::abs(block.normal.z()) - 1.0) > 1e-12) {
        fail(major_pos_, "a CIRCLE/ out of the XY plane with CUTCOM on (expected its axis along Z)");
      }
      compensator.arc(block, {true, true, true}, block.normal.z() > 0.0 ? 1 : -1, column);
    } else {
      compensator.straight(block, {true, true, true}, column);
    }
    state_.pose_axis = state_.axis = end_axis;
    return;
  }
  if (comp.arc_not_allowed && kind == MotionKind::Arc) {
    fail(major_pos_, "a CIRCLE/ just after CUTCOM/OFF (expected a straight move: the exit from cutter compensation)");
  }
  comp.arc_not_allowed = false;
  if (comp.machine_mm) {  // the exit move after CUTCOM/OFF: from where the tool is
    block.start_mm = *comp.machine_mm;
    comp.machine_mm.reset();
  }
  out_.program.blocks.push_back(block);
  state_.position_mm = end;
  state_.pose_axis = state_.axis = end_axis;
}

void Reader::do_goto() {
  if (state_.multax) {
    count_of({3, 6}, "x,y,z or x,y,z,i,j,k");
  } else if (nargs_ == 6) {
    fail(args_[3].pos,
         "GOTO/ with a tool axis i,j,k without MULTAX/ON (expected x,y,z, or MULTAX/ON before "
         "five-axis motions)");
  } else {
    count(3, 3, "x,y,z (MULTAX is off)");
  }
  Eigen::Vector3d end(length(0, "x"), length(1, "y"), length(2, "z"));
  const Eigen::Vector3d end_axis = nargs_ == 6 ? unit_vector(3, "tool axis") : state_.axis;
  if (!state_.circle_pending) {
    motion(state_.rapid_next ? MotionKind::Rapid : MotionKind::Linear, end, end_axis);
    return;
  }
  // The GOTO/ that ends a CIRCLE/'s arc.
  const Eigen::Vector3d c = state_.circle_center_mm, n = state_.circle_normal;
  const double r = state_.circle_radius_mm;
  Eigen::Vector3d d = end - c;
  d -= n * n.dot(d);
  const double r_end = d.norm();
  const double allowed = std::max(options_.arc_tolerance_mm, kArcRelativeTolerance * r);
  if (!(std::abs(r_end - r) <= allowed) || r_end <= kSamePointMm) {
    fail(major_pos_, "GOTO/ " + point(end) + " is " + num(r_end) + " mm from the axis of the CIRCLE/ at " +
                         state_.circle_where + " (expected a point on that circle: radius " + num(r) + " mm within " +
                         num(allowed) + " mm)");
  }
  // A full circle: the end equals the start, exactly, so that the sweep is 2*pi, not ~0.
  if ((end - programmed_point()).norm() <= kSamePointMm) end = programmed_point();
  motion(MotionKind::Arc, end, end_axis);
  state_.circle_pending = false;
}

void Reader::do_from() {
  no_circle_pending("FROM/");
  no_cutcom("FROM/");
  count_of({3, 6}, "x,y,z or x,y,z,i,j,k");
  state_.position_mm = Eigen::Vector3d(length(0, "x"), length(1, "y"), length(2, "z"));
  if (nargs_ == 6) state_.pose_axis = state_.axis = unit_vector(3, "tool axis");
  state_.known = true;
}

void Reader::do_godlta() {
  no_circle_pending("GODLTA/");
  count_of({1, 3}, "dx,dy,dz, or d along the tool axis");
  if (!state_.known) {
    fail(major_pos_, "GODLTA/ from an unknown position (expected FROM/ or GOTO/ before it)");
  }
  Eigen::Vector3d delta;
  if (nargs_ == 1) {
    delta = length(0, "d") * state_.axis;
  } else {
    delta = Eigen::Vector3d(length(0, "dx"), length(1, "dy"), length(2, "dz"));
  }
  const Eigen::Vector3d end = programmed_point() + delta;
  if (!(end.cwiseAbs().maxCoeff() <= kMaxMagnitude)) {
    fail(args_[0].pos, "GODLTA/ ends at " + point(end) +
                           " mm, out of range (expected within "
                           "+-1e6 mm)");
  }
  motion(state_.rapid_next ? MotionKind::Rapid : MotionKind::Linear, end, state_.axis);
}

void Reader::do_fedrat() {
  count(1, 2, "f, f,MMPM, f,IPM or MMPM,f");
  int feed_index = -1, unit_index = -1;
  for (size_t k = 0; k < nargs_; ++k) {
    if (args_[k].is_number) {
      if (feed_index >= 0) fail(args_[k].pos, "two feeds in FEDRAT/ (expected one number)");
      feed_index = static_cast<int>(k);
    } else {
      if (unit_index >= 0) fail(args_[k].pos, "two units in FEDRAT/ (expected MMPM or IPM)");
      unit_index = static_cast<int>(k);
    }
  }
  if (feed_index < 0) fail(args_pos_, "FEDRAT/ without a feed (expected a number)");
  double per_unit = unit();  // no unit word: the units of UNITS/ per minute
  if (unit_index >= 0) {
    const Arg& u = args_[static_cast<size_t>(unit_index)];
    if (u.word == "MMPM") {
      per_unit = 1.0;
    } else if (u.word == "IPM") {
      per_unit = kMmPerInch;
    } else if (u.word == "MMPR" || u.word == "IPR") {
      fail(u.pos, "feed per revolution (" + u.word + ") is not supported (expected MMPM or IPM)");
    } else {
      fail(u.pos, "unknown feed unit '" + u.word + "' (expected MMPM or IPM)");
    }
  }
  const Arg& f = args_[static_cast<size_t>(feed_index)];
  const double feed = f.value * per_unit;
  if (!(feed > 0.0)) fail(f.pos, "FEDRAT/ " + num(f.value) + " (expected a feed > 0)");
  if (!(feed <= kMaxMagnitude)) {
    fail(f.pos, "FEDRAT/ " + num(feed) + " mm/min is out of range (expected <= 1e6 mm/min)");
  }
  state_.feed_mm_per_min = feed;
}

// APT's general cutter, CUTTER/d,r,e,f,alpha,beta,h (the APT 7-parameter tool, ISO 3592): in
// the tool's (radius, height) half-plane, the bottom is the line through the tip rising at
// alpha from the horizontal, the side is the line at beta from the vertical (radius d/2 where
// it meets the extended bottom), and between them a corner arc of radius r centred at (e, f);
// h is the height. With beta = 0 the side is radius = d/2, so a corner tangent to it has
// e = d/2 - r, and one tangent to a flat bottom has f = r. removal::Cutter has:
//   alpha = 0,  r = 0        flat end mill      (e = d/2, f = 0)
//   alpha = 0,  r = d/2      ball end mill      (e = 0,   f = d/2)
//   alpha = 0,  0 < r < d/2  bull-nose end mill (e = d/2 - r, f = r)
//   alpha > 0,  r = 0        V-bit (chamfer/engraving), included angle 180 - 2 alpha
//                            (e = d/2, f = (d/2) tan alpha)
// all with beta = 0. With r = 0 some CAM systems print e = f = 0 (the corner is a point):
// accepted too. Tapers (beta != 0) and rounded cones (alpha > 0 with r > 0) are errors.
// Parameters left out take the plain shape's values (e = d/2 - r, f = r, alpha = beta = 0,
// h = 4 d).
void Reader::do_cutter() {
  count(1, 7, "d, d,r or d,r,e,f,alpha,beta,h");
  const double d = length(0, "diameter d");
  if (!(d > 0.0)) fail(args_[0].pos, "cutter diameter " + num(d) + " mm (expected d > 0)");
  const double radius = d / 2.0;
  double r = nargs_ > 1 ? length(1, "corner radius r") : 0.0;
  if (r < 0.0) fail(args_[1].pos, "corner radius " + num(r) + " mm (expected r >= 0)");
  if (r > radius + kCutterMatchMm) {
    fail(args_[1].pos,
         "corner radius " + num(r) + " mm is more than half the diameter " + num(d) + " mm (expected r <= d/2)");
  }
  if (r <= kCutterMatchMm) r = 0.0;
  if (std::abs(r - radius) <= kCutterMatchMm) r = radius;
  const double alpha = nargs_ > 4 ? number(4, "alpha") : 0.0;
  const double beta = nargs_ > 5 ? number(5, "beta") : 0.0;
  if (std::abs(beta) > kZeroAngleDeg) {
    fail(args_[5].pos, "tapered cutter (beta = " + num(beta) +
                           " deg) cannot be represented (expected beta = 0: a flat, ball, "
                           "bull-nose or V-bit cutter)");
  }
  const bool pointed = std::abs(alpha) > kZeroAngleDeg;
  if (pointed && !(alpha > 0.0 && alpha < 90.0)) {
    fail(args_[4].pos, "alpha " + num(alpha) + " deg (expected 0 <= alpha < 90)");
  }
  if (pointed && r > 0.0) {
    fail(args_[4].pos, "a cone tip (alpha = " + num(alpha) + " deg) with a corner radius (r = " + num(r) +
                           " mm) cannot be represented (expected r = 0 for a V-bit, or alpha = "
                           "0 for a flat, ball or bull-nose cutter)");
  }
  const double alpha_rad = alpha * M_PI / 180.0;
  const double e_plain = pointed ? radius : radius - r;
  const double f_plain = pointed ? radius * std::tan(alpha_rad) : r;
  const double e = nargs_ > 2 ? length(2, "e") : e_plain;
  const double f = nargs_ > 3 ? length(3, "f") : f_plain;
  const bool plain = std::abs(e - e_plain) <= kCutterMatchMm && std::abs(f - f_plain) <= kCutterMatchMm;
  const bool point_corner = r == 0.0 && std::abs(e) <= kCutterMatchMm && std::abs(f) <= kCutterMatchMm;
  if (!plain && !point_corner) {
    fail(args_[2].pos, "the corner centre (e, f) = (" + num(e) + ", " + num(f) + ") mm does not fit d = " + num(d) +
                           " mm, r = " + num(r) + " mm, alpha = " + num(alpha) + " deg (expected e = " + num(e_plain) +
                           ", f = " + num(f_plain) + ")");
  }
  const double h = nargs_ > 6 ? length(6, "height h") : kDefaultHeightPerDiameter * d;
  if (!(h > 0.0) || h < r) {
    fail(args_[std::min<size_t>(6, nargs_ - 1)].pos,
         "cutter height " + num(h) + " mm (expected h > 0 and at least the corner radius " + num(r) + " mm)");
  }
  Cutter c;
  c.diameter_mm = d;
  c.corner_radius_mm = r;
  if (pointed) {
    c.type = CutterType::VBit;
    c.corner_radius_mm = 0.0;
    c.tip_angle_deg = 180.0 - 2.0 * alpha;
  } else if (r == 0.0) {
    c.type = CutterType::Flat;
  } else if (r == radius) {
    c.type = CutterType::Ball;
  } else {
    c.type = CutterType::BullNose;
  }
  c.flute_length_mm = h;
  c.shank_diameter_mm = d;
  c.length_mm = h;
  c.gauge_length_mm = h;  // as the tool library without gauge_length: the tool sits in the nose
  state_.cutter = c;
  state_.has_cutter = true;
  state_.cutter_bound = false;
  state_.cutter_where = where_line();
}

// LOADTL/n[,...] (APT) and LOAD/TOOL,n[,...] (NX): tool n goes into the spindle. Further
// parameters (ADJUST, length registers...) do not change the path: ignored with one warning.
void Reader::do_loadtl(bool load_tool) {
  no_cutcom(load_tool ? "LOAD/TOOL" : "LOADTL/");
  const size_t k = load_tool ? 1 : 0;
  if (load_tool) {
    if (nargs_ == 0 || args_[0].is_number || args_[0].word != "TOOL") {
      warn_once("LOAD", [&] {
        return where(major_pos_) +
               ": statement LOAD is only read as LOAD/TOOL,n; ignored (and so is every later "
               "other LOAD)";
      });
      return;
    }
  }
  if (nargs_ <= k) fail(args_pos_, major_ + "/ without a tool number (expected a number)");
  const double t = number(k, "the tool number");
  if (!(t >= 1.0 && t <= kMaxToolNumber) || t != std::floor(t)) {
    fail(args_[k].pos, "tool number " + num(t) + " (expected a whole number from 1 to 99999)");
  }
  if (nargs_ > k + 1) {
    warn_once(major_ + "/ parameters", [&] {
      return where(args_[k + 1].pos) + ": " + major_ + "/ parameters after the tool number are ignored";
    });
  }
  const int tool = static_cast<int>(t);
  state_.tool = tool;
  state_.loadtl_seen = true;
  const auto it = out_.cutters.find(tool);
  if (it != out_.cutters.end()) {
    // A tool that has cut before: its cutter is known, unless a CUTTER/ is waiting for it.
    if (!state_.has_cutter || state_.cutter_bound) {
      state_.cutter = it->second;
      state_.has_cutter = true;
      state_.cutter_bound = true;
    }
  } else if (state_.has_cutter && state_.cutter_bound) {
    state_.has_cutter = false;  // a new tool whose shape the file has not given (yet)
  }
}

void Reader::do_multax() {
  no_cutcom("MULTAX");
  count(0, 1, "nothing, ON or OFF");
  if (nargs_ == 0) {
    state_.multax = true;
    return;
  }
  const Arg& a = args_[0];
  if (!a.is_number && a.word == "ON") {
    state_.multax = true;
  } else if (!a.is_number && a.word == "OFF") {
    state_.multax = false;
  } else {
    fail(a.pos, "MULTAX/ takes ON or OFF");
  }
}

void Reader::do_tlaxis() {
  count(3, 3, "i,j,k");
  state_.axis = unit_vector(0, "tool axis");
}

void Reader::do_circle() {
  count(7, 11, "cx,cy,cz,i,j,k,r and up to 4 tolerances");
  const Eigen::Vector3d c(length(0, "cx"), length(1, "cy"), length(2, "cz"));
  const Eigen::Vector3d n = unit_vector(3, "circle axis");
  const double r = length(6, "radius r");
  for (size_t k = 7; k < nargs_; ++k) number(k, "a tolerance");
  if (state_.circle_pending) {
    fail(major_pos_, "second CIRCLE/ before the GOTO/ of the CIRCLE/ at " + state_.circle_where +
                         " (expected a GOTO/ after each CIRCLE/)");
  }
  if (!(r > kSamePointMm)) fail(args_[6].pos, "circle radius " + num(r) + " mm (expected r > 0)");
  if (state_.rapid_next) {
    fail(major_pos_, "CIRCLE/ after RAPID (expected RAPID only before a straight motion)");
  }
  if (!state_.known) {
    fail(major_pos_, "CIRCLE/ from an unknown position (expected FROM/ or GOTO/ before it)");
  }
  Eigen::Vector3d d = programmed_point() - c;
  d -= n * n.dot(d);
  const double r_start = d.norm();
  const double allowed = std::max(options_.arc_tolerance_mm, kArcRelativeTolerance * r);
  if (!(std::abs(r_start - r) <= allowed) || r_start <= kSamePointMm) {
    fail(args_[6].pos, "the arc's start, the current point " + point(programmed_point()) + ", is " + num(r_start) +
                           " mm from the circle's axis (expected a point on the circle: radius " + num(r) +
                           " mm within " + num(allowed) + " mm)");
  }
  state_.circle_pending = true;
  state_.circle_center_mm = c;
  state_.circle_normal = n;
  state_.circle_radius_mm = r;
  state_.circle_where = where(major_pos_);
  std::tie(state_.circle_line, state_.circle_column) = locate(major_pos_);
}

void Reader::do_spindl() {
  count(1, 8, "rpm,CLW|CCLW, RPM,rpm,CLW|CCLW, ON or OFF");
  if (nargs_ == 1 && !args_[0].is_number && (args_[0].word == "OFF" || args_[0].word == "ON")) {
    state_.spindle = args_[0].word == "OFF" ? SpindleState::Off : state_.spindle_direction;
    return;
  }
  size_t k = 0;
  if (!args_[0].is_number) {
    if (args_[0].word == "SFM" || args_[0].word == "SMM") {
      fail(args_[0].pos, "constant surface speed (" + args_[0].word + ") is not supported (expected RPM)");
    }
    if (args_[0].word != "RPM") {
      fail(args_[0].pos, "unexpected '" + args_[0].word + "' in SPINDL/ (expected rpm, RPM,rpm, ON or OFF)");
    }
    k = 1;
  }
  if (k >= nargs_) fail(args_pos_, "SPINDL/ without a speed (expected a number of rpm)");
  const double rpm = number(k, "the spindle speed");
  if (!(rpm >= 0.0 && rpm <= kMaxMagnitude)) {
    fail(args_[k].pos, "spindle speed " + num(rpm) + " rpm (expected 0 to 1e6 rpm)");
  }
  SpindleState direction = SpindleState::Clockwise;  // APT's default
  for (++k; k < nargs_; ++k) {
    const Arg& a = args_[k];
    if (a.is_number) fail(a.pos, "unexpected number in SPINDL/ (expected CLW or CCLW)");
    if (a.word == "CLW") {
      direction = SpindleState::Clockwise;
    } else if (a.word == "CCLW") {
      direction = SpindleState::CounterClockwise;
    } else if (a.word == "RANGE" || a.word == "MAXRPM") {
      ++k;  // gear range / speed limit: its number does not change the path
      if (k >= nargs_ || !args_[k].is_number) {
        fail(a.pos, a.word + " without its number in SPINDL/");
      }
    } else {
      fail(a.pos, "unexpected '" + a.word + "' in SPINDL/ (expected CLW or CCLW)");
    }
  }
  state_.spindle_rpm = rpm;
  state_.spindle_direction = direction;
  state_.spindle = rpm > 0.0 ? direction : SpindleState::Off;
}

// CUTCOM/LEFT | RIGHT [,XYPLAN] [,register]: the CL points that follow are the part's contour
// and the tool runs the CUTTER/'s radius to the left or right of it, as G41/G42 in G17 (the
// register is the control's; the radius comes from CUTTER/). CUTCOM/OFF as G40: the held move
// ends at its offset point, the next (straight) move goes to its programmed point.
void Reader::do_cutcom() {
  if (nargs_ == 0) fail(args_pos_, "CUTCOM without its side (expected CUTCOM/LEFT, RIGHT or OFF)");
  const Arg& a = args_[0];
  Comp& comp = state_.comp;
  if (!a.is_number && a.word == "OFF") {
    if (compensating() && !comp.first_move) {
      comp_end(a.pos);
      comp.machine_mm = state_.position_mm;
      state_.position_mm = comp.program_mm;
      comp.arc_not_allowed = true;
    }
    comp.side = Comp::Side::Off;
    comp.first_move = true;
    return;
  }
  if (a.is_number || (a.word != "LEFT" && a.word != "RIGHT")) fail(a.pos, "CUTCOM/ takes LEFT, RIGHT or OFF");
  for (size_t k = 1; k < nargs_; ++k) {
    const Arg& extra = args_[k];
    if (!extra.is_number && extra.word != "XYPLAN") {
      fail(extra.pos, "CUTCOM/" + a.word + " with " + extra.word +
                          " (expected XYPLAN or a register number: compensation works in the XY plane)");
    }
  }
  if (comp.side != Comp::Side::Off)
    fail(a.pos, "CUTCOM/" + a.word + " with compensation already on (expected CUTCOM/OFF first)");
  if (state_.multax)
    fail(a.pos,
         "CUTCOM/" + a.word + " with MULTAX/ON (expected three-axis CL data: compensation works in the XY plane)");
  if (!state_.has_cutter)
    fail(a.pos, "CUTCOM/" + a.word + " before any CUTTER/ (expected the cutter, whose radius the path is offset by)");
  if (state_.circle_pending)
    fail(a.pos, "CUTCOM/" + a.word + " between a CIRCLE/ and its GOTO/ (expected it before the CIRCLE/)");
  comp.side = a.word == "LEFT" ? Comp::Side::Left : Comp::Side::Right;
  comp.radius_mm = state_.cutter.radius_mm();
  comp.first_move = true;
  comp.held.clear();
  comp.endpoint_valid = false;
}

void Reader::comp_end(size_t pos) {
  detail::Compensator compensator(state_.comp, *this);
  compensator.move_end_and_flush(state_.position_mm.head<2>(), static_cast<int>(pos));
  compensator.flush();
}

void Reader::comp_append(Block block, const std::array<bool, 3>&, bool held, const Eigen::Vector2d& direction,
                         double sweep_rad) {
  block.tool_pose = true;
  block.start_axis = block.end_axis = Eigen::Vector3d::UnitZ();
  block.orientation = kinematics::OrientationMode::Vector;
  block.feed_mode = kinematics::FeedMode::UnitsPerMinute;
  block.tool = state_.tool;
  block.spindle = state_.spindle;
  block.spindle_rpm = state_.spindle_rpm;
  block.source = kinematics::SourceRef{file_index_, statement_line_};
  state_.position_mm = block.end_mm;
  if (held) {
    state_.comp.held.push_back({block, direction, sweep_rad});
  } else {
    out_.program.blocks.push_back(block);
  }
}

void Reader::do_units() {
  count(1, 1, "INCHES or MM");
  const Arg& a = args_[0];
  if (!a.is_number && (a.word == "INCHES" || a.word == "INCH")) {
    state_.inches = true;
  } else if (!a.is_number && (a.word == "MM" || a.word == "MILLIM")) {
    state_.inches = false;
  } else {
    fail(a.pos, "UNITS/ takes INCHES or MM");
  }
}

}  // namespace

void read_apt(std::istream& in, const std::string& name, const AptOptions& options, AptProgram& out, AptState& state) {
  if (!std::isfinite(options.arc_tolerance_mm) || options.arc_tolerance_mm < 0.0) {
    throw InputError(
        name, 0, 0,
        "arc tolerance " + num(options.arc_tolerance_mm) + " mm in the options (expected a finite value >= 0)");
  }
  const int file_index = static_cast<int>(out.program.files.size());
  out.program.files.push_back(name);
  Reader reader(name, options, out, state, file_index);
  detail::read_guarded(name, [&] { reader.run(in); });
  state.rapid_next = false;  // RAPID applies to the next motion of its own file only
}

AptProgram read_apt(const std::string& path, const AptOptions& options) {
  std::ifstream in = detail::open_program_file(path, "an APT CL file", "the CL file");
  AptProgram out;
  AptState state;
  read_apt(in, path, options, out, state);
  return out;
}

}  // namespace vcut::io
