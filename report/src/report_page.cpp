#include "vcut/report/report_page.h"

#include <nlohmann/json.hpp>
#include <tbb/parallel_for.h>
#include <tbb/task_group.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <deque>
#include <filesystem>
#include <fstream>
#include <limits>
#include <map>
#include <sstream>

#include "vcut/io/atomic_file.h"
#include "vcut/io/input_error.h"

namespace vcut::report {

using pipeline::CollisionRecord;
using pipeline::PoseEvent;
using pipeline::PoseRun;
using pipeline::RegionRecord;
using pipeline::SimulationResult;
namespace {

using nlohmann::ordered_json;

ordered_json vec(const Eigen::Vector3d& v) { return ordered_json::array({v.x(), v.y(), v.z()}); }

// The page's arrays, base64 (tens of MB on a fine mesh), bypass the JSON writer, which looks
// at every character of a string to escape it (on W1 at 0.05 mm that and the '<' scan after
// it were a third of the page's 1.3 s): the JSON holds for each a number no field of the page
// takes, 2^64 - 1 - its index (counts and sizes are far smaller, measures are written with a
// point or an exponent), and the page is assembled with the quoted base64 text in its place.
// A number with a sign, a point or an exponent is never one; one inside a string is text.
// The largest (the machined mesh's) are made on other threads while the rest of the page is
// put together, each in its place in the order.
class Blobs {
 public:
  Blobs() = default;
  Blobs(const Blobs&) = delete;
  Blobs& operator=(const Blobs&) = delete;
  ~Blobs() {
    try {
      tasks_.wait();
    } catch (...) {  // the page is not written: its error is the one already on its way
    }
  }
  template <typename T>
  ordered_json of(const std::vector<T>& values) {  // x86-64: little-endian, as the page reads
    texts_.push_back(base64(values.data(), values.size() * sizeof(T)));
    return std::numeric_limits<std::uint64_t>::max() - (texts_.size() - 1);
  }
  // The same for the values `make` returns, made on another thread (wait() before splice()).
  template <typename Make>
  ordered_json later(Make make) {
    texts_.emplace_back();
    std::string* const slot = &texts_.back();  // a deque's elements stay where they are as it grows
    tasks_.run([slot, make] {
      const auto values = make();
      *slot = base64(values.data(), values.size() * sizeof(values[0]));
    });
    return std::numeric_limits<std::uint64_t>::max() - (texts_.size() - 1);
  }
  void wait() { tasks_.wait(); }

  // The JSON text onto `out` with each placeholder (a number, outside the strings: an NC
  // comment may hold the same digits) replaced by its quoted text, and every '<' written as
  // \u003c: inside a <script> element neither "</script" nor "<!--" may appear (an NC comment
  // could hold either); '<' occurs only inside JSON strings, where "\u003c" is the same
  // character. Base64 holds neither '<' nor '"'.
  void splice(const std::string& data, std::ostream& out) const {
    static const std::string kMax = std::to_string(std::numeric_limits<std::uint64_t>::max());
    std::size_t from = 0;
    bool in_string = false;
    for (std::size_t i = 0; i < data.size(); ++i) {
      const char c = data[i];
      if (in_string) {
        if (c == '\\') {
          ++i;  // an escape: the next character (a quote among them) is not special
        } else if (c == '"') {
          in_string = false;
        } else if (c == '<') {
          out.write(data.data() + from, static_cast<std::streamsize>(i - from));
          out << "\\u003c";
          from = i + 1;
        }
        continue;
      }
      if (c == '"') {
        in_string = true;
        continue;
      }
      if (c < '0' || c > '9') continue;
      // A number: a placeholder when it is a whole, unsigned integer of kMax's digits that
      // stands for a held text (not part of a sign, fraction or exponent).
      std::size_t end = i;
      while (end < data.size() && data[end] >= '0' && data[end] <= '9') ++end;
      const bool integer = (i == 0 || std::strchr("-+.eE", data[i - 1]) == nullptr) &&
                           (end == data.size() || std::strchr(".eE", data[end]) == nullptr);
      if (integer && end - i == kMax.size() && data.compare(i, end - i, kMax) <= 0) {
        const std::uint64_t index = std::numeric_limits<std::uint64_t>::max() - std::stoull(data.substr(i, end - i));
        if (index < texts_.size()) {
          out.write(data.data() + from, static_cast<std::streamsize>(i - from));
          out << '"' << texts_[static_cast<std::size_t>(index)] << '"';
          from = end;
        }
      }
      i = end - 1;
    }
    out.write(data.data() + from, static_cast<std::streamsize>(data.size() - from));
  }

