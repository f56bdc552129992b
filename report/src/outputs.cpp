#include "vcut/report/outputs.h"

#include <tbb/global_control.h>
#include <tbb/task_group.h>

#include <algorithm>
#include <chrono>
#include <filesystem>
#include <string>
#include <vector>

#include "vcut/io/mesh_io.h"
#include "vcut/io/sha256.h"
#include "vcut/removal/mesh.h"
#include "vcut/report/report.h"
#include "vcut/report/report_page.h"
#include "vcut/report/snapshot.h"

namespace vcut::report {

void write_simulation(const std::string& out_dir, const io::Job& job, pipeline::SimulationResult& result,
                      const std::function<void(const std::string&, std::size_t, std::size_t)>& progress) {
  using Clock = std::chrono::steady_clock;
  const auto t_start = Clock::now();
  const double wall_before_s = result.wall_time_s;
  auto wall_now = [&] { return wall_before_s + std::chrono::duration<double>(Clock::now() - t_start).count(); };
  // The mesh, the deviation map, the pictures and the page only read the results: they are
  // written side by side (the kernel's copying of 100 MB into files is a good part of this
  // stage) and listed in a fixed order.
  // The run's thread count holds for its outputs too (simulate() limits its own stages).
  tbb::global_control limit(tbb::global_control::max_allowed_parallelism,
                            static_cast<std::size_t>(std::max(1, result.threads)));
  if (progress) progress("write", 0, 1);
  for (const auto& f : result.input_files)
    result.input_hashes.emplace_back(io::display_name(f, job.file), io::sha256_file(f));
  const std::filesystem::path out(out_dir);
  const removal::SurfaceMesh& machined = result.machined;
  const std::vector<double>& deviation = result.deviation_mm;
  const kinematics::Program& program = result.pose_run.program;
  const double colour_scale = [&] {
    const double scale = std::max(3.0 * job.gouge_tolerance_mm, job.excess_tolerance_mm);
    return scale > 0.0 ? scale : result.resolution_mm;
  }();
  std::vector<std::string> snapshot_files;
  const std::string page = report_template_path();
  // The page shows the run's time and memory up to its writing.
  result.wall_time_s = wall_now();
  result.peak_memory_mb = pipeline::peak_memory_mb();
  tbb::task_group writers;
  writers.run([&] { io::write_stl((out / "machined.stl").string(), machined.mesh); });
  if (result.compared) {
    writers.run([&] {
      io::PlyAttributes a;
      a.normals = removal::vertex_normals(machined.mesh);
      for (double d : deviation) a.colors.push_back(io::deviation_color(d, colour_scale));
      a.deviation_mm = deviation;
      a.move = machined.vertex_move;
      for (int m : machined.vertex_move) {
        const int block = m < 0 ? -1 : result.move_blocks[static_cast<std::size_t>(m)];
        a.line.push_back(block < 0 ? 0 : program.blocks[static_cast<std::size_t>(block)].source.line);
      }
      io::write_deviation_ply((out / "deviation.ply").string(), machined.mesh, a);
    });
  }
  writers.run([&] {
    // Pictures for reports and CI artefacts: the deviation map (or the bare machined stock
    // when there is no design) from three fixed views.
    SnapshotOptions options;
    std::vector<Rgb> colours;
    std::string stem = "machined";
    options.title = job.name.empty() ? std::string("machined stock") : job.name;
    if (result.compared) {
      const double s = colour_scale;
      for (double d : deviation) colours.push_back(io::deviation_color(d, s));
      options.legend = ColourScale{"deviation (mm): red gouge, blue excess", -s, s,
                                   [s](double d) { return io::deviation_color(d, s); }, 5};
      stem = "deviation";
    }
    snapshot_files = write_snapshots(out.string(), stem, machined.mesh, colours, options);
  });
  writers.run([&] { write_gouges_csv((out / "gouges.csv").string(), result); });
  writers.run([&] { write_collisions_csv((out / "collisions.csv").string(), result); });
  if (!page.empty()) {
    writers.run([&] {
      ReportPageInput in;
      in.machined = &machined;
      in.move_blocks = &result.move_blocks;
      in.deviation_mm = deviation;
      in.design = result.design ? &*result.design : nullptr;
      in.stock_box = result.stock_box;
      in.max_triangles = job.page_triangles;
      write_report_page((out / "report.html").string(), page, job, result, in);
    });
  }
  writers.wait();
  result.outputs.push_back("machined.stl");
  if (result.compared) result.outputs.push_back("deviation.ply");
  for (const auto& f : snapshot_files) result.outputs.push_back(f);
  result.outputs.push_back("gouges.csv");
  result.outputs.push_back("collisions.csv");
  if (!page.empty())
    result.outputs.push_back("report.html");
  else
    result.warnings.push_back(
        "report.html not written: its page template was not built (it needs Node.js and npm; `make` builds it from "
        "web/)");
  result.stage_seconds.emplace_back("write", std::chrono::duration<double>(Clock::now() - t_start).count());
  result.outputs.push_back("report.json");
  result.wall_time_s = wall_now();
  result.peak_memory_mb = pipeline::peak_memory_mb();
  write_report_json((out / "report.json").string(), out_dir, job, result);
}

}  // namespace vcut::report
