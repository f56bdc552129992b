// Reads APT CL data in its text form as CAM systems print it (CATIA, NX "APT source",
// Mastercam/Fusion APT posts): one statement per line, `$` continuations, `$$` comments.
// The statement words and their parameters follow ISO 4343 (CLDATA) and the APT language
// (ISO 3592); where this reader picks one of several readings it says so next to the code.
// Memory: one line and one statement at a time, plus the Blocks and the cutters.
#include <vcut/io/apt_reader.h>
#include <vcut/io/input_error.h>

#include <Eigen/Geometry>
#include <Eigen/LU>
#include <Eigen/SVD>

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

using detail::kMmPerInch;
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
// CSYS/ and MSYS/ print their matrices with 6 decimals: a rotation's entries are off by up to
// 5e-7 and R^T R and det by a few 1e-6; a matrix off by more is not a rotation.
constexpr double kFrameTolerance = 1e-5;
constexpr double kMaxPecks = 10000.0;  // pecks per hole of a CYCLE/DEEP or BRKCHP

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
  kCsys,
  kMsys,
  kCycle,
  kTldata,
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
  kGohome,
  kFini,
  kIndirv,
};

Word lookup(const std::string& w) {
  switch (w.size()) {
    case 3:
      if (w == "END") return Word::kEnd;
      break;
    case 4:
      if (w == "GOTO") return Word::kGoto;
      if (w == "CSYS") return Word::kCsys;
      if (w == "MSYS") return Word::kMsys;
      if (w == "FROM") return Word::kFrom;
      if (w == "FINI") return Word::kFini;
      if (w == "LOAD") return Word::kLoad;
      break;
    case 5:
      if (w == "RAPID") return Word::kRapid;
      if (w == "CYCLE") return Word::kCycle;
      if (w == "UNITS") return Word::kUnits;
      break;
    case 6:
      if (w == "GODLTA") return Word::kGodlta;
      if (w == "GOHOME") return Word::kGohome;
      if (w == "FEDRAT") return Word::kFedrat;
      if (w == "CUTTER") return Word::kCutter;
      if (w == "LOADTL") return Word::kLoadtl;
      if (w == "MULTAX") return Word::kMultax;
      if (w == "TLAXIS") return Word::kTlaxis;
      if (w == "CIRCLE") return Word::kCircle;
      if (w == "SPINDL") return Word::kSpindl;
      if (w == "CUTCOM") return Word::kCutcom;
      if (w == "TLDATA") return Word::kTldata;
      if (w == "INDIRV") return Word::kIndirv;
      break;
    default:
      break;
  }
  return Word::kUnknown;
}

