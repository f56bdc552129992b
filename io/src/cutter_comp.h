// Cutter radius compensation as LinuxCNC's interpreter computes it (rs274ngc's straight and
// arc comp, GcodeState::CutterComp holds its state), shared by the G-code reader (G41/G42) and
// the APT reader (CUTCOM/LEFT, RIGHT). The tool's path is offset by the radius in the plane;
// each move is held until the next decides its end: a concave corner moves it to where the
// offset paths meet, a convex one gets an arc of the tool radius about the programmed corner.
#pragma once

#include <Eigen/Core>
#include <array>
#include <string>
#include <vector>

#include "vcut/io/gcode_reader.h"
#include "vcut/kinematics/program.h"

namespace vcut::io::detail {

// What a reader lends the compensation: the tool's position, the plane, a way to append a
// block (filled like any other of its moves) and to fail naming the line.
class CompHost {
 public:
  virtual ~CompHost() = default;
  virtual Eigen::Vector3d& tool_position() = 0;               // the tip, workpiece frame (mm)
  virtual void comp_plane(int& a, int& b, int& c) const = 0;  // the plane's axes and its normal's
  virtual double comp_unit() const = 0;                       // mm per program unit: rs274ngc's tolerances are in those
  // Appends `block`; held: into CutterComp::held (with the move's direction, or an arc's sweep
  // in rad) for the next move to end, instead of into the program.
  virtual void comp_append(kinematics::Block block, const std::array<bool, 3>& programmed, bool held,
                           const Eigen::Vector2d& direction, double sweep_rad) = 0;
  virtual kinematics::BlockList& comp_blocks() = 0;
  [[noreturn]] virtual void comp_fail(int column, const std::string& message) const = 0;
};

class Compensator {
 public:
  Compensator(GcodeState::CutterComp& comp, CompHost& host) : comp_(comp), host_(host) {}

  // A compensated straight move or arc (turn: signed turns, > 0 counterclockwise about the
  // plane's normal), its end the programmed point.
  void straight(kinematics::Block& block, const std::array<bool, 3>& programmed, int column);
  void arc(kinematics::Block& block, const std::array<bool, 3>& programmed, int turn, int column);
  // Moves the end of every held move to x (along its circle for an arc), checking that none
  // runs backwards or further round than programmed (a gouge), then emits them.
  void move_end_and_flush(const Eigen::Vector2d& x, int column);
  // Emits the held moves, each from where the one before ended.
  void flush();
  void check_range(const kinematics::Block& block) const;  // comp_fail beyond the readers' 1e6 mm bound

 private:
  // A compensated move in the plane's coordinates: the axes, the radius and side, the
  // programmed end P and the tool's point C.
  struct Move {
    int a = 0, b = 1, c = 2;
    double r = 0.0;
    bool left = true;
    Eigen::Vector3d programmed_end = Eigen::Vector3d::Zero();
    Eigen::Vector2d p = Eigen::Vector2d::Zero(), cur = Eigen::Vector2d::Zero();
  };
  Move move(const kinematics::Block& block) const;
  void corner(const kinematics::Block& main, const Eigen::Vector2d& corner, const Eigen::Vector2d& end, int turn);
  void convex_corner(const kinematics::Block& main, const Eigen::Vector2d& corner_point, const Eigen::Vector2d& start,
                     int turn);
  void straight_on(const Eigen::Vector2d& at);
  // Holds `block` ending at `end` (an arc: about `center`) until the next move decides its
  // end; its programmed end becomes the point O the next move starts from.
  void hold_move(kinematics::Block& block, const std::array<bool, 3>& programmed, const Move& m,
                 const Eigen::Vector2d& end, const Eigen::Vector2d* center, const Eigen::Vector2d& direction,
                 double sweep_rad);

  GcodeState::CutterComp& comp_;
  CompHost& host_;
};

}  // namespace vcut::io::detail
