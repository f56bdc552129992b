#include "fcl_queries.h"

#include <fcl/geometry/bvh/BVH_model.h>
#include <fcl/geometry/shape/sphere.h>
#include <fcl/math/bv/OBBRSS.h>
#include <fcl/narrowphase/collision.h>
#include <fcl/narrowphase/distance.h>

#include <vector>

namespace vcut::pipeline::detail {

class CollisionMesh {
 public:
  fcl::BVHModel<fcl::OBBRSSd> bvh;
};

std::shared_ptr<const CollisionMesh> collision_mesh(const removal::TriangleMesh& mesh) {
  auto out = std::make_shared<CollisionMesh>();
  std::vector<fcl::Vector3d> points(mesh.vertices_mm.begin(), mesh.vertices_mm.end());
  std::vector<fcl::Triangle> triangles;
  triangles.reserve(mesh.triangles.size());
  for (const Eigen::Vector3i& t : mesh.triangles)
    triangles.emplace_back(static_cast<std::size_t>(t[0]), static_cast<std::size_t>(t[1]),
                           static_cast<std::size_t>(t[2]));
  out->bvh.beginModel();
  out->bvh.addSubModel(points, triangles);
  out->bvh.endModel();
  return out;
}

MeshDistance mesh_distance(const CollisionMesh& a, const Eigen::Isometry3d& ta, const CollisionMesh& b,
                           const Eigen::Isometry3d& tb) {
  fcl::DistanceRequestd request(true);
  fcl::DistanceResultd result;
  fcl::distance(&a.bvh, fcl::Transform3d(ta.matrix()), &b.bvh, fcl::Transform3d(tb.matrix()), request, result);
  MeshDistance out;
  out.distance_mm = result.min_distance > 0.0 ? result.min_distance : 0.0;
  out.point = 0.5 * (result.nearest_points[0] + result.nearest_points[1]);
  return out;
}

bool mesh_contact(const CollisionMesh& a, const Eigen::Isometry3d& ta, const CollisionMesh& b,
                  const Eigen::Isometry3d& tb, double& depth_mm, Eigen::Vector3d& point) {
  fcl::CollisionRequestd request(64, true);
  fcl::CollisionResultd result;
  fcl::collide(&a.bvh, fcl::Transform3d(ta.matrix()), &b.bvh, fcl::Transform3d(tb.matrix()), request, result);
  for (std::size_t k = 0; k < result.numContacts(); ++k) {
    const fcl::Contactd& c = result.getContact(k);
    if (k == 0 || c.penetration_depth > depth_mm) {
      depth_mm = c.penetration_depth;
      point = c.pos;
    }
  }
  return result.isCollision();
}

double point_distance_mm(const CollisionMesh& mesh, const Eigen::Vector3d& point) {
  const fcl::Sphered dot(1e-9);
  fcl::Transform3d at = fcl::Transform3d::Identity();
  at.translation() = point;
  fcl::DistanceRequestd request;
  fcl::DistanceResultd result;
  fcl::distance(&dot, at, &mesh.bvh, fcl::Transform3d::Identity(), request, result);
  return result.min_distance;
}

}  // namespace vcut::pipeline::detail
