// Dialect detection and the one entry point for reading NC programs of any dialect.
#include <vcut/io/input_error.h>
#include <vcut/io/program_reader.h>
#include <vcut/io/sinumerik_reader.h>
#include <vcut/kinematics/forward_kinematics.h>
#include <vcut/kinematics/inverse_kinematics.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <cstdlib>
#include <cerrno>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <memory>
#include <tuple>
#include <utility>
#include <vector>

#include "reader_util.h"

namespace vcut::io {
namespace {

namespace fs = std::filesystem;

// How much of a file the detector and the binary check look at: the header of any NC program.
constexpr std::size_t kSniffBytes = std::size_t{1} << 16;
constexpr int kSniffLines = 200;

std::string lower(std::string s) {
  for (char& c : s) c = (c >= 'A' && c <= 'Z') ? static_cast<char>(c - 'A' + 'a') : c;
  return s;
}
std::string upper(std::string s) {
  for (char& c : s) c = (c >= 'a' && c <= 'z') ? static_cast<char>(c - 'a' + 'A') : c;
  return s;
}
bool is_alnum(char c) { return (c >= 'A' && c <= 'Z') || (c >= 'a' && c <= 'z') || (c >= '0' && c <= '9') || c == '_'; }
bool is_digit(char c) { return c >= '0' && c <= '9'; }
bool is_blank(char c) { return c == ' ' || c == '\t'; }

std::string sniff(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) return {};
  std::string head(kSniffBytes, '\0');
  in.read(head.data(), static_cast<std::streamsize>(head.size()));
  head.resize(static_cast<std::size_t>(std::max<std::streamsize>(0, in.gcount())));
  return head;
}

// `word` in `line` as a whole word (not part of a longer name).
bool has_word(const std::string& line, const char* word) {
  const std::size_t n = std::strlen(word);
  for (std::size_t at = line.find(word); at != std::string::npos; at = line.find(word, at + 1)) {
    const bool left = at == 0 || !is_alnum(line[at - 1]);
    const bool right = at + n >= line.size() || !is_alnum(line[at + n]) || !is_alnum(word[n - 1]);
    if (left && right) return true;
  }
  return false;
}

// An APT statement word followed by '/' (or a bare APT word) at the start of the line.
bool apt_statement(const std::string& line) {
  static const char* const kSlashWords[] = {"GOTO",   "FEDRAT", "CUTTER", "FROM",   "LOADTL", "MULTAX", "TLAXIS",
                                            "CIRCLE", "SPINDL", "UNITS",  "GODLTA", "COOLNT", "INTOL",  "OUTTOL"};
  static const char* const kBareWords[] = {"PARTNO", "PPRINT", "MULTAX", "FINI", "RAPID"};
  std::size_t j = 0;
  while (j < line.size() && is_alnum(line[j])) ++j;
  const std::string word = line.substr(0, j);
  while (j < line.size() && is_blank(line[j])) ++j;
  if (j < line.size() && line[j] == '/') {
    for (const char* w : kSlashWords) {
      if (word == w) return true;
    }
  }
  for (const char* w : kBareWords) {
    if (word == w && (j == line.size() || word == "PARTNO" || word == "PPRINT")) return true;
  }
  return false;
}

// "N7 X -1320": an N block whose words are written letter, blank, number.
bool letter_space_number(const std::string& line) {
  if (line.empty() || line[0] != 'N' || line.size() < 2 || !is_digit(line[1])) return false;
  for (std::size_t i = 1; i + 2 < line.size(); ++i) {
    if (!(line[i] >= 'A' && line[i] <= 'Z') || is_alnum(line[i - 1]) || !is_blank(line[i + 1])) {
      continue;
    }
    std::size_t j = i + 1;
    while (j < line.size() && is_blank(line[j])) ++j;
    if (j < line.size() && (line[j] == '-' || line[j] == '+')) ++j;
    if (j < line.size() && (is_digit(line[j]) || line[j] == '.')) return true;
  }
  return false;
}

Dialect detect_from_text(const std::string& head) {
  static const char* const kSinumerikWords[] = {"TRAORI",   "TRAFOOF",  "ORIVECT",  "ORIAXES",   "ORIWKS",
                                                "ORIMKS",   "ORIPLANE", "ORICONCW", "ORICONCCW", "ORICONIO",
                                                "ORICONTO", "G641",     "G642"};
  bool semicolon = false, letter_space = false, gcode_sign = false;
  std::size_t start = 0;
  for (int lines = 0; start < head.size() && lines < kSniffLines; ++lines) {
    std::size_t end = head.find('\n', start);
    if (end == std::string::npos) end = head.size();
    std::string line = upper(head.substr(start, end - start));
    start = end + 1;
    std::size_t i = 0;
    while (i < line.size() && (is_blank(line[i]) || line[i] == '\r')) ++i;
    line.erase(0, i);
    while (!line.empty() && (line.back() == '\r' || is_blank(line.back()))) line.pop_back();
    if (line.empty()) continue;
    if (line.rfind("$$", 0) == 0) return Dialect::Apt;
    if (apt_statement(line)) return Dialect::Apt;
    // G-code and SINUMERIK: look at the words only, not at comments.
    std::string words;
    bool paren = false;
    for (char c : line) {
      if (paren) {
        paren = c != ')';
      } else if (c == '(' && !words.empty() && words.back() >= 'A' && words.back() <= 'Z') {
        words += c;  // AC( IC( MSG( ...: a SINUMERIK call, not a comment
      } else if (c == '(') {
        paren = true;
        gcode_sign = true;
      } else if (c == ';') {
        semicolon = true;
        break;
      } else {
        words += c;
      }
    }
    if (words.empty()) continue;
    if (words[0] == '%' || words[0] == 'O' || words.find('#') != std::string::npos) {
      gcode_sign = true;
    }
    for (const char* w : kSinumerikWords) {
      if (has_word(words, w)) return Dialect::Sinumerik;
    }
    if (words.find("CR=") != std::string::npos || words.find("MSG(") != std::string::npos ||
        words.find("AC(") != std::string::npos || words.find("IC(") != std::string::npos ||
        words.rfind("DEF ", 0) == 0) {
      return Dialect::Sinumerik;
    }
    if (letter_space_number(words)) letter_space = true;
  }
  return semicolon && letter_space && !gcode_sign ? Dialect::Sinumerik : Dialect::Gcode;
}

ProgramReader reader_of(Dialect dialect) {
  return dialect == Dialect::Apt         ? ProgramReader::Apt
         : dialect == Dialect::Sinumerik ? ProgramReader::Sinumerik
                                         : ProgramReader::Gcode;
}

constexpr Dialect kDialects[] = {Dialect::Auto,  Dialect::Gcode, Dialect::LinuxCnc,
                                 Dialect::Fanuc, Dialect::Apt,   Dialect::Sinumerik};

const char* describe_dialect(ProgramReader reader) {
  return reader == ProgramReader::Apt ? "APT CL data" : reader == ProgramReader::Sinumerik ? "SINUMERIK" : "G-code";
}

// A NUL byte does not occur in any NC program in text; it does in every binary file.
void check_text(const std::string& path, const std::string& head) {
  const std::size_t nul = head.find('\0');
  if (nul == std::string::npos) return;
  const std::size_t line_start = head.rfind('\n', nul);
  const int line = 1 + static_cast<int>(std::count(head.begin(), head.begin() + nul, '\n'));
  const int column = static_cast<int>(nul - (line_start == std::string::npos ? 0 : line_start + 1)) + 1;
  throw InputError(path, line, column, "not a text file (a NUL byte; expected an NC program)");
}

}  // namespace

