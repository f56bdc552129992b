#include "vcut/pipeline/machine_check.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <limits>
#include <map>
#include <memory>
#include <optional>
#include <utility>

#include "fcl_queries.h"
#include "vcut/io/input_error.h"
#include "vcut/io/mesh_io.h"
#include "vcut/kinematics/forward_kinematics.h"
#include "vcut/pipeline/simulate.h"
#include "vcut/removal/cutter.h"
#include "vcut/removal/move.h"

namespace vcut::pipeline {

namespace {

using kinematics::AxisValues;

// A body: a closed triangle mesh in its own coordinates, hung on a node. `local` takes body
// coordinates to the node's coordinates, which coincide with the frame F at all-zero axes.
struct Body {
  std::string name;
  BodySide side = BodySide::Frame;
  BodyKind kind = BodyKind::Model;
  char node = 'F';
  int slot = 0;  // the node's place in Frames
  int tool = 0;  // tool parts: the T number they belong to
  Eigen::Isometry3d local = Eigen::Isometry3d::Identity();
  removal::TriangleMesh mesh;
  std::shared_ptr<const detail::CollisionMesh> bvh;
  Eigen::Vector3d center = Eigen::Vector3d::Zero();  // bounding sphere, body coordinates
  double radius_mm = 0.0;
  Eigen::AlignedBox3d box;  // body coordinates
};

void finish(Body& b) {
  const auto& v = b.mesh.vertices_mm;
  Eigen::AlignedBox3d box;
  for (const Eigen::Vector3d& p : v) box.extend(p);
  b.box = box;
  b.center = box.center();
  for (const Eigen::Vector3d& p : v) b.radius_mm = std::max(b.radius_mm, (p - b.center).norm());
  b.bvh = detail::collision_mesh(b.mesh);
}

// A solid of revolution about z: the profile (radius, z) from the bottom pole to the top pole,
// radii > 0 in between, each ring a polygon of n sides circumscribing its circle (so that the
// mesh holds the round body).
removal::TriangleMesh revolved(const std::vector<std::pair<double, double>>& profile, int n = 48) {
  removal::TriangleMesh m;
  const double grow = 1.0 / std::cos(M_PI / n);
  std::vector<int> first;  // first vertex of each profile point (a pole: one vertex)
  for (const auto& [r, z] : profile) {
    first.push_back(static_cast<int>(m.vertices_mm.size()));
    if (r <= 0.0) {
      m.vertices_mm.emplace_back(0.0, 0.0, z);
      continue;
    }
    for (int k = 0; k < n; ++k) {
      const double a = 2.0 * M_PI * k / n;
      m.vertices_mm.emplace_back(r * grow * std::cos(a), r * grow * std::sin(a), z);
    }
  }
  for (std::size_t j = 0; j + 1 < profile.size(); ++j) {
    const bool pole0 = profile[j].first <= 0.0, pole1 = profile[j + 1].first <= 0.0;
    const int a = first[j], b = first[j + 1];
    for (int k = 0; k < n; ++k) {
      const int k1 = (k + 1) % n;
      if (pole0 && pole1) break;
      if (pole0)
        m.triangles.emplace_back(a, b + k1, b + k);
      else if (pole1)
        m.triangles.emplace_back(a + k, a + k1, b);
      else {
        m.triangles.emplace_back(a + k, a + k1, b + k1);
        m.triangles.emplace_back(a + k, b + k1, b + k);
      }
    }
  }
  return m;
}

removal::TriangleMesh box_mesh(const Eigen::Vector3d& lo, const Eigen::Vector3d& hi) {
  removal::TriangleMesh m;
  for (int i = 0; i < 8; ++i)
    m.vertices_mm.emplace_back(i & 1 ? hi.x() : lo.x(), i & 2 ? hi.y() : lo.y(), i & 4 ? hi.z() : lo.z());
  const int f[12][3] = {{0, 2, 1}, {1, 2, 3}, {4, 5, 6}, {5, 7, 6}, {0, 1, 4}, {1, 5, 4},
                        {2, 6, 3}, {3, 6, 7}, {0, 4, 2}, {2, 4, 6}, {1, 3, 5}, {3, 7, 5}};
  for (const auto& t : f) m.triangles.emplace_back(t[0], t[1], t[2]);
  return m;
}

// The stock's initial shape (simulate's stock_shape: a mesh stock read and checked closed) as
// a mesh in the workpiece frame.
removal::TriangleMesh stock_mesh(const io::Job& job) {
  removal::StockShape shape = stock_shape(job);
  if (auto* mesh = std::get_if<removal::TriangleMesh>(&shape)) return std::move(*mesh);
  if (const auto* box = std::get_if<removal::BoxShape>(&shape)) return box_mesh(box->min_mm, box->max_mm);
  const auto& c = std::get<removal::CylinderShape>(shape);
  removal::TriangleMesh m =
      revolved({{0.0, 0.0}, {c.radius_mm, 0.0}, {c.radius_mm, c.height_mm}, {0.0, c.height_mm}}, 96);
  const Eigen::Quaterniond turn = Eigen::Quaterniond::FromTwoVectors(Eigen::Vector3d::UnitZ(), c.axis);
  for (Eigen::Vector3d& p : m.vertices_mm) p = c.base_center_mm + turn * p;
  return m;
}

removal::TriangleMesh closed_mesh(const std::string& file, const std::string& what) {
  removal::TriangleMesh m = io::read_mesh(file);
  if (m.triangles.empty()) throw InputError(file, 0, 0, what + ": expected a mesh with triangles");
  if (!removal::is_closed(m))
    throw InputError(file, 0, 0,
                     what + ": not a closed mesh (expected a solid: every edge shared by exactly two triangles)");
  return m;
}

std::string stem(const std::string& file) { return std::filesystem::path(file).stem().string(); }

// The tool's parts in tool coordinates (tip at the origin, +z toward the spindle): the
// cutting part as steps that hold its profile, the shank and the holder where the cut's probes
// (removal::add_tool_bodies) have them, or the tool's holder model.
void add_tool_parts(std::vector<Body>& bodies, int number, const removal::Cutter& c, const Eigen::Isometry3d& local) {
  auto add = [&](BodyKind kind, const std::string& part, removal::TriangleMesh mesh, const Eigen::Isometry3d& at) {
    Body b;
    b.name = "T" + std::to_string(number) + " " + part;
    b.side = BodySide::Tool;
    b.kind = kind;
    b.node = 'T';
    b.tool = number;
    b.local = at;
    b.mesh = std::move(mesh);
    finish(b);
    bodies.push_back(std::move(b));
  };
  // A cylinder of a probe cutter, from `height_mm` above the tip up its length.
  auto cylinder = [](const removal::Cutter& probe, double height_mm) {
    const double r = probe.radius_mm(), z0 = height_mm, z1 = height_mm + probe.length_mm;
    return revolved({{0.0, z0}, {r, z0}, {r, z1}, {0.0, z1}});
  };
  if (c.flute_length_mm > 0.0) {
    constexpr int kSteps = 12;
    std::vector<std::pair<double, double>> profile = {{0.0, 0.0}};
    for (int j = 1; j <= kSteps; ++j) {
      const double z0 = c.flute_length_mm * (j - 1) / kSteps, z1 = c.flute_length_mm * j / kSteps;
      // Each profile rises with height: the step's radius is the one at its top.
      const double r = std::max(removal::section_radius(c, z1), 1e-3);
      profile.emplace_back(r, z0);
      profile.emplace_back(r, z1);
    }
    profile.emplace_back(0.0, c.flute_length_mm);
    add(BodyKind::Cutter, "cutter", revolved(profile), local);
  }
  removal::MoveList parts;
  parts.cutters.push_back(c);
  const removal::ToolBody probes = removal::add_tool_bodies(parts).front();
  if (probes.shank >= 0)
    add(BodyKind::Shank, "shank",
        cylinder(parts.cutters[static_cast<std::size_t>(probes.shank)], probes.shank_height_mm), local);
  if (!c.holder_mesh_file.empty())  // hanging from the spindle nose, a gauge length above the tip
    add(BodyKind::Holder, "holder", closed_mesh(c.holder_mesh_file, "holder of T" + std::to_string(number)),
        local * Eigen::Translation3d(0.0, 0.0, c.gauge_length_mm));
  else if (probes.holder >= 0)
    add(BodyKind::Holder, "holder",
        cylinder(parts.cutters[static_cast<std::size_t>(probes.holder)], probes.holder_height_mm), local);
}

// A point inside a closed mesh: the parity of a ray's crossings (a direction no bundled
// model has faces or edges along).
bool inside(const removal::TriangleMesh& m, const Eigen::Vector3d& p) {
  const Eigen::Vector3d d = Eigen::Vector3d(0.5773, 0.5774, 0.5775).normalized();
  int crossings = 0;
  for (const Eigen::Vector3i& t : m.triangles) {
    const Eigen::Vector3d& a = m.vertices_mm[static_cast<std::size_t>(t[0])];
    const Eigen::Vector3d e1 = m.vertices_mm[static_cast<std::size_t>(t[1])] - a;
    const Eigen::Vector3d e2 = m.vertices_mm[static_cast<std::size_t>(t[2])] - a;
    const Eigen::Vector3d h = d.cross(e2);
    const double det = e1.dot(h);
    if (std::abs(det) < 1e-12) continue;
    const Eigen::Vector3d s = p - a;
    const double u = s.dot(h) / det;
    if (u < 0.0 || u > 1.0) continue;
    const Eigen::Vector3d q = s.cross(e1);
    const double v = d.dot(q) / det;
    if (v < 0.0 || u + v > 1.0) continue;
    if (e2.dot(q) / det > 0.0) ++crossings;
  }
  return crossings % 2 == 1;
}

// How deep body a reaches into body b: the largest distance from b's surface of a's vertices
// that lie inside b (0 when none does: edges crossing).
double vertex_depth_mm(const Body& a, const Eigen::Isometry3d& ta, const Body& b, const Eigen::Isometry3d& tb) {
  const Eigen::Isometry3d to_b = tb.inverse() * ta;
  double depth = 0.0;
  for (const Eigen::Vector3d& v : a.mesh.vertices_mm) {
    const Eigen::Vector3d in_b = to_b * v;
    if (!b.box.contains(in_b) || !inside(b.mesh, in_b)) continue;
    depth = std::max(depth, detail::point_distance_mm(*b.bvh, in_b));
  }
  return depth;
}

Eigen::AlignedBox3d framed_box(const Eigen::AlignedBox3d& box, const Eigen::Isometry3d& pose) {
  Eigen::AlignedBox3d out;
  for (int i = 0; i < 8; ++i) out.extend(pose * box.corner(static_cast<Eigen::AlignedBox3d::CornerType>(i)));
  return out;
}

double box_distance_mm(const Eigen::AlignedBox3d& a, const Eigen::AlignedBox3d& b) {
  const Eigen::Vector3d gap = (a.min() - b.max()).cwiseMax(b.min() - a.max()).cwiseMax(0.0);
  return gap.norm();
}

// Node frames at one set of axis values: node coordinates (F at all-zero axes) -> F, by slot:
// the machine's axes in its order, then F, W and T.
struct Frames {
  std::array<Eigen::Isometry3d, 8> node;
  const Eigen::Isometry3d& at(int slot) const { return node[static_cast<std::size_t>(slot)]; }
};

int slot_of(const kinematics::Machine& m, char node) {
  if (node == 'F') return m.axis_count();
  if (node == 'W') return m.axis_count() + 1;
  if (node == 'T') return m.axis_count() + 2;
  return m.axis_index(node);
}

Frames frames_at(const kinematics::Machine& m, const AxisValues& q) {
  Frames f;
  for (const kinematics::NodePose& n : kinematics::node_frames(m, q))
    f.node[static_cast<std::size_t>(slot_of(m, n.node))] = n.pose;
  return f;
}

// The axes that move a node, from the frame outward (its chain up to it; W and T: the whole
// chain; F: none).
std::vector<int> chain_of(const kinematics::Machine& machine, char node) {
  for (const auto* chain : {&machine.workpiece_chain(), &machine.tool_chain()}) {
    if (node == (chain == &machine.tool_chain() ? 'T' : 'W')) return *chain;
    std::vector<int> prefix;
    for (int k : *chain) {
      prefix.push_back(k);
      if (machine.axis(k).letter == node) return prefix;
    }
  }
  return {};
}

// How far any point within radius_mm of c (frame F, at q0) on a body moved by `chain` can move
// while the axes go linearly from q0 to q1, per unit of the interval: each axis of the chain,
// from the outermost in, moves it at most by its step (linear), or by its step times the
// point's distance from the axis line (rotary): the sphere's centre's distance plus its radius
// plus what the outer axes move it (a rotation does not change a point's distance from its own
// line, and the inner axes carry the line with the point).
double chain_motion_bound_mm(const kinematics::Machine& machine, const std::vector<int>& chain, const Frames& f0,
                             const Eigen::Vector3d& c, double radius_mm, const AxisValues& q0, const AxisValues& q1) {
  double moved = 0.0;
  for (auto it = chain.rbegin(); it != chain.rend(); ++it) {
    const int k = *it;
    const double step = std::abs(q1[k] - q0[k]);
    const kinematics::AxisSpec& axis = machine.axis(k);
    if (axis.kind == kinematics::AxisKind::Linear) {
      moved += step;
      continue;
    }
    const Eigen::Isometry3d& pose = f0.at(k);
    const Eigen::Vector3d point = pose * axis.center_mm, dir = (pose.linear() * axis.direction).normalized();
    const Eigen::Vector3d r = c - point;
    moved += ((r - r.dot(dir) * dir).norm() + radius_mm + moved) * step;
  }
  return moved;
}

struct Eval {
  double distance_mm = std::numeric_limits<double>::infinity();  // exact, or a lower bound when !exact
  bool exact = false;
  bool hit = false;
  double depth_mm = 0.0;
  Eigen::Vector3d point = Eigen::Vector3d::Zero();  // frame F
};

// The playback's frames and tool path, recorded along the samples in order (machine_check.h:
// Playback): sample p * n / max for p < max, and the last.
class PlaybackRecorder {
 public:
  PlaybackRecorder(Playback& out, const kinematics::Machine& machine, const kinematics::Program& program,
                   std::size_t samples, std::size_t max_frames, const Eigen::Isometry3d& on_workpiece)
      : out_(out),
        program_(program),
        samples_(samples),
        frames_(max_frames),
        points_(10 * max_frames),
        work_slot_(slot_of(machine, 'W')),
        on_workpiece_(on_workpiece) {
    for (char node : out.nodes) slots_.push_back(slot_of(machine, node));
  }

