// Probing G38.2..G38.5 and G31: where the probe stops, what #5061.. and #5070 say, and what
// is refused - with a stock given as a contact function (the plane z = 0 as the top of the
// stock below it), and without one (LinuxCNC's standalone rs274: the probe trips 0.254 mm
// before its end, #5070 = 0).
#include <gtest/gtest.h>

#include <optional>
#include <string>

#include "gcode_text.h"

namespace vcut::io {
namespace {

using gcode_test::error_text;
using gcode_test::read_text;

// Stock filling z <= 0: a move from a to b first touches it at the fraction where z crosses 0.
GcodeOptions with_floor(GcodeOptions::Flavor flavor = GcodeOptions::Flavor::Generic) {
  GcodeOptions options;
  options.flavor = flavor;
  options.start_mm = Eigen::Vector3d(0, 0, 50);
  options.probe_contact = [](const Eigen::Vector3d& a, const Eigen::Vector3d& b) -> std::optional<double> {
    if (a.z() <= 0.0) return 0.0;
    if (b.z() > 0.0) return std::nullopt;
    return a.z() / (a.z() - b.z());
  };
  return options;
}

TEST(Probe, G382StopsOnTheStockAndReportsWhere) {
  // From Z10 toward Z-5 the tip meets z = 0 two thirds of the way; G10 L20 then makes that
  // Z0 of G54 (offset 0 here, so a G1 Z-2 goes 2 below the surface).
  const auto program = read_text(
      "G21 G90 F100\nG0 X3 Y4 Z10\nG38.2 Z-5\n#1 = #5063\n#2 = #5070\nG10 L20 P1 Z0\nG0 Z[#1 + 5 + #2 * 100]\n",
      with_floor(), "probe.ngc");
  ASSERT_EQ(program.blocks.size(), 3u);
  EXPECT_EQ(program.blocks[1].kind, kinematics::MotionKind::Linear);
  EXPECT_DOUBLE_EQ(program.blocks[1].feed_mm_per_min, 100.0);
  EXPECT_LT((program.blocks[1].end_mm - Eigen::Vector3d(3, 4, 0)).norm(), 1e-12);
  // #5063 = 0 (the surface) and #5070 = 1: the last move goes to 105 mm above the new zero,
  // which is the surface: workpiece z 105.
  EXPECT_NEAR(program.blocks[2].end_mm.z(), 105.0, 1e-9);
}

TEST(Probe, WithoutContact) {
  // G38.3 and G31 run to their end (#5070 = 0); G38.2 is an error, as on the control.
  const auto program =
      read_text("G21 G90 F100\nG0 X0 Y0 Z10\nG38.3 Z2\nG0 Z[20 + #5070 * 100]\n", with_floor(), "miss.ngc");
  EXPECT_NEAR(program.blocks[1].end_mm.z(), 2.0, 1e-12);
  EXPECT_NEAR(program.blocks.back().end_mm.z(), 20.0, 1e-12);
  const std::string e = error_text("G21 G90 F100\nG0 X0 Y0 Z10\nG38.2 Z2\n", with_floor(), "miss2.ngc");
  EXPECT_NE(e.find("miss2.ngc:3:1: G38.2 ends without touching the stock"), std::string::npos) << e;
  // Starting inside the stock: the probe is already tripped.
  const std::string inside = error_text("G21 G90 F100\nG0 X0 Y0 Z-1\nG38.3 Z-5\n", with_floor(), "in.ngc");
  EXPECT_NE(inside.find("in.ngc:3:1: G38.3: the probe touches the stock where it starts"), std::string::npos) << inside;
}

TEST(Probe, AwayFromTheStock) {
  // G38.4 from inside (z -4) up to z 6 loses contact at z = 0, 40 % of the way.
  const auto program = read_text("G21 G90 F100\nG0 X0 Y0 Z-4\nG38.4 Z6\n", with_floor(), "away.ngc");
  EXPECT_NEAR(program.blocks.back().end_mm.z(), 0.0, 1e-12);
  const std::string e = error_text("G21 G90 F100\nG0 X0 Y0 Z4\nG38.4 Z6\n", with_floor(), "away2.ngc");
  EXPECT_NE(e.find("G38.4: the probe does not touch the stock where it starts"), std::string::npos) << e;
}

TEST(Probe, FanucSkipG31IsOneShot) {
  // G31 probes on its line only; the next line moves in the G1 mode of before. Fanuc's skip
  // position is #5061..#5063.
  const auto program = read_text("G21 G90 G1 F100\nG0 X0 Y0 Z10\nG31 Z-5 F50\nG0 X[#5063 + 7]\nZ20\n",
                                 with_floor(GcodeOptions::Flavor::Fanuc), "g31.nc");
  ASSERT_EQ(program.blocks.size(), 4u);
  EXPECT_DOUBLE_EQ(program.blocks[1].feed_mm_per_min, 50.0);
  EXPECT_NEAR(program.blocks[1].end_mm.z(), 0.0, 1e-12);
  EXPECT_NEAR(program.blocks[2].end_mm.x(), 7.0, 1e-12);
  EXPECT_EQ(program.blocks[3].kind, kinematics::MotionKind::Rapid);  // G0 still in force
}

TEST(Probe, WithoutAStockAsLinuxCncsRs274) {
  // No contact function: the probe trips 0.254 mm before its end (rs274's saicanon), behind
  // its start on a shorter move; #5070 = 0; a G38.2 of zero length is refused.
  GcodeOptions options;
  options.start_mm = Eigen::Vector3d::Zero();
  const auto program =
      read_text("G21 G90 F10\nG0 Z5\nG38.2 Z-10\nG38.3 X0.1\nG0 Y[#5070 + #5061 * 1000]\n", options, "stub.ngc");
  ASSERT_EQ(program.blocks.size(), 4u);
  EXPECT_NEAR(program.blocks[1].end_mm.z(), -9.746, 1e-12);
  EXPECT_NEAR(program.blocks[2].end_mm.x(), 0.1 - 0.254, 1e-12);
  EXPECT_NEAR(program.blocks[3].end_mm.y(), -154.0, 1e-9);
  ASSERT_EQ(program.warnings.size(), 1u);
  EXPECT_NE(program.warnings[0].find("stub.ngc:3:1: G38.2 with no stock to touch"), std::string::npos)
      << program.warnings[0];
  const std::string e = error_text("G21 G90 F10\nG0 Z5\nG38.2 Z5\n", options, "zero.ngc");
  EXPECT_NE(e.find("zero.ngc:3:1: G38.2 to where the probe is"), std::string::npos) << e;
}

}  // namespace
}  // namespace vcut::io
