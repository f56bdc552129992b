#include "rs274_expression.h"

#include "reader_util.h"

#include <charconv>
#include <climits>
#include <cmath>
#include <cstdio>
#include <system_error>

namespace vcut::io::detail {
namespace {

constexpr double kDegPerRad = 180.0 / M_PI;
constexpr double kEqualTolerance = 1e-4;  // LinuxCNC's TOLERANCE_EQUAL for EQ and NE
constexpr double kWholeTolerance = 1e-4;  // a parameter number this close to whole is whole
constexpr int kMaxParameter = 5601;       // LinuxCNC 2.9 has #1..#5601
constexpr int kMaxNesting = 64;           // brackets and functions within one value

bool is_blank(char c) { return c == ' ' || c == '\t'; }

std::size_t skip_blanks(const std::string& s, std::size_t i) {
  while (i < s.size() && is_blank(s[i])) ++i;
  return i;
}

std::string found(const std::string& s, std::size_t i) { return i >= s.size() ? "end of line" : describe(s[i]); }

// Letters starting at s[i] (blanks between them skipped, as LinuxCNC strips blanks), upper case.
std::string read_letters(const std::string& s, std::size_t& i) {
  std::string word;
  std::size_t j = skip_blanks(s, i);
  while (j < s.size() && is_letter(s[j]) && word.size() < 8) {
    word += upper(s[j]);
    i = ++j;
    j = skip_blanks(s, j);
  }
  return word;
}

enum class Op { Power, Times, Divide, Mod, Plus, Minus, Eq, Ne, Gt, Ge, Lt, Le, And, Or, Xor, None };

int precedence(Op op, bool fanuc = false) {
  if (fanuc && op == Op::And) return 5;                    // Fanuc: with * and /
  if (fanuc && (op == Op::Or || op == Op::Xor)) return 4;  // with + and -
  switch (op) {
    case Op::Power:
      return 6;
    case Op::Times:
    case Op::Divide:
    case Op::Mod:
      return 5;
    case Op::Plus:
    case Op::Minus:
      return 4;
    case Op::Eq:
    case Op::Ne:
    case Op::Gt:
    case Op::Ge:
    case Op::Lt:
    case Op::Le:
      return 3;
    case Op::And:
    case Op::Or:
    case Op::Xor:
      return 2;
    case Op::None:
      return 0;
  }
  return 0;
}

// The operator at s[i] (blanks skipped) without consuming it; `length` its extent.
Op peek_operator(const std::string& s, std::size_t i, std::size_t& next) {
  i = skip_blanks(s, i);
  if (i >= s.size()) return Op::None;
  const char c = s[i];
  if (c == '*') {
    const std::size_t j = skip_blanks(s, i + 1);
    if (j < s.size() && s[j] == '*') {
      next = j + 1;
      return Op::Power;
    }
    next = i + 1;
    return Op::Times;
  }
  if (c == '/') {
    next = i + 1;
    return Op::Divide;
  }
  if (c == '+') {
    next = i + 1;
    return Op::Plus;
  }
  if (c == '-') {
    next = i + 1;
    return Op::Minus;
  }
  if (!is_letter(c)) return Op::None;
  std::size_t j = i;
  const std::string word = read_letters(s, j);
  static const struct {
    const char* name;
    Op op;
  } kWords[] = {{"MOD", Op::Mod}, {"EQ", Op::Eq}, {"NE", Op::Ne},   {"GT", Op::Gt}, {"GE", Op::Ge},
                {"LT", Op::Lt},   {"LE", Op::Le}, {"AND", Op::And}, {"OR", Op::Or}, {"XOR", Op::Xor}};
  for (const auto& w : kWords) {
    if (word == w.name) {
      next = j;
      return w.op;
    }
  }
  return Op::None;
}

const char* op_name(Op op) {
  switch (op) {
    case Op::Power:
      return "**";
    case Op::Times:
      return "*";
    case Op::Divide:
      return "/";
    case Op::Mod:
      return "MOD";
    case Op::Plus:
      return "+";
    case Op::Minus:
      return "-";
    case Op::Eq:
      return "EQ";
    case Op::Ne:
      return "NE";
    case Op::Gt:
      return "GT";
    case Op::Ge:
      return "GE";
    case Op::Lt:
      return "LT";
    case Op::Le:
      return "LE";
    case Op::And:
      return "AND";
    case Op::Or:
      return "OR";
    case Op::Xor:
      return "XOR";
    case Op::None:
      return "?";
  }
  return "?";
}

const char* const kFunctions[] = {"ABS",   "ACOS", "ASIN", "ATAN", "COS", "EXISTS", "EXP", "FIX", "FUP",
                                  "ROUND", "LN",   "SIN",  "SQRT", "TAN", "POW",    "BIN", "BCD"};
bool is_function(const std::string& name) {
  for (const char* f : kFunctions) {
    if (name == f) return true;
  }
  return false;
}

class Parser {
 public:
  Parser(const std::string& s, ValueContext& context) : s_(s), context_(context), fanuc_(context.fanuc_macros()) {}

