#include "machine_commands.h"

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include <cmath>
#include <cstdio>
#include <iostream>
#include <sstream>

#include "vcut/io/atomic_file.h"
#include "vcut/io/csv.h"
#include "vcut/io/input_error.h"
#include "vcut/io/machine_file.h"
#include "vcut/kinematics/compensation.h"
#include "vcut/kinematics/forward_kinematics.h"
#include "vcut/kinematics/inverse_kinematics.h"

namespace vcut::cli {
namespace {

using json = nlohmann::ordered_json;
using namespace vcut::kinematics;

constexpr double kDegPerRad = 180.0 / M_PI;

bool rotary(const Machine& m, int i) { return m.axis(i).kind == AxisKind::Rotary; }
// Axis values at the file boundary: mm and deg.
double to_file(const Machine& m, int i, double v) { return (rotary(m, i) ? v * kDegPerRad : v) + 0.0; }  // no -0
double from_file(const Machine& m, int i, double v) { return rotary(m, i) ? v / kDegPerRad : v; }

std::string num(double v) { return fmt::format("{:.10g}", v); }

std::string vec(const Eigen::Vector3d& v) { return "(" + num(v.x()) + ", " + num(v.y()) + ", " + num(v.z()) + ")"; }

json array(const Eigen::Vector3d& v) { return json::array({v.x(), v.y(), v.z()}); }

json axes_json(const Machine& m, const AxisValues& q) {
  json j = json::object();
  for (int i = 0; i < m.axis_count(); ++i) j[std::string(1, m.axis(i).letter)] = to_file(m, i, q[i]);
  return j;
}

Machine load(const std::string& file) {
  std::vector<std::string> warnings;
  MachineSpec spec = io::read_machine_file(io::resolve_machine(file), &warnings);
  for (const auto& w : warnings) std::fprintf(stderr, "vcut: warning: %s\n", w.c_str());
  return Machine(std::move(spec));
}

// "X=1,Y=2,A=30" -> axis values (mm, deg -> rad); unnamed axes stay 0.
AxisValues parse_axes(const Machine& m, const std::string& text, const std::string& option) {
  AxisValues q = m.zero();
  std::stringstream in(text);
  std::string item;
  std::string seen;
  while (std::getline(in, item, ',')) {
    const size_t eq = item.find('=');
    const int i = (eq == 1) ? m.axis_index(item[0]) : -1;
    if (i < 0)
      throw InputError(option + ": expected LETTER=value for the axes " + m.axis_letters() + ", not '" + item + "'");
    if (seen.find(item[0]) != std::string::npos)
      throw InputError(option + ": axis " + item.substr(0, 1) + " given twice");
    seen += item[0];
    char* end = nullptr;
    const double v = std::strtod(item.c_str() + 2, &end);
    if (end == item.c_str() + 2 || *end != '\0' || !std::isfinite(v))
      throw InputError(option + ": expected a number after " + item.substr(0, 2) + ", not '" + item.substr(2) + "'");
    q[i] = from_file(m, i, v);
  }
  return q;
}

Eigen::Vector3d parse_vec(const std::string& text, const std::string& option) {
  std::stringstream in(text);
  std::string item;
  std::vector<double> v;
  while (std::getline(in, item, ',')) {
    char* end = nullptr;
    const double x = std::strtod(item.c_str(), &end);
    if (item.empty() || *end != '\0' || !std::isfinite(x))
      throw InputError(option + ": expected x,y,z numbers, not '" + text + "'");
    v.push_back(x);
  }
  if (v.size() != 3) throw InputError(option + ": expected three numbers x,y,z, not '" + text + "'");
  return {v[0], v[1], v[2]};
}

std::string limit_violations(const Machine& m, const AxisValues& q) {
  std::string out;
  for (int i = 0; i < m.axis_count(); ++i) {
    const AxisSpec& a = m.axis(i);
    if (a.limits && (q[i] < a.limits->first - 1e-9 || q[i] > a.limits->second + 1e-9))
      out += std::string(out.empty() ? "" : "; ") + "axis " + a.letter + " beyond its limits";
  }
  return out;
}

const char* status_name(IkStatus s) {
  return s == IkStatus::Ok ? "ok" : s == IkStatus::Singular ? "singular" : "unreachable";
}

void print_json(const json& j) { std::printf("%s\n", j.dump(2).c_str()); }

// ---------------------------------------------------------------------------------------- machine

std::string axis_words(const Machine& m, int i) {
  const AxisSpec& a = m.axis(i);
  std::string s = std::string(1, a.letter) + ": ";
  if (a.kind == AxisKind::Linear) {
    s += "linear along " + vec(a.direction);
    s += a.limits ? ", limits " + num(a.limits->first) + " .. " + num(a.limits->second) + " mm" : ", no limits";
    if (a.max_velocity_per_s > 0) s += ", max " + num(a.max_velocity_per_s * 60) + " mm/min";
    if (a.max_acceleration_per_s2 > 0) s += ", " + num(a.max_acceleration_per_s2) + " mm/s^2";
    if (a.max_jerk_per_s3 > 0) s += ", " + num(a.max_jerk_per_s3) + " mm/s^3";
  } else {
    s += "rotary about " + vec(a.direction) + " through " + vec(a.center_mm);
    s += a.limits
             ? ", limits " + num(a.limits->first * kDegPerRad) + " .. " + num(a.limits->second * kDegPerRad) + " deg"
             : ", continuous";
    if (a.max_velocity_per_s > 0) s += ", max " + num(a.max_velocity_per_s * kDegPerRad * 60) + " deg/min";
    if (a.max_acceleration_per_s2 > 0) s += ", " + num(a.max_acceleration_per_s2 * kDegPerRad) + " deg/s^2";
    if (a.max_jerk_per_s3 > 0) s += ", " + num(a.max_jerk_per_s3 * kDegPerRad) + " deg/s^3";
  }
  return s;
}

std::string error_words(const Machine& m, int i) {
  const AxisSpec& a = m.axis(i);
  const char* t = "XYZ";
  const char* r = "ABC";
  std::string s;
  auto term = [&](const std::string& name, const ErrorTable& e, double scale, const char* unit) {
    if (e.empty()) return;
    s += "    " + name + ": ";
    if (e.positions.empty())
      s += num(e.values.front() * scale) + " " + unit;
    else
      s += "table of " + std::to_string(e.values.size()) + " rows, " + num(e.values.front() * scale) + " .. " +
           num(e.values.back() * scale) + " " + unit;
    s += "\n";
  };
  for (size_t k = 0; k < 3; ++k) {
    term(std::string("E_") + t[k] + a.letter, a.errors.translation_mm[k], 1000.0, "um");
    term(std::string("E_") + r[k] + a.letter, a.errors.rotation_rad[k], 1e6, "urad");
  }
  for (int k = 0; k < 3; ++k) {
    if (a.location.offset_mm[k] != 0.0)
      s += std::string("    E_") + t[k] + "0" + a.letter + ": " + num(a.location.offset_mm[k] * 1000) + " um\n";
    if (a.location.tilt_rad[k] != 0.0)
      s += std::string("    E_") + r[k] + "0" + a.letter + ": " + num(a.location.tilt_rad[k] * 1e6) + " urad\n";
  }
  return s;
}

int run_machine(const std::string& file) {
  const Machine m = load(file);
  const MachineSpec& s = m.spec();
  std::printf("machine %s, topology %s, axes %s\n", s.name.c_str(), s.topology.c_str(), m.axis_letters().c_str());
  std::string w = "frame";
  for (int i : m.workpiece_chain()) w += std::string(" -> ") + m.axis(i).letter;
  std::printf("workpiece chain: %s -> workpiece (programming zero at %s at all-zero axes)\n", w.c_str(),
              vec(s.workpiece_origin_mm).c_str());
  std::string t = "frame";
  for (int i : m.tool_chain()) t += std::string(" -> ") + m.axis(i).letter;
  std::printf(
      "tool chain: %s -> spindle (gauge point %s, tool axis %s at all-zero axes; tip = gauge point - tool length x "
      "axis)\n",
      t.c_str(), vec(s.gauge_point_mm).c_str(), vec(s.spindle_axis).c_str());
  std::printf("axes:\n");
  for (int i = 0; i < m.axis_count(); ++i) std::printf("  %s\n", axis_words(m, i).c_str());
  if (m.rotary_count() == 0) {
    std::printf("orientation: fixed, the tool axis is always %s\n", vec(s.spindle_axis).c_str());
  } else {
    std::string eq = "u_workpiece =";
    for (int k = 0; k < m.rotary_count(); ++k)
      eq += std::string(" R(") + m.axis(m.rotary_axis(k)).letter + ", " + (m.rotary_sign(k) < 0 ? "-" : "+") +
            m.axis(m.rotary_axis(k)).letter + ")";
    std::printf("orientation: %s %s\n", eq.c_str(), vec(s.spindle_axis).c_str());
    if (m.rotary_count() == 2)
      std::printf("singular: tool axis within %s deg of the %s axis (%s keeps its previous angle there)\n",
                  num(s.singularity_angle_rad * kDegPerRad).c_str(),
                  std::string(1, m.axis(m.rotary_axis(0)).letter).c_str(),
                  std::string(1, m.axis(m.rotary_axis(0)).letter).c_str());
  }
  std::string errors;
  for (int i = 0; i < m.axis_count(); ++i) {
    const std::string e = error_words(m, i);
    if (!e.empty()) errors += "  axis " + std::string(1, m.axis(i).letter) + ":\n" + e;
  }
  std::printf("geometric errors:%s", errors.empty() ? " none\n" : ("\n" + errors).c_str());  // error lines end in \n
  for (const auto& [node, models] : s.models)
    for (const ModelSpec& model : models)
      std::printf("model on %c: %s at %s\n", node, model.file.c_str(), vec(model.origin_mm).c_str());
  return 0;
}

// --------------------------------------------------------------------------------------------- fk

json fk_json(const Machine& m, const AxisValues& q, double length, bool errors) {
  json j;
  j["machine"] = m.name();
  j["axes"] = axes_json(m, q);
  j["tool_length_mm"] = length;
  const ToolPose p = forward(m, q, length);
  j["tip"] = array(p.tip_mm);
  j["axis"] = array(p.axis);
  const std::string limits = limit_violations(m, q);
  j["status"] = limits.empty() ? "ok" : "beyond limits: " + limits;
  const Geometry g = errors ? Geometry::Actual : Geometry::Ideal;
  j["nodes"] = json::array();
  for (const NodePose& n : node_poses(m, q, g)) {
    json node;
    node["node"] = std::string(1, n.node);
    node["origin"] = array(n.pose.translation());
    json rot = json::array();
    for (int r = 0; r < 3; ++r)
      rot.push_back(json::array({n.pose.linear()(r, 0), n.pose.linear()(r, 1), n.pose.linear()(r, 2)}));
    node["rotation"] = rot;
    j["nodes"].push_back(node);
  }
  j["models"] = json::array();
  for (const ModelPose& mp : model_poses(m, q, g)) {
    json model;
    model["node"] = std::string(1, mp.node);
    model["file"] = mp.file;
    model["origin"] = array(mp.pose.translation());
    j["models"].push_back(model);
  }
  if (errors) {
    const ToolPose a = forward(m, q, length, Geometry::Actual);
    const PoseError e = pose_error(p, a);
    j["actual"] = {{"tip", array(a.tip_mm)}, {"axis", array(a.axis)}};
    j["error"] = {{"tip_um", array(e.tip_um)}, {"tip_um_norm", e.tip_um.norm()}, {"axis_tilt_urad", e.axis_tilt_urad}};
  }
  return j;
}

// --------------------------------------------------------------------------------------------- ik

struct IkOutcome {
  IkResult result;
  std::optional<ToolPose> actual;
  std::optional<CompensationResult> compensated;
};

IkOutcome solve(const Machine& m, const ToolPose& pose, double length, const AxisValues* previous,
                const IkSettings& settings, bool errors) {
  IkOutcome o;
  o.result = inverse(m, pose, length, previous, settings);
  if (errors && o.result.ok()) {
    o.actual = forward(m, o.result.q(), length, Geometry::Actual);
    o.compensated = compensate(m, pose, length, o.result.q());
  }
  return o;
}

json ik_json(const Machine& m, const ToolPose& pose, double length, const IkOutcome& o) {
  json j;
  j["machine"] = m.name();
  j["tip"] = array(pose.tip_mm);
  j["axis"] = array(pose.axis);
  j["tool_length_mm"] = length;
  j["status"] = status_name(o.result.status);
  j["reason"] = o.result.reason;
  j["solutions"] = json::array();
  for (const IkSolution& s : o.result.solutions) {
    json sol = axes_json(m, s.q);
    sol["branch"] = s.branch;
    sol["within_limits"] = s.within_limits;
    if (!s.violation.empty()) sol["violation"] = s.violation;
    j["solutions"].push_back(sol);
  }
  j["chosen_index"] = o.result.chosen;
  j["chosen"] = o.result.ok() ? axes_json(m, o.result.q()) : json(nullptr);
  if (o.result.status == IkStatus::Singular) j["orientation_error_urad"] = o.result.orientation_error_rad * 1e6;
  if (o.actual) {
    const PoseError e = pose_error(pose, *o.actual);
    j["actual"] = {{"tip", array(o.actual->tip_mm)},
                   {"axis", array(o.actual->axis)},
                   {"error_tip_um", array(e.tip_um)},
                   {"error_axis_tilt_urad", e.axis_tilt_urad}};
    const CompensationResult& c = *o.compensated;
    j["compensated"] = {{"axes", axes_json(m, c.q)},
                        {"converged", c.converged},
                        {"residual_tip_um", c.residual_tip_um},
                        {"residual_axis_urad", c.residual_axis_urad},
                        {"iterations", c.iterations},
                        {"note", c.note}};
  }
  return j;
}

// ------------------------------------------------------------------------------------------ batches

std::string csv_field(const std::string& s) {
  if (s.find_first_of(",\"\n") == std::string::npos) return s;
  std::string q = "\"";
  for (char c : s) q += c == '"' ? std::string("\"\"") : std::string(1, c);
  return q + "\"";
}

std::string join(const std::vector<std::string>& fields) {
  std::string line;
  for (size_t i = 0; i < fields.size(); ++i) line += (i ? "," : "") + csv_field(fields[i]);
  return line + "\n";
}

void run_fk_csv(const Machine& m, const std::string& in, const std::string& out, double length, bool errors) {
  const io::CsvTable t = io::read_csv(in);
  std::vector<int> col(static_cast<size_t>(m.axis_count()));
  for (int i = 0; i < m.axis_count(); ++i) {
    col[static_cast<size_t>(i)] = t.column(std::string(1, m.axis(i).letter));
    if (col[static_cast<size_t>(i)] < 0)
      throw InputError(in, 1, 1,
                       std::string("a column '") + m.axis(i).letter + "' for every axis (" + m.axis_letters() + ")");
  }
  std::vector<std::string> header = t.header;
  for (const char* c : {"tip_x", "tip_y", "tip_z", "axis_i", "axis_j", "axis_k"}) header.push_back(c);
  if (errors)
    for (const char* c :
         {"actual_x", "actual_y", "actual_z", "actual_i", "actual_j", "actual_k", "error_um", "tilt_urad"})
      header.push_back(c);
  header.push_back("status");
  std::string text = join(header);
  for (const auto& row : t.rows) {
    std::vector<std::string> f;
    for (double v : row) f.push_back(num(v));
    AxisValues q = m.zero();
    for (int i = 0; i < m.axis_count(); ++i)
      q[i] = from_file(m, i, row[static_cast<size_t>(col[static_cast<size_t>(i)])]);
    const ToolPose p = forward(m, q, length);
    for (int k = 0; k < 3; ++k) f.push_back(num(p.tip_mm[k]));
    for (int k = 0; k < 3; ++k) f.push_back(num(p.axis[k]));
    if (errors) {
      const ToolPose a = forward(m, q, length, Geometry::Actual);
      const PoseError e = pose_error(p, a);
      for (int k = 0; k < 3; ++k) f.push_back(num(a.tip_mm[k]));
      for (int k = 0; k < 3; ++k) f.push_back(num(a.axis[k]));
      f.push_back(num(e.tip_um.norm()));
      f.push_back(num(e.axis_tilt_urad));
    }
    const std::string limits = limit_violations(m, q);
    f.push_back(limits.empty() ? "ok" : "beyond limits: " + limits);
    text += join(f);
  }
  io::write_text_atomically(out, text);
}

void run_ik_csv(const Machine& m, const std::string& in, const std::string& out, double length, bool errors,
                const IkSettings& settings, const AxisValues* first_previous) {
  const io::CsvTable t = io::read_csv(in);
  const char* pose_cols[] = {"tip_x", "tip_y", "tip_z", "axis_i", "axis_j", "axis_k"};
  std::array<int, 6> col{};
  for (int k = 0; k < 6; ++k) {
    col[static_cast<size_t>(k)] = t.column(pose_cols[k]);
    if (col[static_cast<size_t>(k)] < 0) throw InputError(in, 1, 1, std::string("a column '") + pose_cols[k] + "'");
  }
  std::vector<int> prev_col(static_cast<size_t>(m.axis_count()));
  bool any_prev = false;
  for (int i = 0; i < m.axis_count(); ++i) {
    prev_col[static_cast<size_t>(i)] = t.column(std::string("prev_") + m.axis(i).letter);
    any_prev = any_prev || prev_col[static_cast<size_t>(i)] >= 0;
  }
  std::vector<std::string> header = t.header;
  for (int i = 0; i < m.axis_count(); ++i) header.push_back(std::string(1, m.axis(i).letter));
  header.push_back("status");
  if (errors) {
    for (const char* c :
         {"actual_x", "actual_y", "actual_z", "actual_i", "actual_j", "actual_k", "error_um", "tilt_urad"})
      header.push_back(c);
    for (int i = 0; i < m.axis_count(); ++i) header.push_back(std::string("comp_") + m.axis(i).letter);
    header.push_back("residual_um");
    header.push_back("residual_urad");
  }
  std::string text = join(header);
  // Without prev_ columns each row starts from the previous row's solution: a path.
  std::optional<AxisValues> previous;
  if (first_previous) previous = *first_previous;
  for (size_t r = 0; r < t.rows.size(); ++r) {
    const auto& row = t.rows[r];
    ToolPose pose;
    pose.tip_mm = {row[static_cast<size_t>(col[0])], row[static_cast<size_t>(col[1])],
                   row[static_cast<size_t>(col[2])]};
    pose.axis = {row[static_cast<size_t>(col[3])], row[static_cast<size_t>(col[4])], row[static_cast<size_t>(col[5])]};
    if (pose.axis.norm() < 1e-9) throw InputError(in, t.lines[r], 1, "a non-zero tool axis axis_i, axis_j, axis_k");
    pose.axis.normalize();
    if (any_prev) {
      AxisValues p = previous ? *previous : m.zero();
      for (int i = 0; i < m.axis_count(); ++i)
        if (prev_col[static_cast<size_t>(i)] >= 0)
          p[i] = from_file(m, i, row[static_cast<size_t>(prev_col[static_cast<size_t>(i)])]);
      previous = p;
    }
    const IkOutcome o = solve(m, pose, length, previous ? &*previous : nullptr, settings, errors);
    std::vector<std::string> f;
    for (double v : row) f.push_back(num(v));
    for (int i = 0; i < m.axis_count(); ++i) f.push_back(o.result.ok() ? num(to_file(m, i, o.result.q()[i])) : "");
    f.push_back(o.result.status == IkStatus::Ok ? "ok"
                                                : std::string(status_name(o.result.status)) + ": " + o.result.reason);
    if (errors) {
      if (o.actual) {
        const PoseError e = pose_error(pose, *o.actual);
        for (int k = 0; k < 3; ++k) f.push_back(num(o.actual->tip_mm[k]));
        for (int k = 0; k < 3; ++k) f.push_back(num(o.actual->axis[k]));
        f.push_back(num(e.tip_um.norm()));
        f.push_back(num(e.axis_tilt_urad));
        for (int i = 0; i < m.axis_count(); ++i) f.push_back(num(to_file(m, i, o.compensated->q[i])));
        f.push_back(num(o.compensated->residual_tip_um));
        f.push_back(num(o.compensated->residual_axis_urad));
        if (!o.compensated->converged)
          f[header.size() - 1 - 8 - static_cast<size_t>(m.axis_count()) - 2] +=
              "; compensation: " + o.compensated->note;
      } else {
        for (size_t k = 0; k < 8 + static_cast<size_t>(m.axis_count()) + 2; ++k) f.push_back("");
      }
    }
    text += join(f);
    if (o.result.ok()) previous = o.result.q();
  }
  io::write_text_atomically(out, text);
}

}  // namespace

void add_machine_commands(CLI::App& app, MachineCommands& c) {
  c.machine = app.add_subcommand("machine", "Print a machine file's chains, axes, limits and errors in words");
  c.machine->add_option("file", c.file, "Machine file (YAML) or bundled machine name")->required();

  c.fk = app.add_subcommand("fk", "Forward kinematics: axis values -> tool pose (JSON, or a CSV batch)");
  c.fk->add_option("file", c.file, "Machine file (YAML) or bundled machine name")->required();
  c.fk->add_option("--axes", c.axes, "Axis values, e.g. X=10,Y=0,Z=-5,A=30,C=90 (mm, deg)");
  c.fk->add_option("--tool-length", c.tool_length_mm, "Tool length out of the spindle nose, mm")
      ->check(CLI::NonNegativeNumber);
  c.fk->add_flag("--errors", c.errors, "Also the actual pose with the machine's geometric errors");
  c.fk->add_option("--csv", c.csv_in, "Batch input: columns named by axis letters");
  c.fk->add_option("--out", c.csv_out, "Batch output CSV");

  c.ik = app.add_subcommand("ik", "Inverse kinematics: tool pose -> all axis solutions and the chosen one");
  c.ik->add_option("file", c.file, "Machine file (YAML) or bundled machine name")->required();
  c.ik->add_option("--tip", c.tip, "Tool tip x,y,z in the workpiece frame, mm");
  c.ik->add_option("--axis", c.axis, "Tool axis i,j,k (tip -> spindle) in the workpiece frame");
  c.ik->add_option("--previous", c.previous, "Previous axis values, e.g. A=10,C=-90 (mm, deg)");
  c.ik->add_option("--prefer", c.prefer, "Preferred sign of one rotary axis, e.g. A+ or B-");
  c.ik->add_option("--singular-deg", c.singular_deg, "Singular cone half-angle, deg (default: the machine's)")
      ->check(CLI::NonNegativeNumber);
  c.ik->add_option("--tool-length", c.tool_length_mm, "Tool length out of the spindle nose, mm")
      ->check(CLI::NonNegativeNumber);
  c.ik->add_flag("--errors", c.errors, "Also the actual pose at the solution and error-compensated axis commands");
  c.ik->add_option("--csv", c.csv_in, "Batch input: tip_x tip_y tip_z axis_i axis_j axis_k [prev_<letter>]");
  c.ik->add_option("--out", c.csv_out, "Batch output CSV");
}

bool run_machine_commands(const MachineCommands& c) {
  if (c.machine && *c.machine) {
    run_machine(c.file);
    return true;
  }
  const bool fk = c.fk && *c.fk, ik = c.ik && *c.ik;
  if (!fk && !ik) return false;
  if (c.csv_in.empty() != c.csv_out.empty()) throw InputError("--csv and --out go together: give both for a batch");
  const Machine m = load(c.file);
  if (fk) {
    if (!c.csv_in.empty()) {
      run_fk_csv(m, c.csv_in, c.csv_out, c.tool_length_mm, c.errors);
      return true;
    }
    print_json(fk_json(m, parse_axes(m, c.axes, "--axes"), c.tool_length_mm, c.errors));
    return true;
  }
  IkSettings settings;
  if (c.singular_deg >= 0.0) settings.singularity_angle_rad = c.singular_deg / kDegPerRad;
  if (!c.prefer.empty()) {
    const int i = c.prefer.size() == 2 ? m.axis_index(c.prefer[0]) : -1;
    if (i < 0 || !rotary(m, i) || (c.prefer[1] != '+' && c.prefer[1] != '-'))
      throw InputError("--prefer: expected a rotary axis letter and a sign, e.g. A+ (not '" + c.prefer + "')");
    settings.preferred_axis = c.prefer[0];
    settings.preferred_sign = c.prefer[1] == '+' ? 1 : -1;
  }
  std::optional<AxisValues> previous;
  if (!c.previous.empty()) previous = parse_axes(m, c.previous, "--previous");
  if (!c.csv_in.empty()) {
    run_ik_csv(m, c.csv_in, c.csv_out, c.tool_length_mm, c.errors, settings, previous ? &*previous : nullptr);
    return true;
  }
  if (c.tip.empty() || c.axis.empty())
    throw InputError("ik: give --tip x,y,z and --axis i,j,k (or --csv IN --out OUT)");
  ToolPose pose;
  pose.tip_mm = parse_vec(c.tip, "--tip");
  pose.axis = parse_vec(c.axis, "--axis");
  if (pose.axis.norm() < 1e-9) throw InputError("--axis: expected a non-zero vector");
  pose.axis.normalize();
  print_json(ik_json(m, pose, c.tool_length_mm,
                     solve(m, pose, c.tool_length_mm, previous ? &*previous : nullptr, settings, c.errors)));
  return true;
}

}  // namespace vcut::cli
