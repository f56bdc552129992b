#include "vcut/io/program_header.h"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <fstream>
#include <regex>
#include <vector>

#include "program_header_words.h"
#include "reader_util.h"
#include "vcut/io/input_error.h"
#include "vcut/io/program_reader.h"

namespace vcut::io {
namespace {

using detail::kMmPerInch;

// A number's text: digits with an optional point, optional sign.
const char* const kNum = R"(([-+]?(?:[0-9]+\.?[0-9]*|\.[0-9]+)))";
// A unit after a value; none: the program's units.
const char* const kUnit = R"(\s*(MM|INCHES|INCH|IN|")?)";

// A length as written: the value and its unit's factor to mm (0: the program's units, known
// only at the end of the scan).
struct Length {
  double value = 0.0;
  double mm_per_unit = 0.0;
};

double unit_factor(const std::string& unit) {
  if (unit.empty()) return 0.0;
  return unit == "MM" ? 1.0 : kMmPerInch;
}

Length length_of(const std::smatch& m, std::size_t value, std::size_t unit) {
  return {std::stod(m[value].str()), unit_factor(m[unit].str())};
}

struct PendingStock {
  std::array<Length, 3> size;
  bool placed = false;
  std::array<Length, 3> min;
  std::optional<std::array<Length, 3>> max;  // Carbide Create: the size is max - min
  std::string form, where;
  int line = 0, column = 0;
};

struct PendingTool {
  int number = 0;
  Length diameter, corner, flute;
  double angle_deg = 0.0;  // included tip angle; 0: by type
  std::string words;       // the type, as written (upper case)
  std::string form, where, text;
};

std::string upper(std::string s) {
  for (char& ch : s) ch = static_cast<char>(std::toupper(static_cast<unsigned char>(ch)));
  return s;
}

class Scanner {
 public:
  explicit Scanner(const std::string& path)
      : path_(path),
        sinumerik_(detect_dialect(path) == Dialect::Sinumerik),
        apt_(detect_dialect(path) == Dialect::Apt) {}

  ProgramHeader run() {
    std::ifstream in(path_, std::ios::binary);
    if (!in) throw InputError(path_, 0, 0, "cannot open the program");
    std::string line;
    while (std::getline(in, line)) {
      ++line_;
      if (!line.empty() && line.back() == '\r') line.pop_back();
      scan_line(line);
    }
    return finish();
  }

 private:
  struct Comment {
    std::string text;  // upper case, without its delimiters
    int column = 0;    // 1-based, of its first character
  };

  // CL data: `$$` comments and INSERT/ PPRINT/ texts are comments; UNITS/ sets the units.
  void scan_apt_line(const std::string& line) {
    const std::size_t first = line.find_first_not_of(" \t");
    if (first == std::string::npos) return;
    const std::string u = upper(line.substr(first));
    if (!units_known_ && (u.rfind("UNITS/", 0) == 0 || u.rfind("UNIT/", 0) == 0)) {
      units_known_ = true;
      header_.inch = u.find("INCH") != std::string::npos;
    }
    for (const char* lead : {"$$", "INSERT/", "INSERT", "PPRINT/", "PPRINT"}) {
      if (u.rfind(lead, 0) == 0) {
        const std::size_t n = std::string(lead).size();
        scan_comment({u.substr(n), static_cast<int>(first + n + 1)}, 0);
        return;
      }
    }
  }

  void scan_line(const std::string& line) {
    if (apt_) {
      scan_apt_line(line);
      return;
    }
    std::string code;
    std::vector<Comment> comments;
    for (std::size_t i = 0; i < line.size(); ++i) {
      const char ch = line[i];
      if (ch == '(' && !sinumerik_) {
        const std::size_t close = line.find(')', i + 1);
        const std::size_t end = close == std::string::npos ? line.size() : close;
        comments.push_back({upper(line.substr(i + 1, end - i - 1)), static_cast<int>(i + 2)});
        i = end;
      } else if (ch == ';') {
        comments.push_back({upper(line.substr(i + 1)), static_cast<int>(i + 2)});
        break;
      } else {
        code += static_cast<char>(std::toupper(static_cast<unsigned char>(ch)));
      }
    }
    const int tool_here = scan_code(code);
    for (const Comment& c : comments) scan_comment(c, tool_here);
    if (tool_here > 0 && pending_cutviewer_) {
      pending_cutviewer_->number = tool_here;
      add_tool(std::move(*pending_cutviewer_));
      pending_cutviewer_.reset();
    }
  }

