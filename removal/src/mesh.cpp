#include "vcut/removal/mesh.h"

#include <OpenMesh/Core/Mesh/TriMesh_ArrayKernelT.hh>
#include <OpenMesh/Core/System/omstream.hh>
#include <OpenMesh/Tools/Decimater/DecimaterT.hh>
#include <OpenMesh/Tools/Decimater/ModQuadricT.hh>

#include <tbb/parallel_for.h>
#include <tbb/parallel_sort.h>

#include <algorithm>
#include <cstdint>
#include <vector>

namespace vcut::removal {
namespace {

struct Traits : OpenMesh::DefaultTraits {
  using Point = OpenMesh::Vec3d;
  using Normal = OpenMesh::Vec3d;
  VertexAttributes(OpenMesh::Attributes::Normal);
  FaceAttributes(OpenMesh::Attributes::Normal);
};
using OMesh = OpenMesh::TriMesh_ArrayKernelT<Traits>;

Eigen::Vector3d area_normal(const TriangleMesh& mesh, const Eigen::Vector3i& t) {
  const auto& a = mesh.vertices_mm[static_cast<std::size_t>(t[0])];
  return (mesh.vertices_mm[static_cast<std::size_t>(t[1])] - a)
      .cross(mesh.vertices_mm[static_cast<std::size_t>(t[2])] - a);
}

}  // namespace

double signed_volume_mm3(const TriangleMesh& mesh) {
  double six_v = 0.0;
  for (const auto& t : mesh.triangles)
    six_v += mesh.vertices_mm[static_cast<std::size_t>(t[0])].dot(
        mesh.vertices_mm[static_cast<std::size_t>(t[1])].cross(mesh.vertices_mm[static_cast<std::size_t>(t[2])]));
  return six_v / 6.0;
}

std::vector<Eigen::Vector3d> vertex_normals(const TriangleMesh& mesh) {
  OMesh om;
  std::vector<OMesh::VertexHandle> handles;
  handles.reserve(mesh.vertices_mm.size());
  for (const auto& p : mesh.vertices_mm) handles.push_back(om.add_vertex(OMesh::Point(p.x(), p.y(), p.z())));
  std::vector<Eigen::Vector3d> extra(mesh.vertices_mm.size(), Eigen::Vector3d::Zero());
  omerr().disable();  // complex edges are expected at thin features; handled below
  for (const auto& t : mesh.triangles) {
    const auto f = om.add_face(handles[static_cast<std::size_t>(t[0])], handles[static_cast<std::size_t>(t[1])],
                               handles[static_cast<std::size_t>(t[2])]);
    if (!f.is_valid()) {
      const Eigen::Vector3d n = area_normal(mesh, t);
      for (int c = 0; c < 3; ++c) extra[static_cast<std::size_t>(t[c])] += n;
    }
  }
  omerr().enable();
  om.request_face_normals();
  om.request_vertex_normals();
  // Area-weighted: sum the unnormalised face normals around each vertex.
  std::vector<Eigen::Vector3d> normals = std::move(extra);
  for (const auto& fh : om.faces()) {
    auto fv = om.cfv_iter(fh);
    const OMesh::Point a = om.point(*fv), b = om.point(*++fv), c = om.point(*++fv);
    const OMesh::Point n = (b - a) % (c - a);
    for (const auto& vh : om.fv_range(fh))
      normals[static_cast<std::size_t>(vh.idx())] += Eigen::Vector3d(n[0], n[1], n[2]);
  }
  for (auto& n : normals) {
    const double len = n.norm();
    if (len > 0.0) n /= len;
  }
  return normals;
}

std::vector<double> vertex_areas_mm2(const TriangleMesh& mesh) {
  std::vector<double> area(mesh.vertices_mm.size(), 0.0);
  for (const auto& t : mesh.triangles) {
    const double third = area_normal(mesh, t).norm() / 6.0;
    for (int c = 0; c < 3; ++c) area[static_cast<std::size_t>(t[c])] += third;
  }
  return area;
}

namespace {

// Quadric decimation of some of a mesh's triangles (indices into mesh.triangles) to at most
// `budget`, vertices marked in `locked` kept: the result's vertices are original ones
// (`kept`: their indices in `mesh`).
TriangleMesh decimate_part(const TriangleMesh& mesh, const std::vector<int>& triangles,
                           const std::vector<std::uint8_t>& locked, std::size_t budget, std::vector<int>& kept) {
  OMesh om;
  OpenMesh::VPropHandleT<int> original;
  om.add_property(original);
  std::vector<int> local(mesh.vertices_mm.size(), -1);
  std::vector<OMesh::VertexHandle> handles;
  for (int t : triangles)
    for (int c = 0; c < 3; ++c) {
      const int v = mesh.triangles[static_cast<std::size_t>(t)][c];
      if (local[static_cast<std::size_t>(v)] >= 0) continue;
      local[static_cast<std::size_t>(v)] = static_cast<int>(handles.size());
      const auto& p = mesh.vertices_mm[static_cast<std::size_t>(v)];
      handles.push_back(om.add_vertex(OMesh::Point(p.x(), p.y(), p.z())));
      om.property(original, handles.back()) = v;
    }
  for (int t : triangles) {
    const Eigen::Vector3i& f = mesh.triangles[static_cast<std::size_t>(t)];
    om.add_face(handles[static_cast<std::size_t>(local[static_cast<std::size_t>(f[0])])],
                handles[static_cast<std::size_t>(local[static_cast<std::size_t>(f[1])])],
                handles[static_cast<std::size_t>(local[static_cast<std::size_t>(f[2])])]);
  }
  om.request_vertex_status();
  om.request_edge_status();
  om.request_halfedge_status();
  om.request_face_status();
  for (const auto& vh : handles)
    if (locked[static_cast<std::size_t>(om.property(original, vh))]) om.status(vh).set_locked(true);
  OpenMesh::Decimater::DecimaterT<OMesh> decimater(om);
  OpenMesh::Decimater::ModQuadricT<OMesh>::Handle quadric;
  decimater.add(quadric);
  decimater.initialize();
  decimater.decimate_to_faces(0, budget);
  om.garbage_collection();
  TriangleMesh out;
  std::vector<int> index(om.n_vertices(), -1);
  for (const auto& vh : om.vertices()) {
    if (om.is_isolated(vh)) continue;
    index[static_cast<std::size_t>(vh.idx())] = static_cast<int>(out.vertices_mm.size());
    const OMesh::Point& p = om.point(vh);
    out.vertices_mm.emplace_back(p[0], p[1], p[2]);
    kept.push_back(om.property(original, vh));
  }
  for (const auto& fh : om.faces()) {
    Eigen::Vector3i t;
    int c = 0;
    for (const auto& vh : om.fv_range(fh)) t[c++] = index[static_cast<std::size_t>(vh.idx())];
    out.triangles.push_back(t);
  }
  return out;
}

}  // namespace

std::size_t decimation_slabs(std::size_t triangles, std::size_t max_triangles) {
  constexpr std::size_t kMaxSlabs = 16, kSlabTriangles = 200'000;
  return std::max<std::size_t>(1, std::min({kMaxSlabs, triangles / kSlabTriangles, max_triangles / kSlabTriangles}));
}

TriangleMesh decimate(const TriangleMesh& mesh, std::size_t max_triangles, std::vector<int>& kept) {
  return decimate(mesh, max_triangles, kept, decimation_slabs(mesh.triangles.size(), max_triangles));
}

TriangleMesh decimate(const TriangleMesh& mesh, std::size_t max_triangles, std::vector<int>& kept, std::size_t slabs) {
  kept.clear();
  const std::size_t n = mesh.triangles.size();
  if (n <= max_triangles) {
    kept.resize(mesh.vertices_mm.size());
    for (std::size_t i = 0; i < kept.size(); ++i) kept[i] = static_cast<int>(i);
    return mesh;
  }
  slabs = std::max<std::size_t>(1, std::min(slabs, n));
  // Slabs of equal triangle counts along the bounding box's longest axis, by centroid (ties by
  // index: the order is the same for any number of threads).
  std::vector<std::pair<double, int>> order(n);
  if (slabs > 1) {
    Eigen::AlignedBox3d box;
    for (const auto& p : mesh.vertices_mm) box.extend(p);
    int axis = 0;
    box.sizes().maxCoeff(&axis);
    tbb::parallel_for(std::size_t{0}, n, [&](std::size_t i) {
      const Eigen::Vector3i& t = mesh.triangles[i];
      double sum = 0.0;
      for (int c = 0; c < 3; ++c) sum += mesh.vertices_mm[static_cast<std::size_t>(t[c])][axis];
      order[i] = {sum, static_cast<int>(i)};
    });
    tbb::parallel_sort(order.begin(), order.end());
  } else {
    for (std::size_t i = 0; i < n; ++i) order[i].second = static_cast<int>(i);
  }
  std::vector<std::vector<int>> part(slabs);
  for (std::size_t r = 0; r < n; ++r) part[r * slabs / n].push_back(order[r].second);
  // A vertex of triangles in two slabs stays, so that the decimated slabs still meet.
  std::vector<int> slab_of(mesh.vertices_mm.size(), -1);
  std::vector<std::uint8_t> locked(mesh.vertices_mm.size(), 0);
  for (std::size_t k = 0; k < slabs; ++k)
    for (int t : part[k])
      for (int c = 0; c < 3; ++c) {
        int& s = slab_of[static_cast<std::size_t>(mesh.triangles[static_cast<std::size_t>(t)][c])];
        if (s < 0)
          s = static_cast<int>(k);
        else if (s != static_cast<int>(k))
          locked[static_cast<std::size_t>(mesh.triangles[static_cast<std::size_t>(t)][c])] = 1;
      }
  std::vector<TriangleMesh> done(slabs);
  std::vector<std::vector<int>> done_kept(slabs);
  omerr().disable();  // complex edges at thin features: OpenMesh leaves those triangles out
  tbb::parallel_for(std::size_t{0}, slabs, [&](std::size_t k) {
    const std::size_t budget = max_triangles * part[k].size() / n;
    done[k] = decimate_part(mesh, part[k], locked, budget, done_kept[k]);
  });
  omerr().enable();
  if (slabs == 1) {
    kept = std::move(done_kept[0]);
    return std::move(done[0]);
  }
  // The slabs joined in order, each shared vertex once.
  TriangleMesh out;
  std::vector<int> index(mesh.vertices_mm.size(), -1);
  for (std::size_t k = 0; k < slabs; ++k) {
    std::vector<int> local(done[k].vertices_mm.size());
    for (std::size_t v = 0; v < local.size(); ++v) {
      int& at = index[static_cast<std::size_t>(done_kept[k][v])];
      if (at < 0) {
        at = static_cast<int>(out.vertices_mm.size());
        out.vertices_mm.push_back(done[k].vertices_mm[v]);
        kept.push_back(done_kept[k][v]);
      }
      local[v] = at;
    }
    for (const Eigen::Vector3i& t : done[k].triangles)
      out.triangles.emplace_back(local[static_cast<std::size_t>(t[0])], local[static_cast<std::size_t>(t[1])],
                                 local[static_cast<std::size_t>(t[2])]);
  }
  return out;
}

bool is_closed(const TriangleMesh& mesh) {
  // Each directed edge must appear once and its reverse once: the sorted directed edges have
  // no repeat and equal the sorted reversed ones. (Two parallel sorts: on a closed sphere of
  // 3.6 M triangles, 2 threads, 0.57-0.81 s against 2.5-2.7 s for a hash map of the edges.)
  auto key = [](int a, int b) {
    return (static_cast<std::uint64_t>(static_cast<std::uint32_t>(a)) << 32) | static_cast<std::uint32_t>(b);
  };
  const std::size_t n = mesh.triangles.size() * 3;
  std::vector<std::uint64_t> directed(n), reversed(n);
  tbb::parallel_for(std::size_t{0}, mesh.triangles.size(), [&](std::size_t i) {
    const Eigen::Vector3i& t = mesh.triangles[i];
    for (int c = 0; c < 3; ++c) {
      directed[3 * i + static_cast<std::size_t>(c)] = key(t[c], t[(c + 1) % 3]);
      reversed[3 * i + static_cast<std::size_t>(c)] = key(t[(c + 1) % 3], t[c]);
    }
  });
  tbb::parallel_sort(directed.begin(), directed.end());
  if (std::adjacent_find(directed.begin(), directed.end()) != directed.end()) return false;
  tbb::parallel_sort(reversed.begin(), reversed.end());
  return directed == reversed;
}

}  // namespace vcut::removal