std::string lower_extension(const std::string& path) { return lower(fs::path(path).extension().string()); }

const char* dialect_name(Dialect dialect) {
  switch (dialect) {
    case Dialect::Auto:
      return "auto";
    case Dialect::Gcode:
      return "gcode";
    case Dialect::LinuxCnc:
      return "linuxcnc";
    case Dialect::Fanuc:
      return "fanuc";
    case Dialect::Apt:
      return "apt";
    case Dialect::Sinumerik:
      return "sinumerik";
  }
  return "auto";
}

Dialect parse_dialect(const std::string& name) {
  for (const Dialect d : kDialects)
    if (name == dialect_name(d)) return d;
  throw InputError("unknown program dialect '" + name + "' (expected auto, gcode, linuxcnc, fanuc, apt or sinumerik)");
}

Dialect detect_dialect(const std::string& path) {
  const std::string ext = lower_extension(path);
  if (ext == ".apt" || ext == ".cl" || ext == ".cls" || ext == ".aptsource") return Dialect::Apt;
  if (ext == ".mpf" || ext == ".spf") return Dialect::Sinumerik;
  if (ext == ".ngc" || ext == ".nc" || ext == ".tap" || ext == ".gcode") return Dialect::Gcode;
  return detect_from_text(sniff(path));
}