  void record(std::size_t i, const kinematics::PoseSample& sample, const Frames& f) {
    const bool last = i + 1 == samples_;
    if (kept(i, frames_, next_frame_) || last) {
      out_.frame_sample.push_back(i);
      out_.frame_block.push_back(sample.block);
      out_.frame_tool.push_back(sample.block >= 0 ? program_.blocks[static_cast<std::size_t>(sample.block)].tool : 0);
      pose(f, out_.frame_pose);
    }
    if (kept(i, points_, next_point_) || last) {
      for (int k = 0; k < 3; ++k) out_.path_mm.push_back(static_cast<float>(sample.pose.tip_mm[k]));
      out_.path_block.push_back(sample.block);
      out_.path_rapid.push_back(sample.block < 0 || program_.blocks[static_cast<std::size_t>(sample.block)].kind ==
                                                        kinematics::MotionKind::Rapid);
    }
  }

  // The nodes' poses in the workpiece frame, then the workpiece frame in F (Playback).
  void pose(const Frames& f, std::vector<float>& out) const {
    const Eigen::Isometry3d work = f.at(work_slot_) * on_workpiece_, to_work = work.inverse();
    auto put = [&out](const Eigen::Isometry3d& m) {
      for (int r = 0; r < 3; ++r)
        for (int c = 0; c < 4; ++c) out.push_back(static_cast<float>(m.matrix()(r, c)));
    };
    for (int slot : slots_) put(to_work * f.at(slot));
    put(work);
  }

