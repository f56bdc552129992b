// The tool library's `tools:` map read from a YAML node: a tool library file's, or a job's
// tools written in the job itself.
#pragma once

#include "vcut/io/tool_library.h"
#include "yaml_util.h"

namespace vcut::io {

ToolLibrary read_tools(const YamlReader& yaml, const YAML::Node& tools);

}  // namespace vcut::io