  // Fanuc: a whole expression without brackets around it.
  double open(std::size_t& i) { return binary(i, 1); }

  double value(std::size_t& i, char letter) {
    if (++depth_ > kMaxNesting) {
      context_.fail(column_at(i),
                    "a value nested more than " + std::to_string(kMaxNesting) + " brackets or functions deep");
    }
    const double v = value_unguarded(i, letter);
    --depth_;
    return v;
  }

  double bracketed(std::size_t& i) {
    const std::size_t open = i;  // at '['
    ++i;
    const double v = binary(i, 1);
    i = skip_blanks(s_, i);
    if (i >= s_.size() || s_[i] != ']') {
      const std::string what = i >= s_.size() ? "end of line" : found(s_, i);
      context_.fail(column_at(i >= s_.size() ? open : i),
                    "expected ']' or an operator in the expression, found " + what);
    }
    ++i;
    return v;
  }

  ParameterRef parameter(std::size_t& i) {
    i = skip_blanks(s_, i);
    if (i < s_.size() && s_[i] == '<') {
      const std::size_t open = i;
      const std::size_t close = s_.find('>', i + 1);
      if (close == std::string::npos) {
        context_.fail(column_at(open), "named parameter without '>' (expected #<name>)");
      }
      ParameterRef ref;
      ref.name = canonical_name(s_.substr(open + 1, close - open - 1), column_at(open), context_);
      i = close + 1;
      return ref;
    }
    const std::size_t at = i;
    const double v = value(i, 0);
    if (is_vacant(v)) context_.fail(column_at(at), "a vacant variable as a variable number (expected a value)");
    const double whole = std::round(v);
    if (std::abs(v - whole) > kWholeTolerance) {
      context_.fail(column_at(at), "parameter number " + num(v) + " (expected a whole number)");
    }
    if (fanuc_ && (whole < 0.0 || whole > 199999.0)) {
      context_.fail(column_at(at), "variable number " + num(whole) + " (expected #0..#199999)");
    }
    if (!fanuc_ && (whole < 1.0 || whole > kMaxParameter)) {
      context_.fail(column_at(at), "parameter number " + num(whole) + " (expected 1..5601)");
    }
    return ParameterRef{static_cast<int>(whole), {}};
  }

 private:
  double value_unguarded(std::size_t& i, char letter) {
    i = skip_blanks(s_, i);
    if (i >= s_.size()) {
      context_.fail(column_at(i), letter ? std::string("expected a value after '") + letter + "', found end of line"
                                         : std::string("expected a value, found end of line"));
    }
    const char c = s_[i];
    const std::size_t after_sign = skip_blanks(s_, i + 1);
    if ((c == '-' || c == '+') && after_sign < s_.size() &&
        (s_[after_sign] == '#' || s_[after_sign] == '[' || is_letter(s_[after_sign]))) {
      i = after_sign;
      const double v = value(i, letter);
      return c == '-' ? -v : v;
    }
    if (c == '[') return bracketed(i);
    if (c == '#') {
      const int column = column_at(i);
      ++i;
      const ParameterRef ref = parameter(i);
      return ref.name.empty() ? context_.numbered_parameter(ref.number, column)
                              : context_.named_parameter(ref.name, column);
    }
    if (is_letter(c)) return function(i);
    std::string text;
    return read_plain_number(s_, i, letter, context_, text);
  }

