// Forward kinematics (ARCHITECTURE §4, seed 000 eqs. 8-13 and Table 5): axis values -> the
// pose of every node in the frame F and the tool pose in the workpiece frame, ideal or with
// the machine's geometric errors (each node transform ideal x error, composed exactly).
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>

#include <string>
#include <vector>

#include "vcut/kinematics/machine.h"
#include "vcut/kinematics/tool_pose.h"

namespace vcut::kinematics {

enum class Geometry { Ideal, Actual };  // Actual: with the machine's geometric errors

// The pose of one node (an axis letter, 'W' the workpiece at its programming zero, 'T' the
// spindle nose) in the frame: x_frame = pose * x_node.
struct NodePose {
  char node = 'F';
  Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
};

struct ModelPose {
  char node = 'F';
  std::string file;
  Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();  // model coordinates -> frame
};

// The tool pose in the workpiece frame for a tool `tool_length_mm` out of the spindle nose.
ToolPose forward(const Machine& machine, const AxisValues& q, double tool_length_mm,
                 Geometry geometry = Geometry::Ideal);

// Every axis node, then W and T, in the frame (animation, collision).
std::vector<NodePose> node_poses(const Machine& machine, const AxisValues& q, Geometry geometry = Geometry::Ideal);
// Every node's frame: node coordinates (the frame F's at all-zero axes) -> F; as node_poses,
// but W and T without their origin offsets (what models and bodies hang on), and F itself.
std::vector<NodePose> node_frames(const Machine& machine, const AxisValues& q, Geometry geometry = Geometry::Ideal);
std::vector<ModelPose> model_poses(const Machine& machine, const AxisValues& q, Geometry geometry = Geometry::Ideal);

// The volumetric error of a pose (seed 002 eqs. 1.16-1.17): actual minus nominal tip in the
// workpiece frame, and the angle between the actual and nominal tool axes.
struct PoseError {
  Eigen::Vector3d tip_um = Eigen::Vector3d::Zero();
  double axis_tilt_urad = 0.0;
};
PoseError pose_error(const ToolPose& nominal, const ToolPose& actual);

}  // namespace vcut::kinematics
