// rs274ngc values: numbers, parameters (#5, ##5, #[2+3], #<name>), bracketed expressions and
// the unary functions, as LinuxCNC documents them (G-code overview: "Parameters",
// "Expressions", "Binary Operators", "Functions"). Internal to vcut::io.
//
// Facts the evaluation follows (LinuxCNC manual):
// - precedence, highest first: **; * / MOD; + -; EQ NE GT GE LT LE; AND OR XOR; operators of
//   equal precedence apply left to right;
// - angles of COS SIN TAN and of the results of ACOS ASIN ATAN are in degrees; ATAN takes
//   [y]/[x] and returns the angle of (x, y) in (-180, 180];
// - FIX rounds down, FUP rounds up, ROUND to the nearest (halves away from zero);
// - logical results are 1.0 or 0.0; any non-zero value is true;
// - EQ and NE compare with a tolerance of 1e-4 (LinuxCNC's TOLERANCE_EQUAL);
// - a parameter number must be whole (to 1e-4) and in 1..5601.
#pragma once

#include <cstddef>
#include <string>

namespace vcut::io::detail {

// What the value reader needs from the interpreter: parameter values and a way to fail.
class ValueContext {
 public:
  virtual ~ValueContext() = default;
  virtual double numbered_parameter(int number, int column) = 0;
  // `name` is canonical (lower case, blanks removed); fails when the name is not defined.
  virtual double named_parameter(const std::string& name, int column) = 0;
  virtual bool named_parameter_exists(const std::string& name) = 0;
  [[noreturn]] virtual void fail(int column, const std::string& message) const = 0;
  // Fanuc custom macro B instead of rs274ngc: variables #0..#99999 (numbered_parameter may
  // return kVacant, the empty value #0); * / AND MOD bind alike, as do + - OR XOR; AND OR XOR
  // work bit by bit on whole numbers; POW[a,b], ATAN[y,x], BIN, BCD; a vacant value counts as
  // 0 in arithmetic and in GT GE LT LE, and EQ / NE tell it from 0.
  virtual bool fanuc_macros() const { return false; }
};

// Fanuc's vacant variable (#0, and locals and commons never set): a quiet NaN.
inline const double kVacant = __builtin_nan("");
inline bool is_vacant(double v) { return v != v; }

// A plain number: [+|-] digits [. [digits]] | [+|-] . digits, blanks allowed anywhere in it
// (LinuxCNC removes them before parsing), no exponent. `letter` names the word in messages
// (0 inside an expression). `text` gets the number as written (for messages and codes).
// `column`: where errors point (0: at the number).
double read_plain_number(const std::string& s, std::size_t& i, char letter, const ValueContext& context,
                         std::string& text, int column = 0);

// Whether the letters at s[i] name a unary function (ABS ... TAN, EXISTS).
bool function_at(const std::string& s, std::size_t i);

// One real value starting at s[i] (blanks skipped): a plain number, a parameter, a bracketed
// expression, a unary function, each with an optional leading sign. Advances i past it.
// `letter` as above. Results are finite or the context fails.
double read_real_value(const std::string& s, std::size_t& i, char letter, ValueContext& context);

// A bracketed expression starting at the '[' at s[i]. (Fanuc: may be vacant.)
double read_expression(const std::string& s, std::size_t& i, ValueContext& context);

// Fanuc: an expression without brackets around it, the right-hand side of "#1 = #2 + 3": it
// ends where no operator follows a value. May be vacant (#1 = #0).
double read_open_expression(const std::string& s, std::size_t& i, ValueContext& context);

// After a '#' at s[i - 1]: the parameter reference, as a number (1..5601) or a canonical name.
struct ParameterRef {
  int number = 0;    // 0 when named
  std::string name;  // canonical, when named
};
ParameterRef read_parameter_ref(const std::string& s, std::size_t& i, ValueContext& context);

// Canonical parameter or o-word name: lower case, blanks removed; fails on characters
// outside letters, digits and _ . - (LinuxCNC allows more, nobody writes them).
std::string canonical_name(const std::string& raw, int column, const ValueContext& context);

}  // namespace vcut::io::detail