  double function(std::size_t& i) {
    const std::size_t start = i;
    const int column = column_at(i);
    const std::string name = read_letters(s_, i);
    auto argument = [&]() {
      i = skip_blanks(s_, i);
      if (i >= s_.size() || s_[i] != '[') {
        context_.fail(column_at(i),
                      name + " without its argument (expected " + name + "[...], found " + found(s_, i) + ")");
      }
      return bracketed(i);
    };
    auto check = [&](double v) {
      if (!std::isfinite(v)) context_.fail(column, name + " gives a value that is not a finite number");
      return v;
    };
    if (fanuc_ && (name == "ATAN" || name == "POW")) {
      // Fanuc: ATAN[y,x] (and ATAN[y]/[x]), POW[a,b].
      i = skip_blanks(s_, i);
      if (i >= s_.size() || s_[i] != '[') {
        context_.fail(column_at(i),
                      name + " without its arguments (expected " + name + "[a,b], found " + found(s_, i) + ")");
      }
      const std::size_t open = i++;
      const double a = zero_if_vacant(binary(i, 1));
      i = skip_blanks(s_, i);
      if (i < s_.size() && s_[i] == ',') {
        ++i;
        const double b = zero_if_vacant(binary(i, 1));
        i = skip_blanks(s_, i);
        if (i >= s_.size() || s_[i] != ']')
          context_.fail(column_at(i >= s_.size() ? open : i), "expected ']' after the second argument of " + name);
        ++i;
        if (name == "POW") return apply(Op::Power, a, b, column);
        return std::atan2(a, b) * kDegPerRad;
      }
      if (i >= s_.size() || s_[i] != ']')
        context_.fail(column_at(i >= s_.size() ? open : i), "expected ',' or ']' in " + name + "[...]");
      ++i;
      if (name == "POW") context_.fail(column, "POW takes two arguments (expected POW[a,b])");
      i = skip_blanks(s_, i);
      if (i >= s_.size() || s_[i] != '/') {
        context_.fail(column_at(i),
                      "ATAN takes two arguments (expected ATAN[y,x] or ATAN[y]/[x], found " + found(s_, i) + ")");
      }
      ++i;
      return std::atan2(a, zero_if_vacant(argument())) * kDegPerRad;
    }
    if (name == "ATAN") {
      const double y = argument();
      i = skip_blanks(s_, i);
      if (i >= s_.size() || s_[i] != '/') {
        context_.fail(column_at(i), "ATAN takes two arguments (expected ATAN[y]/[x], found " + found(s_, i) + ")");
      }
      ++i;
      const double x = argument();
      return std::atan2(y, x) * kDegPerRad;
    }
    if (name == "EXISTS") {
      i = skip_blanks(s_, i);
      if (i >= s_.size() || s_[i] != '[')
        context_.fail(column_at(i), "EXISTS without its argument (expected EXISTS[#<name>])");
      const std::size_t j = skip_blanks(s_, i + 1);
      if (j >= s_.size() || s_[j] != '#')
        context_.fail(column_at(j), "EXISTS takes a parameter (expected EXISTS[#<name>])");
      std::size_t k = j + 1;
      const ParameterRef ref = parameter(k);
      k = skip_blanks(s_, k);
      if (k >= s_.size() || s_[k] != ']') context_.fail(column_at(k), "expected ']' after the parameter of EXISTS");
      i = k + 1;
      return ref.name.empty() ? 1.0 : (context_.named_parameter_exists(ref.name) ? 1.0 : 0.0);
    }
    if (!is_function(name) || (!fanuc_ && (name == "POW" || name == "BIN" || name == "BCD"))) {
      context_.fail(column, (name.empty() ? "unexpected " + found(s_, start) : "unknown function '" + name + "'") +
                                " (expected a number, #parameter, [expression] or one of ABS ACOS ASIN ATAN "
                                "COS EXISTS EXP FIX FUP LN ROUND SIN SQRT TAN)");
    }
    const double x = zero_if_vacant(argument());
    if (name == "BIN" || name == "BCD") {
      // Fanuc: BCD code to binary, binary to BCD, on whole numbers >= 0.
      if (x < 0.0 || x != std::floor(x) || x > 99999999.0)
        context_.fail(column, name + "[" + num(x) + "] (expected a whole number 0..99999999)");
      long long in = static_cast<long long>(x), out = 0, scale = 1;
      for (; in > 0; scale *= name == "BIN" ? 10 : 16) {
        const long long digit = name == "BIN" ? in % 16 : in % 10;
        if (name == "BIN" && digit > 9)
          context_.fail(column, "BIN[" + num(x) + "] is not a BCD code (a nibble above 9)");
        out += digit * scale;
        in /= name == "BIN" ? 16 : 10;
      }
      return static_cast<double>(out);
    }
    if (name == "ABS") return std::abs(x);
    if (name == "ACOS" || name == "ASIN") {
      if (x < -1.0 || x > 1.0) context_.fail(column, name + "[" + num(x) + "] (expected an argument in -1..1)");
      return (name == "ACOS" ? std::acos(x) : std::asin(x)) * kDegPerRad;
    }
    if (name == "COS") return std::cos(x / kDegPerRad);
    if (name == "SIN") return std::sin(x / kDegPerRad);
    if (name == "TAN") return check(std::tan(x / kDegPerRad));
    if (name == "EXP") return check(std::exp(x));
    // Fanuc's FIX and FUP work on the magnitude (FIX[-1.2] = -1, FUP[-1.2] = -2); LinuxCNC's
    // round down and up.
    if (name == "FIX") return fanuc_ ? std::trunc(x) : std::floor(x);
    if (name == "FUP") return fanuc_ ? (x < 0.0 ? -std::ceil(-x) : std::ceil(x)) : std::ceil(x);
    if (name == "ROUND") return std::round(x);  // halves away from zero, as Fanuc's ROUND
    if (name == "LN") {
      if (x <= 0.0) context_.fail(column, "LN[" + num(x) + "] (expected an argument > 0)");
      return std::log(x);
    }
    // SQRT
    if (x < 0.0) context_.fail(column, "SQRT[" + num(x) + "] (expected an argument >= 0)");
    return std::sqrt(x);
  }

