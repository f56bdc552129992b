// Reading typed values from YAML nodes with errors that name file:line:column and the key.
#pragma once

#include <yaml-cpp/yaml.h>

#include <Eigen/Core>

#include <initializer_list>
#include <filesystem>
#include <string>
#include <vector>

#include "vcut/io/input_error.h"

namespace vcut::io {

// A number as YAML writes it back exactly: the shortest text that reads as the same double.
std::string yaml_number(double v);

// A path a YAML file names, relative to `base` (the file's folder) unless absolute, normalised.
std::string resolve(const std::filesystem::path& base, const std::string& relative);

class YamlReader {
 public:
  explicit YamlReader(std::string file) : file_(std::move(file)) {}

  // Parses the whole file; invalid YAML or a missing file is an InputError.
  YAML::Node load() const;

  [[noreturn]] void fail(const YAML::Node& node, const std::string& key, const std::string& expected) const;
  // Rejects keys of a map that are not in `allowed` (typos are errors, not silence).
  void only_keys(const YAML::Node& map, const std::string& where, std::initializer_list<const char*> allowed) const;
  void only_keys(const YAML::Node& map, const std::string& where, const std::vector<std::string>& allowed) const;

  const YAML::Node require(const YAML::Node& map, const std::string& key, const std::string& where) const;
  double number(const YAML::Node& node, const std::string& key) const;  // finite
  double positive(const YAML::Node& node, const std::string& key) const;
  double non_negative(const YAML::Node& node, const std::string& key) const;
  int integer(const YAML::Node& node, const std::string& key) const;
  std::string text(const YAML::Node& node, const std::string& key) const;
  bool boolean(const YAML::Node& node, const std::string& key) const;
  Eigen::Vector3d vec3(const YAML::Node& node, const std::string& key) const;
  const std::string& file() const { return file_; }

 private:
  std::string file_;
};

}  // namespace vcut::io