 private:
  std::deque<std::string> texts_;
  tbb::task_group tasks_;
};

std::vector<float> positions_of(const removal::TriangleMesh& mesh) {
  std::vector<float> positions;
  positions.reserve(mesh.vertices_mm.size() * 3);
  for (const auto& p : mesh.vertices_mm)
    for (int k = 0; k < 3; ++k) positions.push_back(static_cast<float>(p[k]));
  return positions;
}

std::vector<std::uint32_t> indices_of(const removal::TriangleMesh& mesh) {
  std::vector<std::uint32_t> indices;
  indices.reserve(mesh.triangles.size() * 3);
  for (const auto& t : mesh.triangles)
    for (int k = 0; k < 3; ++k) indices.push_back(static_cast<std::uint32_t>(t[k]));
  return indices;
}

ordered_json encode_mesh(const removal::TriangleMesh& mesh, Blobs& blobs) {
  return {{"vertices", mesh.vertices_mm.size()},
          {"triangles", mesh.triangles.size()},
          {"positions", blobs.of(positions_of(mesh))},
          {"indices", blobs.of(indices_of(mesh))}};
}

// encode_mesh on other threads: `mesh` must outlive `blobs`.
ordered_json encode_mesh_later(const removal::TriangleMesh& mesh, Blobs& blobs) {
  return {{"vertices", mesh.vertices_mm.size()},
          {"triangles", mesh.triangles.size()},
          {"positions", blobs.later([&mesh] { return positions_of(mesh); })},
          {"indices", blobs.later([&mesh] { return indices_of(mesh); })}};
}

// The NC lines a report names, with their text: a region's spans, an event's blocks (from the
// first block's line to the last's in one file, else the first's alone), at most 20 each.
class SourceTexts {
 public:
  SourceTexts(const kinematics::Program& program, const std::vector<std::string>& paths)
      : program_(program), paths_(paths) {}

