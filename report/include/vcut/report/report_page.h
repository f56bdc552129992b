// report.html: the page a person reads (built from web/ at build time: three.js and the
// page's code inlined into one template) with this run's data put into its one data slot.
// One self-contained file that opens offline from disk. Written atomically.
#pragma once

#include <Eigen/Geometry>

#include <cstddef>
#include <optional>
#include <string>
#include <vector>

#include "vcut/io/job.h"
#include "vcut/pipeline/simulate.h"
#include "vcut/removal/mesh.h"
#include "vcut/removal/stock.h"

namespace vcut::report {

// The marker the template holds once, inside <script id="vcut-data" type="application/json">.
inline constexpr const char* kReportDataMarker = "__VCUT_REPORT_DATA__";

struct ReportPageInput {
  const removal::SurfaceMesh* machined = nullptr;
  const std::vector<int>* move_blocks = nullptr;  // the block of each move cut (vertex_move indexes it)
  std::vector<double> deviation_mm;               // per machined vertex; empty: no design
  const removal::TriangleMesh* design = nullptr;  // in the workpiece frame; null: none
  Eigen::AlignedBox3d stock_box;
  std::size_t max_triangles = 2'000'000;  // the machined mesh is decimated to this for the page
};

// The template to fill: $VCUT_REPORT_TEMPLATE when set, else the one this build made
// (<build>/web/report-template.html). Empty when neither exists.
std::string report_template_path();

// Throws vcut::InputError when the template cannot be read or holds no data slot.
void write_report_page(const std::string& path, const std::string& template_path, const io::Job& job,
                       const pipeline::SimulationResult& result, const ReportPageInput& input);

// Standard base64 (RFC 4648, with padding) of raw bytes.
std::string base64(const void* data, std::size_t bytes);

}  // namespace vcut::report
