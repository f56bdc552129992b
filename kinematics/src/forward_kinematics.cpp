#include "vcut/kinematics/forward_kinematics.h"

#include <cmath>

#include "chain.h"

namespace vcut::kinematics {
namespace detail {

Eigen::Matrix3d rotation(const Eigen::Vector3d& k, double angle_rad) {
  const double c = std::cos(angle_rad), s = std::sin(angle_rad), v = 1.0 - c;
  Eigen::Matrix3d r;
  r << c + k.x() * k.x() * v, k.x() * k.y() * v - k.z() * s, k.x() * k.z() * v + k.y() * s,  //
      k.y() * k.x() * v + k.z() * s, c + k.y() * k.y() * v, k.y() * k.z() * v - k.x() * s,   //
      k.z() * k.x() * v - k.y() * s, k.z() * k.y() * v + k.x() * s, c + k.z() * k.z() * v;
  return r;
}

Eigen::Matrix3d rotation_vector(const Eigen::Vector3d& v) {
  const double angle = v.norm();
  if (angle == 0.0) return Eigen::Matrix3d::Identity();
  return rotation(v / angle, angle);
}

namespace {

// The component errors at position q: Tr(translation) Rot(rotation) about the node origin.
Rigid component_error(const ComponentErrors& e, double q) {
  Rigid r;
  Eigen::Vector3d rot;
  for (int i = 0; i < 3; ++i) {
    r.t[i] = e.translation_mm[static_cast<size_t>(i)].at(q);
    rot[i] = e.rotation_rad[static_cast<size_t>(i)].at(q);
  }
  r.R = rotation_vector(rot);
  return r;
}

}  // namespace

Rigid node_transform(const AxisSpec& a, double q, Geometry geometry) {
  const bool actual = geometry == Geometry::Actual;
  if (a.kind == AxisKind::Linear) {
    // Squareness turns the direction of motion; component errors follow the ideal motion
    // (ideal x error, seed 002 eq. 1.15).
    Rigid ideal;
    ideal.t = q * (actual ? rotation_vector(a.location.tilt_rad) * a.direction : a.direction);
    if (!actual || a.errors.empty()) return ideal;
    return ideal * component_error(a.errors, q);
  }
  const Eigen::Matrix3d turn = rotation(a.direction, q);
  if (!actual || (a.errors.empty() && a.location.empty())) return {turn, a.center_mm - turn * a.center_mm};
  // Tr(c) Tr(offset) Rot(tilt) R(axis, q) E(q) Tr(-c): the node turns about the displaced,
  // tilted axis line; the component errors follow the rotation.
  Rigid to_center{Eigen::Matrix3d::Identity(), a.center_mm};
  Rigid location{rotation_vector(a.location.tilt_rad), a.location.offset_mm};
  Rigid ideal{turn, Eigen::Vector3d::Zero()};
  Rigid from_center{Eigen::Matrix3d::Identity(), -a.center_mm};
  return to_center * location * ideal * component_error(a.errors, q) * from_center;
}

void append_node(Rigid& r, const AxisSpec& a, double q, Geometry geometry) {
  // A linear node without component errors is a pure translation: r * {I, t} = {R, R t + r.t}
  // bit for bit (R I = R exactly), without the 3x3 product - the interpolator pays a forward
  // kinematics every period.
  if (a.kind == AxisKind::Linear && (geometry == Geometry::Ideal || a.errors.empty())) {
    r.t += r.R * node_transform(a, q, geometry).t;
    return;
  }
  r = r * node_transform(a, q, geometry);
}

Chains chains(const Machine& m, const AxisValues& q, Geometry geometry) {
  Chains c;
  for (int i : m.workpiece_chain()) append_node(c.workpiece, m.axis(i), q[i], geometry);
  c.workpiece.t = c.workpiece.apply(m.spec().workpiece_origin_mm);
  for (int i : m.tool_chain()) append_node(c.tool, m.axis(i), q[i], geometry);
  return c;
}

}  // namespace detail

ToolPose forward(const Machine& m, const AxisValues& q, double tool_length_mm, Geometry geometry) {
  const detail::Chains c = detail::chains(m, q, geometry);
  const Eigen::Vector3d tip_frame = c.tool.apply(m.spec().gauge_point_mm - tool_length_mm * m.spec().spindle_axis);
  const Eigen::Vector3d axis_frame = c.tool.R * m.spec().spindle_axis;
  ToolPose pose;
  pose.tip_mm = c.workpiece.R.transpose() * (tip_frame - c.workpiece.t);
  pose.axis = (c.workpiece.R.transpose() * axis_frame).normalized();
  return pose;
}

std::vector<NodePose> node_poses(const Machine& m, const AxisValues& q, Geometry geometry) {
  std::vector<NodePose> out;
  auto add = [&](char node, const detail::Rigid& r) {
    NodePose p;
    p.node = node;
    p.pose.linear() = r.R;
    p.pose.translation() = r.t;
    out.push_back(p);
  };
  detail::Rigid w, t;
  for (int i : m.workpiece_chain()) {
    w = w * detail::node_transform(m.axis(i), q[i], geometry);
    add(m.axis(i).letter, w);
  }
  for (int i : m.tool_chain()) {
    t = t * detail::node_transform(m.axis(i), q[i], geometry);
    add(m.axis(i).letter, t);
  }
  w.t = w.apply(m.spec().workpiece_origin_mm);
  add('W', w);
  t.t = t.apply(m.spec().gauge_point_mm);
  add('T', t);
  return out;
}

std::vector<NodePose> node_frames(const Machine& m, const AxisValues& q, Geometry geometry) {
  std::vector<NodePose> out = node_poses(m, q, geometry);
  for (NodePose& n : out) {
    if (n.node == 'W') n.pose.translation() -= n.pose.linear() * m.spec().workpiece_origin_mm;
    if (n.node == 'T') n.pose.translation() -= n.pose.linear() * m.spec().gauge_point_mm;
  }
  out.push_back({'F', Eigen::Isometry3d::Identity()});
  return out;
}

std::vector<ModelPose> model_poses(const Machine& m, const AxisValues& q, Geometry geometry) {
  const std::vector<NodePose> nodes = node_frames(m, q, geometry);
  std::vector<ModelPose> out;
  for (const auto& [node, models] : m.spec().models) {
    // A model moves with its node.
    Eigen::Isometry3d node_pose = Eigen::Isometry3d::Identity();
    for (const NodePose& n : nodes)
      if (n.node == node) node_pose = n.pose;
    for (const ModelSpec& model : models) {
      ModelPose p;
      p.node = node;
      p.file = model.file;
      p.pose = node_pose * Eigen::Translation3d(model.origin_mm);
      out.push_back(p);
    }
  }
  return out;
}

PoseError pose_error(const ToolPose& nominal, const ToolPose& actual) {
  PoseError e;
  e.tip_um = (actual.tip_mm - nominal.tip_mm) * 1000.0;
  e.axis_tilt_urad = std::atan2(nominal.axis.cross(actual.axis).norm(), nominal.axis.dot(actual.axis)) * 1e6;
  return e;
}

}  // namespace vcut::kinematics