  // Index in the sources table of a block's line (-1 for no block): each block's looked up
  // once (W1's page names 706 k vertices' blocks).
  int of_block(int block) {
    if (block < 0) return -1;
    if (block_index_.empty()) block_index_.assign(program_.blocks.size(), -2);
    int& i = block_index_[static_cast<std::size_t>(block)];
    if (i == -2) {
      const kinematics::SourceRef& src = program_.blocks[static_cast<std::size_t>(block)].source;
      i = index(src.file, src.line);
    }
    return i;
  }
  // Index in the sources table of a program line (registered for reading).
  int index(int file, int line) {
    const auto key = std::make_pair(file, line);
    const auto it = index_.find(key);
    if (it != index_.end()) return it->second;
    const int i = static_cast<int>(refs_.size());
    index_.emplace(key, i);
    refs_.push_back(key);
    return i;
  }
  // The lines of a span, each registered: at most `limit`.
  std::vector<int> add(const kinematics::SourceSpan& span, std::size_t limit = 20) {
    std::vector<int> out;
    for (int l = span.first_line; l <= span.last_line && out.size() < limit; ++l) out.push_back(index(span.file, l));
    return out;
  }
  // Reads every registered line's text (each file once, streaming) and returns the table.
  ordered_json table() const {
    // The registered lines by file and line (each registered once), each file read up to the
    // last of them; a line that is not in the file has no text.
    std::vector<std::size_t> order(refs_.size());
    for (std::size_t i = 0; i < order.size(); ++i) order[i] = i;
    std::sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) { return refs_[a] < refs_[b]; });
    std::vector<std::string> text(refs_.size());
    for (std::size_t first = 0; first < order.size();) {
      const int file = refs_[order[first]].first;
      std::size_t last = first;
      while (last < order.size() && refs_[order[last]].first == file) ++last;
      if (file >= 0 && static_cast<std::size_t>(file) < paths_.size()) {
        std::ifstream in(paths_[static_cast<std::size_t>(file)]);
        std::string s;
        int n = 0;
        for (std::size_t k = first; k < last;) {
          const int wanted = refs_[order[k]].second;
          if (wanted <= n) {  // before the file's first line
            ++k;
            continue;
          }
          if (!std::getline(in, s)) break;
          if (++n < wanted) continue;
          if (!s.empty() && s.back() == '\r') s.pop_back();
          if (s.size() > 200) s = s.substr(0, 200) + "...";
          text[order[k]] = std::move(s);
          ++k;
        }
      }
      first = last;
    }
    ordered_json out = ordered_json::array();
    out.get_ref<ordered_json::array_t&>().reserve(refs_.size());
    for (std::size_t i = 0; i < refs_.size(); ++i)
      out.push_back({{"file", program_.files[static_cast<std::size_t>(refs_[i].first)]},
                     {"line", refs_[i].second},
                     {"text", std::move(text[i])}});
    return out;
  }
  ordered_json lines_of(const std::vector<int>& indices, const ordered_json& table) const {
    ordered_json out = ordered_json::array();
    for (int i : indices) out.push_back(table[static_cast<std::size_t>(i)]);
    return out;
  }

 private:
  const kinematics::Program& program_;
  const std::vector<std::string>& paths_;
  std::map<std::pair<int, int>, int> index_;
  std::vector<std::pair<int, int>> refs_;
  std::vector<int> block_index_;  // -2: not looked up yet
};

const char* body_kind_name(pipeline::BodyKind kind) {
  switch (kind) {
    case pipeline::BodyKind::Model:
      return "model";
    case pipeline::BodyKind::Fixture:
      return "fixture";
    case pipeline::BodyKind::Stock:
      return "stock";
    case pipeline::BodyKind::Cutter:
      return "cutter";
    case pipeline::BodyKind::Shank:
      return "shank";
    case pipeline::BodyKind::Holder:
      return "holder";
  }
  return "model";
}