// Fanuc custom macro B in a G-code file: IF [..] GOTO/THEN, WHILE [..] DOm, ENDm, GOTO n at
// the start of a block, G65 P (a macro call), M98 P (a subprogram call) or #3000 / #3006 set
// (an alarm, a stop), and no LinuxCNC o-word keywords.
bool reads_like_fanuc_macro(const std::string& head) {
  bool fanuc = false;
  std::size_t start = 0;
  while (start < head.size()) {
    std::size_t end = head.find_first_of("\r\n", start);
    if (end == std::string::npos) end = head.size();
    const std::string line = upper(head.substr(start, end - start));
    start = end + 1;
    std::size_t i = 0;
    while (i < line.size() && is_blank(line[i])) ++i;
    if (i < line.size() && line[i] == 'O' && i + 1 < line.size() && (line[i + 1] == '<' || is_digit(line[i + 1]))) {
      std::size_t j = i + 1;
      if (line[j] == '<')
        j = line.find('>', j);
      else
        while (j < line.size() && is_digit(line[j])) ++j;
      while (j != std::string::npos && j < line.size() && is_blank(line[j])) ++j;
      if (j != std::string::npos && j < line.size() && line[j] >= 'A' && line[j] <= 'Z')
        return false;  // o<name> sub, o100 if ...
    }
    if (i < line.size() && line[i] == 'N') {
      ++i;
      while (i < line.size() && (is_digit(line[i]) || is_blank(line[i]))) ++i;
    }
    auto starts = [&](const char* word) { return line.compare(i, std::strlen(word), word) == 0; };
    std::size_t after = i;
    while (after < line.size() && line[after] >= 'A' && line[after] <= 'Z') ++after;
    while (after < line.size() && is_blank(line[after])) ++after;
    if ((starts("IF") || starts("WHILE")) && after < line.size() && line[after] == '[') fanuc = true;
    if (starts("GOTO") || (starts("END") && i + 3 < line.size() && is_digit(line[i + 3]))) fanuc = true;
    if (has_word(line, "G65") || has_word(line, "M98")) fanuc = true;
    // #3000 = n (alarm) and #3006 = n (stop): Fanuc's system variables; a plain parameter in
    // rs274ngc, which no LinuxCNC program sets.
    if (starts("#3000") || starts("#3006")) {
      std::size_t j = i + 5;
      while (j < line.size() && is_blank(line[j])) ++j;
      if (j < line.size() && line[j] == '=') fanuc = true;
    }
  }
  return fanuc;
}