  // Units, rotary letters and the T word of a tool change (returned; 0: none) in the code.
  int scan_code(const std::string& code) {
    int tool = 0;
    bool change = false;
    if (sinumerik_) {
      // CYCLE800 with parameters turns the rotaries (CYCLE800() only deselects).
      for (std::size_t at = code.find("CYCLE800"); at != std::string::npos; at = code.find("CYCLE800", at + 8)) {
        std::size_t k = at + 8;
        while (k < code.size() && code[k] == ' ') ++k;
        if (k < code.size() && code[k] == '(') {
          ++k;
          while (k < code.size() && code[k] == ' ') ++k;
          if (k < code.size() && code[k] != ')') header_.swivels = true;
        }
      }
    }
    for (std::size_t i = 0; i < code.size(); ++i) {
      const char ch = code[i];
      if (ch < 'A' || ch > 'Z') continue;
      const char before = i > 0 ? code[i - 1] : ' ';
      if (std::isalpha(static_cast<unsigned char>(before)) || before == '_' || before == '<') continue;
      std::size_t j = i + 1;
      while (j < code.size() && code[j] == ' ') ++j;
      const char next = j < code.size() ? code[j] : '\0';
      const bool value = std::isdigit(static_cast<unsigned char>(next)) || next == '.' || next == '-' || next == '+' ||
                         next == '=' || next == '#' || next == '[';
      if (!value) continue;
      if ((ch == 'A' || ch == 'B' || ch == 'C') && next != '=') header_.rotary_letters.insert(ch);
      if ((ch == 'A' || ch == 'B' || ch == 'C') && next == '=' && sinumerik_) header_.rotary_letters.insert(ch);
      std::size_t k = j;
      while (k < code.size() && std::isdigit(static_cast<unsigned char>(code[k]))) ++k;
      const std::string digits = code.substr(j, k - j);
      if (digits.empty() || (k < code.size() && code[k] == '.')) continue;
      const long n = digits.size() > 6 ? -1 : std::stol(digits);
      if (ch == 'G' && !units_known_) {
        const bool inch = n == 20 || (sinumerik_ && n == 70), mm = n == 21 || (sinumerik_ && n == 71);
        if (inch || mm) {
          units_known_ = true;
          header_.inch = inch;
        }
      }
      if (ch == 'T' && n > 0 && n <= 99999) {
        tool = static_cast<int>(n);
        header_.tool_numbers.insert(tool);
        if (header_.first_tool == 0) header_.first_tool = tool;
      }
      if (ch == 'M' && n == 6) change = true;
      // D and H registers name tools too (cutter compensation's radius, Fanuc 0M's H).
      if ((ch == 'D' || ch == 'H') && n > 0 && n <= 99999 && next != '=')
        header_.tool_numbers.insert(static_cast<int>(n));
    }
    last_code_tool_change_ = change;
    return tool;
  }

  void scan_comment(const Comment& c, int tool_here) {
    const std::string& t = c.text;
    if (t.find_first_not_of(" \t") == std::string::npos) return;
    if (material_size_next_) {
      material_size_next_ = false;
      static const std::regex vectric(std::string(R"(^\s*X\s*=\s*)") + kNum + R"(\s*,\s*Y\s*=\s*)" + kNum +
                                      R"(\s*,?\s*Z\s*=\s*)" + kNum);
      std::smatch m;
      if (std::regex_search(t, m, vectric)) {
        PendingStock s;
        for (int k = 0; k < 3; ++k) s.size[k] = {std::stod(m[k + 1].str()), 0.0};
        declare_stock(std::move(s), "Vectric Material Size", c);
        return;
      }
    }
    if (t.find("MATERIAL SIZE") != std::string::npos) material_size_next_ = true;
    if (t.find("STOCK") != std::string::npos) stock_comment(c);
    if (t.find('T') != std::string::npos || tool_here > 0) tool_comment(c, tool_here);
  }