// The machine posed along the program (pipeline::Playback), each frame with its time (the
// timeline's, interpolated by sample) and NC line; null when nothing was posed.
ordered_json playback_json(const pipeline::Playback& play, const PoseRun& run, SourceTexts& sources, Blobs& blobs) {
  if (play.frame_sample.empty()) return nullptr;
  const std::size_t frames = play.frame_sample.size();
  ordered_json bodies = ordered_json::array();
  for (const pipeline::Playback::Body& b : play.bodies) {
    ordered_json body = {{"name", b.name}, {"kind", body_kind_name(b.kind)}, {"node", b.node}, {"tool", b.tool}};
    body["mesh"] = encode_mesh(b.mesh, blobs);
    bodies.push_back(body);
  }
  // Time at a sample: linear between the timeline's points (its samples rise).
  const auto& line = run.timeline;
  auto time_at = [&line](std::size_t sample) {
    if (line.sample.empty() || line.sample.size() != line.t_s.size()) return 0.0;
    const auto next = std::upper_bound(line.sample.begin(), line.sample.end(), sample);
    if (next == line.sample.begin()) return line.t_s.front();
    if (next == line.sample.end()) return line.t_s.back();
    const std::size_t b = static_cast<std::size_t>(next - line.sample.begin()), a = b - 1;
    const double f =
        static_cast<double>(sample - line.sample[a]) / static_cast<double>(line.sample[b] - line.sample[a]);
    return line.t_s[a] + f * (line.t_s[b] - line.t_s[a]);
  };
  std::vector<float> t_s;
  std::vector<std::int32_t> sample, source;
  for (std::size_t f = 0; f < frames; ++f) {
    t_s.push_back(static_cast<float>(time_at(play.frame_sample[f])));
    sample.push_back(static_cast<std::int32_t>(play.frame_sample[f]));
    source.push_back(sources.of_block(play.frame_block[f]));
  }
  ordered_json nodes = ordered_json::array();
  for (char n : play.nodes) nodes.push_back(std::string(1, n));
  // A pose whose rotation is the same in every frame (every pose of a three-axis machine)
  // gives its rotation once and its translation per frame: 3 floats a frame instead of 12.
  const std::size_t slots = play.nodes.size() + 1, per = 12 * slots;
  ordered_json layout = ordered_json::array();
  std::vector<bool> fixed_rotation(slots, true);
  for (std::size_t k = 0; k < slots; ++k) {
    const float* first = play.frame_pose.data() + 12 * k;
    for (std::size_t f = 1; f < frames && fixed_rotation[k]; ++f)
      for (int c : {0, 1, 2, 4, 5, 6, 8, 9, 10})
        if (play.frame_pose[f * per + 12 * k + static_cast<std::size_t>(c)] != first[c]) fixed_rotation[k] = false;
    layout.push_back(fixed_rotation[k] ? ordered_json{{"rotation",
                                                       {first[0], first[1], first[2], first[4], first[5], first[6],
                                                        first[8], first[9], first[10]}}}
                                       : ordered_json{{"rotation", nullptr}});
  }
  std::vector<float> pose;
  for (std::size_t f = 0; f < frames; ++f)
    for (std::size_t k = 0; k < slots; ++k) {
      const float* m = play.frame_pose.data() + f * per + 12 * k;
      if (fixed_rotation[k])
        pose.insert(pose.end(), {m[3], m[7], m[11]});
      else
        pose.insert(pose.end(), m, m + 12);
    }
  std::vector<std::int32_t> block(play.frame_block.begin(), play.frame_block.end());
  std::vector<std::int32_t> tool(play.frame_tool.begin(), play.frame_tool.end());
  std::vector<std::int32_t> path_block(play.path_block.begin(), play.path_block.end());
  return {{"nodes", nodes},
          {"bodies", bodies},
          {"frames",
           {{"count", frames},
            {"t_s", blobs.of(t_s)},
            {"sample", blobs.of(sample)},
            {"block", blobs.of(block)},
            {"tool", blobs.of(tool)},
            {"source", blobs.of(source)},
            {"layout", layout},
            {"pose", blobs.of(pose)}}},
          {"path",
           {{"points", play.path_block.size()},
            {"position", blobs.of(play.path_mm)},
            {"block", blobs.of(path_block)},
            {"rapid", blobs.of(play.path_rapid)}}}};
}

std::string fixed(double x, int digits, const char* unit) {
  std::ostringstream s;
  s.precision(digits);
  s << std::fixed << x << (*unit ? " " : "") << unit;
  return s.str();
}

}  // namespace

