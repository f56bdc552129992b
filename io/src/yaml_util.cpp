#include "yaml_util.h"

#include <charconv>

#include <cmath>
#include <fstream>
#include <sstream>
#include <vector>

namespace vcut::io {

YAML::Node YamlReader::load() const {
  std::ifstream in(file_);
  if (!in) throw InputError(file_, 0, 0, "cannot open file for reading");
  std::stringstream text;
  text << in.rdbuf();
  if (in.bad()) throw InputError(file_, 0, 0, "cannot read file");
  try {
    // One document: a second one after '---' would be silently ignored by YAML::Load.
    const std::vector<YAML::Node> documents = YAML::LoadAll(text.str());
    if (documents.size() > 1) {
      const YAML::Mark mark = documents[1].Mark();
      const bool known = !mark.is_null();
      throw InputError(file_, known ? mark.line + 1 : 0, known ? mark.column + 1 : 0,
                       "one YAML document (found a second one after '---')");
    }
    return documents.empty() ? YAML::Node() : documents.front();
  } catch (const YAML::ParserException& e) {
    throw InputError(file_, e.mark.line + 1, e.mark.column + 1, "invalid YAML: " + e.msg);
  }
}

void YamlReader::fail(const YAML::Node& node, const std::string& key, const std::string& expected) const {
  const YAML::Mark mark = node.IsDefined() ? node.Mark() : YAML::Mark::null_mark();
  const int line = mark.is_null() ? 0 : mark.line + 1;
  const int column = mark.is_null() ? 0 : mark.column + 1;
  throw InputError(file_, line, column, "'" + key + "': expected " + expected);
}

void YamlReader::only_keys(const YAML::Node& map, const std::string& where,
                           std::initializer_list<const char*> allowed) const {
  only_keys(map, where, std::vector<std::string>(allowed.begin(), allowed.end()));
}

void YamlReader::only_keys(const YAML::Node& map, const std::string& where,
                           const std::vector<std::string>& allowed) const {
  if (!map.IsMap()) fail(map, where, "a map of keys");
  for (const auto& kv : map) {
    const std::string key = kv.first.as<std::string>();
    bool known = false;
    std::string list;
    for (const std::string& a : allowed) {
      known = known || key == a;
      list += (list.empty() ? "" : ", ") + a;
    }
    if (!known) fail(kv.first, where.empty() ? key : where + "." + key, "one of the keys " + list + " (unknown key)");
  }
}

const YAML::Node YamlReader::require(const YAML::Node& map, const std::string& key, const std::string& where) const {
  const YAML::Node node = map[key];
  if (!node.IsDefined() || node.IsNull()) fail(map, where.empty() ? key : where + "." + key, "a value (missing key)");
  return node;
}

double YamlReader::number(const YAML::Node& node, const std::string& key) const {
  if (!node.IsScalar()) fail(node, key, "a number");
  double value = 0.0;
  try {
    value = node.as<double>();
  } catch (const YAML::Exception&) {
    fail(node, key, "a number, not '" + node.Scalar() + "'");
  }
  if (!std::isfinite(value) || std::abs(value) > 1e9) fail(node, key, "a finite number of sensible size");
  return value;
}

double YamlReader::positive(const YAML::Node& node, const std::string& key) const {
  const double v = number(node, key);
  if (!(v > 0.0)) fail(node, key, "a positive number");
  return v;
}

double YamlReader::non_negative(const YAML::Node& node, const std::string& key) const {
  const double v = number(node, key);
  if (v < 0.0) fail(node, key, "a number >= 0");
  return v;
}

int YamlReader::integer(const YAML::Node& node, const std::string& key) const {
  if (!node.IsScalar()) fail(node, key, "an integer");
  try {
    return node.as<int>();
  } catch (const YAML::Exception&) {
    fail(node, key, "an integer, not '" + node.Scalar() + "'");
  }
}

std::string YamlReader::text(const YAML::Node& node, const std::string& key) const {
  if (!node.IsScalar()) fail(node, key, "a string");
  return node.Scalar();
}

bool YamlReader::boolean(const YAML::Node& node, const std::string& key) const {
  if (!node.IsScalar()) fail(node, key, "true or false");
  try {
    return node.as<bool>();
  } catch (const YAML::Exception&) {
    fail(node, key, "true or false, not '" + node.Scalar() + "'");
  }
}

Eigen::Vector3d YamlReader::vec3(const YAML::Node& node, const std::string& key) const {
  if (!node.IsSequence() || node.size() != 3) fail(node, key, "a list of three numbers [x, y, z]");
  return {number(node[0], key), number(node[1], key), number(node[2], key)};
}

std::string resolve(const std::filesystem::path& base, const std::string& relative) {
  const std::filesystem::path p(relative);
  return (p.is_absolute() ? p : base / p).lexically_normal().string();
}

std::string yaml_number(double v) {
  char buffer[32];
  const auto r = std::to_chars(buffer, buffer + sizeof buffer, v);
  return std::string(buffer, r.ptr);
}

}  // namespace vcut::io
