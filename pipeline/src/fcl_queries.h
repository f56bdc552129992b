// The FCL queries the machine check makes (machine_check.cpp), behind a small interface: FCL's
// templates (BVH building, mesh distance and collision) take 25 s to compile, so they live in
// one translation unit, fcl_queries.cpp, built with the same flags in both of `make test`'s
// builds (uninstrumented, like libfcl itself) so that ccache compiles it once.
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>

#include <memory>

#include "vcut/removal/mesh.h"

namespace vcut::pipeline::detail {

class CollisionMesh;  // a bounding-volume tree (OBBRSS) of a mesh's triangles

std::shared_ptr<const CollisionMesh> collision_mesh(const removal::TriangleMesh& mesh);

struct MeshDistance {
  double distance_mm = 0.0;                         // 0 where the surfaces meet
  Eigen::Vector3d point = Eigen::Vector3d::Zero();  // between the nearest points, frame of the poses
};
MeshDistance mesh_distance(const CollisionMesh& a, const Eigen::Isometry3d& ta, const CollisionMesh& b,
                           const Eigen::Isometry3d& tb);

// The deepest of up to 64 triangle contacts (FCL's depth: the overlap along a contact) and
// where; false when the surfaces do not meet.
bool mesh_contact(const CollisionMesh& a, const Eigen::Isometry3d& ta, const CollisionMesh& b,
                  const Eigen::Isometry3d& tb, double& depth_mm, Eigen::Vector3d& point);

// The distance from a point to a mesh's surface (the mesh's coordinates).
double point_distance_mm(const CollisionMesh& mesh, const Eigen::Vector3d& point);

}  // namespace vcut::pipeline::detail