std::string base64(const void* data, std::size_t bytes) {
  static const char* kAlphabet = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  const auto* p = static_cast<const std::uint8_t*>(data);
  std::string out((bytes + 2) / 3 * 4, '=');
  // Whole groups of three bytes, in chunks side by side (each chunk's text has its own place).
  const std::size_t groups = bytes / 3;
  constexpr std::size_t kChunkGroups = std::size_t{1} << 16;
  tbb::parallel_for(std::size_t{0}, (groups + kChunkGroups - 1) / kChunkGroups, [&](std::size_t c) {
    const std::size_t g1 = std::min(groups, (c + 1) * kChunkGroups);
    char* o = out.data() + 4 * c * kChunkGroups;
    for (std::size_t g = c * kChunkGroups; g < g1; ++g, o += 4) {
      const std::size_t i = 3 * g;
      const std::uint32_t v =
          static_cast<std::uint32_t>(p[i]) << 16 | static_cast<std::uint32_t>(p[i + 1]) << 8 | p[i + 2];
      o[0] = kAlphabet[(v >> 18) & 63];
      o[1] = kAlphabet[(v >> 12) & 63];
      o[2] = kAlphabet[(v >> 6) & 63];
      o[3] = kAlphabet[v & 63];
    }
  });
  const std::size_t i = 3 * groups;
  char* o = out.data() + 4 * groups;
  if (i < bytes) {  // one or two bytes left: two or three characters, then '=' padding
    std::uint32_t v = static_cast<std::uint32_t>(p[i]) << 16;
    if (i + 1 < bytes) v |= static_cast<std::uint32_t>(p[i + 1]) << 8;
    o[0] = kAlphabet[(v >> 18) & 63];
    o[1] = kAlphabet[(v >> 12) & 63];
    if (i + 1 < bytes) o[2] = kAlphabet[(v >> 6) & 63];
  }
  return out;
}

std::string report_template_path() {
  if (const char* env = std::getenv("VCUT_REPORT_TEMPLATE"); env != nullptr && *env != '\0') return env;
#ifdef VCUT_REPORT_TEMPLATE
  if (std::filesystem::exists(VCUT_REPORT_TEMPLATE)) return VCUT_REPORT_TEMPLATE;
#endif
  return "";
}