// Statements whose remainder is free text: not parsed, no `$` continuation.
bool free_text(const char* w, size_t n, bool& silent) {
  auto is = [&](const char* k) { return std::strlen(k) == n && std::memcmp(w, k, n) == 0; };
  silent = is("PPRINT") || is("INSERT");  // operator messages and post text: comments
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
  void do_csys();
  void do_msys();
  void do_cycle();
  void do_tldata();
  void do_tlon(size_t pos);  // TLON,GOFWD/...: the text from pos (after TLON)
  void cycle_point(const Eigen::Vector3d& point, const Eigen::Vector3d& axis);
  Eigen::Matrix3d checked_rotation(const Eigen::Matrix3d& r, const char* what) const;
  // A point, a direction as written, in the workpiece frame (CSYS/, MSYS/).
  Eigen::Vector3d placed(const Eigen::Vector3d& p) const {
    return state_.frame_rotation * p + state_.frame_translation_mm;
  }
  Eigen::Vector3d turned(const Eigen::Vector3d& v) const { return state_.frame_rotation * v; }
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
  kinematics::BlockList& comp_blocks() override { return out_.program.blocks; }
  [[noreturn]] void comp_fail(int column, const std::string& message) const override {
    fail(static_cast<size_t>(column), message +
                                          "; if the CL points are the tool's centre (control compensation for wear), "
                                          "set program.cutcom: centre in the job");
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
  bool continuing_ = false;         // the last line ended in '$'
  bool comment_continues_ = false;  // a `$$` comment line ended in '$'
  bool seen_statement_ = false;     // a line other than blanks has been read
  bool in_listing_header_ = false;  // in NX's "Information listing" header
  std::string stmt_;                // the statement's text, continuation lines joined
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
  while (true) {
    const detail::LineSource::Result r = source.next(text);
    if (r == detail::LineSource::kEnd) break;
    // Nothing a CL file reads changes a block once made: every whole chunk goes to the compact
    // store (block_list.h).
    out_.program.blocks.seal_before(out_.program.blocks.size());
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
  if (comment_continues_) {
    // A `$$` comment line that ended in '$' (Creo's "$$-> CSYS / ... $"): this line is the
    // comment's too.
    const std::string_view rest(text.data() + i, n - i);
    const size_t last = rest.find_last_not_of(" \t");
    comment_continues_ = last != std::string_view::npos && rest[last] == '$';
    return true;
  }
  if (!continuing_) {
    while (i < n && is_blank(text[i])) ++i;
    if (in_listing_header_) {  // NX's information listing: its header ends at a blank line
      in_listing_header_ = i < n;
      return true;
    }
    if (i == n) return true;
    const std::string_view rest(text.data() + i, n - i);
    if (!seen_statement_ && rest.rfind("Information listing created by", 0) == 0) {
      in_listing_header_ = true;
      return true;
    }
    if (rest.rfind("Tool Path Listing has ", 0) == 0) return true;  // the listing's last line
    seen_statement_ = true;
    if (rest.rfind("$$", 0) == 0) {
      const size_t last = rest.find_last_not_of(" \t");
      comment_continues_ = last > 2 && rest[last] == '$' && rest[last - 1] != '$';
      if (comment_continues_) return true;
      // NX marks tool-centre output so; its CUTCOM/ then asks the control for wear only.
      std::string words(rest.substr(2, last - 1));
      for (char& ch : words) ch = upper(ch);
      if (words.find("CENTERLINE DATA") != std::string::npos) state_.centre_path = "NX's \"$$ centerline data\"";
    }
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
  if (i >= n) return;  // WORD/ alone (SolidWorks CAM's RAPID/): each statement checks its count
  while (true) {
    i = skip_blanks(s, i);
    if (nargs_ == kMaxParameters) {
      fail(i, "more than " + std::to_string(kMaxParameters) + " parameters in " + major_ + "/");
    }
    if (nargs_ == args_.size()) args_.emplace_back();
    Arg& arg = args_[nargs_];
    // A comma that ends the statement (CAMWorks' CUTTER/): nothing more follows.
    if (i >= n && nargs_ > 0) return;
    if (i >= n || s[i] == ',') {
      fail(i, "empty parameter in " + major_ + "/ (expected a number or a word)");
    }
    const char c = s[i];
    // A word that starts with digits (SolidWorks CAM's CYCLE/ ... 1STPECK): a word.
    size_t d = i;
    while (d < n && is_digit(s[d])) ++d;
    const bool exponent = d < n && (s[d] == 'e' || s[d] == 'E') && d + 1 < n &&
                          (is_digit(s[d + 1]) || s[d + 1] == '+' || s[d + 1] == '-');
    const bool digit_word = d > i && d < n && is_letter(s[d]) && !exponent;
    if (!digit_word && (is_digit(c) || c == '+' || c == '-' || c == '.')) {
      i = parse_number(i, arg);
    } else if (is_letter(c) || digit_word) {
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
  if (word == Word::kUnknown && major_ == "TLON" && j < n && s[j] == ',') {
    do_tlon(j);
    return true;
  }
  i = j;
  const bool slash = i < n && s[i] == '/';
  if (!slash && i < n) {
    fail(i, "unexpected " + describe(s[i]) + " after " + major_ +
                " (expected '/' and its parameters, or the end of the statement)");
  }
  if (word == Word::kUnknown) {
    // SolidWorks CAM (CAMWorks) writes its CSI_ statements, and the tool's centre with CUTCOM/
    // (its lead-in arcs are a fifth of the tool's radius: no contour for the tool to follow).
    if (major_.rfind("CSI_", 0) == 0 && state_.centre_path.empty())
      state_.centre_path = "SolidWorks CAM's CSI_ statements";
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
    case Word::kCsys:
      do_csys();
      break;
    case Word::kMsys:
      do_msys();
      break;
    case Word::kCycle:
      do_cycle();
      break;
    case Word::kTldata:
      do_tldata();
      break;
    case Word::kIndirv:
      count(3, 3, "i,j,k");
      state_.indirv = turned(unit_vector(0, "direction"));
      break;
    case Word::kGohome: {
      // GOHOME[/x,y,z[,i,j,k]] (NX): a rapid to the home point, the FROM/ point when none is
      // given.
      no_circle_pending("GOHOME");
      no_cutcom("GOHOME");
      if (nargs_ == 0) {
        if (!state_.home_known) fail(major_pos_, "GOHOME without a point before any FROM/ (expected GOHOME/x,y,z)");
        motion(MotionKind::Rapid, state_.home_mm, state_.home_axis);
        break;
      }
      count_of({3, 6}, "x,y,z or x,y,z,i,j,k");
      const Eigen::Vector3d p = placed(Eigen::Vector3d(length(0, "x"), length(1, "y"), length(2, "z")));
      motion(MotionKind::Rapid, p, nargs_ == 6 ? turned(unit_vector(3, "tool axis")) : state_.axis);
      break;
    }
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
  // At the first parameter past the largest count allowed below the given one.
  size_t below = 0;
  for (size_t a : allowed)
    if (a < nargs_) below = std::max(below, a);
  const size_t pos = below > 0 ? args_[below].pos : args_pos_;
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
  state_.indirv = Eigen::Vector3d::Zero();  // INDIRV/ is for the next TLON only
  // A point within range as written can leave it once a CSYS/ or MSYS/ frame places it, or a
  // CYCLE/ adds its depth.
  if (!(end.cwiseAbs().maxCoeff() <= kMaxMagnitude)) {
    fail(major_pos_, "motion to " + point(end) + " mm in the workpiece frame, out of range (expected within +-1e6 mm)");
  }
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
    // After a CSYS/ that turns the part over, this is a second clamping, not a motion.
    const std::string setup = state_.setup_where.empty()
                                  ? std::string()
                                  : "; the CSYS/ at " + state_.setup_where +
                                        " turns the part over: a new clamping, to simulate as a job of its own";
    fail(major_pos_, "the tool axis turns from " + point(state_.pose_axis) + " to its opposite " + point(end_axis) +
                         " in one motion (expected an intermediate axis: no single great circle "
                         "joins opposite axes)" +
                         setup);
  }
  state_.setup_where.clear();
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
    block.turns = state_.circle_turns;
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

// GOTO/x,y,z[,i,j,k]. NX and SolidWorks CAM write the tool axis without MULTAX/ON (their
// three-axis and 3+2 operations alike): it is read either way.
void Reader::do_goto() {
  count_of({3, 6}, "x,y,z or x,y,z,i,j,k");
  Eigen::Vector3d end = placed(Eigen::Vector3d(length(0, "x"), length(1, "y"), length(2, "z")));
  const Eigen::Vector3d end_axis = nargs_ == 6 ? turned(unit_vector(3, "tool axis")) : state_.axis;
  if (state_.cycle.on) {
    state_.rapid_next = false;
    cycle_point(end, end_axis);
    return;
  }
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
  state_.position_mm = placed(Eigen::Vector3d(length(0, "x"), length(1, "y"), length(2, "z")));
  if (!(state_.position_mm.cwiseAbs().maxCoeff() <= kMaxMagnitude)) {
    fail(major_pos_,
         "FROM/ " + point(state_.position_mm) + " mm in the workpiece frame, out of range (expected within +-1e6 mm)");
  }
  if (nargs_ == 6) state_.pose_axis = state_.axis = turned(unit_vector(3, "tool axis"));
  state_.known = true;
  state_.home_known = true;  // GOHOME goes back here
  state_.home_mm = state_.position_mm;
  state_.home_axis = state_.axis;
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
    delta = turned(Eigen::Vector3d(length(0, "dx"), length(1, "dy"), length(2, "dz")));
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
  // Within the tolerance of d/2 (beyond it, above, is the error just above): a ball. r - d/2
  // rounds, so the test above can let through an r whose difference from d/2 here is a hair
  // over the tolerance: anything over d/2 is a ball too.
  if (std::abs(r - radius) <= kCutterMatchMm || r > radius) r = radius;
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
  if (t == 0.0 && !state_.loadtl_seen) {
    // NX's LOAD/TOOL,0: a tool the CAM model gave no number: numbered by its cutter, as in a
    // program without LOADTL/.
    warn_once(major_ + "/0", [&] {
      return where(args_[k].pos) + ": " + major_ + "/ tool 0 (no number): each different cutter is numbered in turn";
    });
    return;
  }
  if (!(t >= 1.0 && t <= kMaxToolNumber) || t != std::floor(t)) {
    fail(args_[k].pos, "tool number " + num(t) + " (expected a whole number from 1 to 99999)");
  }
  if (nargs_ > k + 1) {
    warn_once(major_ + "/ parameters", [&] {
      return where(args_[k + 1].pos) + ": " + major_ + "/ parameters after the tool number are ignored";
    });
  }
  const int tool = static_cast<int>(t);
  state_.cycle.on = false;  // a tool change ends a drilling cycle (SolidWorks CAM omits CYCLE/OFF)
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
  state_.axis = turned(unit_vector(0, "tool axis"));
}

// CIRCLE/cx,cy,cz,i,j,k,r[,tolerances...][,TIMES,n]: NX's TIMES,n goes round n times, as
// G2/G3 with P n (the turns beyond the first are full circles).
void Reader::do_circle() {
  count(6, 13, "cx,cy,cz,i,j,k[,r, up to 4 tolerances and TIMES,n]");
  if (state_.cycle.on) fail(major_pos_, "CIRCLE/ in a CYCLE/ (expected CYCLE/OFF first)");
  const Eigen::Vector3d c = placed(Eigen::Vector3d(length(0, "cx"), length(1, "cy"), length(2, "cz")));
  const Eigen::Vector3d n = turned(unit_vector(3, "circle axis"));
  // Without r (SolidWorks CAM): the current point's distance from the axis.
  Eigen::Vector3d from_axis = programmed_point() - c;
  from_axis -= n * n.dot(from_axis);
  const double r = nargs_ > 6 ? length(6, "radius r") : from_axis.norm();
  int turns = 1;
  for (size_t k = 7; k < nargs_; ++k) {
    if (!args_[k].is_number && args_[k].word == "TIMES" && k + 2 == nargs_) {
      const double t = number(k + 1, "the number of times round");
      if (!(t >= 1.0 && t <= 1000.0) || t != std::floor(t))
        fail(args_[k + 1].pos, "TIMES " + num(t) + " (expected a whole number of turns from 1 to 1000)");
      turns = static_cast<int>(t);
      break;
    }
    if (k > 10) fail(args_[k].pos, "CIRCLE/ with more than 4 tolerances (expected TIMES,n at most after them)");
    number(k, "a tolerance");
  }
  if (state_.circle_pending) {
    fail(major_pos_, "second CIRCLE/ before the GOTO/ of the CIRCLE/ at " + state_.circle_where +
                         " (expected a GOTO/ after each CIRCLE/)");
  }
  if (!(r > kSamePointMm))
    fail(args_[std::min<size_t>(6, nargs_ - 1)].pos, "circle radius " + num(r) + " mm (expected r > 0)");
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
    fail(args_[std::min<size_t>(6, nargs_ - 1)].pos,
         "the arc's start, the current point " + point(programmed_point()) + ", is " + num(r_start) +
             " mm from the circle's axis (expected a point on the circle: radius " + num(r) + " mm within " +
             num(allowed) + " mm)");
  }
  state_.circle_pending = true;
  state_.circle_turns = turns;
  state_.circle_center_mm = c;
  state_.circle_normal = n;
  state_.circle_radius_mm = r;
  state_.circle_where = where(major_pos_);
  std::tie(state_.circle_line, state_.circle_column) = locate(major_pos_);
}

// TLON,GOFWD/(CIRCLE/cx,cy,cz,r),ON,[n,INTOF,](LINE/x1,y1,z1,x2,y2,z2) (CATIA V5, after
// INDIRV/): the tool centre goes forward on the circle, from the current point in the direction
// INDIRV/ gives, until it is on the line the n-th time (n = 1 without n,INTOF). The circle's
// plane holds the start, the centre and that direction; the line must lie in it. Parentheses
// are optional, as some CATIA posts leave them out.
void Reader::do_tlon(size_t pos) {
  const std::string& s = stmt_;
  const size_t n = s.size();
  no_circle_pending("TLON");
  // Tokens: words, numbers and the '/' after a word; parentheses and commas separate.
  struct Token {
    std::string word;  // empty: a number
    double value = 0.0;
    size_t pos = 0;
  };
  std::vector<Token> tokens;
  for (size_t i = pos; i < n;) {
    const char c = s[i];
    if (c == ',' || c == '(' || c == ')' || c == '/' || c == ' ' || c == '\t') {
      ++i;
      continue;
    }
    Token t;
    t.pos = i;
    if (is_letter(c)) {
      while (i < n && is_word_char(s[i])) t.word.push_back(upper(s[i++]));
    } else if (is_digit(c) || c == '+' || c == '-' || c == '.') {
      Arg a;
      i = parse_number(i, a);
      t.value = a.value;
    } else {
      fail(i, "unexpected " + describe(c) + " in TLON (expected TLON,GOFWD/(CIRCLE/...),ON,(LINE/...))");
    }
    if (tokens.size() > 64) fail(t.pos, "TLON with more than 64 values (expected CIRCLE/ and LINE/)");
    tokens.push_back(t);
  }
  size_t k = 0;
  auto expect_word = [&](const char* w, const std::string& what) {
    if (k >= tokens.size() || tokens[k].word != w)
      fail(k < tokens.size() ? tokens[k].pos : n, "TLON: expected " + what);
    ++k;
  };
  auto value = [&](const char* what) {
    if (k >= tokens.size() || !tokens[k].word.empty())
      fail(k < tokens.size() ? tokens[k].pos : n, std::string("TLON: expected a number for ") + what);
    const double v = tokens[k++].value * unit();
    if (!(std::abs(v) <= kMaxMagnitude)) fail(tokens[k - 1].pos, std::string(what) + " out of range");
    return v;
  };
  expect_word("GOFWD", "GOFWD/ (TLON,GOFWD/: forward along a circle)");
  if (k < tokens.size() && tokens[k].word == "CYLNDR")
    fail(tokens[k].pos, "TLON,GOFWD/ along a CYLNDR/ is not supported (expected CIRCLE/)");
  expect_word("CIRCLE", "CIRCLE/cx,cy,cz,r after GOFWD/");
  const double cx = value("cx"), cy = value("cy"), cz = value("cz");
  const Eigen::Vector3d c = placed(Eigen::Vector3d(cx, cy, cz));
  const size_t radius_pos = k < tokens.size() ? tokens[k].pos : n;
  const double r = value("r");
  int crossing = 1;
  bool on = false;
  while (k < tokens.size() && tokens[k].word != "LINE") {
    const Token& t = tokens[k];
    if (t.word == "ON") {
      on = true;
    } else if (t.word.empty() && k + 1 < tokens.size() && tokens[k + 1].word == "INTOF") {
      if (!(t.value >= 1.0 && t.value <= 2.0) || t.value != std::floor(t.value))
        fail(t.pos, "TLON: intersection " + num(t.value) + " (expected 1 or 2: a line crosses a circle twice)");
      crossing = static_cast<int>(t.value);
      ++k;
    } else {
      fail(t.pos, "TLON: unexpected '" + (t.word.empty() ? num(t.value) : t.word) +
                      "' (expected ON, n,INTOF and the check line LINE/...; TO and PAST are not supported)");
    }
    ++k;
  }
  if (!on) fail(k < tokens.size() ? tokens[k].pos : n, "TLON without ON (expected ON before the LINE/)");
  expect_word("LINE", "LINE/x1,y1,z1,x2,y2,z2, the check line");
  Eigen::Vector3d a, b;  // one value at a time: the order of a call's arguments is not fixed
  for (int i = 0; i < 3; ++i) a[i] = value("the line's first point");
  for (int i = 0; i < 3; ++i) b[i] = value("the line's second point");
  a = placed(a);
  b = placed(b);
  if (k < tokens.size()) fail(tokens[k].pos, "TLON: unexpected text after the LINE/ (expected the end)");
  if (state_.cycle.on) fail(major_pos_, "TLON in a CYCLE/ (expected CYCLE/OFF first)");
  if (!state_.known) fail(major_pos_, "TLON from an unknown position (expected FROM/ or GOTO/ before it)");
  if (state_.indirv.isZero()) fail(major_pos_, "TLON,GOFWD/ without INDIRV/ (expected INDIRV/i,j,k before it)");
  if (!(r > kSamePointMm)) fail(radius_pos, "circle radius " + num(r) + " mm (expected r > 0)");
  const Eigen::Vector3d p0 = programmed_point();
  const double allowed = std::max(options_.arc_tolerance_mm, kArcRelativeTolerance * r);
  if (!(std::abs((p0 - c).norm() - r) <= allowed))
    fail(radius_pos, "the current point " + point(p0) + " is " + num((p0 - c).norm()) +
                         " mm from the circle's centre (expected a point on the circle: radius " + num(r) +
                         " mm within " + num(allowed) + " mm)");
  const Eigen::Vector3d normal_raw = (p0 - c).cross(state_.indirv);
  if (!(normal_raw.norm() > 1e-6 * r))
    fail(major_pos_, "INDIRV/ along the circle's radius at the start (expected a direction along the circle)");
  const Eigen::Vector3d nrm = normal_raw.normalized();
  // The line's crossings with the circle: q = a + s u, |q - c| = r, in the circle's plane.
  const Eigen::Vector3d u = (b - a).normalized();
  if (!((b - a).norm() > kSamePointMm) || std::abs(u.dot(nrm)) > 1e-6 || std::abs((a - c).dot(nrm)) > allowed)
    fail(major_pos_, "TLON's LINE/ does not lie in the circle's plane (expected a line in it)");
  const Eigen::Vector3d w = a - c;
  const double half_b = u.dot(w), disc = half_b * half_b - (w.squaredNorm() - r * r);
  if (!(disc > 0.0)) fail(major_pos_, "TLON's LINE/ does not cross the circle (expected a line through it)");
  // The crossings in the order the tool meets them: by the angle from the start about nrm.
  std::vector<std::pair<double, Eigen::Vector3d>> met;
  for (const double sign : {-1.0, 1.0}) {
    const Eigen::Vector3d q = a + (-half_b + sign * std::sqrt(disc)) * u;
    double angle = std::atan2(nrm.dot((p0 - c).cross(q - c)), (p0 - c).dot(q - c));
    if (angle <= kSamePointMm / r) angle += 2.0 * M_PI;  // forward: in (0, 2 pi], the start not met again
    met.emplace_back(angle, q);
  }
  std::sort(met.begin(), met.end(), [](const auto& x, const auto& y) { return x.first < y.first; });
  const Eigen::Vector3d end = met[static_cast<size_t>(crossing - 1)].second;
  state_.circle_pending = true;
  state_.circle_turns = 1;
  state_.circle_center_mm = c;
  state_.circle_normal = nrm;
  state_.circle_radius_mm = r;
  state_.circle_where = where(major_pos_);
  std::tie(state_.circle_line, state_.circle_column) = locate(major_pos_);
  motion(MotionKind::Arc, end, state_.axis);
  state_.circle_pending = false;
  // The direction at the end, for a next TLON without INDIRV/ (CATIA repeats INDIRV/ anyway);
  // any other motion clears it (Reader::motion).
  state_.indirv = nrm.cross(end - c).normalized();
}

// SPINDL/ in the orders CAM systems write it: n[,RPM][,CLW|CCLW] (SolidWorks CAM, CATIA),
// RPM,n[,CLW|CCLW] (APT, Creo, NX), ON, OFF; RANGE,n and MAXRPM,n do not change the path.
void Reader::do_spindl() {
  count(1, 8, "rpm[,RPM][,CLW|CCLW], RPM,rpm[,CLW|CCLW], ON or OFF");
  if (nargs_ == 1 && !args_[0].is_number && (args_[0].word == "OFF" || args_[0].word == "ON")) {
    state_.spindle = args_[0].word == "OFF" ? SpindleState::Off : state_.spindle_direction;
    return;
  }
  int speed = -1;
  SpindleState direction = SpindleState::Clockwise;  // APT's default
  for (size_t k = 0; k < nargs_; ++k) {
    const Arg& a = args_[k];
    if (a.is_number) {
      if (speed >= 0) fail(a.pos, "two speeds in SPINDL/ (expected one number of rpm)");
      speed = static_cast<int>(k);
    } else if (a.word == "RPM") {
      continue;
    } else if (a.word == "SFM" || a.word == "SMM") {
      fail(a.pos, "constant surface speed (" + a.word + ") is not supported (expected RPM)");
    } else if (a.word == "CLW") {
      direction = SpindleState::Clockwise;
    } else if (a.word == "CCLW") {
      direction = SpindleState::CounterClockwise;
    } else if (a.word == "RANGE" || a.word == "MAXRPM") {
      ++k;  // gear range / speed limit: its number does not change the path
      if (k >= nargs_ || !args_[k].is_number) fail(a.pos, a.word + " without its number in SPINDL/");
    } else {
      fail(a.pos, "unexpected '" + a.word + "' in SPINDL/ (expected rpm, RPM, CLW, CCLW, RANGE or MAXRPM)");
    }
  }
  if (speed < 0) fail(args_pos_, "SPINDL/ without a speed (expected a number of rpm)");
  const double rpm = number(static_cast<size_t>(speed), "the spindle speed");
  if (!(rpm >= 0.0 && rpm <= kMaxMagnitude)) {
    fail(args_[static_cast<size_t>(speed)].pos, "spindle speed " + num(rpm) + " rpm (expected 0 to 1e6 rpm)");
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
  if (!state_.centre_path.empty() || options_.cutcom_on_centre) {
    // The points are the tool's centre already (NX "$$ centerline data", program.cutcom:
    // centre): the control's compensation holds the wear only, zero here.
    warn_once("CUTCOM/centre", [&] {
      return where(a.pos) + ": CUTCOM/ on " +
             (state_.centre_path.empty() ? std::string("program.cutcom: centre") : state_.centre_path) +
             " (the points are the tool's centre): no offset";
    });
    return;
  }
  if (state_.multax)
    fail(a.pos,
         "CUTCOM/" + a.word + " with MULTAX/ON (expected three-axis CL data: compensation works in the XY plane)");
  if (!state_.has_cutter)
    fail(a.pos, "CUTCOM/" + a.word + " before any CUTTER/ (expected the cutter, whose radius the path is offset by)");
  if (state_.circle_pending)
    fail(a.pos, "CUTCOM/" + a.word + " between a CIRCLE/ and its GOTO/ (expected it before the CIRCLE/)");
  comp.side = a.word == "LEFT" ? Comp::Side::Left : Comp::Side::Right;
  comp.radius_mm = state_.cutter.radius_mm();
  comp.max_radius_mm = std::max(comp.max_radius_mm, comp.radius_mm);
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

// CSYS/r11,r12,r13,tx,r21,r22,r23,ty,r31,r32,r33,tz (SolidWorks CAM): the setup's frame in the
// part frame, part = R setup + t (the columns of R are the setup's axes; its post takes the
// third as the tool axis). What it places, as found in its output (41 files): in a setup turned
// about Z or moved (3 values per GOTO/) the motions are written in the setup's frame, so they
// are placed by R and t (two copies of a part 150 mm apart give the same hole 150 mm apart in
// the part frame); in a tilted setup the motions are written in the part frame with their tool
// axis (the approaches run along that axis), so they are read as written.
void Reader::do_csys() {
  no_circle_pending("CSYS/");
  no_cutcom("CSYS/");
  count(12, 12, "r11,r12,r13,tx,r21,r22,r23,ty,r31,r32,r33,tz");
  Eigen::Matrix3d r;
  Eigen::Vector3d t;
  for (int row = 0; row < 3; ++row) {
    for (int col = 0; col < 3; ++col) r(row, col) = number(static_cast<size_t>(4 * row + col), "a matrix entry");
    t[row] = length(static_cast<size_t>(4 * row + 3), "a translation");
  }
  const Eigen::Matrix3d rotation = checked_rotation(r, "CSYS/");
  const bool tilted = (rotation.col(2) - Eigen::Vector3d::UnitZ()).norm() > kFrameTolerance;
  state_.setup_where = where_line();
  state_.frame_rotation = tilted ? Eigen::Matrix3d::Identity() : rotation;
  state_.frame_translation_mm = tilted ? Eigen::Vector3d::Zero() : t;
}

// MSYS/x,y,z,xi,xj,xk,yi,yj,yk (NX): the machine coordinate system, its origin and X and Y
// axes in NX's absolute frame; the motions after it are written in it. The first MSYS/ is
// the workpiece frame (what the machine runs as its work offset); a later, different one
// (another setup of a 3+2 program) places its motions in the first: p = M1^-1 M2 p'.
void Reader::do_msys() {
  no_circle_pending("MSYS/");
  no_cutcom("MSYS/");
  count(9, 9, "x,y,z, the X axis i,j,k and the Y axis i,j,k");
  const Eigen::Vector3d origin(length(0, "x"), length(1, "y"), length(2, "z"));
  Eigen::Matrix3d r;
  r.col(0) = Eigen::Vector3d(number(3, "the X axis"), number(4, "the X axis"), number(5, "the X axis"));
  r.col(1) = Eigen::Vector3d(number(6, "the Y axis"), number(7, "the Y axis"), number(8, "the Y axis"));
  r.col(2) = r.col(0).cross(r.col(1));
  const Eigen::Matrix3d rotation = checked_rotation(r, "MSYS/");
  if (!state_.msys_seen) {
    state_.msys_seen = true;
    state_.msys_rotation = rotation;
    state_.msys_origin_mm = origin;
  }
  state_.frame_rotation = state_.msys_rotation.transpose() * rotation;
  state_.frame_translation_mm = state_.msys_rotation.transpose() * (origin - state_.msys_origin_mm);
}

// A frame's rotation as printed (6 decimals: entries off by 5e-7, products by ~2e-6): checked
// to be one within kFrameTolerance, then made exactly orthonormal (the nearest rotation).
Eigen::Matrix3d Reader::checked_rotation(const Eigen::Matrix3d& r, const char* what) const {
  const double off = (r.transpose() * r - Eigen::Matrix3d::Identity()).cwiseAbs().maxCoeff();
  const double det = r.determinant();
  if (!(off <= kFrameTolerance) || !(std::abs(det - 1.0) <= kFrameTolerance)) {
    fail(args_pos_, std::string(what) + " matrix is not a rotation: |R^T R - I| = " + num(off) + ", det = " + num(det) +
                        " (expected orthonormal rows with determinant 1 within " + num(kFrameTolerance) + ")");
  }
  const Eigen::JacobiSVD<Eigen::Matrix3d> svd(r, Eigen::ComputeFullU | Eigen::ComputeFullV);
  return svd.matrixU() * svd.matrixV().transpose();
}

// TLDATA/MILL,d,r,h,taper,tip (NX): the milling tool's diameter, lower radius, length, taper
// and tip angle, read as CUTTER/d,r,e,f,tip,taper,h (tip angle as alpha, taper as beta).
void Reader::do_tldata() {
  if (nargs_ == 0 || args_[0].is_number || args_[0].word != "MILL") {
    warn_once("TLDATA", [&] {
      return where(major_pos_) + ": TLDATA/ other than MILL is not read; the tool library gives its shape";
    });
    return;
  }
  count(2, 6, "MILL,d[,r[,h[,taper[,tip angle]]]]");
  const double d = number(1, "diameter d");
  const double r = nargs_ > 2 ? number(2, "lower radius r") : 0.0;
  const double alpha = nargs_ > 5 ? number(5, "tip angle") : 0.0;
  const bool pointed = std::abs(alpha) > kZeroAngleDeg;
  const double e = pointed ? d / 2.0 : d / 2.0 - r;
  const double f = pointed ? d / 2.0 * std::tan(alpha * M_PI / 180.0) : r;
  // In CUTTER/'s order, each value at its TLDATA/ position for messages.
  std::vector<Arg> as_cutter(7);
  const size_t from[7] = {1, 2, 2, 2, 5, 4, 3};
  const double value[7] = {d,
                           r,
                           e,
                           f,
                           alpha,
                           nargs_ > 4 ? number(4, "taper") : 0.0,
                           nargs_ > 3 ? number(3, "length h") : kDefaultHeightPerDiameter * d};
  for (size_t k = 0; k < 7; ++k) {
    as_cutter[k].is_number = true;
    as_cutter[k].value = value[k];
    as_cutter[k].pos = args_[std::min(from[k], nargs_ - 1)].pos;
  }
  args_ = std::move(as_cutter);
  nargs_ = 7;
  do_cutter();
}

// CYCLE/kind[,modifiers][,WORD,value ...] ... CYCLE/OFF: the drilling cycles of SolidWorks CAM
// (DRILL, DEEP, DEEP2 with FEDTO, RAPTO, RTRCTO, MMPM|IPM, DWELL, INCR, 1STPECK, SUBPECK), NX
// (DRILL[,DEEP|BRKCHP] with RAPTO, FEDTO, MMPM) and Creo (DEEP with DEPTH, STEP, CLEAR). Each
// GOTO/ while it is on is a hole at that point of the surface, drilled along the tool axis:
// rapid across at the current level (at least the clearance) to above the point, rapid to
// RAPTO above it, feed to FEDTO below it (DEEP, BRKCHP: in pecks of INCR, back to RAPTO after
// each), back to RTRCTO above it (else the level it came at) at rapid, or at feed for TAP,
// BORE and REAM. CYCLE/INIT and CYCLE/CLEAR change nothing; CYCLE/ON takes up the last cycle.
void Reader::do_cycle() {
  no_circle_pending("CYCLE/");
  no_cutcom("CYCLE/");
  if (nargs_ == 0) fail(args_pos_, "CYCLE without its kind (expected CYCLE/DRILL, DEEP, ... or OFF)");
  const Arg& first = args_[0];
  if (first.is_number) fail(first.pos, "expected a cycle kind (DRILL, DEEP, BRKCHP, TAP, BORE, REAM) or OFF");
  if (nargs_ == 1 && (first.word == "INIT" || first.word == "CLEAR")) return;
  if (nargs_ == 1 && first.word == "OFF") {
    state_.cycle.on = false;
    return;
  }
  if (nargs_ == 1 && first.word == "ON") {
    if (state_.cycle.kind == AptState::Cycle::Kind::None)
      fail(first.pos, "CYCLE/ON before any cycle (expected CYCLE/DRILL, ... first)");
    state_.cycle.on = true;
    return;
  }
  AptState::Cycle c;
  c.where = where(major_pos_);
  using Kind = AptState::Cycle::Kind;
  static const std::pair<const char*, Kind> kKinds[] = {
      {"DRILL", Kind::Drill}, {"DEEP", Kind::Peck},    {"DEEP2", Kind::Peck},  {"BRKCHP", Kind::Peck},
      {"TAP", Kind::FeedOut}, {"BORE", Kind::FeedOut}, {"REAM", Kind::FeedOut}};
  auto kind_of = [](const std::string& w) {
    for (const auto& [word, kind] : kKinds)
      if (w == word) return kind;
    return Kind::None;
  };
  c.kind = kind_of(first.word);
  if (c.kind == Kind::None) {
    fail(first.pos, "cycle " + first.word + " is not supported (expected DRILL, DEEP, DEEP2, BRKCHP, TAP, BORE, REAM)");
  }
  bool depth = false;
  for (size_t k = 1; k < nargs_; ++k) {
    const Arg& a = args_[k];
    if (a.is_number) fail(a.pos, "a number without its word in CYCLE/ (expected FEDTO, RAPTO, RTRCTO, MMPM, ...)");
    if (const Kind kind = kind_of(a.word); kind != Kind::None) {  // NX: CYCLE/DRILL,DEEP
      if (kind != Kind::Drill) c.kind = kind;
      continue;
    }
    if (a.word == "G98" || a.word == "G99") continue;
    if (k + 1 >= nargs_ || !args_[k + 1].is_number) fail(a.pos, a.word + " without its number in CYCLE/");
    const double v = args_[k + 1].value;
    if (a.word == "FEDTO" || a.word == "DEPTH") {
      c.depth_mm = length(k + 1, "the depth");
      depth = true;
    } else if (a.word == "RAPTO" || a.word == "CLEAR") {
      c.clearance_mm = length(k + 1, "the clearance");
    } else if (a.word == "RTRCTO") {
      c.retract_mm = length(k + 1, "the retract");
    } else if (a.word == "MMPM" || a.word == "IPM") {
      c.feed_mm_per_min = v * (a.word == "IPM" ? kMmPerInch : 1.0);
      if (!(c.feed_mm_per_min > 0.0 && c.feed_mm_per_min <= kMaxMagnitude))
        fail(args_[k + 1].pos, "cycle feed " + num(v) + " (expected > 0 and <= 1e6 mm/min)");
    } else if (a.word == "INCR" || a.word == "1STPECK" || a.word == "STEP") {
      c.first_peck_mm = length(k + 1, "the peck");
      if (c.peck_mm <= 0.0) c.peck_mm = c.first_peck_mm;
    } else if (a.word == "SUBPECK") {
      c.peck_mm = length(k + 1, "the peck");
    } else if (a.word == "DWELL" || a.word == "REV" || a.word == "MMPR" || a.word == "IPR") {
      if (a.word == "MMPR" || a.word == "IPR") {
        const double rpm = state_.spindle_rpm;
        if (!(rpm > 0.0))
          fail(a.pos, "cycle feed per revolution with the spindle's speed unknown (expected SPINDL/ first)");
        c.feed_mm_per_min = v * rpm * (a.word == "IPR" ? kMmPerInch : 1.0);
        if (!(c.feed_mm_per_min > 0.0 && c.feed_mm_per_min <= kMaxMagnitude))
          fail(args_[k + 1].pos, "cycle feed " + num(c.feed_mm_per_min) + " mm/min (expected > 0 and <= 1e6 mm/min)");
      }
    } else {
      fail(a.pos,
           "unknown CYCLE/ parameter " + a.word +
               " (expected FEDTO, DEPTH, RAPTO, CLEAR, RTRCTO, MMPM, IPM, MMPR, IPR, DWELL, INCR, STEP, 1STPECK, "
               "SUBPECK)");
    }
    ++k;
  }
  if (!depth) fail(args_pos_, "CYCLE/" + first.word + " without its depth (expected FEDTO,d or DEPTH,d)");
  if (c.depth_mm < 0.0) fail(args_pos_, "cycle depth " + num(c.depth_mm) + " mm (expected >= 0: below the point)");
  if (c.kind == Kind::Peck && !(c.first_peck_mm > 0.0)) c.first_peck_mm = c.peck_mm = c.depth_mm;
  if (c.peck_mm < 0.0 || c.first_peck_mm < 0.0) fail(args_pos_, "a negative peck in CYCLE/ (expected > 0)");
  // Bounded work: a peck too small for its depth is a typo (and a million blocks per hole).
  if (c.kind == Kind::Peck && c.depth_mm > 0.0 && c.depth_mm > kMaxPecks * std::min(c.first_peck_mm, c.peck_mm))
    fail(args_pos_, "a peck of " + num(std::min(c.first_peck_mm, c.peck_mm)) + " mm for a hole " + num(c.depth_mm) +
                        " mm deep: more than 10000 pecks (expected a larger INCR, STEP or SUBPECK)");
  c.on = true;
  state_.cycle = c;
}

void Reader::cycle_point(const Eigen::Vector3d& point, const Eigen::Vector3d& axis) {
  const AptState::Cycle& c = state_.cycle;
  if (!state_.known) {
    // The program's first motion is a hole (NX): it starts above it, at the clearance.
    state_.known = true;
    state_.position_mm = point + c.clearance_mm * axis;
    state_.pose_axis = state_.axis = axis;
  }
  const double saved_feed = state_.feed_mm_per_min;
  if (c.feed_mm_per_min > 0.0) state_.feed_mm_per_min = c.feed_mm_per_min;
  const double level = (state_.position_mm - point).dot(axis);  // where the tool comes from
  const double across = std::max(level, c.clearance_mm);
  const double retract = c.retract_mm >= 0.0 ? c.retract_mm : across;
  const Eigen::Vector3d bottom = point - c.depth_mm * axis;
  if (level < across) motion(MotionKind::Rapid, state_.position_mm + (across - level) * axis, axis);
  motion(MotionKind::Rapid, point + across * axis, axis);
  motion(MotionKind::Rapid, point + c.clearance_mm * axis, axis);
  if (c.kind == AptState::Cycle::Kind::Peck) {
    // Pecks: each feeds from where the last stopped (rapid back to it) down one peck more.
    double reached = -c.clearance_mm;  // below the point
    double peck = c.first_peck_mm;
    while (reached < c.depth_mm) {
      const double next = std::min(c.depth_mm, std::max(reached, 0.0) + peck);
      if (reached > 0.0) motion(MotionKind::Rapid, point - reached * axis, axis);
      motion(MotionKind::Linear, point - next * axis, axis);
      reached = next;
      peck = c.peck_mm > 0.0 ? c.peck_mm : c.first_peck_mm;
      if (reached < c.depth_mm) motion(MotionKind::Rapid, point + c.clearance_mm * axis, axis);
    }
  } else {
    motion(MotionKind::Linear, bottom, axis);
  }
  const bool feed_out = c.kind == AptState::Cycle::Kind::FeedOut;
  if (feed_out) motion(MotionKind::Linear, point + c.clearance_mm * axis, axis);
  motion(MotionKind::Rapid, point + retract * axis, axis);
  state_.feed_mm_per_min = saved_feed;
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
