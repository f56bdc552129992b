#include "vcut/pipeline/program_job.h"

#include <fmt/format.h>
#include <algorithm>
#include <cmath>
#include <filesystem>
#include <limits>
#include <optional>
#include <set>

#include "vcut/io/camotics_project.h"
#include "vcut/io/input_error.h"
#include "vcut/io/machine_file.h"
#include "vcut/io/program_header.h"
#include "vcut/io/program_reader.h"
#include "vcut/io/tool_table.h"
#include "vcut/kinematics/densify.h"
#include "vcut/pipeline/poses.h"

namespace vcut::pipeline {
namespace fs = std::filesystem;

namespace {

std::string mm(double v) { return fmt::format("{:.4g}", std::abs(v) < 5e-5 ? 0.0 : v); }

std::string describe(const removal::Cutter& c) {
  std::string s = mm(c.diameter_mm) + " mm ";
  switch (c.type) {
    case removal::CutterType::Flat:
      return s + "flat end mill";
    case removal::CutterType::Ball:
      return s + "ball end mill";
    case removal::CutterType::BullNose:
      return s + "bull nose end mill, corner radius " + mm(c.corner_radius_mm) + " mm";
    case removal::CutterType::VBit:
      return s + "pointed cutter of " + mm(c.tip_angle_deg) + " deg";
  }
  return s;
}

// (io::assume_lengths gives the flutes as declared, else 4 diameters; job_for_program lengthens
// them to the depth the tool cuts: no false shank collision for an assumed length.)

void set_machine(io::Job& job, const std::string& name) {
  if (!io::load_machine(job, name, fs::current_path().string()))
    throw InputError("--machine " + name + ": expected a bundled machine (" + io::kBundledMachines +
                     ") or a machine file (not found)");
}

// Two significant digits, rounded down (a finer grid, never a coarser one).
double two_digits(double v) {
  const double scale = std::pow(10.0, std::floor(std::log10(v)) - 1.0);
  return std::max(1.0, std::floor(v / scale + 1e-9)) * scale;  // 1.2 less rounding is still 1.2
}

struct Extent {
  Eigen::AlignedBox3d box;
  double highest_level_mm = -std::numeric_limits<double>::infinity();  // of a feed move at one Z
  double max_radius_mm = 0.0;
  // The first plunge: a rapid down followed by a feed further down; a CAM system rapids to
  // just above the stock there, so the stock's top is no higher (NaN: none).
  Eigen::Vector3d first_plunge_mm = Eigen::Vector3d::Constant(std::numeric_limits<double>::quiet_NaN());
};

// The cutting (feed) moves' tips, arcs by their whole circles (a bound), and the largest
// radius of the tools that make them.
Extent cutting_extent(const kinematics::Program& program, const io::ToolLibrary& tools) {
  Extent e;
  std::optional<kinematics::Block> before;
  for (const kinematics::Block& b : program.blocks) {
    const bool after_rapid_down =
        before && before->kind == kinematics::MotionKind::Rapid && before->end_mm.z() < before->start_mm.z() - 1e-9;
    const Eigen::Vector3d rapid_end = before ? before->end_mm : Eigen::Vector3d::Zero();
    before = b;
    if (b.kind == kinematics::MotionKind::Rapid) continue;
    if (after_rapid_down && std::isnan(e.first_plunge_mm.z()) && b.end_mm.z() < b.start_mm.z() - 1e-9)
      e.first_plunge_mm = rapid_end;
    e.box.extend(b.start_mm);
    e.box.extend(b.end_mm);
    if (b.kind == kinematics::MotionKind::Arc) {
      // Points every 2 deg at most: within r (1 - cos 1 deg) = 0.015 % of the radius of the
      // arc's own box (a long flat arc of a large radius stays small).
      const int n =
          std::clamp(static_cast<int>(std::ceil(kinematics::arc_angle_rad(b) / (2.0 * M_PI / 180.0))), 1, 100000);
      for (int k = 1; k < n; ++k) e.box.extend(kinematics::arc_point(b, static_cast<double>(k) / n));
    }
    if (std::abs(b.start_mm.z() - b.end_mm.z()) < 1e-9) e.highest_level_mm = std::max(e.highest_level_mm, b.end_mm.z());
    const auto t = tools.find(b.tool);
    if (t != tools.end()) e.max_radius_mm = std::max(e.max_radius_mm, t->second.radius_mm());
  }
  return e;
}

// Where a declared size goes along one axis: the placement (low corner at 0, centred, high
// corner at 0) whose middle is nearest the cutting moves' middle.
double place(double size_mm, double cut_low_mm, double cut_high_mm, std::string& how) {
  const double middle = 0.5 * (cut_low_mm + cut_high_mm);
  const double lows[3] = {0.0, -0.5 * size_mm, -size_mm};
  const char* names[3] = {"low side", "centre", "high side"};
  int best = 0;
  for (int k = 1; k < 3; ++k)
    if (std::abs(lows[k] + 0.5 * size_mm - middle) < std::abs(lows[best] + 0.5 * size_mm - middle) - 1e-9) best = k;
  how = names[best];
  return lows[best];
}

void set_stock(io::Job& job, const std::optional<io::DeclaredStock>& declared, const Extent& cut,
               const std::string& name) {
  job.stock.kind = io::StockSpec::Kind::Box;
  removal::BoxShape& box = job.stock.box;
  const Eigen::Vector3d lo = cut.box.min(), hi = cut.box.max();
  if (declared && declared->placed) {
    box.min_mm = declared->min_mm;
    box.max_mm = declared->min_mm + declared->size_mm;
    job.assumptions.push_back("stock: the " + declared->form + " at " + declared->where + ", X " + mm(box.min_mm.x()) +
                              ".." + mm(box.max_mm.x()) + " Y " + mm(box.min_mm.y()) + ".." + mm(box.max_mm.y()) +
                              " Z " + mm(box.min_mm.z()) + ".." + mm(box.max_mm.z()) + " mm");
    return;
  }
  if (declared) {
    const Eigen::Vector3d size = declared->size_mm;
    std::string hx, hy;
    box.min_mm.x() = place(size.x(), lo.x(), hi.x(), hx);
    box.min_mm.y() = place(size.y(), lo.y(), hi.y(), hy);
    const bool top_at_zero = lo.z() < -1e-9;
    box.min_mm.z() = top_at_zero ? -size.z() : 0.0;
    box.max_mm = box.min_mm + size;
    job.assumptions.push_back("stock: " + mm(size.x()) + " x " + mm(size.y()) + " x " + mm(size.z()) + " mm from the " +
                              declared->form + " at " + declared->where + ", placed with its " +
                              (top_at_zero ? "top" : "bottom") + " at Z0, its X " + hx + " and Y " + hy +
                              " at 0 (where it holds the cutting moves best): X " + mm(box.min_mm.x()) + ".." +
                              mm(box.max_mm.x()) + " Y " + mm(box.min_mm.y()) + ".." + mm(box.max_mm.y()) + " Z " +
                              mm(box.min_mm.z()) + ".." + mm(box.max_mm.z()));
    return;
  }
  const bool top_at_zero = lo.z() < -1e-9;
  double top = top_at_zero ? 0.0 : (std::isfinite(cut.highest_level_mm) ? cut.highest_level_mm : hi.z());
  // No higher than the first plunge's rapid end over the cutting moves (their XY box).
  const Eigen::Vector3d& plunge = cut.first_plunge_mm;
  const bool lowered = plunge.allFinite() && plunge.z() < top && plunge.z() > lo.z() && plunge.x() >= lo.x() &&
                       plunge.x() <= hi.x() && plunge.y() >= lo.y() && plunge.y() <= hi.y();
  if (lowered) top = plunge.z();
  // No margin in X and Y: the approaches start outside the part, and a margin would put
  // their rapids into the assumed stock.
  const double margin_z = std::max(1.0, 0.05 * (top - lo.z()));
  const double grow = cut.max_radius_mm;
  // Outward to 0.01 mm: a box the user reads and types again.
  auto down = [](double v) { return std::floor(v * 100.0) / 100.0; };
  auto up = [](double v) { return std::ceil(v * 100.0) / 100.0; };
  box.min_mm = Eigen::Vector3d(down(lo.x() - grow), down(lo.y() - grow), down(lo.z() - margin_z));
  box.max_mm = Eigen::Vector3d(up(hi.x() + grow), up(hi.y() + grow), std::max(top, box.min_mm.z() + margin_z));
  job.assumptions.push_back(
      "stock: " + name + " declares none; the cutting moves' box grown by the largest tool's radius (" +
      mm(cut.max_radius_mm) + " mm), from their lowest Z less " + mm(margin_z) + " mm up to " +
      (lowered ? "Z" + mm(top) + ", where the first plunge's rapid ends (CAM systems rapid to just above the stock)"
       : top_at_zero ? "Z0 (the stock's top, where CAM systems put it)"
                     : "their highest cutting level") +
      ": X " + mm(box.min_mm.x()) + ".." + mm(box.max_mm.x()) + " Y " + mm(box.min_mm.y()) + ".." + mm(box.max_mm.y()) +
      " Z " + mm(box.min_mm.z()) + ".." + mm(box.max_mm.z()));
}

// The deepest each tool cuts below the stock's top (mm; 0 where it stays above).
std::map<int, double> depth_of_tools(const kinematics::Program& program, double top_mm) {
  std::map<int, double> depth;
  for (const kinematics::Block& b : program.blocks) {
    if (b.kind == kinematics::MotionKind::Rapid) continue;
    const double low = std::min(b.start_mm.z(), b.end_mm.z());
    double& d = depth[b.tool];
    d = std::max(d, top_mm - low);
  }
  return depth;
}

}  // namespace

io::Job job_for_program(const std::string& program_path, const ProgramJobOptions& options) {
  if (!fs::is_regular_file(program_path)) throw InputError(program_path, 0, 0, "no such program file");
  io::Job job;
  const fs::path absolute = fs::absolute(program_path).lexically_normal();
  const std::string name = absolute.filename().string();
  job.file = program_path;
  job.name = absolute.stem().string();
  job.out_dir = options.out_dir.empty() ? (fs::current_path() / "out" / job.name).string() : options.out_dir;
  job.program_files = {absolute.string()};
  job.dialect = options.dialect;
  const io::Dialect dialect =
      options.dialect == io::Dialect::Auto ? io::detect_dialect(absolute.string()) : options.dialect;
  const io::ProgramHeader header = io::read_program_header(program_path);
  const double unit_mm = header.inch ? 25.4 : 1.0;

  // Machine: as named, else by the rotary words (a tilting tool axis is found after reading).
  std::string machine = options.machine;
  const std::set<char>& rotary = header.rotary_letters;
  if (machine.empty()) {
    machine = rotary.count('B') ? "table-table-bc" : rotary.empty() && !header.swivels ? "3axis" : "xyzac-trt";
  }
  set_machine(job, machine);

  // Tools: the table, else the comments; each with an assumed length.
  std::map<int, std::string> origin;  // T number -> where its shape comes from
  if (!options.tool_table.empty() && io::lower_extension(options.tool_table) == ".json") {
    // A CAMotics tool table: shapes and lengths given.
    job.tools_file = fs::absolute(options.tool_table).lexically_normal().string();
    for (const auto& [number, c] : io::read_camotics_tools(options.tool_table)) {
      job.tools[number] = c;
      origin[number] = "the CAMotics tool table " + options.tool_table;
    }
  } else if (!options.tool_table.empty()) {
    job.tools_file = fs::absolute(options.tool_table).lexically_normal().string();
    for (const auto& [number, t] : io::read_tool_table(options.tool_table, unit_mm)) {
      removal::Cutter c = t.cutter;
      io::assume_lengths(c, 0.0);
      if (t.z_offset_mm > c.length_mm) c.gauge_length_mm = t.z_offset_mm;
      job.tools[number] = c;
      origin[number] = "the tool table " + t.where;
    }
  }
  for (const auto& [number, t] : header.tools) {
    if (job.tools.count(number)) continue;
    removal::Cutter c = t.cutter;
    io::assume_lengths(c, t.flute_length_mm);
    job.tools[number] = c;
    origin[number] = "the " + t.form + " comment at " + t.where;
  }
  std::set<int> used = header.tool_numbers;
  if (dialect != io::Dialect::Apt) {
    // The tool in the spindle at the start: the first one the program names, else T1.
    job.initial_tool = header.first_tool > 0 ? header.first_tool : 1;
    used.insert(job.initial_tool);
  }
  auto assume_default = [&](int number) {
    removal::Cutter c;
    c.diameter_mm = options.default_tool_diameter_mm;
    io::assume_lengths(c, 0.0);
    job.tools[number] = c;
    origin[number] = "nothing in the program (the default diameter; --tool-diameter to change)";
  };
  for (int number : used)
    if (!job.tools.count(number)) assume_default(number);

  // Read it as the job will, then what the program showed: a tilting tool axis, its tools.
  job.stock.kind = io::StockSpec::Kind::Mesh;  // no stock yet: probes trip at their ends
  JobProgram read = read_job_program(job);
  const bool tilts =
      std::any_of(read.program.blocks.begin(), read.program.blocks.end(), [](const kinematics::Block& b) {
        const auto zero = [](const kinematics::RotaryWords& r) {
          return r.angle_rad[0] == 0.0 && r.angle_rad[1] == 0.0 && r.angle_rad[2] == 0.0;
        };
        return b.start_axis.z() < 1.0 - 1e-9 || b.end_axis.z() < 1.0 - 1e-9 || !zero(b.start_rotary) ||
               !zero(b.end_rotary);
      });
  bool held_at_zero = false;  // rotary words that only ever say 0 (a post's home line)
  if (options.machine.empty() && (machine == "3axis") == tilts) {
    held_at_zero = !tilts;
    machine = tilts ? "xyzac-trt" : "3axis";
    set_machine(job, machine);
    read = read_job_program(job);
  }
  std::set<int> from_cl;  // tools whose lengths the CL file's CUTTER/ gives
  for (const kinematics::Block& b : read.program.blocks) {
    if (b.tool == 0 || job.tools.count(b.tool)) continue;
    const auto cl = read.tools.find(b.tool);
    if (cl != read.tools.end()) {
      origin[b.tool] = "the program's CUTTER/";
      from_cl.insert(b.tool);
      continue;
    }
    assume_default(b.tool);
    read.tools[b.tool] = job.tools[b.tool];
  }
  job.assumptions.push_back(
      "machine: " + machine +
      (!options.machine.empty() ? std::string(" (--machine)")
       : held_at_zero       ? std::string(" (the program's rotary words hold them at 0; --machine to choose another)")
       : machine == "3axis" ? std::string(" (the program moves X Y Z only; --machine to choose another)")
                            : std::string(" (the program moves rotary axes; --machine to choose another)")));

  const Extent cut = cutting_extent(read.program, read.tools);
  if (cut.box.isEmpty())
    throw InputError(program_path, 0, 0,
                     "the program makes no cutting move (G1 G2 G3 or a feed GOTO): nothing to simulate without a job "
                     "file and its stock");
  set_stock(job, header.stock, cut, name);

  // Lengths that reach as deep as each tool cuts, now that the stock's top is known.
  const std::map<int, double> depth = depth_of_tools(read.program, job.stock.box.max_mm.z());
  for (auto& [number, c] : job.tools) {
    const auto d = depth.find(number);
    if (d != depth.end() && d->second + 1.0 > c.flute_length_mm) {
      c.flute_length_mm = c.length_mm = std::min(d->second + 1.0, c.gauge_length_mm);
    }
  }
  for (const auto& [number, c] : read.tools)
    if (!job.tools.count(number) && depth.count(number)) job.tools[number] = c;  // APT CUTTER/ shapes
  double smallest_mm = std::numeric_limits<double>::infinity();
  for (const auto& [number, c] : job.tools) {
    if (!depth.count(number) && !used.count(number)) continue;
    smallest_mm = std::min(smallest_mm, c.diameter_mm);
    const bool cl = from_cl.count(number) != 0;
    job.assumptions.push_back(
        "T" + std::to_string(number) + ": " + describe(c) + " from " + origin[number] + "; flutes " +
        mm(c.flute_length_mm) + " mm, gauge length " + mm(c.gauge_length_mm) +
        (cl ? std::string(" mm (no holder checked)") : std::string(" mm assumed (no holder checked)")));
  }
  if (job.initial_tool > 0)
    job.assumptions.push_back("T" + std::to_string(job.initial_tool) +
                              " is in the spindle when the program starts (the first tool it names)");

  const Eigen::Vector3d size = job.stock.box.max_mm - job.stock.box.min_mm;
  if (options.resolution_mm > 0.0) {
    job.resolution_mm = options.resolution_mm;
  } else {
    // No coarser than the stock's thinnest side, which a coarser lattice cannot hold (refused).
    job.resolution_mm = two_digits(std::min({size.maxCoeff() / 1000.0, smallest_mm / 4.0, size.minCoeff()}));
    job.assumptions.push_back("resolution: " + mm(job.resolution_mm) +
                              " mm (the longest stock side / 1000, at most a quarter of the smallest tool and the "
                              "stock's thinnest side; --resolution to change)");
  }
  job.assumptions.push_back(
      "design: none, so no gouge or excess is measured (give a job file with design: to compare)");
  return job;
}

}  // namespace vcut::pipeline