 private:
  // Sample i is kept where it is p * n / max for the next p (all samples when n <= max).
  bool kept(std::size_t i, std::size_t max, std::size_t& next) const {
    if (samples_ <= max) return true;
    if (next >= max || i != next * samples_ / max) return false;
    ++next;
    return true;
  }

  Playback& out_;
  const kinematics::Program& program_;
  std::size_t samples_, frames_, points_;
  std::size_t next_frame_ = 0, next_point_ = 0;
  int work_slot_;
  Eigen::Isometry3d on_workpiece_;
  std::vector<int> slots_;
};

struct Finding {
  int pair = 0;
  std::size_t sample = 0;  // the pose, or the end of the interval it lies in
  int block = -1;
  Eval eval;
  AxisValues q;
  bool between = false;
};

class Checker {
 public:
  Checker(const kinematics::Machine& machine, const PoseRun& run, std::vector<Body>& bodies, double clearance_mm)
      : machine_(machine), run_(run), bodies_(bodies), clearance_mm_(clearance_mm) {
    for (std::size_t i = 0; i < bodies_.size(); ++i) chain_.push_back(chain_of(machine_, bodies_[i].node));
  }

  std::vector<std::pair<int, int>> pairs;
  std::vector<Finding> findings;
  std::size_t queries = 0;
  PlaybackRecorder* playback = nullptr;  // records the frames when set