void set_machine(GcodeOptions& options, const kinematics::MachineSpec& spec,
                 const std::map<int, removal::Cutter>& tools, bool axis_program) {
  const kinematics::Machine machine(spec);
  auto gauge_at = [&](const std::map<char, double>& home, Eigen::Vector3d& point, std::array<double, 3>& rotary_deg) {
    kinematics::AxisValues q = machine.zero();
    for (const auto& [letter, value] : home) {
      const int i = machine.axis_index(letter);
      if (i >= 0) q[i] = value;
    }
    rotary_deg = {0.0, 0.0, 0.0};
    for (int r = 0; r < 3; ++r) {
      const int i = machine.axis_index(static_cast<char>('A' + r));
      if (i >= 0) rotary_deg[static_cast<size_t>(r)] = q[i] * 180.0 / M_PI;
    }
    // An axis program's X Y Z are the tip with the rotary axes at zero (as the pose engine
    // reads them): the gauge point there, the rotaries left out.
    if (axis_program)
      for (int k = 0; k < machine.axis_count(); ++k)
        if (machine.axis(k).kind == kinematics::AxisKind::Rotary) q[k] = 0.0;
    const kinematics::ToolPose pose = kinematics::forward(machine, q, 0.0);
    point = pose.tip_mm;
    options.spindle_axis = pose.axis;
  };
  std::array<double, 3> unused_deg{};
  gauge_at({}, options.machine_zero_mm, unused_deg);
  Eigen::Vector3d start;
  gauge_at(spec.home, start, options.reference_rotary_deg[0]);
  options.start_mm = start;
  options.reference_mm[0] = start;
  gauge_at(spec.second_home ? *spec.second_home : spec.home, options.reference_mm[1], options.reference_rotary_deg[1]);
  options.m_codes_ignored = spec.ignored_m_codes;
  options.extra_axes.clear();  // vcut's machines move X Y Z and their rotaries: no U V W
  options.tool_length_mm.clear();
  options.tool_radius_mm.clear();
  auto lengths = std::make_shared<std::map<int, double>>();
  for (const auto& [number, cutter] : tools) {
    options.tool_length_mm[number] = cutter.gauge_length_mm;
    options.tool_radius_mm[number] = cutter.radius_mm();
    (*lengths)[number] = cutter.gauge_length_mm;
  }
  // G53.1 / G53.6: the machine's rotaries for a tool axis, and the tip's swing.
  auto shared = std::make_shared<const kinematics::Machine>(spec);
  auto axis_values = [shared](const kinematics::RotaryWords& rotary) {
    kinematics::AxisValues q = shared->zero();
    for (int r = 0; r < 3; ++r) {
      const int i = shared->axis_index(static_cast<char>('A' + r));
      if (i >= 0) q[i] = rotary.angle_rad[static_cast<size_t>(r)];
    }
    return q;
  };
  auto length_of = [lengths](int tool) {
    const auto it = lengths->find(tool);
    return it == lengths->end() ? 0.0 : it->second;
  };
  options.orient = [shared, axis_values, length_of](int tool, const Eigen::Vector3d& tip, const Eigen::Vector3d& axis,
                                                    const kinematics::RotaryWords& from, int tilt_sign,
                                                    kinematics::RotaryWords& to) {
    if (shared->rotary_count() == 0) return std::string("it has no rotary axis");
    // The tilting axis: the rotary least parallel to the spindle at all-zero axes.
    int tilt = -1;
    double least = 2.0;
    for (int k = 0; k < shared->rotary_count(); ++k) {
      const int i = shared->rotary_axis(k);
      const double parallel =
          std::abs(shared->axis(i).direction.normalized().dot(shared->spec().spindle_axis.normalized()));
      if (parallel < least - 1e-9) {
        least = parallel;
        tilt = i;
      }
    }
    const kinematics::AxisValues previous = axis_values(from);
    const kinematics::IkResult ik = kinematics::inverse(*shared, {tip, axis}, length_of(tool), &previous);
    // The rotaries' limits decide here (the linear axes' travel is the path's business: the
    // pose engine reports it): of the solutions within them, the least rotary motion.
    const kinematics::IkSolution* best = nullptr;
    double best_cost = 0.0;
    std::string violation;
    for (const kinematics::IkSolution& solution : ik.solutions) {
      double cost = 0.0;
      std::string outside;
      for (int k = 0; k < shared->rotary_count(); ++k) {
        const int i = shared->rotary_axis(k);
        const auto& limits = shared->axis(i).limits;
        if (limits && (solution.q[i] < limits->first - 1e-9 || solution.q[i] > limits->second + 1e-9) &&
            outside.empty()) {
          outside = "axis " + std::string(1, shared->axis(i).letter) + " would need " +
                    detail::num(solution.q[i] * 180.0 / M_PI) + " deg, outside its limits [" +
                    detail::num(limits->first * 180.0 / M_PI) + ", " + detail::num(limits->second * 180.0 / M_PI) + "]";
        }
        cost += std::abs(solution.q[i] - previous[i]);
      }
      if (!outside.empty()) {
        if (violation.empty()) violation = outside;
        continue;
      }
      if (tilt_sign != 0 && solution.q[tilt] * tilt_sign < -1e-9) {
        if (violation.empty()) {
          violation = "no solution with axis " + std::string(1, shared->axis(tilt).letter) +
                      (tilt_sign > 0 ? " >= 0" : " <= 0") + " within the limits";
        }
        continue;
      }
      if (best == nullptr || cost < best_cost - 1e-9) {
        best = &solution;
        best_cost = cost;
      }
    }
    if (best == nullptr)
      return violation.empty() ? (ik.reason.empty() ? std::string("no solution") : ik.reason) : violation;
    to = kinematics::RotaryWords{};
    for (int r = 0; r < 3; ++r) {
      const int i = shared->axis_index(static_cast<char>('A' + r));
      if (i < 0) continue;
      to.angle_rad[static_cast<size_t>(r)] = best->q[i];
      to.given[static_cast<size_t>(r)] = true;
    }
    return std::string();
  };
  // Rotary axes numbered as a Siemens swivel data record does: the head's first (type T and
  // M), from the base (F) outward, then the table's (type P and M), from the base inward.
  options.rotary_axes.clear();
  std::vector<std::tuple<bool, long, char>> rotaries;
  const std::string& chain = spec.topology;
  const auto base = static_cast<long>(chain.find('F'));
  for (int k = 0; k < shared->rotary_count(); ++k) {
    const char letter = shared->axis(shared->rotary_axis(k)).letter;
    const auto at = static_cast<long>(chain.find(letter));
    rotaries.emplace_back(at < base, std::labs(at - base), letter);
  }
  std::sort(rotaries.begin(), rotaries.end());
  for (const auto& r : rotaries) options.rotary_axes += std::get<2>(r);
  // u_w = R(k_1, s_1 q_1) R(k_2, s_2 q_2) u_0 (Machine::rotary_axis): the whole frame turns so.
  options.frame_rotation = [shared](const kinematics::RotaryWords& rotary) {
    Eigen::Matrix3d r = Eigen::Matrix3d::Identity();
    for (int k = 0; k < shared->rotary_count(); ++k) {
      const kinematics::AxisSpec& axis = shared->axis(shared->rotary_axis(k));
      const double angle = rotary.angle_rad[static_cast<std::size_t>(axis.letter - 'A')];
      r = r * Eigen::AngleAxisd(shared->rotary_sign(k) * angle, axis.direction.normalized()).toRotationMatrix();
    }
    return r;
  };
  options.tip_after_turn = [shared, axis_values, length_of](int tool, const Eigen::Vector3d& tip,
                                                            const kinematics::RotaryWords& from,
                                                            const kinematics::RotaryWords& to) {
    kinematics::AxisValues q = axis_values(from);
    if (!kinematics::solve_linear_axes(*shared, q, tip, length_of(tool))) return tip;
    const kinematics::AxisValues turned = axis_values(to);
    for (int r = 0; r < 3; ++r) {
      const int i = shared->axis_index(static_cast<char>('A' + r));
      if (i >= 0) q[i] = turned[i];
    }
    return kinematics::forward(*shared, q, length_of(tool)).tip_mm;
  };
}