  void stock_comment(const Comment& c) {
    const std::string& t = c.text;
    std::smatch m;
    static const std::regex block(R"(^\s*STOCK/BLOCK\s*,(.*)$)");
    if (std::regex_search(t, m, block)) {
      const std::vector<double> v = numbers(m[1].str(), c, "STOCK/BLOCK, length, width, height, x, y, z origin");
      if (v.size() != 3 && v.size() != 6)
        fail(c, "STOCK/BLOCK with 3 or 6 values (length, width, height[, x, y, z origin])");
      PendingStock s;
      for (int k = 0; k < 3; ++k) s.size[k] = {v[k], 0.0};
      if (v.size() == 6) {
        s.placed = true;
        for (int k = 0; k < 3; ++k) s.min[k] = {0.0 - v[k + 3], 0.0};  // 0 - 0 is +0, not -0
      }
      declare_stock(std::move(s), "CutViewer STOCK/BLOCK", c);
      return;
    }
    static const std::regex corner(R"(^\s*STOCK(MIN|MAX)\s*:(.*)$)");
    if (std::regex_search(t, m, corner)) {
      std::array<Length, 3> p;
      static const std::regex value(std::string(kNum) + kUnit);
      const std::string rest = m[2].str();
      int k = 0;
      for (auto it = std::sregex_iterator(rest.begin(), rest.end(), value); it != std::sregex_iterator() && k < 3;
           ++it, ++k)
        p[k] = length_of(*it, 1, 2);
      if (k != 3) fail(c, std::string("stock") + (m[1] == "MIN" ? "Min" : "Max") + ": with x, y and z");
      if (m[1] == "MIN") {
        stock_min_ = p;
      } else if (stock_min_) {
        PendingStock s;
        s.placed = true;
        s.min = *stock_min_;
        s.max = p;
        declare_stock(std::move(s), "Carbide Create stockMin/stockMax", c);
      }
      return;
    }
    if (t.find("LEAVE") != std::string::npos) return;  // "XY STOCK TO LEAVE": an allowance
    static const std::regex deltas(std::string(R"(\bDX\s*[=:]?\s*)") + kNum + kUnit + R"(\s*,?\s*DY\s*[=:]?\s*)" +
                                   kNum + kUnit + R"(\s*,?\s*DZ\s*[=:]?\s*)" + kNum + kUnit);
    // SolidWorks CAM: INSERT/Stock Size X465.40922 Y243.942457 Z6.
    static const std::regex letters(std::string(R"(\bSTOCK\s+SIZE\s*:?\s*X\s*=?\s*)") + kNum + kUnit +
                                    R"(\s*,?\s*Y\s*=?\s*)" + kNum + kUnit + R"(\s*,?\s*Z\s*=?\s*)" + kNum + kUnit);
    if (std::regex_search(t, m, letters)) {
      PendingStock s;
      for (int k = 0; k < 3; ++k) s.size[k] = length_of(m, 1 + 2 * k, 2 + 2 * k);
      declare_stock(std::move(s), "comment", c);
      return;
    }
    static const std::regex times(std::string(R"(\bSTOCK\b(?:\s*SIZE)?\s*[:=]?\s*)") + kNum + kUnit + R"(\s*X\s*)" +
                                  kNum + kUnit + R"(\s*X\s*)" + kNum + kUnit);
    if (std::regex_search(t, m, deltas) || std::regex_search(t, m, times)) {
      PendingStock s;
      for (int k = 0; k < 3; ++k) s.size[k] = length_of(m, 1 + 2 * k, 2 + 2 * k);
      declare_stock(std::move(s), "comment", c);
    }
  }

