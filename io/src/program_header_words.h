// The cutter a tool's description names (shared by the program header scanner and the tool
// table reader).
#pragma once

#include <string>

#include "vcut/removal/cutter.h"

namespace vcut::io::detail {

// From upper-case words: BALL -> ball end mill; CHAMFER, SPOT, ENGRAV..., V-BIT, CENTER
// DRILL -> a V-bit of `angle_deg` included (90 unless given); DRILL -> a twist drill (118
// unless given); else a bull nose when 0 < corner < d/2, a ball when corner >= d/2, flat.
removal::Cutter cutter_of_words(const std::string& words, double diameter_mm, double corner_mm, double angle_deg);

}  // namespace vcut::io::detail
