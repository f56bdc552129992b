#include "vcut/io/camotics_project.h"

#include <nlohmann/json.hpp>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "reader_util.h"
#include "vcut/io/input_error.h"
#include "vcut/io/machine_file.h"
#include "vcut/io/program_reader.h"

namespace vcut::io {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;

using detail::kMmPerInch;

// The file parsed, a syntax error named by line and column.
json parse(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw InputError(path, 0, 0, "cannot open the file");
  std::stringstream buffer;
  buffer << in.rdbuf();
  const std::string text = buffer.str();
  try {
    return json::parse(text);
  } catch (const json::parse_error& e) {
    // e.byte: 1-based offset of the byte where parsing failed.
    const std::size_t at = std::min<std::size_t>(e.byte > 0 ? e.byte - 1 : 0, text.size());
    int line = 1, column = 1;
    for (std::size_t k = 0; k < at; ++k) {
      if (text[k] == '\n') {
        ++line;
        column = 1;
      } else {
        ++column;
      }
    }
    throw InputError(path, line, column, "not valid JSON (expected a CAMotics project or tool table)");
  }
}

[[noreturn]] void fail(const std::string& path, const std::string& key, const std::string& expected) {
  throw InputError(path, 0, 0, key + ": expected " + expected);
}

double number(const std::string& path, const json& node, const std::string& key) {
  if (!node.is_number() || !std::isfinite(node.get<double>())) fail(path, key, "a number");
  return node.get<double>();
}

ToolLibrary tools_of(const std::string& path, const json& tools) {
  if (!tools.is_object()) fail(path, "tools", "a map from tool number to tool");
  ToolLibrary library;
  for (const auto& [key, t] : tools.items()) {
    const std::string where = "tools." + key;
    int number_ = 0;
    try {
      std::size_t used = 0;
      number_ = std::stoi(key, &used);
      if (used != key.size()) number_ = 0;
    } catch (const std::exception&) {
      number_ = 0;
    }
    if (number_ < 1 || number_ > 99999) fail(path, where, "a tool number from 1 to 99999");
    if (!t.is_object()) fail(path, where, "a tool: {units, shape, length, diameter}");
    const std::string units = t.value("units", std::string("metric"));
    if (units != "metric" && units != "imperial") fail(path, where + ".units", "metric or imperial");
    const double scale = units == "imperial" ? kMmPerInch : 1.0;
    if (!t.contains("diameter")) fail(path, where + ".diameter", "the tool's diameter");
    removal::Cutter c;
    c.diameter_mm = number(path, t["diameter"], where + ".diameter") * scale;
    const double length = t.contains("length") ? number(path, t["length"], where + ".length") * scale : 0.0;
    if (!(c.diameter_mm > 0.0 && c.diameter_mm <= 1e4)) fail(path, where + ".diameter", "a diameter over 0");
    if (!(length >= 0.0 && length <= 1e4)) fail(path, where + ".length", "a length of at least 0");
    const std::string shape = t.value("shape", std::string("cylindrical"));
    if (shape == "cylindrical") {
      c.type = removal::CutterType::Flat;
    } else if (shape == "ballnose") {
      c.type = removal::CutterType::Ball;
      c.corner_radius_mm = c.radius_mm();
    } else if (shape == "conical") {
      if (!(length > 0.0)) fail(path, where + ".length", "the cone's length over 0 for a conical tool");
      c.type = removal::CutterType::VBit;
      c.tip_angle_deg = 2.0 * std::atan(c.radius_mm() / length) * 180.0 / M_PI;
    } else if (shape == "snubnose") {
      fail(path, where + ".shape",
           "cylindrical, ballnose or conical (a snubnose, a cone cut flat, is no cutter vcut has)");
    } else {
      fail(path, where + ".shape", "cylindrical, ballnose or conical");
    }
    assume_lengths(c, std::max(length, c.corner_radius_mm));
    library[number_] = c;
  }
  return library;
}

Eigen::Vector3d vec3(const std::string& path, const json& node, const std::string& key) {
  if (!node.is_array() || node.size() != 3) fail(path, key, "[x, y, z] in mm");
  return Eigen::Vector3d(number(path, node[0], key), number(path, node[1], key), number(path, node[2], key));
}

}  // namespace

ToolLibrary read_camotics_tools(const std::string& path) {
  const json root = parse(path);
  return tools_of(path, root.is_object() && root.contains("tools") ? root["tools"] : root);
}

Job read_camotics_project(const std::string& path) {
  const json root = parse(path);
  if (!root.is_object()) fail(path, "project", "a JSON object with files, tools and workpiece");
  const fs::path base = fs::absolute(path).parent_path();
  Job job;
  job.file = path;
  job.name = fs::path(path).stem().string();
  job.out_dir = (base / "out" / job.name).lexically_normal().string();
  load_machine(job, "3axis", base.string());  // bundled: always there
  job.assumptions.push_back("machine: 3axis (a CAMotics project is three-axis)");
  if (!root.contains("files") || !root["files"].is_array() || root["files"].empty())
    fail(path, "files", "a list of the project's program files");
  for (const auto& f : root["files"]) {
    if (!f.is_string()) fail(path, "files", "file names");
    const fs::path p = fs::path(f.get<std::string>());
    if (lower_extension(p.string()) == ".tpl")
      fail(path, "files",
           "G-code files (" + p.string() + " is a CAMotics TPL program, JavaScript that vcut does not run)");
    job.program_files.push_back((p.is_absolute() ? p : base / p).lexically_normal().string());
  }
  job.tools = tools_of(path, root.contains("tools") ? root["tools"] : json::object());
  for (const auto& [number, c] : job.tools)
    job.assumptions.push_back("T" + std::to_string(number) + ": gauge length " +
                              std::to_string(static_cast<int>(c.gauge_length_mm)) +
                              " mm assumed (a project gives the cutting length only; no holder checked)");
  if (!root.contains("workpiece") || !root["workpiece"].is_object()) fail(path, "workpiece", "the workpiece's bounds");
  const json& w = root["workpiece"];
  if (!w.contains("bounds") || !w["bounds"].is_object()) fail(path, "workpiece.bounds", "{min: [..], max: [..]}");
  job.stock.kind = StockSpec::Kind::Box;
  job.stock.box.min_mm = vec3(path, w["bounds"].value("min", json()), "workpiece.bounds.min");
  job.stock.box.max_mm = vec3(path, w["bounds"].value("max", json()), "workpiece.bounds.max");
  if (!((job.stock.box.max_mm - job.stock.box.min_mm).array() > 0.0).all())
    fail(path, "workpiece.bounds.max", "greater than workpiece.bounds.min in x, y and z");
  if (w.value("automatic", false))
    job.assumptions.push_back("stock: the automatic workpiece as CAMotics saved it (bounds in the project)");
  if (root.contains("resolution")) {
    job.resolution_mm = number(path, root["resolution"], "resolution");
    if (!(job.resolution_mm > 0.0 && job.resolution_mm <= 100.0)) fail(path, "resolution", "a voxel size over 0 mm");
  }
  // CAMotics runs a program with the first tool loaded; vcut's reader starts with none.
  if (!job.tools.empty()) job.initial_tool = job.tools.begin()->first;
  job.assumptions.push_back("design: none, so no gouge or excess is measured");
  return job;
}

}  // namespace vcut::io