  double zero_if_vacant(double v) const { return is_vacant(v) ? 0.0 : v; }

  double apply(Op op, double a, double b, int column) {
    if (fanuc_ && (op == Op::Eq || op == Op::Ne) && (is_vacant(a) || is_vacant(b))) {
      // Fanuc: vacant EQ #0 is true, vacant EQ 0 is not.
      const bool equal = is_vacant(a) && is_vacant(b);
      return (op == Op::Eq) == equal ? 1.0 : 0.0;
    }
    a = zero_if_vacant(a);
    b = zero_if_vacant(b);
    if (fanuc_ && (op == Op::And || op == Op::Or || op == Op::Xor)) {
      // Fanuc: bit by bit on whole numbers (on 0 and 1, the logical operation).
      if (a != std::floor(a) || b != std::floor(b) || std::abs(a) > 2147483647.0 || std::abs(b) > 2147483647.0) {
        context_.fail(column, num(a) + " " + op_name(op) + " " + num(b) + " (expected whole numbers: Fanuc's " +
                                  op_name(op) + " works bit by bit)");
      }
      const long long x = static_cast<long long>(a), y = static_cast<long long>(b);
      return static_cast<double>(op == Op::And ? (x & y) : op == Op::Or ? (x | y) : (x ^ y));
    }
    double r = 0.0;
    switch (op) {
      case Op::Power:
        if (a < 0.0 && b != std::floor(b)) {
          context_.fail(column, num(a) + " ** " + num(b) + ": a negative number to a non-whole power");
        }
        r = std::pow(a, b);
        break;
      case Op::Times:
        r = a * b;
        break;
      case Op::Divide:
        if (b == 0.0) context_.fail(column, "division by zero (" + num(a) + " / 0)");
        r = a / b;
        break;
      case Op::Mod:
        if (b == 0.0) context_.fail(column, "division by zero (" + num(a) + " MOD 0)");
        r = std::fmod(a, b);
        if (r < 0.0) r += std::abs(b);  // LinuxCNC: the result is never negative
        break;
      case Op::Plus:
        r = a + b;
        break;
      case Op::Minus:
        r = a - b;
        break;
      case Op::Eq:
        r = std::abs(a - b) < kEqualTolerance;
        break;
      case Op::Ne:
        r = !(std::abs(a - b) < kEqualTolerance);
        break;
      case Op::Gt:
        r = a > b;
        break;
      case Op::Ge:
        r = a >= b;
        break;
      case Op::Lt:
        r = a < b;
        break;
      case Op::Le:
        r = a <= b;
        break;
      case Op::And:
        r = a != 0.0 && b != 0.0;
        break;
      case Op::Or:
        r = a != 0.0 || b != 0.0;
        break;
      case Op::Xor:
        r = (a != 0.0) != (b != 0.0);
        break;
      case Op::None:
        break;
    }
    if (!std::isfinite(r)) {
      context_.fail(column, num(a) + " " + op_name(op) + " " + num(b) + " is not a finite number");
    }
    return r;
  }

