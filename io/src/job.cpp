#include "vcut/io/job.h"

#include <fmt/format.h>
#include <cctype>
#include <cmath>
#include <filesystem>

#include "vcut/io/machine_file.h"
#include "tool_library_node.h"
#include "yaml_util.h"

namespace vcut::io {

const char* engine_name(Engine engine) {
  switch (engine) {
    case Engine::Dexel:
      return "dexel";
    case Engine::Vdb:
      return "vdb";
    case Engine::Both:
      return "both";
  }
  return "dexel";
}
namespace fs = std::filesystem;

namespace {

// One axis's loop keys, over the values it has (`where` prefixes the key in messages).
void read_servo_axis(const YamlReader& yaml, const YAML::Node& node, const std::string& where,
                     kinematics::ServoAxis& axis) {
  if (node["kv"]) axis.kv_per_s = yaml.positive(node["kv"], where + "kv");
  if (const YAML::Node wn = node["omega_n"]) {
    // `ideal`: an ideal velocity loop, the position loop of first order (x' = Kv (c - x)).
    if (wn.IsScalar() && wn.Scalar() == "ideal") {
      axis.omega_n_per_s = 0.0;
    } else {
      const double value = wn.IsScalar() ? yaml.number(wn, where + "omega_n") : 0.0;
      if (!(value > 0.0))
        yaml.fail(wn, where + "omega_n", "a positive number (1/s), or ideal for an ideal velocity loop (first order)");
      axis.omega_n_per_s = value;
    }
  }
  if (node["zeta"]) axis.zeta = yaml.non_negative(node["zeta"], where + "zeta");
  if (node["feed_forward"]) {
    axis.feed_forward = yaml.non_negative(node["feed_forward"], where + "feed_forward");
    if (axis.feed_forward > 1.0) yaml.fail(node["feed_forward"], where + "feed_forward", "a fraction from 0 to 1");
  }
}

// servo: {kv, omega_n, zeta, feed_forward, period, axes: {X: {kv: 18}, C: {...}}}: the loop
// of every machine axis (seed 004's parameters by default), overridden per axis letter.
void read_servo(const YamlReader& yaml, const YAML::Node& servo, Job& job) {
  yaml.only_keys(servo, "servo", {"kv", "omega_n", "zeta", "period", "feed_forward", "axes"});
  kinematics::ServoSettings s;
  kinematics::ServoAxis all;
  read_servo_axis(yaml, servo, "servo.", all);
  if (servo["period"]) {
    // A period beyond a second is a unit mistake (ms for s), not an interpolator.
    s.period_s = yaml.positive(servo["period"], "servo.period");
    if (s.period_s > 1.0)
      yaml.fail(servo["period"], "servo.period", "the interpolation period in seconds, > 0 and at most 1 (e.g. 0.001)");
  }
  const std::vector<kinematics::AxisSpec>& axes = job.machine_spec.axes;
  s.axes.assign(std::max<std::size_t>(1, axes.size()), all);
  if (const YAML::Node per_axis = servo["axes"]) {
    if (!per_axis.IsMap())
      yaml.fail(per_axis, "servo.axes", "a map from axis letters to loop settings, e.g. {X: {kv: 18}}");
    std::string letters;
    for (const auto& a : axes) letters += a.letter;
    for (const auto& kv : per_axis) {
      const std::string key = kv.first.as<std::string>();
      const std::size_t index = key.size() == 1 ? letters.find(key[0]) : std::string::npos;
      if (index == std::string::npos)
        yaml.fail(kv.first, "servo.axes." + key,
                  "an axis of the machine " + job.machine_spec.name + " (one of " + letters + ")");
      yaml.only_keys(kv.second, "servo.axes." + key, {"kv", "omega_n", "zeta", "feed_forward"});
      read_servo_axis(yaml, kv.second, "servo.axes." + key + ".", s.axes[index]);
    }
  }
  // A sampled loop that diverges at this period is a setting no machine runs with.
  for (std::size_t i = 0; i < s.axes.size(); ++i) {
    if (kinematics::servo_stable(s.axes[i], s.period_s)) continue;
    const std::string letter = i < axes.size() ? std::string(1, axes[i].letter) : "";
    const YAML::Node per_axis = servo["axes"] && !letter.empty() ? servo["axes"][letter] : YAML::Node();
    const bool own = per_axis.IsDefined() && per_axis["kv"];
    const std::string what = fmt::format(
        "a position loop stable at the period {:g} s (axis {}: Kv {:g}/s diverges when sampled; "
        "an ideal velocity loop needs Kv x period < 2)",
        s.period_s, letter, s.axes[i].kv_per_s);
    yaml.fail(own           ? per_axis["kv"]
              : servo["kv"] ? servo["kv"]
                            : servo,
              own ? "servo.axes." + letter + ".kv" : "servo.kv", what);
  }
  job.servo = s;
}

// machine: a bundled machine's name or a machine file relative to the job (3axis when absent).
void read_machine_key(const YamlReader& yaml, const YAML::Node& node, const fs::path& base, Job& job) {
  // Read and validated here so that a bad machine file stops the job before anything is cut.
  if (!load_machine(job, node ? yaml.text(node, "machine") : job.machine, base.string()))
    yaml.fail(node, "machine",
              std::string("a bundled machine (") + kBundledMachines +
                  ") or a machine file (not found: " + job.machine_file + ")");
}

// tools: the tool library file, or its `tools:` map written here.
void read_tools_key(const YamlReader& yaml, const YAML::Node& node, const fs::path& base, Job& job) {
  if (node.IsMap()) {
    job.tools = read_tools(yaml, node);
    return;
  }
  job.tools_file = resolve(base, yaml.text(node, "tools"));
  job.tools = read_tool_library(job.tools_file);
}

// program: the program files and how to read them.
void read_program_key(const YamlReader& yaml, const YAML::Node& program, const fs::path& base, Job& job) {
  yaml.only_keys(program, "program",
                 {"file", "files", "dialect", "unsupported", "subroutine_path", "max_lines", "tcp_m_codes",
                  "initial_tool", "block_delete", "arc_tolerance", "cutcom"});
  if (program["file"] && program["files"]) yaml.fail(program, "program", "either 'file' or 'files', not both");
  if (program["file"]) {
    job.program_files.push_back(resolve(base, yaml.text(program["file"], "program.file")));
  } else {
    const YAML::Node files = yaml.require(program, "files", "program");
    if (!files.IsSequence() || files.size() == 0)
      yaml.fail(files, "program.files", "a non-empty list of program files");
    for (const auto& f : files) job.program_files.push_back(resolve(base, yaml.text(f, "program.files")));
  }
  if (program["dialect"]) {
    const std::string dialect = yaml.text(program["dialect"], "program.dialect");
    try {
      job.dialect = parse_dialect(dialect);
    } catch (const InputError&) {
      yaml.fail(program["dialect"], "program.dialect", "auto, gcode, linuxcnc, fanuc, apt or sinumerik");
    }
  }
  if (const YAML::Node path = program["subroutine_path"]) {
    if (!path.IsSequence()) yaml.fail(path, "program.subroutine_path", "a list of folders");
    for (const auto& f : path) job.subroutine_path.push_back(resolve(base, yaml.text(f, "program.subroutine_path")));
  }
  if (const YAML::Node codes = program["tcp_m_codes"]) {
    // {M428: on, M429: off}: M codes that switch tool-centre-point kinematics (LinuxCNC's
    // table-rotary-tilting demos); on acts like G43.4.
    if (!codes.IsMap()) yaml.fail(codes, "program.tcp_m_codes", "a map like {M428: on, M429: off}");
    for (const auto& kv : codes) {
      const std::string name = kv.first.Scalar();
      const std::string key = "program.tcp_m_codes." + name;
      int number = -1;
      if (name.size() >= 2 && (name[0] == 'M' || name[0] == 'm') && name.size() <= 4 &&
          name.find_first_not_of("0123456789", 1) == std::string::npos) {
        number = std::stoi(name.substr(1));
      }
      if (number < 10 || number == 30) yaml.fail(kv.first, key, "an M code M10..M999 other than M30");
      const std::string state = yaml.text(kv.second, key);
      if (state != "on" && state != "off") yaml.fail(kv.second, key, "on or off");
      job.tcp_m_codes[number] = state == "on";
    }
  }
  if (program["initial_tool"]) {
    const double t = yaml.positive(program["initial_tool"], "program.initial_tool");
    if (t != std::floor(t) || t > 99999)
      yaml.fail(program["initial_tool"], "program.initial_tool", "a T number from 1 to 99999");
    job.initial_tool = static_cast<int>(t);
  }
  if (program["cutcom"]) {
    const std::string mode = yaml.text(program["cutcom"], "program.cutcom");
    if (mode != "contour" && mode != "centre" && mode != "center")
      yaml.fail(program["cutcom"], "program.cutcom",
                "contour (APT CUTCOM/: the CL points are the part's contour) or centre (they are the tool's centre; "
                "the control compensates wear only)");
    job.apt_cutcom_on_centre = mode != "contour";
  }
  if (program["max_lines"]) {
    const double n = yaml.positive(program["max_lines"], "program.max_lines");
    if (n != std::floor(n) || n > 1e12)
      yaml.fail(program["max_lines"], "program.max_lines", "a whole number of lines up to 1e12");
    job.max_lines = static_cast<long long>(n);
  }
  if (program["block_delete"]) {
    const std::string mode = yaml.text(program["block_delete"], "program.block_delete");
    if (mode != "on" && mode != "off")
      yaml.fail(program["block_delete"], "program.block_delete", "on (skip lines starting with '/') or off (run them)");
    job.block_delete = mode == "on";
  }
  if (program["arc_tolerance"]) {
    const double t = yaml.non_negative(program["arc_tolerance"], "program.arc_tolerance");
    if (t > 10.0) yaml.fail(program["arc_tolerance"], "program.arc_tolerance", "a radius mismatch in mm up to 10");
    job.arc_tolerance_mm = t;
  }
  if (program["unsupported"]) {
    const std::string mode = yaml.text(program["unsupported"], "program.unsupported");
    if (mode != "error" && mode != "warn") yaml.fail(program["unsupported"], "program.unsupported", "error or warn");
    job.unsupported_as_warning = mode == "warn";
    job.unknown_m_code_as_error = mode == "error";
  }
}

// offsets: work offsets by name, mm.
void read_offsets_key(const YamlReader& yaml, const YAML::Node& offsets, const fs::path& /*base*/, Job& job) {
  if (!offsets.IsMap()) yaml.fail(offsets, "offsets", "a map like {G54: [x, y, z]}");
  for (const auto& kv : offsets) {
    const std::string name = kv.first.Scalar();
    static const char* kNames[] = {"G54", "G55", "G56", "G57", "G58", "G59", "G59.1", "G59.2", "G59.3"};
    bool ok = false;
    for (const char* n : kNames) ok = ok || name == n;
    // SINUMERIK's settable offsets beyond G57: G505..G599.
    ok =
        ok || (name.size() == 4 && name.compare(0, 2, "G5") == 0 && std::isdigit(static_cast<unsigned char>(name[2])) &&
               std::isdigit(static_cast<unsigned char>(name[3])) && name >= "G505");
    if (!ok) yaml.fail(kv.first, "offsets." + name, "a work offset name G54..G59, G59.1..G59.3 or G505..G599");
    job.offsets_mm[name] = yaml.vec3(kv.second, "offsets." + name);
  }
}

// stock: exactly one of box, cylinder or mesh.
void read_stock_key(const YamlReader& yaml, const YAML::Node& stock, const fs::path& base, Job& job) {
  yaml.only_keys(stock, "stock", {"box", "cylinder", "mesh"});
  if (stock.size() != 1) yaml.fail(stock, "stock", "exactly one of box, cylinder or mesh");
  if (!stock.Mark().is_null()) {
    job.stock.line = stock.Mark().line + 1;
    job.stock.column = stock.Mark().column + 1;
  }
  if (const YAML::Node box = stock["box"]) {
    yaml.only_keys(box, "stock.box", {"min", "max"});
    job.stock.kind = StockSpec::Kind::Box;
    job.stock.box.min_mm = yaml.vec3(yaml.require(box, "min", "stock.box"), "stock.box.min");
    job.stock.box.max_mm = yaml.vec3(yaml.require(box, "max", "stock.box"), "stock.box.max");
    if (!((job.stock.box.max_mm - job.stock.box.min_mm).array() > 0.0).all())
      yaml.fail(box["max"], "stock.box.max", "greater than stock.box.min in x, y and z");
  } else if (const YAML::Node cyl = stock["cylinder"]) {
    yaml.only_keys(cyl, "stock.cylinder", {"center", "axis", "radius", "height"});
    job.stock.kind = StockSpec::Kind::Cylinder;
    job.stock.cylinder.base_center_mm =
        yaml.vec3(yaml.require(cyl, "center", "stock.cylinder"), "stock.cylinder.center");
    job.stock.cylinder.axis = cyl["axis"] ? yaml.vec3(cyl["axis"], "stock.cylinder.axis") : Eigen::Vector3d::UnitZ();
    if (job.stock.cylinder.axis.norm() < 1e-9) yaml.fail(cyl["axis"], "stock.cylinder.axis", "a non-zero vector");
    job.stock.cylinder.axis.normalize();
    job.stock.cylinder.radius_mm =
        yaml.positive(yaml.require(cyl, "radius", "stock.cylinder"), "stock.cylinder.radius");
    job.stock.cylinder.height_mm =
        yaml.positive(yaml.require(cyl, "height", "stock.cylinder"), "stock.cylinder.height");
  } else {
    job.stock.kind = StockSpec::Kind::Mesh;
    const YAML::Node mesh = stock["mesh"];
    job.stock.mesh_file =
        resolve(base, yaml.text(mesh.IsMap() ? yaml.require(mesh, "file", "stock.mesh") : mesh, "stock.mesh"));
  }
}

// design: the part to compare with, placed by its transform.
DesignSpec read_placed_file(const YamlReader& yaml, const YAML::Node& node, const fs::path& base,
                            const std::string& where) {
  yaml.only_keys(node, where, {"file", "transform"});
  DesignSpec d;
  const YAML::Node file = yaml.require(node, "file", where);
  d.file = resolve(base, yaml.text(file, where + ".file"));
  if (const YAML::Node t = node["transform"]) {
    yaml.only_keys(t, where + ".transform", {"translate", "rotate_deg"});
    if (t["translate"]) d.translate_mm = yaml.vec3(t["translate"], where + ".transform.translate");
    if (t["rotate_deg"]) d.rotate_deg = yaml.vec3(t["rotate_deg"], where + ".transform.rotate_deg");
  }
  return d;
}

void read_design_key(const YamlReader& yaml, const YAML::Node& design, const fs::path& base, Job& job) {
  job.design = read_placed_file(yaml, design, base, "design");
}

// fixtures: a list of placed mesh files, each an existing file.
void read_fixtures_key(const YamlReader& yaml, const YAML::Node& fixtures, const fs::path& base, Job& job) {
  if (!fixtures.IsSequence())
    yaml.fail(fixtures, "fixtures", "a list like [{file: vice.stl, transform: {translate: [0, 0, -40]}}]");
  for (std::size_t i = 0; i < fixtures.size(); ++i) {
    const std::string where = "fixtures[" + std::to_string(i) + "]";
    if (!fixtures[i].IsMap()) yaml.fail(fixtures[i], where, "a map with file and transform");
    DesignSpec d = read_placed_file(yaml, fixtures[i], base, where);
    std::error_code ec;
    if (!fs::is_regular_file(d.file, ec))
      yaml.fail(fixtures[i]["file"], where + ".file", "an existing mesh file (no file " + d.file + ")");
    job.fixtures.push_back(d);
  }
}

// engine: kind, resolution (mm), threads and the turning moves' tolerance (mm).
void read_engine_key(const YamlReader& yaml, const YAML::Node& engine, const fs::path& /*base*/, Job& job) {
  yaml.only_keys(engine, "engine", {"kind", "resolution", "threads", "turn_tolerance"});
  if (engine["kind"]) {
    const std::string kind = yaml.text(engine["kind"], "engine.kind");
    if (kind == "dexel")
      job.engine = Engine::Dexel;
    else if (kind == "vdb")
      job.engine = Engine::Vdb;
    else if (kind == "both")
      job.engine = Engine::Both;
    else
      yaml.fail(engine["kind"], "engine.kind", "dexel, vdb or both");
  }
  if (engine["resolution"]) job.resolution_mm = yaml.positive(engine["resolution"], "engine.resolution");
  if (engine["turn_tolerance"])
    job.turn_tolerance_mm = yaml.positive(engine["turn_tolerance"], "engine.turn_tolerance");
  if (const YAML::Node threads = engine["threads"]) {
    if (threads.IsScalar() && threads.Scalar() == "auto")
      job.threads = 0;
    else {
      job.threads = yaml.integer(threads, "engine.threads");
      if (job.threads < 1) yaml.fail(threads, "engine.threads", "auto or a positive count");
    }
  }
}

// report: the output folder and the tolerances (mm).
void read_report_key(const YamlReader& yaml, const YAML::Node& report, const fs::path& base, Job& job) {
  yaml.only_keys(
      report, "report",
      {"out", "gouge_tolerance", "excess_tolerance", "collision_tolerance", "machine_clearance", "page_triangles"});
  if (report["out"]) job.out_dir = resolve(base, yaml.text(report["out"], "report.out"));
  if (report["gouge_tolerance"])
    job.gouge_tolerance_mm = yaml.non_negative(report["gouge_tolerance"], "report.gouge_tolerance");
  if (report["excess_tolerance"])
    job.excess_tolerance_mm = yaml.non_negative(report["excess_tolerance"], "report.excess_tolerance");
  if (report["collision_tolerance"])
    job.collision_tolerance_mm = yaml.non_negative(report["collision_tolerance"], "report.collision_tolerance");
  if (report["machine_clearance"])
    job.machine_clearance_mm = yaml.non_negative(report["machine_clearance"], "report.machine_clearance");
  if (const YAML::Node page = report["page_triangles"]) {
    const int n = yaml.integer(page, "report.page_triangles");
    if (n < 1000)
      yaml.fail(page, "report.page_triangles", "a count of at least 1000 (the machined mesh shown in report.html)");
    job.page_triangles = static_cast<std::size_t>(n);
  }
}

// densify: chord tolerance, step (mm), angle (deg), tolerance (mm).
void read_densify_key(const YamlReader& yaml, const YAML::Node& densify, const fs::path& /*base*/, Job& job) {
  yaml.only_keys(densify, "densify", {"chord_tolerance", "step", "angle", "tolerance"});
  if (densify["chord_tolerance"])
    job.chord_tolerance_mm = yaml.positive(densify["chord_tolerance"], "densify.chord_tolerance");
  if (densify["step"]) job.step_mm = yaml.positive(densify["step"], "densify.step");
  if (densify["angle"]) job.angle_step_deg = yaml.positive(densify["angle"], "densify.angle");
  if (densify["tolerance"]) job.densify_tolerance_mm = yaml.positive(densify["tolerance"], "densify.tolerance");
  job.densify_given = true;
}

// feed: the path limits where the machine gives none.
void read_feed_key(const YamlReader& yaml, const YAML::Node& feed, const fs::path& /*base*/, Job& job) {
  yaml.only_keys(feed, "feed", {"acceleration", "jerk", "lookahead", "rapid"});
  if (feed["acceleration"])
    job.feed.path_acceleration_mm_per_s2 = yaml.positive(feed["acceleration"], "feed.acceleration");
  if (feed["jerk"]) job.feed.path_jerk_mm_per_s3 = yaml.positive(feed["jerk"], "feed.jerk");
  if (feed["rapid"]) job.feed.rapid_mm_per_min = yaml.positive(feed["rapid"], "feed.rapid");
  if (feed["lookahead"]) {
    job.feed.lookahead_blocks = yaml.integer(feed["lookahead"], "feed.lookahead");
    if (job.feed.lookahead_blocks < 1) yaml.fail(feed["lookahead"], "feed.lookahead", "a positive number of blocks");
  }
}

// servo: the axes' loops.
void read_servo_key(const YamlReader& yaml, const YAML::Node& node, const fs::path& /*base*/, Job& job) {
  read_servo(yaml, node, job);
}

// start: the tip when the program starts (G53, mm).
void read_start_key(const YamlReader& yaml, const YAML::Node& start, const fs::path& /*base*/, Job& job) {
  // Where the tool's tip is when the program starts, in machine coordinates (G53: the
  // workpiece frame without work offsets, mm); axes not named are at the machine's home.
  if (!start.IsMap()) yaml.fail(start, "start", "a map like {X: 0, Y: 0, Z: 100} (mm, G53 coordinates)");
  yaml.only_keys(start, "start", {"X", "Y", "Z"});
  std::map<char, double> values;
  for (const char* letter : {"X", "Y", "Z"}) {
    if (!start[letter]) continue;
    const double v = yaml.number(start[letter], std::string("start.") + letter);
    if (std::abs(v) > 1e6) yaml.fail(start[letter], std::string("start.") + letter, "a position within +-1e6 mm");
    values[letter[0]] = v;
  }
  job.start_mm = values;
}

// errors: machine or none.
void read_errors_key(const YamlReader& yaml, const YAML::Node& errors, const fs::path& /*base*/, Job& job) {
  const std::string e = yaml.text(errors, "errors");
  if (e != "machine" && e != "none")
    yaml.fail(errors, "errors", "machine (apply the machine file's geometric errors) or none");
  job.apply_errors = e == "machine";
}

// A job file's keys, read in this order: whether a job must give it, and its reader (run
// for an absent key too where it sets a default: the machine).
struct JobKey {
  const char* name;
  enum { Optional, Required, Default } presence;
  // The key's node (null where absent) and the job's folder.
  void (*read)(const YamlReader&, const YAML::Node&, const fs::path&, Job&);
};
const JobKey kJobKeys[] = {
    {"machine", JobKey::Default, read_machine_key},  {"tools", JobKey::Required, read_tools_key},
    {"program", JobKey::Required, read_program_key}, {"offsets", JobKey::Optional, read_offsets_key},
    {"stock", JobKey::Required, read_stock_key},     {"design", JobKey::Optional, read_design_key},
    {"engine", JobKey::Optional, read_engine_key},   {"report", JobKey::Optional, read_report_key},
    {"densify", JobKey::Optional, read_densify_key}, {"feed", JobKey::Optional, read_feed_key},
    {"servo", JobKey::Optional, read_servo_key},     {"start", JobKey::Optional, read_start_key},
    {"errors", JobKey::Optional, read_errors_key},   {"fixtures", JobKey::Optional, read_fixtures_key},
};

}  // namespace

const char* const kBundledMachines =
    "3axis, table-table-ac, table-table-bc, head-table-bc, head-head-ac, gantry-wyxzcat, xyzac-trt";

bool load_machine(Job& job, const std::string& name_or_path, const std::string& base_folder) {
  job.machine = name_or_path;
  job.machine_file = resolve_machine(name_or_path);
  if (job.machine_file == name_or_path) job.machine_file = resolve(base_folder, name_or_path);
  if (!fs::exists(job.machine_file)) return false;
  job.machine_spec = read_machine_file(job.machine_file, &job.warnings);
  return true;
}

std::string display_name(const std::string& path, const std::string& job_file) {
  const fs::path base = fs::absolute(job_file).parent_path();
  const fs::path rel = fs::path(path).lexically_relative(base);
  return rel.empty() || *rel.begin() == ".." ? path : rel.string();
}

Job read_job(const std::string& path) {
  const YamlReader yaml(path);
  const YAML::Node root = yaml.load();
  if (!root.IsMap()) yaml.fail(root, "job", "a map of job settings");
  std::vector<std::string> keys = {"job"};
  for (const JobKey& k : kJobKeys) keys.push_back(k.name);
  yaml.only_keys(root, "", keys);
  const fs::path base = fs::absolute(fs::path(path)).parent_path();
  Job job;
  job.file = path;
  job.name = root["job"] ? yaml.text(root["job"], "job") : fs::path(path).stem().string();
  job.out_dir = resolve(base, "out/" + job.name);  // report.out may move it
  for (const JobKey& k : kJobKeys) {
    const YAML::Node node = k.presence == JobKey::Required ? yaml.require(root, k.name, "") : root[k.name];
    if (node || k.presence == JobKey::Default) k.read(yaml, node, base, job);
  }
  return job;
}

namespace {
std::string vec_text(const Eigen::Vector3d& v) {
  return "[" + yaml_number(v.x()) + ", " + yaml_number(v.y()) + ", " + yaml_number(v.z()) + "]";
}
}  // namespace

std::string job_yaml(const Job& job, const std::string& program_as_given) {
  std::string s = "# The job vcut assumed for " + program_as_given + " (vcut job); check what it assumed:\n";
  for (const std::string& a : job.assumptions) s += "#   " + a + "\n";
  s += "job: " + job.name + "\n";
  s += "machine: " + job.machine + "\n";
  s += "program: {file: \"" + program_as_given + "\"";
  if (job.dialect != Dialect::Auto) s += std::string(", dialect: ") + dialect_name(job.dialect);
  if (job.initial_tool > 0) s += ", initial_tool: " + std::to_string(job.initial_tool);
  s += "}\n";
  s += tool_library_yaml(job.tools);
  if (job.stock.kind == StockSpec::Kind::Box)
    s += "stock: {box: {min: " + vec_text(job.stock.box.min_mm) + ", max: " + vec_text(job.stock.box.max_mm) + "}}\n";
  s += std::string("engine: {kind: ") + engine_name(job.engine) + ", resolution: " + yaml_number(job.resolution_mm) +
       "}\n";
  return s;
}

}  // namespace vcut::io
