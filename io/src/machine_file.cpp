#include "vcut/io/machine_file.h"

#include <algorithm>
#include <filesystem>
#include <set>
#include <string_view>
#include <system_error>

#include "yaml_util.h"

namespace vcut::io {
namespace fs = std::filesystem;
using kinematics::AxisKind;
using kinematics::AxisSpec;
using kinematics::ErrorTable;
using kinematics::MachineSpec;

namespace {

constexpr double kRadPerDeg = 3.14159265358979323846 / 180.0;
constexpr double kMmPerUm = 1e-3;
constexpr double kRadPerUrad = 1e-6;
constexpr double kMinPerS = 1.0 / 60.0;
// Translations along, then rotations about the frame's x y z.
constexpr std::string_view kAxisLetters = "XYZABC";

std::string join(const std::string& where, const std::string& key) { return where.empty() ? key : where + "." + key; }

// A key that is a list, a map or null ("? [a, b]: 1", "~: 1") is never one of ours (and
// yaml-cpp cannot give its text).
void scalar_keys(const YamlReader& yaml, const YAML::Node& map, const std::string& where) {
  for (const auto& kv : map)
    if (!kv.first.IsScalar())
      yaml.fail(kv.first, where.empty() ? "machine" : where, "a plain key (not a list, map or null)");
}

// yaml-cpp keeps both entries of a repeated key and answers map[key] with the first one, so
// a repeated key would silently lose a value.
void unique_keys(const YamlReader& yaml, const YAML::Node& map, const std::string& where) {
  scalar_keys(yaml, map, where);
  std::set<std::string> seen;
  for (const auto& kv : map)
    if (!seen.insert(kv.first.Scalar()).second)
      yaml.fail(kv.first, join(where, kv.first.Scalar()), "each key once (duplicate key)");
}

void check_keys(const YamlReader& yaml, const YAML::Node& map, const std::string& where,
                std::initializer_list<const char*> allowed) {
  if (map.IsMap()) scalar_keys(yaml, map, where);
  yaml.only_keys(map, where, allowed);
  unique_keys(yaml, map, where);
}

AxisSpec read_axis(const YamlReader& yaml, const YAML::Node& key, const YAML::Node& a) {
  const std::string letter = yaml.text(key, "axes");
  const std::string where = "axes." + letter;
  if (letter.size() != 1 || kAxisLetters.find(letter[0]) == std::string::npos)
    yaml.fail(key, where, "an axis letter X, Y, Z, A, B or C");
  if (!a.IsMap()) yaml.fail(a, where, "a map like {kind: linear, direction: [1, 0, 0], limits: [min, max]}");
  AxisSpec axis;
  axis.letter = letter[0];
  const YAML::Node kind = yaml.require(a, "kind", where);
  const std::string kind_text = yaml.text(kind, where + ".kind");
  if (kind_text == "linear")
    axis.kind = AxisKind::Linear;
  else if (kind_text == "rotary")
    axis.kind = AxisKind::Rotary;
  else
    yaml.fail(kind, where + ".kind", "linear or rotary");

  if (axis.kind == AxisKind::Linear) {
    for (const char* k : {"axis", "center"})
      if (a[k])
        yaml.fail(a[k], join(where, k), "'direction' for a linear axis ('axis' and 'center' are for rotary axes)");
    check_keys(yaml, a, where, {"kind", "direction", "limits", "max_velocity", "max_acceleration", "max_jerk"});
    axis.direction = yaml.vec3(yaml.require(a, "direction", where), where + ".direction");
  } else {
    if (a["direction"])
      yaml.fail(a["direction"], where + ".direction",
                "'axis' and 'center' for a rotary axis ('direction' is for linear axes)");
    check_keys(yaml, a, where, {"kind", "axis", "center", "limits", "max_velocity", "max_acceleration", "max_jerk"});
    axis.direction = yaml.vec3(yaml.require(a, "axis", where), where + ".axis");
    axis.center_mm = yaml.vec3(yaml.require(a, "center", where), where + ".center");
  }

  // Lengths stay mm; angles arrive in deg, velocities per minute, accelerations and jerks
  // per second (deg/s^2 and deg/s^3 for rotary axes).
  const double unit = axis.kind == AxisKind::Rotary ? kRadPerDeg : 1.0;
  if (const YAML::Node limits = a["limits"]; limits && !limits.IsNull()) {
    if (!limits.IsSequence() || limits.size() != 2)
      yaml.fail(limits, where + ".limits", "a list of two numbers [min, max], or null for a continuous axis");
    axis.limits = std::make_pair(yaml.number(limits[0], where + ".limits") * unit,
                                 yaml.number(limits[1], where + ".limits") * unit);
  }
  // 0 inside means "not given": a positive value so tiny that it rounds to 0 (4.9e-324) is
  // an error, not silence.
  const auto rate = [&](const char* key, double factor) {
    const double v = yaml.positive(a[key], join(where, key)) * factor;
    if (!(v > 0.0)) yaml.fail(a[key], join(where, key), "a positive number of sensible size");
    return v;
  };
  if (a["max_velocity"]) axis.max_velocity_per_s = rate("max_velocity", unit * kMinPerS);
  if (a["max_acceleration"]) axis.max_acceleration_per_s2 = rate("max_acceleration", unit);
  if (a["max_jerk"]) axis.max_jerk_per_s3 = rate("max_jerk", unit);
  return axis;
}

// A component error: a constant, or {table: [[position, value], ...]} interpolated over the
// axis position. Values in um or urad, positions in mm or deg.
ErrorTable read_error_table(const YamlReader& yaml, const YAML::Node& node, const std::string& where, double value_unit,
                            double position_unit) {
  ErrorTable table;
  if (node.IsScalar()) {
    table.values.push_back(yaml.number(node, where) * value_unit);
    return table;
  }
  if (!node.IsMap()) yaml.fail(node, where, "a number or {table: [[position, value], ...]}");
  check_keys(yaml, node, where, {"table"});
  const YAML::Node rows = yaml.require(node, "table", where);
  if (!rows.IsSequence() || rows.size() < 2)
    yaml.fail(rows, where + ".table", "a list of at least two rows [position, value]");
  for (const auto& row : rows) {
    if (!row.IsSequence() || row.size() != 2) yaml.fail(row, where + ".table", "a row [position, value]");
    // Compared in internal units: deg -> rad can round two tiny positions (0 and 4.9e-324
    // deg) to the same one.
    const double position = yaml.number(row[0], where + ".table") * position_unit;
    if (!table.positions.empty() && !(position > table.positions.back()))
      yaml.fail(row[0], where + ".table", "positions in strictly ascending order");
    table.positions.push_back(position);
    table.values.push_back(yaml.number(row[1], where + ".table") * value_unit);
  }
  return table;
}

// ISO 230-1 names: E_<T><L> a component error of axis L (T = X Y Z translation along, A B C
// rotation about the frame's x y z), E_<T>0<L> a location error of axis L.
void read_errors(const YamlReader& yaml, const YAML::Node& errors, MachineSpec& spec) {
  if (!errors.IsMap()) yaml.fail(errors, "errors", "a map from ISO 230-1 error names to values, like {E_XX: 5}");
  unique_keys(yaml, errors, "errors");
  for (const auto& kv : errors) {
    const std::string name = yaml.text(kv.first, "errors");
    const std::string where = "errors." + name;
    const bool location = name.size() == 5 && name[3] == '0';
    if (name.rfind("E_", 0) != 0 || (name.size() != 4 && !location) || kAxisLetters.find(name[2]) == std::string::npos)
      yaml.fail(kv.first, where,
                "an ISO 230-1 error name like E_XX, E_CZ (component) or E_X0C, E_C0Y (location) "
                "(unknown error name)");
    const char letter = name.back();
    AxisSpec* axis = nullptr;
    for (AxisSpec& a : spec.axes)
      if (a.letter == letter) axis = &a;
    if (!axis)
      yaml.fail(kv.first, where, std::string("an error of an axis of this machine (it has no axis ") + letter + ")");
    const size_t term = kAxisLetters.find(name[2]);
    const bool rotation = term >= 3;
    const int i = static_cast<int>(term % 3);
    if (location) {
      if (!kv.second.IsScalar()) yaml.fail(kv.second, where, "a number (location errors are constants)");
      const double value = yaml.number(kv.second, where);
      if (axis->kind == AxisKind::Linear && !rotation)
        yaml.fail(kv.first, where,
                  std::string("a squareness error E_A0") + letter + "/E_B0" + letter + "/E_C0" + letter +
                      ": offsets have no meaning for a linear axis");
      if (rotation)
        axis->location.tilt_rad[i] = value * kRadPerUrad;
      else
        axis->location.offset_mm[i] = value * kMmPerUm;
    } else {
      const double position_unit = axis->kind == AxisKind::Rotary ? kRadPerDeg : 1.0;
      ErrorTable& table = rotation ? axis->errors.rotation_rad[static_cast<size_t>(i)]
                                   : axis->errors.translation_mm[static_cast<size_t>(i)];
      table = read_error_table(yaml, kv.second, where, rotation ? kRadPerUrad : kMmPerUm, position_unit);
    }
  }
}

// Where a validate() key ("axes.A.axis") sits in the file: the dotted path walked from the
// root, stopping at the nearest parent that exists. A scalar or flow value is marked where
// it starts; a block value at its key, since the value itself starts on the next line.
YAML::Mark mark_of(const YAML::Node& map, const std::string& path, const YAML::Mark& fallback) {
  if (path.empty() || !map.IsMap()) return fallback;
  const size_t dot = path.find('.');
  const std::string head = path.substr(0, dot);
  for (const auto& kv : map) {
    if (!kv.first.IsScalar() || kv.first.Scalar() != head) continue;
    const YAML::Node& value = kv.second;
    const bool inline_value = value.IsScalar() || value.Style() == YAML::EmitterStyle::Flow;
    const YAML::Mark here = inline_value && !value.Mark().is_null() ? value.Mark() : kv.first.Mark();
    return dot == std::string::npos ? here : mark_of(value, path.substr(dot + 1), here);
  }
  return fallback;
}

InputError problem_at(const std::string& file, const YAML::Node& root, const kinematics::SpecProblem& p) {
  const YAML::Mark mark = mark_of(root, p.key, root.Mark());
  const int line = mark.is_null() ? 0 : mark.line + 1;
  const int column = mark.is_null() ? 0 : mark.column + 1;
  // validate() words its problems as what was expected, like YamlReader::fail; a warning
  // says what it repaired.
  return InputError(file, line, column, "'" + p.key + "': " + (p.warning ? "" : "expected ") + p.message);
}

MachineSpec read_spec(const YamlReader& yaml, const YAML::Node& root, const fs::path& base) {
  if (!root.IsMap()) {
    // An empty file (or one of comments only) has no node to point at: its first line.
    if (root.Mark().is_null())
      throw InputError(yaml.file(), 1, 1, "'machine': expected a map of machine settings (the file is empty)");
    yaml.fail(root, "machine", "a map of machine settings");
  }
  check_keys(yaml, root, "",
             {"machine", "topology", "axes", "spindle", "workpiece", "singularity_deg", "models", "errors",
              "feed_interpretation", "home", "second_home", "m_codes"});
  MachineSpec spec;
  spec.name = yaml.text(yaml.require(root, "machine", ""), "machine");
  spec.topology = yaml.text(yaml.require(root, "topology", ""), "topology");

  const YAML::Node axes = yaml.require(root, "axes", "");
  if (!axes.IsMap()) yaml.fail(axes, "axes", "a map from axis letter to axis, like {X: {kind: linear, ...}}");
  unique_keys(yaml, axes, "axes");
  for (const auto& kv : axes) spec.axes.push_back(read_axis(yaml, kv.first, kv.second));
  // Axis values are X Y Z A B C in that order whatever the file's order (as Machine keeps them).
  std::stable_sort(spec.axes.begin(), spec.axes.end(), [](const AxisSpec& a, const AxisSpec& b) {
    return kAxisLetters.find(a.letter) < kAxisLetters.find(b.letter);
  });

  if (const YAML::Node spindle = root["spindle"]) {
    check_keys(yaml, spindle, "spindle", {"gauge_point", "axis"});
    if (spindle["gauge_point"]) spec.gauge_point_mm = yaml.vec3(spindle["gauge_point"], "spindle.gauge_point");
    if (spindle["axis"]) spec.spindle_axis = yaml.vec3(spindle["axis"], "spindle.axis");
  }
  if (const YAML::Node workpiece = root["workpiece"]) {
    check_keys(yaml, workpiece, "workpiece", {"origin"});
    if (workpiece["origin"]) spec.workpiece_origin_mm = yaml.vec3(workpiece["origin"], "workpiece.origin");
  }
  if (const YAML::Node feed = root["feed_interpretation"]) {
    const std::string f = yaml.text(feed, "feed_interpretation");
    if (f == "linuxcnc")
      spec.feed_interpretation = kinematics::FeedInterpretation::LinuxCnc;
    else if (f == "combined")
      spec.feed_interpretation = kinematics::FeedInterpretation::Combined;
    else if (f == "tip")
      spec.feed_interpretation = kinematics::FeedInterpretation::Tip;
    else
      yaml.fail(feed, "feed_interpretation",
                "linuxcnc (F on X Y Z, else on the rotary axes in deg/min), combined (F on "
                "sqrt(dx^2 + ... + dc^2), "
                "Fanuc and Haas) or tip (F on the tool tip's path)");
  }
  // home / second_home: {X: mm, ..., A: deg} for axes of this machine.
  auto read_home = [&](const YAML::Node& node, const std::string& key) {
    if (!node.IsMap()) yaml.fail(node, key, "a map from axis letter to value, like {X: 0, Y: 0, Z: 0}");
    std::map<char, double> home;
    for (const auto& kv : node) {
      const std::string letter = kv.first.Scalar();
      const auto axis = std::find_if(spec.axes.begin(), spec.axes.end(),
                                     [&](const AxisSpec& a) { return letter.size() == 1 && a.letter == letter[0]; });
      if (axis == spec.axes.end()) yaml.fail(kv.first, key + "." + letter, "an axis of this machine");
      const double v = yaml.number(kv.second, key + "." + letter);
      if (std::abs(v) > 1e6) yaml.fail(kv.second, key + "." + letter, "a value within +-1e6 (mm or deg)");
      home[axis->letter] = axis->kind == AxisKind::Rotary ? v * kRadPerDeg : v;
    }
    return home;
  };
  if (const YAML::Node home = root["home"]) spec.home = read_home(home, "home");
  if (const YAML::Node home = root["second_home"]) spec.second_home = read_home(home, "second_home");
  if (const YAML::Node codes = root["m_codes"]) {
    // {M31: ignore, ...}: codes the control runs without a path effect.
    if (!codes.IsMap()) yaml.fail(codes, "m_codes", "a map like {M31: ignore}");
    for (const auto& kv : codes) {
      const std::string name = kv.first.Scalar();
      const std::string key = "m_codes." + name;
      if (name.size() < 2 || name.size() > 4 || (name[0] != 'M' && name[0] != 'm') ||
          name.find_first_not_of("0123456789", 1) != std::string::npos) {
        yaml.fail(kv.first, key, "an M code like M31");
      }
      const int number = std::stoi(name.substr(1));
      if (number == 97 || number == 98 || number == 99 || number == 2 || number == 30 || number == 6)
        yaml.fail(kv.first, key, "an M code other than M2, M6, M30, M97, M98 and M99 (they change the program's path)");
      if (yaml.text(kv.second, key) != "ignore") yaml.fail(kv.second, key, "ignore");
      spec.ignored_m_codes.insert(number);
    }
  }
  if (root["singularity_deg"])
    spec.singularity_angle_rad = yaml.non_negative(root["singularity_deg"], "singularity_deg") * kRadPerDeg;

  if (const YAML::Node models = root["models"]) {
    if (!models.IsMap()) yaml.fail(models, "models", "a map from node letter to a list of models");
    unique_keys(yaml, models, "models");
    for (const auto& kv : models) {
      const std::string node = yaml.text(kv.first, "models");
      const std::string where = "models." + node;
      bool known = node == "W" || node == "T" || node == "F";
      for (const AxisSpec& a : spec.axes) known = known || node == std::string(1, a.letter);
      if (!known) yaml.fail(kv.first, where, "a node of this machine: one of its axis letters, W, T or F");
      if (!kv.second.IsSequence() || kv.second.size() == 0)
        yaml.fail(kv.second, where, "a list of models like [{file: models/x.stl, origin: [0, 0, 0]}]");
      for (const auto& m : kv.second) {
        check_keys(yaml, m, where, {"file", "origin", "name"});
        kinematics::ModelSpec model;
        const YAML::Node file = yaml.require(m, "file", where);
        model.file = resolve(base, yaml.text(file, where + ".file"));
        std::error_code ec;
        if (!fs::is_regular_file(model.file, ec))
          yaml.fail(file, where + ".file", "an existing model file (no file " + model.file + ")");
        if (m["origin"]) model.origin_mm = yaml.vec3(m["origin"], where + ".origin");
        if (m["name"]) model.name = yaml.text(m["name"], where + ".name");
        spec.models[node[0]].push_back(model);
      }
    }
  }

  if (const YAML::Node errors = root["errors"]) read_errors(yaml, errors, spec);
  return spec;
}

}  // namespace

MachineSpec read_machine_file(const std::string& path, std::vector<std::string>* warnings) {
  const YamlReader yaml(path);
  const YAML::Node root = yaml.load();
  const fs::path base = fs::absolute(fs::path(path)).parent_path();
  MachineSpec spec;
  try {
    spec = read_spec(yaml, root, base);
  } catch (const YAML::Exception& e) {  // a node yaml-cpp cannot convert (a non-scalar key)
    throw InputError(path, e.mark.is_null() ? 0 : e.mark.line + 1, e.mark.is_null() ? 0 : e.mark.column + 1, e.msg);
  }
  const std::vector<kinematics::SpecProblem> problems = kinematics::validate(spec);
  for (const kinematics::SpecProblem& p : problems)
    if (!p.warning) throw problem_at(path, root, p);
  for (const kinematics::SpecProblem& p : problems)
    if (warnings) warnings->push_back(problem_at(path, root, p).what());
  return spec;
}

std::string resolve_machine(const std::string& name_or_path) {
  const std::string& n = name_or_path;
  const bool yaml_suffix = n.size() >= 5 && n.compare(n.size() - 5, 5, ".yaml") == 0;
  if (!n.empty() && n.find('/') == std::string::npos && !yaml_suffix) {
    const std::string file = std::string(VCUT_MACHINES_DIR) + "/" + n + ".yaml";
    std::error_code ec;
    if (fs::is_regular_file(file, ec)) return file;
  }
  return n;
}

}  // namespace vcut::io
