// Internal: rigid transforms of the node chains, shared by forward and inverse kinematics.
#pragma once

#include <Eigen/Core>

#include "vcut/kinematics/forward_kinematics.h"
#include "vcut/kinematics/machine.h"

namespace vcut::kinematics::detail {

// x_parent = R x_node + t.
struct Rigid {
  Eigen::Matrix3d R = Eigen::Matrix3d::Identity();
  Eigen::Vector3d t = Eigen::Vector3d::Zero();

  Rigid operator*(const Rigid& o) const { return {R * o.R, R * o.t + t}; }
  Eigen::Vector3d apply(const Eigen::Vector3d& x) const { return R * x + t; }
};

// The rotation by angle_rad about the unit vector k (Rodrigues).
Eigen::Matrix3d rotation(const Eigen::Vector3d& k, double angle_rad);
// The exact rotation for a rotation vector (angle |v| about v / |v|).
Eigen::Matrix3d rotation_vector(const Eigen::Vector3d& v);

// One node's transform in its parent's frame for axis value q (mm or rad).
Rigid node_transform(const AxisSpec& axis, double q, Geometry geometry);

// r = r * node_transform(axis, q, geometry), a translation's product done as one.
void append_node(Rigid& r, const AxisSpec& axis, double q, Geometry geometry);

// The frame -> workpiece-zero and frame -> spindle-nose transforms.
struct Chains {
  Rigid workpiece;  // x_frame = workpiece.apply(x_w)
  Rigid tool;       // x_frame = tool.apply(x_spindle), spindle coordinates = frame at zero
};
Chains chains(const Machine& machine, const AxisValues& q, Geometry geometry);

}  // namespace vcut::kinematics::detail