  // The samples in order: the run's own, or densified again block by block where the run
  // streamed them (simulate): the same samples, with their axis values. Batches of samples
  // are checked in parallel; what each sample and each interval finds is kept apart and
  // joined in sample order, so that the findings are the same for any number of threads.
  void run() {
    const auto& samples = run_.densified.samples;
    if (!samples.empty() || !run_.streamed) {
      for (std::size_t i = 0; i < samples.size(); i += kBatch)
        check_batch(samples.data() + i, std::min(kBatch, samples.size() - i));
      return;
    }
    kinematics::Densifier densifier(run_.program, run_.densify_settings, run_.densify_machine);
    std::vector<kinematics::PoseSample> batch = {densifier.start()};
    kinematics::BlockReport report;
    while (!densifier.done()) {
      densifier.next_block(batch, report);
      if (batch.size() >= kBatch) {
        check_batch(batch.data(), batch.size());
        batch.clear();
      }
    }
    check_batch(batch.data(), batch.size());
  }

 private:
  // Each pair along the samples: checked at the last sample (with which tool), and its
  // distance there (exact, or a lower bound).
  struct PairState {
    bool active = false;
    int tool = 0;
    Eval last;
  };
  static constexpr std::size_t kBatch = 2048;
  static constexpr std::size_t kChunk = 256;  // a pair's samples checked by one task