const char* reader_name(ProgramReader reader) {
  switch (reader) {
    case ProgramReader::Gcode:
      return "gcode";
    case ProgramReader::Apt:
      return "apt";
    case ProgramReader::Sinumerik:
      return "sinumerik";
  }
  return "gcode";
}

// The SINUMERIK reader takes the G-code options that apply to it: the job's work offsets
// (G54..G57, G505..), unsupported words as warnings, the arc tolerance, the loop limit, the
// subprogram folders and the machine where one is known (set_machine was called).
SinumerikOptions sinumerik_options(const GcodeOptions& gcode) {
  SinumerikOptions sinumerik;
  sinumerik.work_offsets_mm = gcode.work_offsets_mm;
  sinumerik.unsupported_as_warning = gcode.unsupported_as_warning;
  sinumerik.unknown_m_code_as_error = gcode.unknown_m_code_as_error;
  sinumerik.m_codes_ignored = gcode.m_codes_ignored;
  if (gcode.arc_tolerance_mm >= 0.0) sinumerik.arc_tolerance_mm = gcode.arc_tolerance_mm;
  sinumerik.max_lines = gcode.max_lines;
  sinumerik.subroutine_path = gcode.subroutine_path;
  sinumerik.orient = gcode.orient;
  sinumerik.tip_after_turn = gcode.tip_after_turn;
  if (gcode.orient) {  // set_machine sets these
    sinumerik.reference_mm = gcode.reference_mm;
    sinumerik.start_mm = gcode.start_mm;
  }
  sinumerik.tool_length_mm = gcode.tool_length_mm;
  sinumerik.spindle_axis = gcode.spindle_axis;
  sinumerik.rotary_axes = gcode.rotary_axes;
  sinumerik.frame_rotation = gcode.frame_rotation;
  sinumerik.machine_zero_mm = gcode.machine_zero_mm;
  sinumerik.initial_tool = gcode.initial_tool;
  return sinumerik;
}

