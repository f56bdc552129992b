// Small pieces the program readers (G-code, rs274 expressions, APT, SINUMERIK) share: byte
// classes, numbers and bytes for messages, columns, opening a program file and the warning
// for axes a file never programmed. Internal to vcut::io.
#pragma once

#include <vcut/io/input_error.h>
#include <vcut/kinematics/program.h>

#include <array>
#include <cerrno>
#include <fmt/format.h>

#include <climits>
#include <cmath>
#include <algorithm>
#include <cstddef>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <ios>
#include <new>
#include <stdexcept>
#include <string>
#include <system_error>
#include <utility>
#include <vector>

namespace vcut::io::detail {

// A turn of the rotaries from `from` to `to` in steps of at most 1 deg (the largest axis
// turn decides), and the rotary values after step n of them.
inline double rotary_turn_deg(const kinematics::RotaryWords& from, const kinematics::RotaryWords& to) {
  double turn_deg = 0.0;
  for (size_t a = 0; a < 3; ++a)
    turn_deg = std::max(turn_deg, std::abs(to.angle_rad[a] - from.angle_rad[a]) * 180.0 / M_PI);
  return turn_deg;
}
inline int rotary_steps(const kinematics::RotaryWords& from, const kinematics::RotaryWords& to) {
  return std::max(1, static_cast<int>(std::ceil(rotary_turn_deg(from, to) - 1e-9)));
}
// Each step is a block (about 400 bytes held): a turn of more steps than this in one move
// (1,000 revolutions) is refused, as a mistyped C901011 made 900,000 blocks and 390 MB from
// one line. The reason, or empty where the turn is within it.
constexpr int kMaxRotarySteps = 360000;
inline std::string rotary_turn_refused(const kinematics::RotaryWords& from, const kinematics::RotaryWords& to) {
  if (rotary_steps(from, to) <= kMaxRotarySteps) return {};
  return "the rotaries turn by " + std::to_string(static_cast<long long>(std::llround(rotary_turn_deg(from, to)))) +
         " deg in one move, which goes out as steps of 1 deg (expected at most " + std::to_string(kMaxRotarySteps) +
         " deg, 1000 turns, in one move: split it)";
}
inline kinematics::RotaryWords rotary_step(const kinematics::RotaryWords& from, const kinematics::RotaryWords& to,
                                           int n, int steps) {
  kinematics::RotaryWords step = to;
  for (size_t a = 0; a < 3; ++a)
    step.angle_rad[a] = from.angle_rad[a] + (to.angle_rad[a] - from.angle_rad[a]) * n / steps;
  return step;
}

// The rigid motion of a point the linear axes hold while the rotaries turn from zero to
// `rotary` (GcodeOptions::tip_after_turn gives where it goes): it lands at r p + t. Identity
// without a machine or with the rotaries at zero.
template <class TipAfterTurn>
std::pair<Eigen::Matrix3d, Eigen::Vector3d> turn_from_zero(const TipAfterTurn& tip_after_turn, int tool,
                                                           const kinematics::RotaryWords& rotary) {
  const auto& angles = rotary.angle_rad;
  if (!tip_after_turn || (angles[0] == 0.0 && angles[1] == 0.0 && angles[2] == 0.0))
    return {Eigen::Matrix3d::Identity(), Eigen::Vector3d::Zero()};
  kinematics::RotaryWords zero = rotary;
  zero.angle_rad = {0.0, 0.0, 0.0};
  auto image = [&](const Eigen::Vector3d& p) { return tip_after_turn(tool, p, zero, rotary); };
  const Eigen::Vector3d t = image(Eigen::Vector3d::Zero());
  Eigen::Matrix3d r;
  for (int a = 0; a < 3; ++a) r.col(a) = image(Eigen::Vector3d::Unit(a)) - t;
  return {r, t};
}

// Runs a reader, turning what the standard library throws on a file too big to hold or
// unreadable into an InputError naming the file.
template <class Read>
void read_guarded(const std::string& name, Read&& read) {
  try {
    read();
  } catch (const std::bad_alloc&) {
    throw InputError(name, 0, 0, "out of memory (too many moves)");
  } catch (const std::length_error&) {
    throw InputError(name, 0, 0, "out of memory (too many moves)");
  } catch (const std::ios_base::failure&) {
    throw InputError(name, 0, 0, "read error (expected a readable text file)");
  }
}

constexpr double kMmPerInch = 25.4;  // exact, by the 1959 definition of the inch

inline bool is_digit(char c) { return c >= '0' && c <= '9'; }
inline bool is_letter(char c) { return (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z'); }
inline char upper(char c) { return (c >= 'a' && c <= 'z') ? static_cast<char>(c - 'a' + 'A') : c; }

// A number for a message: up to 10 significant digits.
inline std::string num(double v) { return fmt::format("{:.10g}", v); }

// A byte for a message: 'x' when printable, else its hex code.
inline std::string describe(char c) {
  const auto u = static_cast<unsigned char>(c);
  return u > 32 && u < 127 ? fmt::format("'{}'", c) : fmt::format("byte 0x{:02X}", static_cast<unsigned>(u));
}

// An index as a 1-based column (saturated at INT_MAX).
inline int column_at(std::size_t i) {
  return i >= static_cast<std::size_t>(INT_MAX) ? INT_MAX : static_cast<int>(i) + 1;
}

// Opens a program file, or throws naming it: `a` and `the` name the kind of file in messages
// ("a G-code file", "the G-code file").
inline std::ifstream open_program_file(const std::string& path, const std::string& a, const std::string& the) {
  std::error_code ec;
  if (std::filesystem::is_directory(path, ec)) throw InputError(path, 0, 0, "is a directory (expected " + a + ")");
  std::ifstream in(path, std::ios::binary);
  if (!in) throw InputError(path, 0, 0, "cannot open " + the + ": " + std::strerror(errno));
  return in;
}

// One warning per axis X Y Z that the file `name` never programmed while moves ran.
inline void warn_unprogrammed_axes(const std::array<std::vector<std::size_t>, 3>& pending, const std::string& name,
                                   kinematics::Program& program) {
  static constexpr char kLetter[3] = {'X', 'Y', 'Z'};
  for (std::size_t a = 0; a < 3; ++a) {
    if (pending[a].empty()) continue;
    program.warnings.push_back(name + ": " + kLetter[a] + " has not been programmed by the end of this file; " +
                               std::to_string(pending[a].size()) + " move(s) hold it at 0 unless a later file sets it");
  }
}

}  // namespace vcut::io::detail
