#include "vcut/io/tool_library.h"

#include <filesystem>

#include "tool_library_node.h"

namespace vcut::io {

ToolLibrary read_tool_library(const std::string& path) {
  const YamlReader yaml(path);
  const YAML::Node root = yaml.load();
  if (!root.IsMap()) yaml.fail(root, "tools", "a map with the key 'tools'");
  yaml.only_keys(root, "", {"tools"});
  return read_tools(yaml, yaml.require(root, "tools", ""));
}

ToolLibrary read_tools(const YamlReader& yaml, const YAML::Node& tools) {
  if (!tools.IsMap()) yaml.fail(tools, "tools", "a map from T number to tool");
  ToolLibrary library;
  for (const auto& kv : tools) {
    const int number = yaml.integer(kv.first, "tools");
    const std::string where = "tools." + kv.first.Scalar();
    if (number < 1 || number > 99999) yaml.fail(kv.first, where, "a T number from 1 to 99999");
    const YAML::Node& t = kv.second;
    yaml.only_keys(t, where,
                   {"type", "diameter", "corner_radius", "angle", "point_angle", "flute_length", "shank_diameter",
                    "length", "gauge_length", "holder_diameter", "holder_length", "holder_mesh", "name"});
    removal::Cutter c;
    const std::string type = yaml.text(yaml.require(t, "type", where), where + ".type");
    if (type == "flat")
      c.type = removal::CutterType::Flat;
    else if (type == "ball")
      c.type = removal::CutterType::Ball;
    else if (type == "bull" || type == "bullnose")
      c.type = removal::CutterType::BullNose;
    else if (type == "vbit" || type == "drill")
      c.type = removal::CutterType::VBit;
    else
      yaml.fail(t["type"], where + ".type", "flat, ball, bull, vbit or drill");
    c.diameter_mm = yaml.positive(yaml.require(t, "diameter", where), where + ".diameter");
    const double radius = 0.5 * c.diameter_mm;
    if (c.type == removal::CutterType::Flat) {
      c.corner_radius_mm = t["corner_radius"] ? yaml.non_negative(t["corner_radius"], where + ".corner_radius") : 0.0;
      if (c.corner_radius_mm != 0.0) yaml.fail(t["corner_radius"], where + ".corner_radius", "0 for a flat end mill");
    } else if (c.type == removal::CutterType::Ball) {
      c.corner_radius_mm = t["corner_radius"] ? yaml.positive(t["corner_radius"], where + ".corner_radius") : radius;
      if (std::abs(c.corner_radius_mm - radius) > 1e-9)
        yaml.fail(t["corner_radius"], where + ".corner_radius", "half the diameter for a ball end mill");
      c.corner_radius_mm = radius;
    } else if (c.type == removal::CutterType::VBit && type == "drill") {
      // A twist drill: its point (included angle, deg; 118 unless given) then its body, the
      // geometry of a V-bit; canned cycles' Z is the point's tip.
      if (t["angle"]) yaml.fail(t["angle"], where + ".angle", "point_angle for a drill");
      c.tip_angle_deg = t["point_angle"] ? yaml.positive(t["point_angle"], where + ".point_angle") : 118.0;
      if (c.tip_angle_deg >= 180.0)
        yaml.fail(t["point_angle"], where + ".point_angle", "an included point angle between 0 and 180 degrees");
      if (t["corner_radius"]) yaml.fail(t["corner_radius"], where + ".corner_radius", "no corner radius for a drill");
    } else if (c.type == removal::CutterType::VBit) {
      // A pointed chamfer cutter: its included tip angle (deg).
      if (t["point_angle"])
        yaml.fail(t["point_angle"], where + ".point_angle", "angle for a V-bit (point_angle is a drill's)");
      c.tip_angle_deg = yaml.positive(yaml.require(t, "angle", where), where + ".angle");
      if (c.tip_angle_deg >= 180.0)
        yaml.fail(t["angle"], where + ".angle", "an included tip angle between 0 and 180 degrees");
      if (t["corner_radius"]) yaml.fail(t["corner_radius"], where + ".corner_radius", "no corner radius for a V-bit");
    } else {
      c.corner_radius_mm = yaml.positive(yaml.require(t, "corner_radius", where), where + ".corner_radius");
      if (c.corner_radius_mm > radius)
        yaml.fail(t["corner_radius"], where + ".corner_radius", "at most half the diameter");
    }
    c.flute_length_mm = yaml.positive(yaml.require(t, "flute_length", where), where + ".flute_length");
    if (c.flute_length_mm < c.corner_radius_mm)
      yaml.fail(t["flute_length"], where + ".flute_length", "at least the corner radius");
    c.shank_diameter_mm =
        t["shank_diameter"] ? yaml.positive(t["shank_diameter"], where + ".shank_diameter") : c.diameter_mm;
    c.length_mm = t["length"] ? yaml.positive(t["length"], where + ".length") : c.flute_length_mm;
    if (c.length_mm < c.flute_length_mm) yaml.fail(t["length"], where + ".length", "at least the flute length");
    // The holder (checked for collisions when its diameter is given): a cylinder from the
    // length out of the holder up to the spindle nose, or holder_length long.
    if (t["holder_length"] && !t["holder_diameter"])
      yaml.fail(t["holder_length"], where + ".holder_length", "holder_diameter with it");
    if (t["holder_diameter"]) {
      c.holder_diameter_mm = yaml.positive(t["holder_diameter"], where + ".holder_diameter");
      if (t["holder_length"])
        c.holder_length_mm = yaml.positive(t["holder_length"], where + ".holder_length");
      else if (t["gauge_length"])
        c.holder_length_mm = yaml.positive(t["gauge_length"], where + ".gauge_length") - c.length_mm;
      if (!(c.holder_length_mm > 0.0))
        yaml.fail(t["holder_diameter"], where + ".holder_diameter",
                  "holder_length (or a gauge_length beyond the length) with it");
    }
    // A holder model (the machine check), relative to the file that names it.
    if (const YAML::Node mesh = t["holder_mesh"]) {
      c.holder_mesh_file =
          resolve(std::filesystem::absolute(yaml.file()).parent_path(), yaml.text(mesh, where + ".holder_mesh"));
      std::error_code ec;
      if (!std::filesystem::is_regular_file(c.holder_mesh_file, ec))
        yaml.fail(mesh, where + ".holder_mesh", "an existing mesh file (no file " + c.holder_mesh_file + ")");
    }
    // The machine's kinematics need the spindle nose to tip distance; without one the tool
    // and its holder sit right in the nose.
    c.gauge_length_mm = t["gauge_length"] ? yaml.positive(t["gauge_length"], where + ".gauge_length")
                                          : c.length_mm + c.holder_length_mm;
    if (c.gauge_length_mm < c.length_mm + c.holder_length_mm - 1e-9)
      yaml.fail(t["gauge_length"], where + ".gauge_length",
                "at least the length out of the holder plus the holder length");
    if (c.type != removal::CutterType::VBit && t["angle"])
      yaml.fail(t["angle"], where + ".angle", "an angle only for a V-bit");
    if (!library.emplace(number, c).second) yaml.fail(kv.first, where, "each T number once");
  }
  if (library.empty()) yaml.fail(tools, "tools", "at least one tool");
  return library;
}

void assume_lengths(removal::Cutter& c, double flute_mm) {
  c.flute_length_mm = std::max(flute_mm > 0.0 ? flute_mm : 4.0 * c.diameter_mm, c.corner_radius_mm);
  c.shank_diameter_mm = c.diameter_mm;
  c.length_mm = c.flute_length_mm;
  c.gauge_length_mm = std::max(kAssumedGaugeLengthMm, c.length_mm);
}

std::string tool_library_yaml(const ToolLibrary& tools, const std::string& indent) {
  std::string s = indent + "tools:\n";
  for (const auto& [number, c] : tools) {
    s += indent + "  " + std::to_string(number) + ": {type: ";
    switch (c.type) {
      case removal::CutterType::Flat:
        s += "flat";
        break;
      case removal::CutterType::Ball:
        s += "ball";
        break;
      case removal::CutterType::BullNose:
        s += "bull, corner_radius: " + yaml_number(c.corner_radius_mm);
        break;
      case removal::CutterType::VBit:
        s += "vbit, angle: " + yaml_number(c.tip_angle_deg);
        break;
    }
    s += ", diameter: " + yaml_number(c.diameter_mm) + ", flute_length: " + yaml_number(c.flute_length_mm);
    if (c.shank_diameter_mm != c.diameter_mm) s += ", shank_diameter: " + yaml_number(c.shank_diameter_mm);
    if (c.length_mm != c.flute_length_mm) s += ", length: " + yaml_number(c.length_mm);
    if (c.holder_diameter_mm > 0.0)
      s += ", holder_diameter: " + yaml_number(c.holder_diameter_mm) +
           ", holder_length: " + yaml_number(c.holder_length_mm);
    if (c.gauge_length_mm != c.length_mm + c.holder_length_mm) s += ", gauge_length: " + yaml_number(c.gauge_length_mm);
    s += "}\n";
  }
  return s;
}

}  // namespace vcut::io
