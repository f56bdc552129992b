// CAMotics projects (.camotics, JSON) read as jobs, and CAMotics tool tables (the `tools` map
// of a project, or a file holding only it): what a CAMotics user already has.
//   {"units": "metric", "resolution": 0.29, "tools": {"1": {"units": "imperial", "shape":
//    "ballnose", "length": 1, "diameter": 0.125}}, "workpiece": {"automatic": false,
//    "margin": 5, "bounds": {"min": [0, 0, -20], "max": [80, 80, 0]}}, "files": ["bear.nc"]}
// Lengths of the workpiece and the resolution are mm (CAMotics stores them so whatever the
// display units); each tool's length and diameter are in its own "units". Shapes:
// cylindrical (flat end mill), ballnose, conical (a V-bit of 2 atan(radius / length)
// included); snubnose (a truncated cone) has no cutter type and is an error. The workpiece
// is the bounds as saved (with "automatic" they are the box CAMotics computed from the tool
// path, margin included). A machine, a gauge length and a design are not in a project: the
// job takes 3axis, 100 mm and none, listed in Job::assumptions.
#pragma once

#include <string>

#include "vcut/io/job.h"
#include "vcut/io/tool_library.h"

namespace vcut::io {

// Throws InputError naming file:line:column for JSON that does not parse, and the key for a
// value of the wrong kind.
Job read_camotics_project(const std::string& path);
ToolLibrary read_camotics_tools(const std::string& path);

}  // namespace vcut::io