  // Samples index_ .. index_ + n - 1; the last sample of the batch before (its frames and
  // each pair's state) opens the interval to the first. The frames in parallel over the
  // samples, then each pair's chunks of samples in parallel, each along its samples in order:
  // a pair's distance falls no faster than its bodies move, so after an exact distance d the
  // pair is queried again only where d less the motion since then (motion_bound_mm) drops
  // below the clearance.
  void check_batch(const kinematics::PoseSample* batch, std::size_t n) {
    if (n == 0) return;
    const std::size_t pair_count = pairs.size();
    std::vector<Frames> frames(n);
    std::vector<int> tools(n);
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n), [&](const tbb::blocked_range<std::size_t>& range) {
      for (std::size_t k = range.begin(); k != range.end(); ++k) {
        frames[k] = frames_at(machine_, batch[k].axes);
        tools[k] = tool_of(batch[k].block);
      }
    });
    if (playback != nullptr)
      for (std::size_t k = 0; k < n; ++k) playback->record(index_ + k, batch[k], frames[k]);
    state_.resize(pair_count);
    // Each pair's samples in chunks of kChunk, all side by side: a chunk after the batch's
    // first opens at the sample before it as a pair's first sample does (its distance there, a
    // box bound or exact; no finding, that sample is the chunk before's), so that a few busy
    // pairs do not keep the rest of the threads waiting. The chunks are fixed, not the thread
    // count's: the same findings for any.
    const std::size_t chunks = (n + kChunk - 1) / kChunk;
    std::vector<std::vector<Finding>> found(pair_count * chunks);
    std::vector<std::size_t> queries(pair_count * chunks, 0);
    std::vector<PairState> ends(pair_count * chunks);
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, pair_count * chunks),
                      [&](const tbb::blocked_range<std::size_t>& range) {
                        for (std::size_t task = range.begin(); task != range.end(); ++task) {
                          const std::size_t p = task / chunks, c = task % chunks;
                          const std::size_t k0 = c * kChunk, k1 = std::min(n, k0 + kChunk);
                          PairState st = c == 0 ? state_[p] : PairState{};
                          if (c > 0 && active(p, tools[k0 - 1]))
                            st = {true, tools[k0 - 1], evaluate(pairs[p], frames[k0 - 1], queries[task])};
                          check_samples(p, batch, k0, k1, frames, tools, st, found[task], queries[task]);
                          ends[task] = st;
                        }
                      });
    for (std::size_t p = 0; p < pair_count; ++p) {
      state_[p] = ends[p * chunks + chunks - 1];
      for (std::size_t c = 0; c < chunks; ++c) {
        findings.insert(findings.end(), found[p * chunks + c].begin(), found[p * chunks + c].end());
        this->queries += queries[p * chunks + c];
      }
    }
    last_frames_ = frames[n - 1];
    last_q_ = batch[n - 1].axes;
    index_ += n;
  }

  // Pair p along samples k0 .. k1 - 1 of the batch, from state st (at the sample before k0).
  void check_samples(std::size_t p, const kinematics::PoseSample* batch, std::size_t k0, std::size_t k1,
                     const std::vector<Frames>& frames, const std::vector<int>& tools, PairState& st,
                     std::vector<Finding>& found, std::size_t& queries) const {
    for (std::size_t k = k0; k < k1; ++k) {
      const std::size_t i = index_ + k;
      const kinematics::PoseSample& sample = batch[k];
      if (!active(p, tools[k])) {
        st.active = false;
        continue;
      }
      const bool continues = st.active && st.tool == tools[k];
      const Frames& f0 = k > 0 ? frames[k - 1] : last_frames_;
      const AxisValues& q0 = k > 0 ? batch[k - 1].axes : last_q_;
      double moved = 0.0;
      if (continues)
        moved = motion_bound_mm(pairs[p].first, f0, q0, sample.axes) +
                motion_bound_mm(pairs[p].second, f0, q0, sample.axes);
      Eval e;
      if (continues && st.last.distance_mm - moved >= clearance_mm_) {
        // Proven apart over the whole interval by the last distance: nothing to query.
        e.distance_mm = st.last.distance_mm - moved;
      } else {
        e = evaluate(pairs[p], frames[k], queries);
        // Where a pair first meets, one body may lie wholly inside the other (no faces cross).
        if (!continues && !e.hit && e.exact) contained(pairs[p], frames[k], e);
        if (e.distance_mm < clearance_mm_ || e.hit)
          found.push_back({static_cast<int>(p), i, sample.block, e, sample.axes, false});
        if (continues)
          between(static_cast<int>(p), i, sample.block, f0, q0, sample.axes, st.last, e, 0, found, queries);
      }
      st.last = e;
      st.active = true;
      st.tool = tools[k];
    }
  }

  int tool_of(int block) const { return block >= 0 ? run_.program.blocks[static_cast<std::size_t>(block)].tool : 0; }
  // A pair with a tool's part is checked while that tool is in the spindle.
  bool active(std::size_t p, int tool) const {
    const Body& a = bodies_[static_cast<std::size_t>(pairs[p].first)];
    return tool >= 0 && (a.tool == 0 || a.tool == tool);
  }

  static Eigen::Isometry3d pose_of(const Body& b, const Frames& f) { return f.at(b.slot) * b.local; }

  Eval evaluate(const std::pair<int, int>& pair, const Frames& f, std::size_t& queries) const {
    const Body& a = bodies_[static_cast<std::size_t>(pair.first)];
    const Body& b = bodies_[static_cast<std::size_t>(pair.second)];
    const Eigen::Isometry3d ta = pose_of(a, f), tb = pose_of(b, f);
    Eval e;
    // A lower bound first: the distance between the bodies' boxes, each the frame-aligned box
    // of its own box's corners where it stands.
    const double apart = box_distance_mm(framed_box(a.box, ta), framed_box(b.box, tb));
    if (apart > clearance_mm_) {
      e.distance_mm = apart;
      return e;
    }
    ++queries;
    const detail::MeshDistance d = detail::mesh_distance(*a.bvh, ta, *b.bvh, tb);
    e.exact = true;
    e.distance_mm = d.distance_mm;
    e.point = d.point;
    if (d.distance_mm > 0.0) return e;
    e.hit = true;
    detail::mesh_contact(*a.bvh, ta, *b.bvh, tb, e.depth_mm, e.point);
    return e;
  }

  void contained(const std::pair<int, int>& pair, const Frames& f, Eval& e) const {
    const Body& a = bodies_[static_cast<std::size_t>(pair.first)];
    const Body& b = bodies_[static_cast<std::size_t>(pair.second)];
    const Eigen::Isometry3d ta = pose_of(a, f), tb = pose_of(b, f);
    const Eigen::Vector3d pa = ta * a.mesh.vertices_mm.front(), pb = tb * b.mesh.vertices_mm.front();
    const bool a_in_b = inside(b.mesh, tb.inverse() * pa);
    if (a_in_b || inside(a.mesh, ta.inverse() * pb)) {
      e.hit = true;
      e.depth_mm = e.distance_mm;  // at least as deep as the faces are apart
      e.distance_mm = 0.0;
      e.point = a_in_b ? pa : pb;
    }
  }

  double motion_bound_mm(int body, const Frames& f0, const AxisValues& q0, const AxisValues& q1) const {
    const Body& b = bodies_[static_cast<std::size_t>(body)];
    // The centre placed by one transform of a point (not a product of two transforms).
    return chain_motion_bound_mm(machine_, chain_[static_cast<std::size_t>(body)], f0,
                                 f0.at(b.slot) * (b.local * b.center), b.radius_mm, q0, q1);
  }

  // Conservative advancement over the interval (q0, q1) of sample `sample`: halved until the
  // pair is proven apart by more than the clearance, or met.
  void between(int p, std::size_t sample, int block, const Frames& f0, const AxisValues& q0, const AxisValues& q1,
               const Eval& e0, const Eval& e1, int depth, std::vector<Finding>& found, std::size_t& queries) const {
    if (e0.hit || e1.hit) return;
    const double reach = motion_bound_mm(pairs[static_cast<std::size_t>(p)].first, f0, q0, q1) +
                         motion_bound_mm(pairs[static_cast<std::size_t>(p)].second, f0, q0, q1);
    const double low = 0.5 * (e0.distance_mm + e1.distance_mm - reach);
    if (low >= clearance_mm_) return;
    if (low > 0.0 && (e0.distance_mm < clearance_mm_ || e1.distance_mm < clearance_mm_)) return;
    if (reach < kFinestMm || depth > 30) return;
    const AxisValues qm = 0.5 * (q0 + q1);
    const Frames fm = frames_at(machine_, qm);
    const Eval em = evaluate(pairs[static_cast<std::size_t>(p)], fm, queries);
    if (em.distance_mm < clearance_mm_ || em.hit) found.push_back({p, sample, block, em, qm, true});
    between(p, sample, block, f0, q0, qm, e0, em, depth + 1, found, queries);
    between(p, sample, block, fm, qm, q1, em, e1, depth + 1, found, queries);
  }

  static constexpr double kFinestMm = 0.01;
  const kinematics::Machine& machine_;
  const PoseRun& run_;
  std::vector<Body>& bodies_;
  double clearance_mm_;
  std::vector<std::vector<int>> chain_;
  std::vector<PairState> state_;
  // The last sample checked: the next index, its frames and axes.
  std::size_t index_ = 0;
  Frames last_frames_;
  AxisValues last_q_;
};

