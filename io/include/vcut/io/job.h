// A simulation job (YAML): machine, tools, program, offsets, stock, design, engine and
// report settings. Paths inside are relative to the job file; read_job makes them absolute.
#pragma once

#include <Eigen/Core>

#include <cstddef>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "vcut/io/dialect.h"
#include "vcut/io/tool_library.h"
#include "vcut/kinematics/feed_planner.h"
#include "vcut/kinematics/machine.h"
#include "vcut/kinematics/servo.h"
#include "vcut/removal/stock.h"

namespace vcut::io {

// The material-removal engine: tri-dexel, OpenVDB, or both (the two cross-checked).
enum class Engine { Dexel, Vdb, Both };
const char* engine_name(Engine engine);  // "dexel", "vdb", "both": as the job file writes it

// A mesh file placed in the workpiece frame: the design part, a fixture.
struct DesignSpec {
  std::string file;
  Eigen::Vector3d translate_mm = Eigen::Vector3d::Zero();
  Eigen::Vector3d rotate_deg = Eigen::Vector3d::Zero();  // about X, then Y, then Z (fixed axes)
};

struct StockSpec {
  enum class Kind { Box, Cylinder, Mesh } kind = Kind::Box;
  removal::BoxShape box{};
  removal::CylinderShape cylinder{};
  std::string mesh_file;
  int line = 0, column = 0;  // where the job file gives it (0: assumed, no job file)
};

struct Job {
  std::string file;  // the job file itself
  std::string name;
  std::string machine = "3axis";  // as written: a bundled machine's name or a path
  std::string machine_file;       // the machine file it names
  kinematics::MachineSpec machine_spec;
  std::vector<std::string> warnings;  // from reading the job's files
  // What vcut assumed for a program simulated without a job file (pipeline/program_job.h):
  // the machine, stock, tools and resolution it chose, for the user to confirm. Empty for a job.
  std::vector<std::string> assumptions;
  std::string tools_file;  // empty: the tools are written in the job (or assumed)
  ToolLibrary tools;
  std::vector<std::string> program_files;
  // As dialect.h names them (auto: detected per file). APT programs define
  // their cutters (CUTTER/); the tool library wins for a T number it has.
  Dialect dialect = Dialect::Auto;
  bool unsupported_as_warning = false;
  bool unknown_m_code_as_error = false;    // program.unsupported: error (unset: such M codes warn)
  bool block_delete = true;                // program.block_delete: on (skip '/' lines) | off
  std::optional<double> arc_tolerance_mm;  // program.arc_tolerance (mm); none: the reader's default
  // start: {X, Y, Z}: the tip's G53 position (mm) when the program starts; none: the machine's home.
  std::optional<std::map<char, double>> start_mm;
  std::vector<std::string> subroutine_path;  // G-code: folders searched for <name>.ngc subroutine files
  long long max_lines = 100'000'000;         // G-code: lines read before a loop is taken to be endless
  std::map<int, bool> tcp_m_codes;           // G-code: M codes switching TCP on (true) / off
  int initial_tool = 0;                      // G-code: the tool in the spindle at the start (0: none)
  bool apt_cutcom_on_centre = false;         // APT: program.cutcom: centre (else contour)
  std::map<std::string, Eigen::Vector3d> offsets_mm;
  StockSpec stock;
  std::optional<DesignSpec> design;
  // fixtures: vices, clamps, plates, carried by the workpiece (closed meshes, workpiece frame).
  std::vector<DesignSpec> fixtures;
  Engine engine = Engine::Dexel;
  double resolution_mm = 0.1;
  int threads = 0;  // 0 = all cores
  std::string out_dir;
  double gouge_tolerance_mm = 0.01;
  double excess_tolerance_mm = 0.1;
  std::size_t page_triangles = 2'000'000;  // report.html shows the machined mesh decimated to this
  double collision_tolerance_mm = 0.01;
  // report.machine_clearance: machine bodies, fixtures and the tool's holder closer than this
  // are near misses (mm); touching or closer is a collision.
  double machine_clearance_mm = 1.0;
  double chord_tolerance_mm = 0.0;  // arcs; 0 = resolution / 20
  // engine.turn_tolerance: how far the translation pieces a turning (five-axis) move is cut as
  // may leave the rigid motion (mm); 0 = min(resolution / 10, gouge_tolerance / 2).
  double turn_tolerance_mm = 0.0;
  double step_mm = 0.0;               // densify.step: lambda; 0 = none
  double angle_step_deg = 0.0;        // densify.angle: phi; 0 = none
  double densify_tolerance_mm = 0.0;  // densify.tolerance: epsilon (tolerance mode); 0 = off
  // false (no `densify:` key): every block within min(resolution / 10, gouge tolerance / 2)
  // of the machine's path (io::default_densify_tolerance_mm).
  bool densify_given = false;
  kinematics::FeedSettings feed;  // feed: acceleration, jerk, lookahead, rapid
  // servo: present = simulate servo lag, one loop per machine axis (in axis order).
  std::optional<kinematics::ServoSettings> servo;
  bool apply_errors = false;  // errors: machine
};

// Throws vcut::InputError (file:line:column, key, what was expected).
Job read_job(const std::string& path);

// The bundled machines' names, for messages: "3axis, table-table-ac, ...".
extern const char* const kBundledMachines;
// The job's machine: a bundled machine's name, else a machine file relative to `base_folder`;
// sets machine, machine_file and machine_spec (read and validated: a bad file is an
// InputError). False, and nothing read, when no such file exists.
bool load_machine(Job& job, const std::string& name_or_path, const std::string& base_folder);

// The job as a job file (`vcut job`): its assumptions as comments at the top, the program as
// `program_as_given`, the tools written in it; read_job reads it back to the same job.
std::string job_yaml(const Job& job, const std::string& program_as_given);

// A path as the job's user wrote it: relative to the job file's folder when inside it.
std::string display_name(const std::string& path, const std::string& job_file);

}  // namespace vcut::io
