#include "check_command.h"

#include <cmath>
#include <cstdio>

#include "vcut/io/job.h"
#include "vcut/pipeline/check.h"
#include "vcut/report/check_report.h"

namespace vcut::cli {
namespace {

int run_check(const std::string& job_file, const std::string& json_out, bool quiet) {
  const io::Job job = io::read_job(job_file);
  const pipeline::CheckResult r = pipeline::run_check(job);
  for (const auto& w : job.warnings) std::fprintf(stderr, "vcut: warning: %s\n", w.c_str());
  for (const auto& w : r.run.program.warnings) std::fprintf(stderr, "vcut: warning: %s\n", w.c_str());
  for (const auto& w : r.notes) std::fprintf(stderr, "vcut: warning: %s\n", w.c_str());
  if (!json_out.empty()) report::write_check_json(json_out, job, r);
  if (!quiet) {
    const double t = r.run.feed.cycle_time_s;
    std::printf("check %s on %s: %zu blocks, %zu poses, cycle time %.1f s (%d:%02d:%02d)\n", job.name.c_str(),
                job.machine.c_str(), r.run.program.blocks.size(), r.run.poses, t, static_cast<int>(t / 3600),
                static_cast<int>(std::fmod(t, 3600.0) / 60), static_cast<int>(std::fmod(t, 60.0)));
    for (const auto& e : r.events)
      std::printf("%-7s %s at %s: %s\n", to_string(e.severity), to_string(e.kind), r.run.program.where(e.lines).c_str(),
                  e.detail.c_str());
    for (const auto& c : r.tools) {
      if (!c.has_holder)
        std::printf("T%d: no holder in the tool library (not checked)\n", c.tool);
      else if (!c.over_stock)
        std::printf("T%d: its holder never comes over the stock\n", c.tool);
      else
        std::printf("T%d: holder %.3f mm %s the stock's top at its lowest over the stock (%s)\n", c.tool,
                    std::abs(c.holder_clearance_mm), c.holder_clearance_mm >= 0.0 ? "above" : "below",
                    r.run.program.where(c.holder_line).c_str());
    }
    if (r.machine_checked)
      std::printf("machine: %zu bodies, %zu pairs, %zu distance queries in %.2f s (clearance %.3g mm)\n",
                  r.bodies.size(), r.body_pairs, r.body_queries, r.machine_seconds, job.machine_clearance_mm);
    std::printf("%s: %zu error(s), %zu warning(s) in %.2f s\n", r.errors == 0 ? "go" : "no-go", r.errors, r.warnings,
                r.wall_time_s);
  }
  return r.errors == 0 ? 0 : 1;
}

}  // namespace

void add_check_command(CLI::App& app, CheckCommand& c) {
  c.command = app.add_subcommand(
      "check",
      "Everything but the cut: parse, densify, time, reach, limits, singularities, "
      "tool clearance against the stock's box, the machine's bodies, fixtures and holder against each "
      "other and the stock; exit 1 on errors");
  c.command->add_option("job", c.job, "Job file (YAML)")->required();
  c.command->add_option("--json", c.json, "Also write the findings as JSON to this file");
  c.command->add_flag("--quiet,-q", c.quiet, "Print nothing but errors and warnings");
}

std::optional<int> run_check_command(const CheckCommand& c) {
  if (!c.command || !*c.command) return std::nullopt;
  return run_check(c.job, c.json, c.quiet);
}

}  // namespace vcut::cli