// Where the workpiece sits on the frame (head-head, gantry: !work_moves), its side never moves
// against the frame: a fixture standing on the bed is not a collision.
bool checked_pair(const Body& a, const Body& b, const MachineCheckOptions& options, bool work_moves) {
  if (a.side == BodySide::Tool && b.side != BodySide::Tool) {
    // The cutting part meets the stock in the cut; the shank and holder there too, or in
    // `check`'s box test where the stock is a box; the machine's bodies (spindle housing,
    // head) must never.
    if (b.kind == BodyKind::Stock)
      return options.stock && (a.kind == BodyKind::Model || (options.stock_parts && a.kind != BodyKind::Cutter));
    return true;
  }
  return work_moves && a.side == BodySide::Work && b.side == BodySide::Frame && a.kind != BodyKind::Stock;
}

std::string model_name(const kinematics::ModelSpec& m, char node) {
  const std::string base = m.name.empty() ? stem(m.file) : m.name;
  return node == 'F' ? base + " (frame)" : base + " (" + std::string(1, node) + ")";
}

}  // namespace

removal::TriangleMesh placed_mesh(removal::TriangleMesh mesh, const io::DesignSpec& d) {
  const double k = M_PI / 180.0;
  const Eigen::Matrix3d r = (Eigen::AngleAxisd(d.rotate_deg.z() * k, Eigen::Vector3d::UnitZ()) *
                             Eigen::AngleAxisd(d.rotate_deg.y() * k, Eigen::Vector3d::UnitY()) *
                             Eigen::AngleAxisd(d.rotate_deg.x() * k, Eigen::Vector3d::UnitX()))
                                .toRotationMatrix();
  for (auto& p : mesh.vertices_mm) p = r * p + d.translate_mm;
  return mesh;
}

std::vector<std::pair<char, double>> axis_readout(const kinematics::Machine& machine, const kinematics::AxisValues& q) {
  std::vector<std::pair<char, double>> out;
  for (int k = 0; k < machine.axis_count() && k < q.size(); ++k) {
    const bool rotary = machine.axis(k).kind == kinematics::AxisKind::Rotary;
    out.emplace_back(machine.axis(k).letter, rotary ? q[k] * 180.0 / M_PI : q[k]);
  }
  return out;
}