LoadedProgram read_programs(const std::vector<std::string>& paths, Dialect dialect, const ProgramOptions& options) {
  LoadedProgram out;
  GcodeState gcode_state;
  AptState apt_state;
  AptProgram apt;
  SinumerikState sinumerik_state;
  bool first = true;
  for (const std::string& path : paths) {
    std::error_code ec;
    if (fs::is_directory(path, ec)) {
      throw InputError(path, 0, 0, "is a directory (expected a program file)");
    }
    std::ifstream in(path, std::ios::binary);
    if (!in) {
      throw InputError(path, 0, 0, std::string("cannot open program file for reading: ") + std::strerror(errno));
    }
    check_text(path, sniff(path));
    const ProgramReader reader = reader_of(dialect == Dialect::Auto ? detect_dialect(path) : dialect);
    if (first) {
      out.reader = reader;
      first = false;
    } else if (reader != out.reader) {
      throw InputError(path, 0, 0,
                       std::string("is ") + describe_dialect(reader) + " but " + paths.front() + " is " +
                           describe_dialect(out.reader) + " (expected one dialect for all program files)");
    }
    if (reader == ProgramReader::Sinumerik) {
      const SinumerikOptions sinumerik = sinumerik_options(options.gcode);
      read_sinumerik(in, path, sinumerik, out.program, sinumerik_state);
    } else if (reader == ProgramReader::Gcode) {
      GcodeOptions gcode = options.gcode;
      if (dialect == Dialect::LinuxCnc) gcode.flavor = GcodeOptions::Flavor::LinuxCnc;
      if (dialect == Dialect::Fanuc) gcode.flavor = GcodeOptions::Flavor::Fanuc;
      if ((dialect == Dialect::Auto || dialect == Dialect::Gcode) && reads_like_fanuc_macro(sniff(path))) {
        gcode.flavor = GcodeOptions::Flavor::Fanuc;
      }
      read_gcode(in, path, gcode, out.program, gcode_state);
    } else {
      read_apt(in, path, options.apt, apt, apt_state);
    }
  }
  if (out.reader == ProgramReader::Apt) {
    out.program = std::move(apt.program);
    out.cutters = std::move(apt.cutters);
  }
  return out;
}

LoadedProgram read_program(const std::string& path, Dialect dialect, const ProgramOptions& options) {
  return read_programs({path}, dialect, options);
}

}  // namespace vcut::io
