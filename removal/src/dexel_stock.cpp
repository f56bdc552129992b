#include "vcut/removal/dexel_stock.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "dexel_impl.h"
#include "initial_stock.h"
#include "ray_sweep.h"

namespace vcut::removal {

void DexelStock::Impl::fill_mesh(const TriangleMesh& mesh) {
  for (Family& f : families) {
    const int k = f.axis;
    const auto [a1, a2] = kOther[static_cast<std::size_t>(k)];
    // Triangles by the rows of rays their projection covers.
    std::vector<std::vector<int>> rows(static_cast<std::size_t>(f.n_w));
    for (std::size_t t = 0; t < mesh.triangles.size(); ++t) {
      double lo = std::numeric_limits<double>::infinity(), hi = -lo;
      for (int c = 0; c < 3; ++c) {
        const double w = mesh.vertices_mm[static_cast<std::size_t>(mesh.triangles[t][c])][a2];
        lo = std::min(lo, w);
        hi = std::max(hi, w);
      }
      const int r0 = std::max(f.lo_w, static_cast<int>(std::ceil(index_of(lo))));
      const int r1 = std::min(f.lo_w + f.n_w - 1, static_cast<int>(std::floor(index_of(hi))));
      for (int r = r0; r <= r1; ++r) rows[static_cast<std::size_t>(r - f.lo_w)].push_back(static_cast<int>(t));
    }
    tbb::parallel_for(0, f.n_w, [&](int row) {
      const int iw = f.lo_w + row;
      const double w = position(iw);
      std::vector<std::vector<std::pair<double, int>>> hits(static_cast<std::size_t>(f.n_u));
      for (int t : rows[static_cast<std::size_t>(row)]) {
        Vector3d p[3];
        for (int c = 0; c < 3; ++c)
          p[c] = mesh.vertices_mm[static_cast<std::size_t>(mesh.triangles[static_cast<std::size_t>(t)][c])];
        auto cross2 = [&](const Vector3d& a, const Vector3d& b, double pu, double pw) {
          return (b[a1] - a[a1]) * (pw - a[a2]) - (b[a2] - a[a2]) * (pu - a[a1]);
        };
        double area = cross2(p[0], p[1], p[2][a1], p[2][a2]);
        if (area == 0.0) continue;  // edge-on
        // The triangle's outward normal along the ray: leaving material where it is positive.
        const double normal_k = k == 1 ? -area : area;
        const int direction = normal_k > 0.0 ? -1 : 1;  // -1 leaves, +1 enters material
        if (area < 0.0) {
          std::swap(p[1], p[2]);
          area = -area;
        }
        double lo = std::numeric_limits<double>::infinity(), hi = -lo;
        for (const auto& q : p) {
          lo = std::min(lo, q[a1]);
          hi = std::max(hi, q[a1]);
        }
        const int u0 = std::max(f.lo_u, static_cast<int>(std::ceil(index_of(lo))));
        const int u1 = std::min(f.lo_u + f.n_u - 1, static_cast<int>(std::floor(index_of(hi))));
        for (int iu = u0; iu <= u1; ++iu) {
          const double u = position(iu);
          double e[3];
          bool in = true;
          for (int c = 0; c < 3 && in; ++c) {
            const Vector3d& a = p[(c + 1) % 3];
            const Vector3d& b = p[(c + 2) % 3];
            e[c] = cross2(a, b, u, w);
            if (e[c] < 0.0) in = false;
            // On an edge: it belongs to exactly one of the two triangles sharing it (the
            // edge's direction decides), so a ray through it counts once.
            if (e[c] == 0.0) {
              const double du = b[a1] - a[a1], dw = b[a2] - a[a2];
              if (!(dw < 0.0 || (dw == 0.0 && du < 0.0))) in = false;
            }
          }
          if (!in) continue;
          const double s = (e[0] * p[0][k] + e[1] * p[1][k] + e[2] * p[2][k]) / area;
          hits[static_cast<std::size_t>(iu - f.lo_u)].emplace_back(s, direction);
        }
      }
      std::vector<DexelSegment> segments;
      for (int iu = f.lo_u; iu < f.lo_u + f.n_u; ++iu) {
        auto& list = hits[static_cast<std::size_t>(iu - f.lo_u)];
        if (list.empty()) continue;
        std::sort(list.begin(), list.end());
        segments.clear();
        int winding = 0;
        double start = 0.0;
        for (const auto& [s, d] : list) {
          const int before = winding;
          winding += d;
          if (before <= 0 && winding > 0) start = s;
          if (before > 0 && winding <= 0 && s - start > kMinSegment_mm)
            segments.push_back({static_cast<float>(start), static_cast<float>(s), kNoMove, kNoMove});
        }
        f.at(iu, iw).assign(segments.data(), static_cast<std::uint32_t>(segments.size()));
      }
    });
  }
}

std::size_t estimate_dexel_memory_bytes(const StockShape& shape, double spacing_mm) {
  const Eigen::AlignedBox3d box = bounds_of(shape);
  const Vector3d n = (box.sizes() / spacing_mm).array() + 4.0;
  const double rays = n.x() * n.y() + n.y() * n.z() + n.x() * n.z();
  // Rays, plus the meshing and the outputs at the end, per surface cell: about 40 bytes on
  // W1 (peak 735 MB, rays 197 MB, 13.5 million surface cells); 48 to be safe.
  const double surface_cells = surface_area_mm2(shape) / (spacing_mm * spacing_mm);
  return static_cast<std::size_t>(rays * sizeof(SegmentList) + surface_cells * 48.0);
}

DexelStock::DexelStock(const StockShape& shape, double spacing_mm) : impl_(std::make_unique<Impl>()) {
  if (!(spacing_mm > 0.0)) throw std::invalid_argument("ray spacing must be positive");
  Impl& m = *impl_;
  m.v = spacing_mm;
  m.shape_bounds = bounds_of(shape);
  m.setup(m.shape_bounds);
  if (const auto* box = std::get_if<BoxShape>(&shape)) {
    m.fill([b = *box](int axis, double u, double w, double& lo, double& hi) {
      const auto [a1, a2] = kOther[static_cast<std::size_t>(axis)];
      if (u < b.min_mm[a1] || u > b.max_mm[a1] || w < b.min_mm[a2] || w > b.max_mm[a2]) return false;
      lo = b.min_mm[axis];
      hi = b.max_mm[axis];
      return true;
    });
  } else if (const auto* cyl = std::get_if<CylinderShape>(&shape)) {
    m.fill([c = *cyl](int axis, double u, double w, double& lo, double& hi) {
      Vector3d o;
      o[axis] = 0.0;
      o[kOther[static_cast<std::size_t>(axis)][0]] = u;
      o[kOther[static_cast<std::size_t>(axis)][1]] = w;
      return detail::line_cylinder(axis, o, c.base_center_mm, c.axis.normalized() * c.height_mm, c.radius_mm, lo, hi);
    });
  } else {
    const auto& mesh = std::get<TriangleMesh>(shape);
    if (!is_closed(mesh)) throw std::invalid_argument("a mesh stock must be closed");
    m.fill_mesh(mesh);
  }
  m.initial_distance = detail::initial_distance(shape, m.initial_mesh);
  m.sum_lengths();
  m.find_occupied();
}

DexelStock::~DexelStock() = default;

double DexelStock::spacing_mm() const { return impl_->v; }

void DexelStock::set_flat_merging(bool on) { impl_->flat_merging = on; }

double DexelStock::volume_mm3() const {
  const Impl& m = *impl_;
  double total = 0.0;
  for (const Family& f : m.families) total += f.length_mm;
  return total * m.v * m.v / 3.0;
}

std::size_t DexelStock::memory_bytes() const {
  std::size_t bytes = sizeof(Impl) + impl_->moves.memory_bytes();
  for (const Family& f : impl_->families) {
    bytes += f.rays.size() * sizeof(SegmentList);
    for (const SegmentList& ray : f.rays) bytes += ray.heap_bytes();
    for (const SegmentArena& arena : f.arenas) bytes += arena.bytes() + sizeof(SegmentArena);
  }
  return bytes;
}

Eigen::AlignedBox3d DexelStock::bounds() const { return impl_->shape_bounds; }

std::vector<DexelSegment> DexelStock::ray(int axis, int iu, int iw) const {
  const Family& f = impl_->families.at(static_cast<std::size_t>(axis));
  if (!f.contains(iu, iw)) return {};
  const SegmentList& r = f.at(iu, iw);
  return {r.data(), r.data() + r.size()};
}

std::size_t DexelStock::endpoint_rows() const {
  const Impl& m = *impl_;
  return static_cast<std::size_t>(m.families[0].n_w + m.families[1].n_w + m.families[2].n_w);
}

void DexelStock::row_endpoints(std::size_t row, std::vector<DexelEndpoint>& out) const {
  const Impl& m = *impl_;
  out.clear();
  int r = static_cast<int>(row), a = 0;
  while (a < 2 && r >= m.families[static_cast<std::size_t>(a)].n_w) r -= m.families[static_cast<std::size_t>(a++)].n_w;
  const Family& f = m.families[static_cast<std::size_t>(a)];
  const int iw = f.lo_w + r;
  for (int iu = f.lo_u; iu < f.lo_u + f.n_u; ++iu) {
    const SegmentList& ray = f.at(iu, iw);
    for (std::uint32_t k = 0; k < ray.size(); ++k) {
      const DexelSegment& seg = ray.data()[k];
      out.push_back({m.point(f.axis, iu, iw, seg.lo_mm), seg.lo_move, f.axis});
      out.push_back({m.point(f.axis, iu, iw, seg.hi_mm), seg.hi_move, f.axis});
    }
  }
}

std::vector<DexelEndpoint> DexelStock::endpoints() const {
  // Each row's list in parallel, then joined in row order.
  std::vector<std::vector<DexelEndpoint>> rows(endpoint_rows());
  tbb::parallel_for(std::size_t{0}, rows.size(), [&](std::size_t r) { row_endpoints(r, rows[r]); });
  std::vector<std::size_t> start(rows.size() + 1, 0);
  for (std::size_t r = 0; r < rows.size(); ++r) start[r + 1] = start[r] + rows[r].size();
  std::vector<DexelEndpoint> out(start.back());
  tbb::parallel_for(std::size_t{0}, rows.size(), [&](std::size_t r) {
    std::copy(rows[r].begin(), rows[r].end(), out.begin() + static_cast<std::ptrdiff_t>(start[r]));
  });
  return out;
}

}  // namespace vcut::removal