std::string axis_text(const kinematics::Machine& machine, const kinematics::AxisValues& q) {
  std::string out;
  for (const auto& [letter, value] : axis_readout(machine, q)) {
    char field[40];
    std::snprintf(field, sizeof field, "%s%c%.3f", out.empty() ? "" : " ", letter, value);
    out += field;
  }
  return out;
}

double motion_bound_mm(const kinematics::Machine& machine, char node, const Eigen::Vector3d& center_mm,
                       double radius_mm, const kinematics::AxisValues& q0, const kinematics::AxisValues& q1) {
  return chain_motion_bound_mm(machine, chain_of(machine, node), frames_at(machine, q0), center_mm, radius_mm, q0, q1);
}

bool has_machine_bodies(const io::Job& job, const PoseRun& run) {
  return run.machine && (!run.machine->spec().models.empty() || !job.fixtures.empty());
}

struct MachineChecker::Parts {
  Parts(const PoseRun& r, const MachineCheckOptions& o) : run(r), options(o) {}
  const PoseRun& run;
  MachineCheckOptions options;
  std::vector<Body> bodies;
  std::vector<std::pair<int, int>> pairs;
  Eigen::Isometry3d on_workpiece = Eigen::Isometry3d::Identity();
  MachineCheck out;
};

MachineChecker::MachineChecker(const io::Job& job, const PoseRun& run, const MachineCheckOptions& options)
    : parts_(std::make_unique<Parts>(run, options)) {
  if (!run.machine) return;
  MachineCheck& out = parts_->out;
  std::vector<Body>& bodies = parts_->bodies;
  const kinematics::Machine& machine = *run.machine;
  const kinematics::MachineSpec& spec = machine.spec();
  auto side_of = [&](char node) {
    if (node == 'T') return BodySide::Tool;
    if (node == 'W') return BodySide::Work;
    if (node == 'F') return BodySide::Frame;
    const int axis = machine.axis_index(node);
    const auto& tool = machine.tool_chain();
    return std::find(tool.begin(), tool.end(), axis) != tool.end() ? BodySide::Tool : BodySide::Work;
  };
  for (const auto& [node, models] : spec.models)
    for (const kinematics::ModelSpec& m : models) {
      Body b;
      b.name = model_name(m, node);
      b.side = side_of(node);
      b.node = node;
      b.local = Eigen::Translation3d(m.origin_mm);
      b.mesh = closed_mesh(m.file, "machine model on " + std::string(1, node));
      finish(b);
      bodies.push_back(std::move(b));
    }
  parts_->on_workpiece = Eigen::Translation3d(spec.workpiece_origin_mm);
  const Eigen::Isometry3d& on_workpiece = parts_->on_workpiece;
  for (const io::DesignSpec& f : job.fixtures) {
    Body b;
    b.name = "fixture " + stem(f.file);
    b.side = BodySide::Work;
    b.kind = BodyKind::Fixture;
    b.node = 'W';
    b.local = on_workpiece;
    b.mesh = placed_mesh(closed_mesh(f.file, "fixture"), f);
    finish(b);
    bodies.push_back(std::move(b));
  }
  // The stock's shape (a fixture in it at the start is a warning; `check` also checks the tool side against it).
  {
    Body b;
    b.name = "the stock";
    b.side = BodySide::Work;
    b.kind = BodyKind::Stock;
    b.node = 'W';
    b.local = on_workpiece;
    b.mesh = stock_mesh(job);
    finish(b);
    for (const Body& f : bodies) {
      if (f.kind != BodyKind::Fixture) continue;
      double depth_mm = 0.0;
      Eigen::Vector3d point;
      const bool meet = detail::mesh_contact(*f.bvh, Eigen::Isometry3d::Identity(), *b.bvh,
                                             Eigen::Isometry3d::Identity(), depth_mm, point);
      if (meet || inside(b.mesh, f.mesh.vertices_mm.front()) || inside(f.mesh, b.mesh.vertices_mm.front()))
        out.warnings.push_back(f.name + " intersects the stock at the start");
    }
    bodies.push_back(std::move(b));
  }
  // The tools' parts, placed at the spindle nose a gauge length above the tip.
  for (const auto& [number, cutter] : run.tools) {
    const auto length = run.densify_machine.tool_length_mm.find(number);
    const double gauge_mm = length == run.densify_machine.tool_length_mm.end() ? 0.0 : length->second;
    Eigen::Isometry3d local = Eigen::Isometry3d::Identity();
    local.translation() = spec.gauge_point_mm - gauge_mm * spec.spindle_axis;
    local.linear() = Eigen::Quaterniond::FromTwoVectors(Eigen::Vector3d::UnitZ(), spec.spindle_axis).toRotationMatrix();
    add_tool_parts(bodies, number, cutter, local);
  }
  for (Body& b : bodies) {
    b.slot = slot_of(machine, b.node);
    out.bodies.push_back(b.name);
  }
  const bool work_moves = !machine.workpiece_chain().empty();
  for (std::size_t a = 0; a < bodies.size(); ++a)
    for (std::size_t b = 0; b < bodies.size(); ++b)
      if (checked_pair(bodies[a], bodies[b], options, work_moves))
        parts_->pairs.emplace_back(static_cast<int>(a), static_cast<int>(b));
  out.pairs = parts_->pairs.size();
}