  void tool_comment(const Comment& c, int tool_here) {
    const std::string& t = c.text;
    const std::size_t first = t.find_first_not_of(" \t");
    // Each form but the tool change's comment starts with T (most comments do not: a cheap
    // test before the expressions, a comment can be on every line).
    if (first == std::string::npos || t[first] != 'T') {
      same_line_tool(c, tool_here);
      return;
    }
    std::smatch m;
    static const std::regex fusion(std::string(R"(^\s*T([0-9]+)\s+D=)") + kNum + R"(\s+CR=)" + kNum +
                                   R"((?:\s+TAPER=([0-9.]+)\s*DEG)?(.*)$)");
    if (std::regex_search(t, m, fusion)) {
      PendingTool tool;
      tool.number = std::stoi(m[1].str());
      tool.diameter = {std::stod(m[2].str()), 0.0};
      tool.corner = {std::stod(m[3].str()), 0.0};
      const std::string rest = m[5].str();
      tool.words = rest.substr(rest.rfind(" - ") == std::string::npos ? 0 : rest.rfind(" - ") + 3);
      if (m[4].matched) {
        // Fusion's taper is the half angle of a chamfer mill, the point angle of a drill.
        const double taper = std::stod(m[4].str());
        const bool drill = tool.words.find("DRILL") != std::string::npos;
        tool.angle_deg = drill ? taper : 2.0 * taper;
      }
      tool.form = "Fusion";
      add_comment_tool(std::move(tool), c);
      return;
    }
    static const std::regex cutviewer(R"(^\s*TOOL/(MILL|DRILL)\s*,(.*)$)");
    if (std::regex_search(t, m, cutviewer)) {
      const bool drill = m[1] == "DRILL";
      const std::vector<double> v = numbers(m[2].str(), c, "TOOL/MILL, diameter, corner radius, height, taper");
      if (v.empty() || !(v[0] > 0.0))
        fail(c,
             drill ? "TOOL/DRILL, diameter, point angle, height" : "TOOL/MILL, diameter, corner radius, height, taper");
      PendingTool tool;
      tool.diameter = {v[0], 0.0};
      if (drill) {
        tool.words = "DRILL";
        if (v.size() > 1) tool.angle_deg = v[1];
        if (v.size() > 2) tool.flute = {v[2], 0.0};
      } else {
        if (v.size() > 1) tool.corner = {v[1], 0.0};
        if (v.size() > 2) tool.flute = {v[2], 0.0};
        // A taper (half angle, deg) makes a V-bit; the diameter is then its widest.
        if (v.size() > 3 && v[3] > 0.0) {
          tool.words = "V-BIT";
          tool.angle_deg = 2.0 * v[3];
        }
      }
      tool.form = "CutViewer";
      tool.where = path_ + ":" + std::to_string(line_);
      tool.text = c.text;
      pending_cutviewer_ = std::move(tool);
      return;
    }
    // The forms that name a T number and a diameter: the groups of each, in order of trust.
    struct NumberedForm {
      std::regex pattern;
      int diameter_group, words_group;  // the unit follows the diameter; words_group 0: none
      const char* form;
      bool needs_cutter_words;  // "(T1 - 3 FLUTES)" is no tool: the words must name one
    };
    static const NumberedForm kForms[] = {
        {std::regex(std::string(R"(^\s*T([0-9]+)\s*=\s*(.*)\{\s*)") + kNum + R"(\s*(MM|INCHES|INCH|IN)\s*\})"), 3, 2,
         "Vectric", false},
        // CamBam's tool list: "T1 : 3.175" (the diameter alone).
        {std::regex(std::string(R"(^\s*T([0-9]+)\s*:\s*)") + kNum + kUnit + R"(\s*$)"), 2, 0, "CamBam", false},
        {std::regex(std::string(R"(^\s*T([0-9]+)\s*[-=:|]\s*)") + kNum + kUnit + R"(\s+(.*)$)"), 2, 4, "comment", true},
    };
    for (const NumberedForm& f : kForms) {
      if (!std::regex_search(t, m, f.pattern)) continue;
      const std::string words = f.words_group > 0 ? m[static_cast<std::size_t>(f.words_group)].str() : std::string();
      if (f.needs_cutter_words && !names_cutter(words)) continue;
      PendingTool tool;
      tool.number = std::stoi(m[1].str());
      tool.diameter =
          length_of(m, static_cast<std::size_t>(f.diameter_group), static_cast<std::size_t>(f.diameter_group + 1));
      tool.words = words;
      tool.form = f.form;
      add_comment_tool(std::move(tool), c);
      return;
    }
    same_line_tool(c, tool_here);
  }

