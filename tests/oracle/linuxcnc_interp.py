#!/usr/bin/python3
"""LinuxCNC's rs274ngc interpreter through its Python module (`gcode`, the one AXIS previews
with), for programs that move U V W: the standalone rs274 has the axis mask X Y Z A B C and
stops at the first U V W word ("Bad character 'w' used"); through the module the axis mask is
the caller's, here all nine axes.

Usage: /usr/bin/python3 linuxcnc_interp.py PROGRAM TOOL_TABLE

Prints the canonical calls as `rs274 -g` prints them ("%5d N..... NAME(args)", numbers %.4f, in
the program's units), with U V W after A B C in STRAIGHT_TRAVERSE, STRAIGHT_FEED,
STRAIGHT_PROBE and ARC_FEED, so that rs274_oracle.py reads both alike. The module hands lengths
over in inches (it divides by 25.4 in G21): they are multiplied back here. Exit status 1 with
the interpreter's message on stderr when the program is refused. Python 3 standard library and
LinuxCNC's module only."""
import re
import sys

import gcode  # linuxcnc-uspace: /usr/lib/python3/dist-packages/gcode.*.so

MM_PER_INCH = 25.4
PLANES = {1: "CANON_PLANE_XY", 2: "CANON_PLANE_YZ", 3: "CANON_PLANE_XZ"}


def tool_table(path):
    """T number -> diameter (in), from the oracle's tool table ("T1 P1 Z0 D0.0625 ;...")."""
    tools = {}
    with open(path) as f:
        for line in f:
            t = re.search(r"\bT(\d+)", line)
            d = re.search(r"\bD([-+.\d]+)", line)
            if t:
                tools[int(t.group(1))] = float(d.group(1)) if d else 0.0
    return tools


class Canon:
    parameter_file = ""

    def __init__(self, tools):
        self.tools = tools
        self.count = 0
        self.metric = True  # G21 at power-on; each line's modes say
        self.units_printed = None

    def out(self, name, args):
        self.count += 1
        print("%5d N..... %s(%s)" % (self.count, name, ", ".join(args)))

    def length(self, v):  # inches from the module -> program units
        return "%.4f" % (v * MM_PER_INCH if self.metric else v)

    def angle(self, v):
        return "%.4f" % v

    def units(self):
        want = "CANON_UNITS_MM" if self.metric else "CANON_UNITS_INCHES"
        if want != self.units_printed:
            self.units_printed = want
            self.out("USE_LENGTH_UNITS", [want])

    # --- What the module asks.
    def next_line(self, linecode):
        self.metric = linecode.units == 210  # G21 (G20 is 200)

    def get_axis_mask(self):
        return 0x1ff  # X Y Z A B C U V W

    def get_block_delete(self):
        return True  # as rs274 -b

    def check_abort(self):
        return False

    def get_external_angular_units(self):
        return 1.0

    def get_external_length_units(self):
        return 1.0 / MM_PER_INCH  # machine units: inches, as the standalone rs274's

    def get_tool(self, pocket):
        d = self.tools.get(pocket, 0.0)
        return (pocket if pocket in self.tools else -1, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, d, 0.0, 0.0, 0)

    # --- Canonical calls the oracle reads.
    def pose(self, x, y, z, a, b, c, u, v, w):
        return [self.length(x), self.length(y), self.length(z), self.angle(a), self.angle(b), self.angle(c),
                self.length(u), self.length(v), self.length(w)]

    def straight_traverse(self, *p):
        self.units()
        self.out("STRAIGHT_TRAVERSE", self.pose(*p))

    def straight_feed(self, *p):
        self.units()
        self.out("STRAIGHT_FEED", self.pose(*p))

    def straight_probe(self, *p):
        self.units()
        self.out("STRAIGHT_PROBE", self.pose(*p))

    def rigid_tap(self, x, y, z):
        self.units()
        self.out("RIGID_TAP", [self.length(x), self.length(y), self.length(z)])

    def arc_feed(self, fe, se, fa, sa, rotation, ae, a, b, c, u, v, w):
        self.units()
        self.out("ARC_FEED", [self.length(fe), self.length(se), self.length(fa), self.length(sa), "%d" % rotation,
                              self.length(ae), self.angle(a), self.angle(b), self.angle(c), self.length(u),
                              self.length(v), self.length(w)])

    def set_g5x_offset(self, index, x, y, z, a, b, c, u=0.0, v=0.0, w=0.0):
        self.units()
        self.out("SET_G5X_OFFSET", ["%d" % index] + self.pose(x, y, z, a, b, c, u, v, w))

    def set_g92_offset(self, x, y, z, a, b, c, u=0.0, v=0.0, w=0.0):
        self.units()
        self.out("SET_G92_OFFSET", self.pose(x, y, z, a, b, c, u, v, w))

    def set_xy_rotation(self, t):
        self.out("SET_XY_ROTATION", ["%.4f" % t])

    def set_plane(self, plane):
        self.out("SELECT_PLANE", [PLANES.get(plane, "CANON_PLANE_%d" % plane)])

    def set_feed_rate(self, rate):
        # The module divides every feed by 25.4 in G21 (inverse time too): undone here.
        self.out("SET_FEED_RATE", ["%.4f" % (rate * MM_PER_INCH if self.metric else rate)])

    def comment(self, text):
        self.out("COMMENT", ['"%s"' % text])

    def __getattr__(self, name):  # the calls the oracle does not read (dwell, change_tool ...)
        if name.startswith("__"):
            raise AttributeError(name)
        return lambda *args: None


def main():
    canon = Canon(tool_table(sys.argv[2]))
    try:
        result, last = gcode.parse(sys.argv[1], canon, "", "")
    except Exception as e:  # the module raises on an interpreter error in a callback
        print("%s" % e, file=sys.stderr)
        return 1
    if result > gcode.MIN_ERROR:
        print(gcode.strerror(result), file=sys.stderr)
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