MachineChecker::~MachineChecker() = default;

MachineCheck MachineChecker::run() {
  MachineCheck out = std::move(parts_->out);
  const PoseRun& poses = parts_->run;
  if (!poses.machine) return out;
  const kinematics::Machine& machine = *poses.machine;
  const MachineCheckOptions& options = parts_->options;
  std::vector<Body>& bodies = parts_->bodies;
  const Eigen::Isometry3d& on_workpiece = parts_->on_workpiece;
  Checker checker(machine, poses, bodies, options.clearance_mm);
  checker.pairs = std::move(parts_->pairs);
  std::optional<PlaybackRecorder> recorder;
  if (options.playback_frames > 0) {
    // Every body but the stock (the page shows the part as cut), in node coordinates.
    Playback& play = out.playback;
    for (const Body& b : bodies) {
      if (b.kind == BodyKind::Stock) continue;
      auto node = std::find(play.nodes.begin(), play.nodes.end(), b.node);
      if (node == play.nodes.end()) node = play.nodes.insert(node, b.node);
      Playback::Body body{b.name, b.kind, static_cast<int>(node - play.nodes.begin()), b.tool, b.mesh};
      for (Eigen::Vector3d& v : body.mesh.vertices_mm) v = b.local * v;
      play.bodies.push_back(std::move(body));
    }
    recorder.emplace(play, machine, poses.program, poses.poses, options.playback_frames, on_workpiece);
    checker.playback = &*recorder;
  }
  checker.run();
  out.queries = checker.queries;

  // Runs of consecutive poses (and the intervals between them) make one contact per pair.
  std::vector<Finding>& found = checker.findings;
  std::stable_sort(found.begin(), found.end(), [](const Finding& x, const Finding& y) {
    return x.pair != y.pair ? x.pair < y.pair : x.sample < y.sample;
  });
  const kinematics::Program& program = poses.program;
  for (std::size_t i = 0; i < found.size();) {
    std::size_t j = i;
    while (j + 1 < found.size() && found[j + 1].pair == found[i].pair && found[j + 1].sample <= found[j].sample + 1)
      ++j;
    MachineContact c;
    const Body& a = bodies[static_cast<std::size_t>(checker.pairs[static_cast<std::size_t>(found[i].pair)].first)];
    const Body& b = bodies[static_cast<std::size_t>(checker.pairs[static_cast<std::size_t>(found[i].pair)].second)];
    c.a = a.name;
    c.b = b.name;
    c.a_kind = a.kind;
    c.b_kind = b.kind;
    std::size_t worst = i;
    for (std::size_t k = i; k <= j; ++k) {
      const Eval& e = found[k].eval;
      const Eval& w = found[worst].eval;
      if (e.hit > w.hit || (e.hit && e.depth_mm > w.depth_mm) || (!e.hit && !w.hit && e.distance_mm < w.distance_mm))
        worst = k;
    }
    const Finding& w = found[worst];
    c.hit = w.eval.hit;
    c.depth_mm = w.eval.depth_mm;
    const Frames f = frames_at(machine, w.q);
    if (c.hit) {
      // FCL's contact depth is the overlap along a contact, not how far apart the bodies must
      // move: where a vertex of one lies inside the other, its distance from the surface is.
      const Eigen::Isometry3d ta = f.at(a.slot) * a.local, tb = f.at(b.slot) * b.local;
      const double depth = std::max(vertex_depth_mm(a, ta, b, tb), vertex_depth_mm(b, tb, a, ta));
      if (depth > 0.0) c.depth_mm = depth;
    }
    c.clearance_mm = w.eval.hit ? 0.0 : w.eval.distance_mm;
    c.axes = w.q;
    c.between_poses = w.between;
    c.sample = w.sample;
    c.where_mm = (f.at(slot_of(machine, 'W')) * on_workpiece).inverse() * w.eval.point;
    c.first_block = std::max(found[i].block, 0);
    c.last_block = std::max(found[j].block, 0);
    c.lines = {program.blocks[static_cast<std::size_t>(c.first_block)].source,
               program.blocks[static_cast<std::size_t>(c.last_block)].source};
    out.contacts.push_back(c);
    i = j + 1;
  }
  std::stable_sort(out.contacts.begin(), out.contacts.end(),
                   [](const MachineContact& x, const MachineContact& y) { return x.first_block < y.first_block; });
  if (recorder)
    for (const MachineContact& c : out.contacts) recorder->pose(frames_at(machine, c.axes), out.playback.contact_pose);
  return out;
}

MachineCheck check_machine(const io::Job& job, const PoseRun& run, const MachineCheckOptions& options) {
  return MachineChecker(job, run, options).run();
}

}  // namespace vcut::pipeline