  // A comment on the tool change's line: its first length with a unit, or after DIA.
  void same_line_tool(const Comment& c, int tool_here) {
    const std::string& t = c.text;
    std::smatch m;
    if (tool_here > 0 && last_code_tool_change_) {
      static const std::regex sized(std::string(kNum) + R"(\s*(MM|IN|")(?![A-Z]))");
      static const std::regex dia(std::string(R"(\b(?:DIAMETER|DIA)\.?\s*[:=]?\s*)") + kNum + kUnit);
      if ((std::regex_search(t, m, sized) || std::regex_search(t, m, dia)) && std::stod(m[1].str()) > 0.0) {
        PendingTool tool;
        tool.number = tool_here;
        tool.diameter = length_of(m, 1, 2);
        tool.words = t;
        tool.form = "comment";
        add_comment_tool(std::move(tool), c);
      }
    }
  }

  static bool names_cutter(const std::string& words) {
    for (const char* w : {"MILL", "DRILL", "CUTTER", "BIT", "REAMER", "TAP", "CHAMFER", "ENGRAV", "ROUTER", "BALL"})
      if (words.find(w) != std::string::npos) return true;
    return false;
  }

  // The comma-separated numbers of a statement.
  std::vector<double> numbers(const std::string& list, const Comment& c, const char* form) const {
    std::vector<double> v;
    std::size_t i = 0;
    while (i <= list.size()) {
      const std::size_t comma = std::min(list.find(',', i), list.size());
      const std::string item = list.substr(i, comma - i);
      const std::size_t a = item.find_first_not_of(" \t");
      if (a != std::string::npos) {
        std::size_t used = 0;
        double value = 0.0;
        try {
          value = std::stod(item.substr(a), &used);
        } catch (const std::exception&) {
          used = 0;
        }
        if (used == 0 || item.find_first_not_of(" \t", a + used) != std::string::npos || !std::isfinite(value))
          fail(c, std::string(form) + " (numbers separated by commas)");
        v.push_back(value);
      }
      i = comma + 1;
    }
    return v;
  }

  [[noreturn]] void fail(const Comment& c, const std::string& expected) const {
    throw InputError(path_, line_, c.column, "expected " + expected);
  }

  // Checked at the end, when the program's units are known.
  void declare_stock(PendingStock s, const char* form, const Comment& c) {
    s.form = form;
    s.where = path_ + ":" + std::to_string(line_);
    s.line = line_;
    s.column = c.column;
    stocks_.push_back(std::move(s));
  }

  void add_comment_tool(PendingTool tool, const Comment& c) {
    tool.where = path_ + ":" + std::to_string(line_);
    tool.text = c.text;
    add_tool(std::move(tool));
  }
  void add_tool(PendingTool tool) {
    if (!(tool.diameter.value > 0.0)) return;
    tools_.emplace(tool.number, std::move(tool));  // the first declaration of a number wins
  }

  double mm(const Length& l) const {
    return l.value * (l.mm_per_unit > 0.0 ? l.mm_per_unit : (header_.inch ? kMmPerInch : 1.0));
  }

  ProgramHeader finish() {
    // Every declaration is checked; the first is the stock.
    for (const PendingStock& p : stocks_) {
      DeclaredStock s;
      for (int k = 0; k < 3; ++k) {
        s.min_mm[k] = mm(p.min[k]);
        s.size_mm[k] = p.max ? mm((*p.max)[k]) - s.min_mm[k] : mm(p.size[k]);
      }
      if (!((s.size_mm.array() > 0.0).all() && s.size_mm.allFinite()))
        throw InputError(path_, p.line, p.column, "expected a " + p.form + " stock size greater than 0 in x, y and z");
      s.placed = p.placed;
      s.form = p.form;
      s.where = p.where;
      if (!header_.stock) header_.stock = s;
    }
    for (const auto& [number, t] : tools_) {
      DeclaredTool d;
      const double diameter = mm(t.diameter);
      d.cutter = detail::cutter_of_words(t.words, diameter, std::min(mm(t.corner), 0.5 * diameter), t.angle_deg);
      d.flute_length_mm = mm(t.flute);
      d.form = t.form;
      d.where = t.where;
      d.text = t.text;
      header_.tools.emplace(number, d);
    }
    return header_;
  }

  const std::string path_;
  const bool sinumerik_, apt_;
  int line_ = 0;
  ProgramHeader header_;
  bool units_known_ = false;
  bool material_size_next_ = false;
  bool last_code_tool_change_ = false;
  std::vector<PendingStock> stocks_;
  std::optional<std::array<Length, 3>> stock_min_;
  std::optional<PendingTool> pending_cutviewer_;
  std::map<int, PendingTool> tools_;
};

}  // namespace

namespace detail {
removal::Cutter cutter_of_words(const std::string& words, double diameter_mm, double corner_mm, double angle_deg) {
  removal::Cutter c;
  c.diameter_mm = diameter_mm;
  auto has = [&](const char* w) { return words.find(w) != std::string::npos; };
  if (has("BALL")) {
    c.type = removal::CutterType::Ball;
    c.corner_radius_mm = 0.5 * diameter_mm;
  } else if (has("CHAMFER") || has("SPOT") || has("ENGRAV") || has("V-BIT") || has("VBIT") || has("V BIT") ||
             has("CENTER DRILL") || has("CENTRE DRILL") || has("DRILL")) {
    c.type = removal::CutterType::VBit;
    const bool twist = has("DRILL") && !has("SPOT") && !has("CENTER") && !has("CENTRE") && !has("CHAM");
    c.tip_angle_deg = angle_deg > 0.0 && angle_deg < 180.0 ? angle_deg : (twist ? 118.0 : 90.0);
  } else if (corner_mm > 0.0 && corner_mm < 0.5 * diameter_mm - 1e-9) {
    c.type = removal::CutterType::BullNose;
    c.corner_radius_mm = corner_mm;
  } else if (corner_mm > 0.0) {
    c.type = removal::CutterType::Ball;
    c.corner_radius_mm = 0.5 * diameter_mm;
  }
  return c;
}

}  // namespace detail

ProgramHeader read_program_header(const std::string& path) { return Scanner(path).run(); }

}  // namespace vcut::io