  // Precedence climbing: operators of equal precedence associate to the left.
  double binary(std::size_t& i, int min_precedence) {
    double left = value(i, 0);
    while (true) {
      std::size_t next = i;
      const Op op = peek_operator(s_, i, next);
      if (op == Op::None || precedence(op, fanuc_) < min_precedence) return left;
      const int column = column_at(skip_blanks(s_, i));
      i = next;
      const double right = binary(i, precedence(op, fanuc_) + 1);
      left = apply(op, left, right, column);
    }
  }

  const std::string& s_;
  ValueContext& context_;
  bool fanuc_ = false;
  int depth_ = 0;
};

}  // namespace

double read_plain_number(const std::string& s, std::size_t& i, char letter, const ValueContext& context,
                         std::string& text, int at_column) {
  const std::size_t n = s.size();
  const int column = at_column > 0 ? at_column : column_at(i);
  std::size_t j = skip_blanks(s, i);
  bool negative = false;
  if (j < n && (s[j] == '+' || s[j] == '-')) {
    negative = s[j] == '-';
    j = skip_blanks(s, j + 1);
  }
  // The number's characters: digits and one point, blanks allowed among them (rs274 reads
  // "X1 0.5" as X10.5); most numbers have none, and are read where they stand.
  bool point = false, any_digit = false, integer_part_nonzero = false, inner_blank = false;
  const std::size_t start = j;
  std::size_t last = j;  // one past the last digit or point
  for (; j < n; ++j) {
    const char c = s[j];
    if (is_digit(c)) {
      any_digit = true;
      if (!point && c != '0') integer_part_nonzero = true;
    } else if (c == '.' && !point) {
      point = true;
    } else if (is_blank(c)) {
      continue;
    } else {
      break;
    }
    inner_blank = inner_blank || last != j;  // a blank between this character and the last one
    last = j + 1;
  }
  inner_blank = inner_blank && any_digit;
  std::string digits;  // only for a number with blanks inside
  if (inner_blank) {
    for (std::size_t k = start; k < last; ++k)
      if (!is_blank(s[k])) digits += s[k];
  }
  const char* first = inner_blank ? digits.data() : s.data() + start;
  const char* end_of_number = inner_blank ? digits.data() + digits.size() : s.data() + last;
  auto after = [&] { return letter ? std::string("after '") + letter + "'" : std::string("in the expression"); };
  if (!any_digit) context.fail(column, "expected a number " + after() + ", found " + found(s, j));
  // rs274 numbers have no exponent: in "m66e0l0" the letter after the digits starts the next word.
  i = j;
  const std::size_t length = static_cast<std::size_t>(end_of_number - first);
  text.assign(negative ? "-" : "");
  text.append(first, std::min<std::size_t>(length, 24));
  if (length > 24) text += "...";
  double value = 0.0;
  const auto [end, ec] = std::from_chars(first, end_of_number, value, std::chars_format::fixed);
  if (ec == std::errc::result_out_of_range) {
    if (integer_part_nonzero) context.fail(column, "number " + text + " " + after() + " is out of range");
    value = 0.0;  // underflow: smaller than any length or speed that matters
  } else if (ec != std::errc() || end != end_of_number) {
    context.fail(column, "malformed number " + text + " " + after());
  }
  return negative ? -value : value;
}

bool function_at(const std::string& s, std::size_t i) { return is_function(read_letters(s, i)); }

double read_real_value(const std::string& s, std::size_t& i, char letter, ValueContext& context) {
  Parser parser(s, context);
  return parser.value(i, letter);
}

double read_expression(const std::string& s, std::size_t& i, ValueContext& context) {
  Parser parser(s, context);
  return parser.bracketed(i);
}

double read_open_expression(const std::string& s, std::size_t& i, ValueContext& context) {
  Parser parser(s, context);
  return parser.open(i);
}

ParameterRef read_parameter_ref(const std::string& s, std::size_t& i, ValueContext& context) {
  Parser parser(s, context);
  return parser.parameter(i);
}

std::string canonical_name(const std::string& raw, int column, const ValueContext& context) {
  std::string name;
  for (char c : raw) {
    if (is_blank(c)) continue;
    const bool ok = is_letter(c) || is_digit(c) || c == '_' || c == '.' || c == '-';
    if (!ok) {
      context.fail(column, "character " + describe(c) + " in a name (expected letters, digits, _ . -)");
    }
    name += (c >= 'A' && c <= 'Z') ? static_cast<char>(c - 'A' + 'a') : c;
  }
  if (name.empty()) context.fail(column, "empty name in <> (expected a name)");
  return name;
}

}  // namespace vcut::io::detail