void write_report_page(const std::string& path, const std::string& template_path, const io::Job& job,
                       const pipeline::SimulationResult& r, const ReportPageInput& input) {
  std::string page;
  {
    std::ifstream in(template_path, std::ios::binary);
    if (!in) throw InputError(template_path, 0, 0, "cannot read the report page template");
    std::ostringstream s;
    s << in.rdbuf();
    page = s.str();
  }
  const std::size_t slot = page.find(kReportDataMarker);
  if (slot == std::string::npos)
    throw InputError(template_path, 0, 0,
                     std::string("not a report page template (no ") + kReportDataMarker + " slot)");

  const PoseRun& run = r.pose_run;
  const kinematics::Program& program = run.program;
  SourceTexts sources(program, job.program_files);
  ordered_json j;
  j["schema"] = "vcut-report-page/1";
  j["title"] = r.job_name;

  // Job settings, as rows a person reads.
  ordered_json settings = ordered_json::array();
  auto row = [&](const std::string& k, const std::string& v) { settings.push_back({k, v}); };
  std::string files;
  for (const auto& f : program.files) files += (files.empty() ? "" : ", ") + f;
  row("program", files + " (" + io::reader_name(run.reader) + ")");
  row("machine", job.machine);
  row("engine", std::string(io::engine_name(job.engine)) + ", " + fixed(r.resolution_mm, 3, "mm") + ", " +
                    std::to_string(r.threads) + " threads");
  if (job.step_mm > 0.0) row("densify step", fixed(job.step_mm, 3, "mm"));
  if (job.angle_step_deg > 0.0) row("densify angle", fixed(job.angle_step_deg, 3, "deg"));
  if (job.densify_tolerance_mm > 0.0) row("densify tolerance", fixed(job.densify_tolerance_mm, 4, "mm"));
  row("chord tolerance", fixed(pipeline::chord_tolerance_mm(job, r.resolution_mm), 4, "mm"));
  row("turn tolerance", fixed(pipeline::turn_tolerance_mm(job, r.resolution_mm), 4, "mm"));
  row("servo", job.servo ? "on" : "off");
  row("machine errors", job.apply_errors ? "on" : "off");
  row("tolerances", "gouge " + fixed(job.gouge_tolerance_mm, 3, "mm") + ", excess " +
                        fixed(job.excess_tolerance_mm, 3, "mm") + ", collision " +
                        fixed(job.collision_tolerance_mm, 3, "mm"));
  for (const auto& [number, tool] : run.tools)
    row("T" + std::to_string(number),
        removal::to_string(tool.type) + " D" + fixed(tool.diameter_mm, 3, "") + " r" +
            fixed(tool.corner_radius_mm, 3, "") + ", flutes " + fixed(tool.flute_length_mm, 1, "mm") +
            ", out of holder " + fixed(tool.length_mm, 1, "mm") +
            (tool.holder_diameter_mm > 0.0 ? ", holder D" + fixed(tool.holder_diameter_mm, 1, "") : ""));
  j["job"] = {{"name", job.name},
              {"file", job.file},
              {"engine", io::engine_name(job.engine)},
              {"resolution_mm", r.resolution_mm},
              {"threads", r.threads},
              {"machine", job.machine},
              {"gouge_tolerance_mm", job.gouge_tolerance_mm},
              {"excess_tolerance_mm", job.excess_tolerance_mm},
              {"collision_tolerance_mm", job.collision_tolerance_mm},
              {"settings", settings}};

  // The machined mesh, decimated for the page where it has more triangles than the page takes
  // (else the mesh itself, not a copy); each vertex keeps its deviation and NC line.
  const removal::SurfaceMesh& machined = *input.machined;
  const bool whole = machined.mesh.triangles.size() <= input.max_triangles;
  std::vector<int> kept;  // the shown vertices' indices in the machined mesh, where decimated
  removal::TriangleMesh decimated;
  if (!whole) decimated = removal::decimate(machined.mesh, input.max_triangles, kept);
  const removal::TriangleMesh& shown = whole ? machined.mesh : decimated;
  const std::size_t shown_vertices = shown.vertices_mm.size();
  auto original = [&](std::size_t i) { return whole ? i : static_cast<std::size_t>(kept[i]); };
  Blobs blobs;
  ordered_json mesh = encode_mesh_later(shown, blobs);
  if (!input.deviation_mm.empty()) {
    std::vector<float> deviation;
    deviation.reserve(shown_vertices);
    for (std::size_t i = 0; i < shown_vertices; ++i)
      deviation.push_back(static_cast<float>(input.deviation_mm[original(i)]));
    mesh["deviation"] = blobs.of(deviation);
  } else {
    mesh["deviation"] = nullptr;
  }
  // The block that made each vertex (-1: the initial stock; the playback shows the part as cut
  // up to its frame's block) and its NC line.
  std::vector<std::int32_t> vertex_block, vertex_source;
  vertex_block.reserve(shown_vertices);
  vertex_source.reserve(shown_vertices);
  for (std::size_t i = 0; i < shown_vertices; ++i) {
    const int move = machined.vertex_move[original(i)];
    const bool known =
        move >= 0 && input.move_blocks != nullptr && static_cast<std::size_t>(move) < input.move_blocks->size();
    vertex_block.push_back(known ? (*input.move_blocks)[static_cast<std::size_t>(move)] : -1);
    vertex_source.push_back(sources.of_block(vertex_block.back()));
  }
  mesh["source"] = blobs.of(vertex_source);
  mesh["block"] = blobs.of(vertex_block);
  j["mesh"] = std::move(mesh);
  if (input.design != nullptr) {
    const removal::TriangleMesh& design = *input.design;
    std::vector<int> design_kept;
    j["design"] = design.triangles.size() <= input.max_triangles / 4
                      ? encode_mesh(design, blobs)
                      : encode_mesh(removal::decimate(design, input.max_triangles / 4, design_kept), blobs);
  } else {
    j["design"] = nullptr;
  }
  j["stock"] = {{"box", {{"min", vec(input.stock_box.min())}, {"max", vec(input.stock_box.max())}}}};

  // Regions and events, each with its NC lines.
  std::vector<std::pair<ordered_json, std::vector<int>>> regions, events;
  auto add_regions = [&](const char* kind, const std::vector<RegionRecord>& list) {
    for (const RegionRecord& g : list) {
      std::vector<int> refs;
      for (const kinematics::SourceSpan& span : g.spans)
        for (int i : sources.add(span, 20 - std::min<std::size_t>(20, refs.size()))) refs.push_back(i);
      regions.push_back({{{"kind", kind},
                          {"depth_mm", g.depth_mm},
                          {"area_mm2", g.area_mm2},
                          {"centroid", vec(g.centroid_mm)},
                          {"deepest", vec(g.deepest_mm)},
                          {"lines", run.program.where(g.spans)},
                          {"tools", g.tools},
                          {"initial_stock", g.initial_stock}},
                         refs});
    }
  };
  add_regions("gouge", r.gouges);
  add_regions("excess", r.excess);
  for (const CollisionRecord& c : r.collisions) {
    std::ostringstream detail;
    detail << "the " << pipeline::collision_part(c.probe) << " of T" << c.tool << " in material over " << c.moves
           << " move(s); deepest at " << run.program.where(c.deepest_line);
    events.push_back({{{"kind", pipeline::collision_kind(c.probe)},
                       {"line", run.program.where(c.lines)},
                       {"detail", detail.str()},
                       {"depth_mm", c.depth_mm},
                       {"where", vec(c.where_mm)},
                       {"block", c.first_block}},
                      sources.add(kinematics::Program::span_in_first_file(c.lines))});
  }
  const pipeline::Playback& play = r.machine.playback;
  const std::size_t pose_floats = play.floats_per_pose();
  for (std::size_t n = 0; n < r.machine.contacts.size(); ++n) {
    const pipeline::MachineContact& c = r.machine.contacts[n];
    std::ostringstream detail;
    detail.precision(3);
    detail << std::fixed << c.a << (c.hit ? " hits " : " passes ") << c.b;
    if (c.hit)
      detail << ", " << c.depth_mm << " mm deep";
    else
      detail << " at " << c.clearance_mm << " mm";
    detail << (c.between_poses ? ", between two poses" : "") << " (" << pipeline::axis_text(*run.machine, c.axes)
           << ")";
    // The machine at the contact's instant, for the playback (which may lie between its frames).
    ordered_json pose = nullptr;
    if (play.contact_pose.size() >= (n + 1) * pose_floats)
      pose = std::vector<float>(play.contact_pose.begin() + static_cast<std::ptrdiff_t>(n * pose_floats),
                                play.contact_pose.begin() + static_cast<std::ptrdiff_t>((n + 1) * pose_floats));
    events.push_back({{{"kind", c.hit ? "machine_collision" : "machine_near_miss"},
                       {"line", run.program.where(c.lines)},
                       {"detail", detail.str()},
                       {"depth_mm", c.hit ? ordered_json(c.depth_mm) : ordered_json(nullptr)},
                       {"where", vec(c.where_mm)},
                       {"block", c.first_block},
                       {"bodies", {c.a, c.b}},
                       {"sample", c.sample},
                       {"pose", pose}},
                      sources.add(kinematics::Program::span_in_first_file(c.lines))});
  }
  for (const PoseEvent& e : run.events)
    events.push_back(
        {{{"kind", pipeline::to_string(e.kind)},
          {"line", run.program.where(e.lines)},
          {"detail", e.detail},
          {"depth_mm", nullptr},
          {"where", nullptr},
          {"block", e.first_block}},
         e.first_block < 0 ? std::vector<int>{} : sources.add(kinematics::Program::span_in_first_file(e.lines))});

  // Feed and contour error over time, at most 4,000 points (PoseRun::timeline: each the
  // largest contour error of its stretch, so peaks survive).
  ordered_json timeline = nullptr;
  const PoseRun::Timeline& line = run.timeline;
  if (!line.t_s.empty()) {
    const bool contour = line.contour_error_um.size() == line.t_s.size();
    ordered_json ts = ordered_json::array(), feed = ordered_json::array(), err = ordered_json::array();
    for (std::size_t p = 0; p < line.t_s.size(); ++p) {
      ts.push_back(std::round(line.t_s[p] * 1e4) / 1e4);
      feed.push_back(std::round(line.speed_mm_per_s[p] * 60.0 * 10) / 10);
      if (contour) err.push_back(std::round(line.contour_error_um[p] * 1e3) / 1e3);
    }
    timeline = {{"t_s", ts}, {"feed_mm_min", feed}, {"contour_error_um", contour ? err : ordered_json(nullptr)}};
  }

  j["playback"] = playback_json(play, run, sources, blobs);

  ordered_json table = sources.table();
  j["sources"] = nullptr;  // its place; the table itself moves in once the regions and events have their lines
  j["regions"] = ordered_json::array();
  for (auto& [record, refs] : regions) {
    record["nc"] = sources.lines_of(refs, table);
    j["regions"].push_back(std::move(record));
  }
  j["events"] = ordered_json::array();
  for (auto& [record, refs] : events) {
    record["nc"] = sources.lines_of(refs, table);
    j["events"].push_back(std::move(record));
  }
  j["sources"] = std::move(table);  // W1's page names 67 k lines: a copy cost a tenth of the page
  if (r.compared) {
    ordered_json edges = ordered_json::array();
    for (double e : r.histogram_edges_mm) edges.push_back(std::isinf(e) ? ordered_json(nullptr) : ordered_json(e));
    j["histogram"] = {{"edges_mm", edges}, {"counts", r.histogram_counts}, {"area_mm2", r.histogram_area_mm2}};
  } else {
    j["histogram"] = nullptr;
  }
  j["timeline"] = timeline;

  ordered_json stages = ordered_json::array();
  for (const auto& [name, seconds] : r.stage_seconds) stages.push_back({name, seconds});
  j["summary"] = {{"blocks", r.blocks},
                  {"moves", r.moves},
                  {"cutting_moves", r.cutting_moves},
                  {"removed_volume_mm3", r.removed_volume_mm3},
                  {"initial_volume_mm3", r.initial_volume_mm3},
                  {"max_gouge_mm", r.max_gouge_mm},
                  {"max_gouge_line", r.endpoints.done ? run.program.where(r.endpoints.deepest_line) : std::string()},
                  {"max_excess_mm", r.max_excess_mm},
                  {"wall_time_s", r.wall_time_s},
                  {"peak_memory_mb", r.peak_memory_mb},
                  {"cycle_time_s", run.feed.cycle_time_s},
                  {"stage_seconds", stages},
                  {"triangles_shown", shown.triangles.size()},
                  {"triangles_machined", machined.mesh.triangles.size()}};
  // What the readers and the pipeline warned about (M codes the machine does not declare,
  // nested comments, #3006 stops ...), each naming its file:line.
  j["warnings"] = r.warnings;
  if (!job.assumptions.empty()) j["assumptions"] = job.assumptions;

  const std::string data = j.dump(-1, ' ', false, ordered_json::error_handler_t::replace);
  blobs.wait();
  // Written as it is put together: the page is tens of MB, and a copy of it in memory cost
  // W1's page a tenth of its time.
  io::write_stream_atomically(path, [&](std::ostream& out) {
    out.write(page.data(), static_cast<std::streamsize>(slot));
    blobs.splice(data, out);
    const std::size_t rest = slot + std::strlen(kReportDataMarker);
    out.write(page.data() + rest, static_cast<std::streamsize>(page.size() - rest));
  });
}

}  // namespace vcut::report
