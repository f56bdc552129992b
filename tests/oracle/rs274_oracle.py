#!/usr/bin/env python3
"""Oracle test: vcut's G-code reader against LinuxCNC's standalone interpreter rs274.

Usage: rs274_oracle.py --vcut PATH/TO/vcut [--report FILE] [--install] [PROGRAMS...]

For each program (default: every sample program of Debian's linuxcnc-uspace, see census.py)
this runs

  rs274 -g -b -i TMP/oracle.ini -t TMP/tool.tbl -v TMP/params.var PROGRAM   (cwd TMP)
  vcut program PROGRAM --dialect gcode

and compares the two motion lists. Status per program:

  PASS      same motions (after the alignment rules below), ends/centres within tolerance
  SKIPPED   vcut rejects the program with an "unsupported"/"not supported" error (the feature
            is named in the detail column), whatever rs274 did
  REJECTED  both reject the program (rs274 with an interpreter error, vcut with an error that is
            not "unsupported"); nothing to compare
  FAIL      anything else: a differing motion (the first one is printed with both records),
            a different count, vcut rejecting what rs274 runs, or vcut accepting what rs274
            rejects

Exit status: 1 if any FAIL, 0 otherwise, 77 (ctest's skip code) if rs274 is missing and
--install was not given (or the install failed). Python 3 standard library only.

What rs274 prints (2.9.0~pre1, src/emc/sai/saicanon.cc), and how it is brought into vcut's frame:
  * One canonical call per line: "%5d N..... NAME(args)" (or "N<number>" when the block has an
    N word; the source line number is not printed). Numbers are printf %.4f.
  * Coordinates are PROGRAM coordinates in PROGRAM units (inches after G20): G5x, G92, G52,
    XY rotation (G10 L2 R) and the tool length offset are not applied. rs274 reports those as
    SET_G5X_OFFSET(n, x, y, z, a, b, c), SET_G92_OFFSET(x, y, z, a, b, c),
    SET_XY_ROTATION(deg) and USE_TOOL_LENGTH_OFFSET(...), each in the units in force when it
    is printed (it does not re-send them when G20/G21 changes). LinuxCNC's canon (emccanon.cc,
    rotate_and_offset_pos) makes the machine position as
        machine = rotate_z(program_mm + g92_mm, xy_rotation) + g5x_mm + tool_offset_mm
    vcut's blocks are "workpiece frame" = programmed point + work offset (job file, default
    zero), with G43 accepted as a no-op (the programmed point is the tool tip). So the oracle
    computes rotate_z(p + g92) + g5x in mm and leaves the tool length offset out. The var file
    the oracle gives rs274 is empty, so every work offset starts at zero, as vcut's defaults.
  * STRAIGHT_TRAVERSE(x, y, z, a, b, c), STRAIGHT_FEED(x, y, z, a, b, c) (no U V W: rs274's
    axis mask is XYZABC and it rejects U V W words with "Bad character 'u' used").
  * ARC_FEED(first_end, second_end, first_axis, second_axis, rotation, axis_end_point, a, b, c):
    G17: first/second = X/Y, axis = Z; G18: first/second = Z/X, axis = Y; G19: first/second =
    Y/Z, axis = X. first_axis/second_axis are the centre. rotation = +turns for G3 (counter-
    clockwise, i.e. a right-hand turn about first x second = +Z, +Y, +X), -turns for G2;
    |rotation| is the P word (default 1). vcut: normal = sign(rotation) * (+Z | +Y | +X),
    turns = |rotation|.
  * SET_FEED_RATE(f) in program units per minute (or inverse time / per rev, announced by a
    COMMENT("interpreter: feed mode set to ...") line). LinuxCNC reads the F word BEFORE it
    applies G20/G21 of the same line (rs274ngc's order of execution).

Alignment rules (where the two may legitimately split the motion differently). Each is applied
only when the rs274 record does not match the next vcut record as it stands:
  R1 zero-length moves: rs274 emits STRAIGHT_TRAVERSE/STRAIGHT_FEED that do not move (e.g. G28's
     intermediate point when it is the current position, "G0 X0" at X0); vcut drops blocks
     whose start equals their end. Such rs274 records are dropped.
  R2 unknown start position: rs274 starts at machine zero; vcut has no start position: until an
     axis has been programmed vcut holds it still, drops moves that move only such axes, and
     later patches the held value in earlier blocks to the axis's first programmed value
     (it warns "... ran while X was unknown; they hold X at V mm"). The oracle treats an axis
     as "possibly unknown to vcut" until its rs274 value first changes from 0; an rs274 record
     that changes only possibly-unknown axes may be dropped, and while an axis is possibly
     unknown, vcut's value for it may be 0 (rs274's) or the V of vcut's warning for that axis.
  R3 no program end: rs274 executes the whole file and then fails with "File ended with no
     percent sign or program end" when there is no M2/M30/closing '%'; vcut does not require
     one. That error alone is not a rejection: the motions are compared (PASS notes R3).
Nothing else is forgiven: a motion in one list and not the other, a different kind, an end or
centre beyond the tolerance, a different normal or turn count, a different feed.

Tolerance: positions are compared per axis within max(--tol (1e-4 mm), the rounding of the
printed numbers that entered the value: 0.5e-4 program units each for the position, the G92
and the G5x offset (an offset printed as all zeros counts as exact)) plus 1e-9 mm. So 1e-4 mm
for a G21 program without offsets, 1.27e-3 mm for a G20 one.
"""
import argparse
import math
import os
import re
import shutil
import subprocess
import sys
import tempfile
import time

sys.dont_write_bytecode = True  # no __pycache__ in the source tree
sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import census  # noqa: E402  (same directory; standard library only)

MM_PER_INCH = 25.4
HALF_ULP = 0.5e-4  # rs274 prints %.4f
SKIP_EXIT = 77

# ---------------------------------------------------------------------------------------------
# Running rs274


def find_rs274(explicit=None):
    if explicit:
        return explicit if os.path.isfile(explicit) and os.access(explicit, os.X_OK) else None
    found = shutil.which("rs274")
    if found:
        return found
    for p in ("/usr/bin/rs274", "/usr/local/bin/rs274"):
        if os.access(p, os.X_OK):
            return p
    return None


def install_rs274():
    """apt-get install linuxcnc-uspace (Debian 12). Returns (ok, message)."""
    apt = shutil.which("apt-get")
    if not apt:
        return False, "no apt-get on this system"
    prefix = [] if os.geteuid() == 0 else (["sudo", "-n"] if shutil.which("sudo") else None)
    if prefix is None:
        return False, "not root and no sudo"
    env = dict(os.environ, DEBIAN_FRONTEND="noninteractive")
    t0 = time.time()
    cmd = prefix + [apt, "install", "-y", "--no-install-recommends", "linuxcnc-uspace"]
    r = subprocess.run(cmd, env=env, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
    if r.returncode != 0:
        # The package lists may be missing (fresh container): update once and retry.
        subprocess.run(prefix + [apt, "update"], env=env, stdout=subprocess.DEVNULL,
                       stderr=subprocess.DEVNULL)
        r = subprocess.run(cmd, env=env, stdout=subprocess.PIPE, stderr=subprocess.STDOUT,
                           text=True)
    if r.returncode != 0:
        tail = r.stdout.strip().splitlines()[-1:] if r.stdout else []
        return False, "apt-get failed: " + (tail[0] if tail else "(no output)")
    return True, "installed linuxcnc-uspace in %.0f s" % (time.time() - t0)


_TOOL_WORD = re.compile(r"(?i)(?<![A-Z#<_])[TH]\s*(\d{1,5})(?!\d)")


def tool_table_text(program_text):
    """A tool table (LinuxCNC format) with tools 1..99 and every T/H number in the program, all
    with zero length and diameter. rs274 errors on G43 Hn / M6 with a tool that is not in its
    table, and without -t it loads the sample table (lengths in inches). Zero lengths keep
    USE_TOOL_LENGTH_OFFSET at zero (vcut ignores tool lengths anyway). Note: rs274's machine
    units are inches, so a real table's Z and D would be read as inches."""
    tools = set(range(1, 100))
    for m in _TOOL_WORD.finditer(program_text):
        n = int(m.group(1))
        if 0 < n <= 99999:
            tools.add(n)
    lines = ["T%d P%d Z0 D%s ;oracle" % (t, i + 1, tool_diameter_in(t)) for i, t in enumerate(sorted(tools))]
    return "\n".join(lines) + "\n"


def tool_diameter_in(t):
    """The diameter (in: rs274's machine units) the oracle gives tool t, for cutter compensation:
    T1 1/16 in (what useful-subroutines.ngc and comp-g1.ngc assume), T2 1/8 in, T3 0.201 in,
    0.1 in for the others."""
    return {1: "0.0625", 2: "0.125", 3: "0.201"}.get(t, "0.1")


def vcut_tools_text(program_text):
    """The same tools as a vcut tool library (mm)."""
    tools = set(range(1, 100))
    for m in _TOOL_WORD.finditer(program_text):
        n = int(m.group(1))
        if 0 < n <= 99999:
            tools.add(n)
    lines = ["tools:"]
    for t in sorted(tools):
        d = float(tool_diameter_in(t)) * 25.4
        lines.append("  %d: {type: flat, diameter: %r, flute_length: 10}" % (t, d))
    return "\n".join(lines) + "\n"


# LinuxCNC's table-rotary-tilting demos switch kinematics with M428 (TCP on), M429 (identity)
# and M430 (user kinematics), remapped in their ini to subroutines that set HAL pins. For rs274
# they are remapped here to empty subroutines (the interpreter's output is program coordinates
# either way); vcut is told the same with --tcp-on/--tcp-off.
KINS_M_CODES = {428: True, 429: False, 430: False}


def uses_kins_m_codes(program_text):
    # Always: the codes may sit in a subroutine file, and no other program uses them.
    return True


def run_rs274(rs274, program, program_text, sub_dirs, timeout):
    """Runs rs274 on `program` in a scratch directory. Returns (rc, stdout, stderr_lines)."""
    with tempfile.TemporaryDirectory(prefix="rs274-oracle-") as tmp:
        tbl = os.path.join(tmp, "tool.tbl")
        var = os.path.join(tmp, "params.var")
        ini = os.path.join(tmp, "oracle.ini")
        with open(tbl, "w") as f:
            f.write(tool_table_text(program_text))
        open(var, "w").close()  # empty: all parameters (work offsets, G28/G30 points) zero
        with open(ini, "w") as f:
            # o<name> call looks for name.ngc in SUBROUTINE_PATH (':'-separated, relative to the
            # cwd), [DISPLAY]PROGRAM_PREFIX and the cwd; not in the program's own directory.
            f.write("[RS274NGC]\nSUBROUTINE_PATH = %s\n" % ":".join(sub_dirs + [tmp]))
            if uses_kins_m_codes(program_text):
                for m in KINS_M_CODES:
                    f.write("REMAP = M%d modalgroup=10 ngc=m%dremap\n" % (m, m))
                    with open(os.path.join(tmp, "m%dremap.ngc" % m), "w") as sub:
                        sub.write("o<m%dremap> sub\no<m%dremap> endsub\nM2\n" % (m, m))
        cmd = [rs274, "-g", "-b", "-i", ini, "-t", tbl, "-v", var, os.path.abspath(program)]
        # LinuxCNC 2.9 keeps the tool table in $HOME/.tool.mmap, shared by every rs274 of the
        # user: a private HOME keeps another rs274 running at the same time out of this one.
        env = dict(os.environ, HOME=tmp)
        try:
            r = subprocess.run(cmd, cwd=tmp, env=env, stdin=subprocess.DEVNULL, stdout=subprocess.PIPE,
                               stderr=subprocess.PIPE, timeout=timeout)
        except subprocess.TimeoutExpired as e:
            out = (e.stdout or b"").decode("utf-8", "replace")
            return 124, out, ["rs274 timed out after %d s (an endless loop?)" % timeout]
        out = r.stdout.decode("utf-8", "replace")
        err = [l for l in r.stderr.decode("utf-8", "replace").splitlines()
               if l.strip() and l.strip() != "executing"]
        return r.returncode, out, err


# The standalone rs274's axis mask is X Y Z A B C: a U V W word stops it ("Bad character 'w'
# used"). LinuxCNC's interpreter through its Python module (linuxcnc_interp.py) takes the
# caller's mask: those programs are compared with its output, all nine axes.
_BAD_UVW = re.compile(r"Bad character '[uvw]' used", re.I)
INTERP_PY = "/usr/bin/python3"  # Debian's, which has linuxcnc-uspace's module
_interp_module = None


def interp_module_available():
    global _interp_module
    if _interp_module is None:
        try:
            _interp_module = subprocess.run([INTERP_PY, "-c", "import gcode"], stdin=subprocess.DEVNULL,
                                            stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL,
                                            timeout=60).returncode == 0
        except (OSError, subprocess.TimeoutExpired):
            _interp_module = False
    return _interp_module


def run_interp_module(program, program_text, sub_dirs, timeout):
    """linuxcnc_interp.py on `program`: (rc, stdout, stderr_lines), as run_rs274."""
    helper = os.path.join(os.path.dirname(os.path.abspath(__file__)), "linuxcnc_interp.py")
    with tempfile.TemporaryDirectory(prefix="rs274-oracle-module-") as tmp:
        tbl = os.path.join(tmp, "tool.tbl")
        with open(tbl, "w") as f:
            f.write(tool_table_text(program_text))
        ini = os.path.join(tmp, "oracle.ini")
        with open(ini, "w") as f:
            f.write("[RS274NGC]\nSUBROUTINE_PATH = %s\n" % ":".join(sub_dirs + [tmp]))
        env = dict(os.environ, HOME=tmp, INI_FILE_NAME=ini)
        try:
            r = subprocess.run([INTERP_PY, helper, os.path.abspath(program), tbl], cwd=tmp, env=env,
                               stdin=subprocess.DEVNULL, stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                               timeout=timeout)
        except subprocess.TimeoutExpired as e:
            return 124, (e.stdout or b"").decode("utf-8", "replace"), ["the interpreter module timed out"]
        err = [l for l in r.stderr.decode("utf-8", "replace").splitlines()
               if l.strip() and not l.startswith("!!!") and "updating variable file" not in l]
        return r.returncode, r.stdout.decode("utf-8", "replace"), err


# ---------------------------------------------------------------------------------------------
# Parsing rs274's canonical calls into motions in vcut's frame

_CANON = re.compile(r"^\s*(\d+)\s+N(\S*)\s*([A-Z_0-9]+)\((.*)\)\s*$")
_NUM = re.compile(r"[-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?|[-+]?(?:nan|inf)", re.I)

PLANE_AXES = {  # plane -> (first, second, normal) axis indices
    "XY": (0, 1, 2),
    "XZ": (2, 0, 1),  # G18: first = Z, second = X, axis = Y
    "YZ": (1, 2, 0),
}


def rotate_z(v, deg):
    if deg == 0.0:
        return list(v)
    t = math.radians(deg)
    c, s = math.cos(t), math.sin(t)
    return [v[0] * c - v[1] * s, v[0] * s + v[1] * c, v[2]]


class Rs274Motion:
    # synchronized: G33 / G33.1, the feed is the spindle's (not compared)
    __slots__ = ("synchronized", "index", "line", "kind", "end", "abc", "center", "normal", "turns", "feed",
                 "feed_mode", "feed_units", "tol", "changed", "unseen", "unseen_abc", "uvw")

    def describe(self):
        s = "#%d %s end=%s" % (self.index, self.kind, fmt_vec(self.end))
        if self.abc != [0.0, 0.0, 0.0]:
            s += " abc=%s" % fmt_vec(self.abc)
        if self.uvw != [0.0, 0.0, 0.0]:
            s += " uvw=%s" % fmt_vec(self.uvw)
        if self.kind == "arc":
            s += " center=%s normal=%s turns=%d" % (fmt_vec(self.center), fmt_vec(self.normal),
                                                    self.turns)
        if self.kind != "rapid" and self.feed is not None:
            s += " feed=%s%s" % (fmt_num(self.feed),
                                 "" if self.feed_mode == "upm" else " (%s)" % self.feed_mode)
        s += "  <- rs274 line %s: %s" % (self.line[0], self.line[1].strip())
        return s


def parse_rs274(stdout):
    """Returns the list of Rs274Motion in vcut's frame (mm, offsets applied, no TLO)."""
    units = 1.0  # mm per program unit
    g5x = [0.0] * 6
    g92 = [0.0] * 6
    g5x_uvw = [0.0] * 3  # U V W offsets (mm), from the interpreter module's 9-axis calls
    g92_uvw = [0.0] * 3
    uvw = [0.0] * 3  # the current U V W (mm, offsets applied)
    g5x_ulp = 0.0  # rounding (mm) in the offsets as printed
    g92_ulp = 0.0
    rot = 0.0
    plane = "XY"
    feed = None  # mm/min (or the raw number in other modes)
    feed_mode = "upm"
    feed_units = 1.0
    pos = [0.0] * 6  # machine (vcut frame) position, xyz mm + abc deg
    motions = []
    seen = [False, False, False]  # rs274 X/Y/Z has changed from its initial 0
    seen_abc = [False, False, False]  # and A/B/C

    def to_frame(p6):
        xyz = [p6[i] * units + g92[i] for i in range(3)]
        xyz = rotate_z(xyz, rot)
        xyz = [xyz[i] + g5x[i] for i in range(3)]
        abc = [p6[3 + i] + g92[3 + i] + g5x[3 + i] for i in range(3)]
        return xyz, abc

    synchronized = False  # between START_SPEED_FEED_SYNC and STOP_SPEED_FEED_SYNCH (G33, G33.1)
    for number, raw in enumerate(stdout.splitlines(), 1):
        m = _CANON.match(raw)
        if not m:
            continue  # (print,...) output and the like
        name, args = m.group(3), m.group(4)
        nums = [float(x) for x in _NUM.findall(args)]
        if name == "USE_LENGTH_UNITS":
            units = MM_PER_INCH if "INCH" in args else 1.0
        elif name == "SET_G5X_OFFSET" and len(nums) >= 7:
            g5x = [nums[1 + i] * (units if i < 3 else 1.0) for i in range(6)]
            g5x_uvw = [x * units for x in nums[7:10]] if len(nums) >= 10 else [0.0] * 3
            # printed zeros are taken as exact (the empty var file, G10 L2 X0 ...)
            g5x_ulp = HALF_ULP * units if any(nums[1:7]) else 0.0
        elif name == "SET_G92_OFFSET" and len(nums) >= 6:
            g92 = [nums[i] * (units if i < 3 else 1.0) for i in range(6)]
            g92_uvw = [x * units for x in nums[6:9]] if len(nums) >= 9 else [0.0] * 3
            g92_ulp = HALF_ULP * units if any(nums[0:6]) else 0.0
        elif name == "SET_XY_ROTATION" and nums:
            rot = nums[0]
        elif name == "SELECT_PLANE":
            plane = "XY" if "XY" in args else "XZ" if "XZ" in args else "YZ" if "YZ" in args else "?"
        elif name == "SET_FEED_RATE" and nums:
            feed = nums[0] * units if feed_mode == "upm" else nums[0]
            feed_units = units
        elif name == "COMMENT" and "feed mode set to" in args:
            feed_mode = ("inverse-time" if "inverse" in args else
                         "per-rev" if "revolution" in args else "upm")
        elif name == "START_SPEED_FEED_SYNC":
            synchronized = True
        elif name.startswith("STOP_SPEED_FEED_SYNC"):
            synchronized = False
        elif name in ("STRAIGHT_TRAVERSE", "STRAIGHT_FEED", "ARC_FEED", "STRAIGHT_PROBE",
                      "RIGID_TAP") or name.startswith("NURBS") or name.startswith("SPLINE"):
            mo = Rs274Motion()
            mo.synchronized = synchronized
            mo.index = len(motions)
            mo.line = (number, raw)
            mo.feed = feed
            mo.feed_mode = feed_mode
            mo.feed_units = feed_units
            mo.center = mo.normal = None
            mo.turns = 0
            mo.uvw = list(uvw)
            # U V W after A B C (the module's calls; rs274's have none): program units + offsets.
            extra = nums[6:9] if name != "ARC_FEED" else nums[9:12]
            if name in ("STRAIGHT_TRAVERSE", "STRAIGHT_FEED", "STRAIGHT_PROBE", "ARC_FEED") and len(extra) == 3:
                mo.uvw = [extra[i] * units + g92_uvw[i] + g5x_uvw[i] for i in range(3)]
            if name in ("STRAIGHT_TRAVERSE", "STRAIGHT_FEED", "STRAIGHT_PROBE") and len(nums) >= 6:
                # STRAIGHT_PROBE: a feed to the point; rs274 standalone trips the probe at its
                # end, as vcut does with no stock to touch (`vcut program`).
                mo.kind = {"STRAIGHT_TRAVERSE": "rapid", "STRAIGHT_FEED": "linear",
                           "STRAIGHT_PROBE": "linear"}[name]
                mo.end, mo.abc = to_frame(nums[:6])
                if name == "STRAIGHT_PROBE":
                    # rs274 prints the target; its probe trips 0.254 mm before it (saicanon's
                    # probe position, where the next move starts), as vcut's probe block ends.
                    start = motions[-1].end if motions else [0.0, 0.0, 0.0]
                    d = [mo.end[i] - start[i] for i in range(3)]
                    length = math.sqrt(sum(x * x for x in d))
                    if length > 0:
                        back = min(1.0, 0.254 / length)
                        mo.end = [mo.end[i] - back * d[i] for i in range(3)]
            elif name == "ARC_FEED" and len(nums) >= 9 and plane in PLANE_AXES:
                fe, se, fc, sc, turn, ae = nums[:6]
                a, b, c = PLANE_AXES[plane]
                end = [0.0] * 6
                end[a], end[b], end[c] = fe, se, ae
                end[3:6] = nums[6:9]
                cen = [0.0] * 6
                cen[a], cen[b] = fc, sc
                cen[c] = ae  # the normal coordinate is not compared (see compare())
                mo.kind = "arc"
                mo.end, mo.abc = to_frame(end)
                mo.center, _ = to_frame(cen)
                n = [0.0, 0.0, 0.0]
                n[c] = 1.0 if turn > 0 else -1.0
                mo.normal = rotate_z(n, rot)
                mo.turns = int(abs(turn))
            elif name == "RIGID_TAP" and len(nums) >= 3:
                # RIGID_TAP(x, y, z): the bottom of the tap; the tool comes back to where it was.
                mo.kind = "rigid_tap"
                mo.end, mo.abc = to_frame(list(nums[:3]) + [0.0, 0.0, 0.0])
                mo.abc = list(pos[3:])
            else:
                mo.kind = name.lower()  # NURBS...: vcut has nothing like it
                mo.end, mo.abc = list(pos[:3]), list(pos[3:])
            mo.tol = HALF_ULP * units + g5x_ulp + g92_ulp
            mo.changed = [abs(mo.end[i] - pos[i]) > 1e-9 for i in range(3)] + \
                         [abs(mo.abc[i] - pos[3 + i]) > 1e-9 for i in range(3)] + \
                         [abs(mo.uvw[i] - uvw[i]) > 1e-9 for i in range(3)]
            uvw = list(mo.uvw)
            mo.unseen = [not s for s in seen]
            mo.unseen_abc = [not s for s in seen_abc]
            for i in range(3):
                if mo.changed[3 + i]:
                    seen_abc[i] = True
            for i in range(3):
                # "changed from 0": against the printed program value, whatever the offsets
                if mo.changed[i]:
                    seen[i] = True
            if mo.kind != "rigid_tap":  # a rigid tap comes back to where it started
                pos = mo.end + mo.abc
            motions.append(mo)
    return motions


# ---------------------------------------------------------------------------------------------
# Running vcut


def run_vcut(vcut, program, timeout, kins_m_codes=False, sub_dirs=(), tools_text=None):
    import json
    cmd = [vcut, "program", program, "--dialect", "gcode"]
    if tools_text is not None:
        tools = tempfile.NamedTemporaryFile("w", suffix=".yaml", prefix="rs274-oracle-tools-", delete=False)
        tools.write(tools_text)
        tools.close()
        cmd += ["--tools", tools.name]
    for d in sub_dirs:
        cmd += ["--subroutine-path", d]
    if kins_m_codes:
        for m, on in KINS_M_CODES.items():
            cmd += ["--tcp-on" if on else "--tcp-off", str(m)]
    try:
        r = subprocess.run(cmd,
                           stdin=subprocess.DEVNULL, stdout=subprocess.PIPE,
                           stderr=subprocess.PIPE, timeout=timeout)
    except subprocess.TimeoutExpired:
        return 124, [], ["vcut timed out after %d s" % timeout]
    except OSError as e:  # e.g. the binary is being relinked
        return 126, [], ["cannot run vcut: %s" % e]
    records = []
    for line in r.stdout.decode("utf-8", "replace").splitlines():
        line = line.strip()
        if line.startswith("{"):
            try:
                records.append(json.loads(line))
            except ValueError:
                records.append({"kind": "?unparsable", "raw": line})
    err = [l for l in r.stderr.decode("utf-8", "replace").splitlines() if l.strip()]
    if tools_text is not None:
        os.unlink(tools.name)
    return r.returncode, records, err


_UNKNOWN_HOLD = re.compile(r"ran while ([XYZ]) was unknown; they hold \1 at (\S+) mm")
_UNSUPPORTED = re.compile(r"unsupported|not supported", re.I)


def vcut_error_message(err_lines):
    errs = [l for l in err_lines if "warning:" not in l]
    return errs[-1] if errs else (err_lines[-1] if err_lines else "(no message)")


def unsupported_feature(msg):
    """'...: parameters (#) are not supported (expected a word)' -> 'parameters (#)'."""
    m = re.search(r"unsupported ([^;(]*(?:\([^)]*\))?)", msg, re.I)
    if m:
        return m.group(1).strip()
    m = re.search(r"(?::\s*)?([^:]*?)\s+(?:is|are) not supported", msg)
    if m:
        return m.group(1).strip()
    return msg


# ---------------------------------------------------------------------------------------------
# Comparison


def fmt_num(v):
    return ("%.6f" % v).rstrip("0").rstrip(".") if isinstance(v, float) else str(v)


def fmt_vec(v):
    return "(" + ", ".join(fmt_num(float(x)) for x in v) + ")" if v is not None else "-"


def describe_vcut(j, rec):
    keys = ("kind", "start", "end", "center", "normal", "turns", "feed", "rotary", "source")
    parts = []
    for k in keys:
        if k in rec:
            v = rec[k]
            parts.append("%s=%s" % (k, fmt_vec(v) if isinstance(v, list) else
                                    ("{" + ", ".join("%s: %s" % (a, fmt_num(float(b)))
                                                     for a, b in v.items()) + "}")
                                    if isinstance(v, dict) else fmt_num(v)))
    return "#%d %s" % (j, " ".join(parts))


def compare_end(r, v, args, holds):
    """Returns None when rs274 motion r and vcut record v are of one kind and end at one point."""
    if v.get("kind") != r.kind:
        return "kind %s vs %s" % (r.kind, v.get("kind"))
    tol = max(args.tol, r.tol) + 1e-9
    end = v.get("end") or [math.nan] * 3
    for i in range(3):
        d = abs(end[i] - r.end[i])
        if d <= tol:
            continue
        # R2: an axis vcut did not know yet holds its first programmed value V (its warning).
        if r.unseen[i] and not r.changed[i] and "XYZ"[i] in holds and \
                abs(end[i] - holds["XYZ"[i]]) <= tol:
            continue
        return "end %s differs by %.6g mm (tolerance %.3g)" % ("XYZ"[i], d, tol)
    # Rotary axes (deg): vcut names those the program gave; the others must be 0 in rs274.
    rotary = v.get("rotary") or {}
    for i, letter in enumerate("ABC"):
        want = rotary.get(letter, 0.0)
        d = abs(want - r.abc[i])
        if d > HALF_ULP + 1e-9 and not (letter not in rotary and r.unseen_abc[i]):
            return "end %s differs by %.6g deg" % (letter, d)
    # U V W (mm): vcut names those the program moved; the others must be 0.
    extra = v.get("extra") or {}
    for i, letter in enumerate("UVW"):
        d = abs(float(extra.get(letter, 0.0)) - r.uvw[i])
        if d > tol:
            return "end %s differs by %.6g mm (tolerance %.3g)" % (letter, d, tol)
    return None


def motion_length(v):
    """(length, angular) of vcut record v: the XYZ path length in mm (helical for arcs), or,
    when X Y Z do not move, the A B C distance in degrees (rs274ngc's find_straight_length)."""
    s = v.get("start") or [0.0] * 3
    e = v.get("end") or [0.0] * 3
    if v.get("kind") == "arc":
        c = v["center"]
        n = v["normal"]
        a = [s[i] - c[i] for i in range(3)]
        b = [e[i] - c[i] for i in range(3)]
        an = sum(a[i] * n[i] for i in range(3))
        bn = sum(b[i] * n[i] for i in range(3))
        a = [a[i] - an * n[i] for i in range(3)]
        b = [b[i] - bn * n[i] for i in range(3)]
        radius = math.sqrt(sum(x * x for x in a))
        cross = [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]]
        theta = math.atan2(sum(cross[i] * n[i] for i in range(3)), sum(a[i] * b[i] for i in range(3)))
        if theta <= 1e-12:
            theta += 2 * math.pi
        theta += 2 * math.pi * (int(v.get("turns", 1)) - 1)
        height = bn - an
        return math.hypot(radius * theta, height), False
    xyz = math.sqrt(sum((e[i] - s[i]) ** 2 for i in range(3)))
    if xyz > 1e-9:
        return xyz, False
    u0 = v.get("start_extra") or {}
    u1 = v.get("extra") or {}
    uvw = math.sqrt(sum((float(u1.get(k, 0.0)) - float(u0.get(k, 0.0))) ** 2 for k in "UVW"))
    if uvw > 1e-9:
        return uvw, False
    r0 = v.get("start_rotary") or {}
    r1 = v.get("rotary") or {}
    return math.sqrt(sum((float(r1.get(k, 0.0)) - float(r0.get(k, 0.0))) ** 2
                         for k in "ABC")), True


def compare_pair(r, v, args, holds):
    """Returns None when rs274 motion r and vcut record v agree, else the reason."""
    why = compare_end(r, v, args, holds)
    if why:
        return why
    tol = max(args.tol, r.tol) + 1e-9
    rotary = v.get("rotary") or {}
    for i, a in enumerate("ABC"):
        want = r.abc[i]
        got = rotary.get(a)
        if got is None:
            if abs(want) > tol:
                return "%s: rs274 %s deg, vcut has no %s" % (a, fmt_num(want), a)
        elif abs(got - want) > max(tol, HALF_ULP) + 1e-9:
            return "%s differs: %s vs %s deg" % (a, fmt_num(want), fmt_num(float(got)))
    if r.kind == "arc":
        n = v.get("normal") or [0, 0, 0]
        dot = sum(n[i] * r.normal[i] for i in range(3))
        if dot < 1 - 1e-9:
            return "normal %s vs %s (turn direction or plane)" % (fmt_vec(r.normal), fmt_vec(n))
        if int(v.get("turns", 0)) != r.turns:
            return "turns %d vs %s" % (r.turns, v.get("turns"))
        c = v.get("center") or [math.nan] * 3
        d = [c[i] - r.center[i] for i in range(3)]
        along = sum(d[i] * r.normal[i] for i in range(3))
        d = [d[i] - along * r.normal[i] for i in range(3)]  # the normal coordinate is free
        # Per axis, like the end point: each printed centre coordinate is rounded on its own.
        worst = max(range(3), key=lambda i: abs(d[i]))
        if not abs(d[worst]) <= tol:
            return "centre %s differs by %.6g mm (tolerance %.3g)" % ("XYZ"[worst], abs(d[worst]),
                                                                     tol)
    if r.kind in ("linear", "arc") and r.feed is not None and not args.no_feed and not r.synchronized and \
            r.feed_mode in ("upm", "inverse-time"):
        want_mode = "mm/min" if r.feed_mode == "upm" else "inverse-time"
        if v.get("feed_mode", want_mode) != want_mode:
            return "feed mode %s vs %s" % (want_mode, v.get("feed_mode"))
        vf = float(v.get("feed", math.nan))
        if r.feed_mode == "upm":
            # program units/min, converted to mm/min with the units of SET_FEED_RATE's time
            ftol = max(1e-6 * abs(r.feed), r.tol) + 1e-9
            if not abs(vf - r.feed) <= ftol:
                return "feed %s vs %s mm/min" % (fmt_num(r.feed), fmt_num(vf))
        else:
            # G93: rs274ngc turns the F word (1/min) into a rate before SET_FEED_RATE
            # (inverse_time_rate_straight/_arc): F x the move's length in program units (the
            # XYZ length, or for a move of A B C only their length in degrees; the helical
            # length for arcs). The printed value is compared with vcut's F x that length.
            length, angular = motion_length(v)
            want = vf * (length if angular else length / r.feed_units)
            ftol = max(1e-6 * abs(r.feed), HALF_ULP) + 1e-6 * abs(vf) + 1e-9
            if not abs(want - r.feed) <= ftol:
                return "inverse-time feed: rs274's rate %s %s/min is F x length; vcut's F %s " \
                       "x length %s gives %s" % (fmt_num(r.feed), "deg" if angular else
                                                 ("in" if r.feed_units != 1.0 else "mm"),
                                                 fmt_num(vf), fmt_num(length), fmt_num(want))
    return None


def stats_of(rs, vc, dropped_zero, dropped_unknown):
    return (len(rs), len(vc), dropped_zero, dropped_unknown)


def mismatch(i, j, r, vc, why):
    return ["first difference at rs274 motion %d / vcut motion %d: %s" % (i, j, why),
            "  rs274: " + r.describe(),
            "  vcut:  " + (describe_vcut(j, vc[j]) if j < len(vc) else "(none)")]


def align(rs, vc, args, holds):
    """Walks both lists. Returns (ok, detail, stats)."""
    i = j = 0
    dropped_zero = dropped_unknown = 0
    splines = taps = 0
    while i < len(rs):
        r = rs[i]
        if (r.kind.startswith("nurbs") or r.kind.startswith("spline")) and j < len(vc) and \
                vc[j].get("kind") == "linear":
            # R4: rs274 prints a spline (G5, G5.1) as one NURBS_FEED without its points; vcut
            # has the straight moves of one source line that follow it within 1 um (their
            # geometry is checked by tests/io/gcode_comp_test.cpp); the moves after must agree.
            source = vc[j].get("source")
            while j < len(vc) and vc[j].get("kind") == "linear" and vc[j].get("source") == source:
                j += 1
            i += 1
            splines += 1
            continue
        if r.kind == "rigid_tap" and j + 1 < len(vc):
            # R5: RIGID_TAP (G33.1) is one canon call; vcut has the feed down to its end and the
            # feed back up to where it started.
            down, up = vc[j], vc[j + 1]
            tol = max(args.tol, r.tol) + 1e-9
            if down.get("kind") == "linear" and up.get("kind") == "linear" and \
                    all(abs(down["end"][k] - r.end[k]) <= tol for k in range(3)) and \
                    all(abs(up["end"][k] - down["start"][k]) <= 1e-9 for k in range(3)):
                i += 1
                j += 2
                taps += 1
                continue
        why = compare_pair(r, vc[j], args, holds) if j < len(vc) else "vcut has no more motions"
        if why is None:
            i += 1
            j += 1
            continue
        if j < len(vc) and compare_end(r, vc[j], args, holds) is None:
            # Same kind and end point but a different centre, normal, turns, rotary or feed:
            # the two agree on where this motion goes, so it is this pair that differs. (Without
            # this, R2 could drop the record and report a later, misleading difference.)
            return False, mismatch(i, j, r, vc, why), stats_of(rs, vc, dropped_zero,
                                                               dropped_unknown)
        moves = any(r.changed) or r.kind == "arc"
        if not moves and r.kind in ("rapid", "linear"):
            dropped_zero += 1  # R1
            i += 1
            continue
        if r.kind in ("rapid", "linear") and \
                all(r.unseen[k] or not r.changed[k] for k in range(3)) and not any(r.changed[3:]):
            dropped_unknown += 1  # R2
            i += 1
            continue
        return False, mismatch(i, j, r, vc, why), stats_of(rs, vc, dropped_zero, dropped_unknown)
    stats = stats_of(rs, vc, dropped_zero, dropped_unknown)
    if j < len(vc):
        return False, ["vcut has %d more motion(s) than rs274; first extra:" % (len(vc) - j),
                       "  vcut:  " + describe_vcut(j, vc[j])], stats
    return True, [], stats


# ---------------------------------------------------------------------------------------------


def check_program(path, args, rs274):
    display = path
    work = None
    program = path
    if path.endswith(".gz"):  # both tools read plain text: decompress to a scratch copy
        work = tempfile.mkdtemp(prefix="rs274-oracle-gz-")
        program = os.path.join(work, os.path.basename(path)[:-3])
        with open(program, "w") as f:
            f.write(census.read_text(path))
    try:
        text = census.read_text(program)
        sub_dirs = [os.path.dirname(os.path.abspath(path))] + \
                   [os.path.abspath(d) for d in args.subroutine_path]
        # A sample configuration keeps its subroutines beside its demos (remap_subs/).
        remap_subs = os.path.join(os.path.dirname(os.path.dirname(os.path.abspath(path))), "remap_subs")
        if os.path.isdir(remap_subs):
            sub_dirs.append(remap_subs)
        rc, out, rerr = run_rs274(rs274, program, text, sub_dirs, args.timeout)
        nine_axes = rc != 0 and any(_BAD_UVW.search(l) for l in rerr) and interp_module_available()
        if nine_axes:
            rc, out, rerr = run_interp_module(program, text, sub_dirs, args.timeout)
        vrc, vrecs, verr = run_vcut(args.vcut, program, args.timeout, uses_kins_m_codes(text), sub_dirs[1:],
                                    vcut_tools_text(text))
    finally:
        if work:
            shutil.rmtree(work, ignore_errors=True)
    rs_ok = rc == 0
    rs_msg = " | ".join(rerr[:2]) if rerr else ""
    # R3: rs274ngc requires M2, M30 or a closing '%' and reports "File ended with no percent sign
    # or program end" when it reaches the end of the file without one - after executing every
    # line before it. vcut does not require a program end. So that error alone does not count as
    # a rejection: the motions (all of the file's) are compared, and the detail says so.
    no_end = not rs_ok and rc != 124 and bool(rerr) and \
        rerr[0].startswith("File ended with no percent sign or program end")
    if no_end:
        rs_ok = True
    if vrc < 0 or vrc >= 124 or (vrc != 0 and not any("error" in l for l in verr)):
        # A signal (crash), the loader's 127, a timeout: not an answer about the program.
        return "FAIL", "-", "vcut did not run properly (exit status %d): %s" % (
            vrc, " | ".join(verr[-2:]) or "(no message)"), []
    if vrc != 0:
        vmsg = vcut_error_message(verr)
        rs_count = "%d/-" % len(parse_rs274(out))  # rs274's motions (before its error, if any)
        if _UNSUPPORTED.search(vmsg):
            return "SKIPPED", rs_count, unsupported_feature(vmsg), [
                "vcut: " + vmsg] + (["rs274 also fails: " + rs_msg] if not rs_ok else [])
        if not rs_ok:
            return "REJECTED", rs_count, "both reject; rs274: %s" % rs_msg, ["vcut: " + vmsg]
        rs = parse_rs274(out)
        return "FAIL", "%d/-" % len(rs), "vcut rejects what rs274 runs: " + vmsg, []
    rs = parse_rs274(out)
    if not rs_ok:
        return "FAIL", "%d/%d" % (len(rs), len(vrecs)), \
            "rs274 rejects (%s) but vcut accepts" % rs_msg, []
    holds = {}
    for l in verr:
        m = _UNKNOWN_HOLD.search(l)
        if m:
            holds[m.group(1)] = float(m.group(2))
    ok, detail, (nr, nv, dz, du) = align(rs, vrecs, args, holds)
    motions = "%d/%d" % (nr, nv)
    extra = []
    if dz:
        extra.append("%d zero-length dropped (R1)" % dz)
    if du:
        extra.append("%d unknown-start dropped (R2)" % du)
    if no_end:
        extra.append("no M2/M30/%: rs274 errors at the end of the file, vcut does not (R3)")
    if nine_axes:
        extra.append("U V W: LinuxCNC's interpreter module with all nine axes (rs274: Bad character used)")
    if ok:
        return "PASS", motions, "; ".join(extra) or "identical", []
    return "FAIL", motions, detail[0], detail[1:] + (["(" + "; ".join(extra) + ")"] if extra else [])


def write_program(folder, name, lines):
    """Writes a generated program (its lines) to folder/name; returns the path."""
    path = os.path.join(folder, name)
    with open(path, "w") as f:
        f.write("\n".join(lines) + "\n")
    return path


def random_comp_programs(n, seed, folder):
    """n random cutter-compensation programs (deterministic for a seed): G41.1/G42.1 with a
    random diameter, then lines and arcs (R and I J, both directions, some helical, some Z
    only) through random points, G40, an exit move, M2. Many corners are concave, convex,
    tangent or too tight; rs274 and vcut must agree on each (or both refuse it)."""
    import random
    rng = random.Random(seed)
    paths = []
    for k in range(n):
        lines = ["G21 G17 G90 G94", "G0 X0 Y0 Z0", "F500",
                 "G%s D%.3f" % (rng.choice(["41.1", "42.1"]), rng.uniform(0.5, 4.0))]
        x, y, z = 0.0, 0.0, 0.0
        for _ in range(rng.randint(2, 9)):
            kind = rng.random()
            if kind < 0.1:
                z = round(z + rng.uniform(-2, 2), 3)
                lines.append("G1 Z%.3f" % z)
                continue
            a = rng.uniform(0, 2 * math.pi)
            length = rng.uniform(4, 30)
            nx, ny = round(x + length * math.cos(a), 3), round(y + length * math.sin(a), 3)
            if kind < 0.55:
                lines.append("G%d X%.3f Y%.3f" % (rng.choice([0, 1, 1, 1]), nx, ny))
            elif kind < 0.8:
                r = round(length / 2 * rng.uniform(1.0, 3.0) * rng.choice([1, 1, -1]), 3)
                lines.append("G%d X%.3f Y%.3f R%.3f" % (rng.choice([2, 3]), nx, ny, r))
            else:  # centre on the chord's bisector: end exactly on the circle (to print precision)
                mx, my = (nx - x) / 2, (ny - y) / 2
                off = rng.uniform(-2, 2) * length / 2
                cx, cy = round(mx - off * math.sin(a), 3), round(my + off * math.cos(a), 3)
                ex, ey = x + cx, y + cy
                # move the end onto the circle about the rounded centre
                rr = math.hypot(cx, cy)
                ang = math.atan2(ny - ey, nx - ex)
                nx, ny = round(ex + rr * math.cos(ang), 3), round(ey + rr * math.sin(ang), 3)
                helix = " Z%.3f" % (z + 1) if rng.random() < 0.2 else ""
                if helix:
                    z += 1
                lines.append("G%d X%.3f Y%.3f I%.3f J%.3f%s" % (rng.choice([2, 3]), nx, ny, cx, cy, helix))
            x, y = nx, ny
        lines += ["G40", "G1 X%.3f Y%.3f" % (x + rng.uniform(-20, 20), y + rng.uniform(-20, 20)), "M2"]
        paths.append(write_program(folder, "comp-random-%03d.ngc" % k, lines))
    return paths


def random_uvw_programs(n, seed, folder):
    """n random programs that move U V W with X Y Z (deterministic for a seed), for LinuxCNC's
    interpreter module: G20/G21, G90/G91, rapids, feeds and arcs (W along the helix), G10 L2/L20
    P0..P9 offsets and G54..G59.3, G92/G92.1/G92.2/G92.3, G52, G53, G28/G30 named and not, G28.1,
    M70/M72, and #5426..#5428 read back into a word. Every line is one LinuxCNC runs."""
    import random
    rng = random.Random(seed)
    systems = ["G54", "G55", "G56", "G57", "G58", "G59", "G59.1", "G59.2", "G59.3"]
    paths = []
    for k in range(n):
        lines = ["G%d G17 G90 G94" % rng.choice([20, 21, 21]), "G0 X0 Y0 Z0", "F500"]
        incremental = False
        saved, saved_incremental = False, False
        for _ in range(rng.randint(10, 25)):
            kind = rng.random()
            words = lambda letters: " ".join("%s%.3f" % (a, rng.uniform(-20, 20)) for a in letters)
            some = "".join(a for a in "XYZUVW" if rng.random() < 0.4) or rng.choice("UVW")
            extra = "".join(a for a in "UVW" if rng.random() < 0.5) or rng.choice("UVW")
            if kind < 0.06:
                incremental = not incremental
                lines.append("G91" if incremental else "G90")
            elif kind < 0.5:
                lines.append("G%d %s" % (rng.choice([0, 1]), words(some)))
            elif kind < 0.58 and not incremental:
                # a helix: a whole circle about a centre 5 mm off in X, U V W along it
                lines.append("G%d I5 J0 %s" % (rng.choice([2, 3]), words(extra)))
            elif kind < 0.68:
                lines.append("G10 L%d P%d %s" % (rng.choice([2, 20]), rng.randint(0, 9), words(extra)))
            elif kind < 0.73:
                lines.append(rng.choice(systems))
            elif kind < 0.8:
                lines.append(rng.choice(["G92 %s" % words(extra), "G92.1", "G92.2", "G92.3",
                                         "G52 %s" % words(some.replace("Z", "") or "X")]))
            elif kind < 0.84 and not incremental:
                lines.append("G53 G0 %s" % words(extra))
            elif kind < 0.92:
                code = rng.choice(["G28", "G30"])
                lines.append(code if rng.random() < 0.3 else "%s %s" % (code, words(extra)))
            elif kind < 0.95:
                lines.append(rng.choice(["G28.1", "G30.1"]))
            elif kind < 0.97:
                # M70 saves the modes (the coordinate system, G90/G91, units); M72 brings them back.
                if saved:
                    lines.append("M72")
                    incremental = saved_incremental
                else:
                    lines.append("M70")
                    saved_incremental = incremental
                saved = not saved
            else:
                lines.append("G0 X#%d" % rng.choice([5426, 5427, 5428]))
        lines.append("M2")
        paths.append(write_program(folder, "uvw-random-%03d.ngc" % k, lines))
    return paths


def random_mixed_programs(n, seed, folder):
    """n random programs mixing what rs274ngc reads (deterministic for a seed): G20/G21,
    G90/G91, G90.1/G91.1, G17/G18/G19 arcs (whole circles by I J K, R arcs through a point
    within reach), G10 L2 P R (a rotated system), G10 L2/L20, G54..G59.3, G92 family, G52, G53,
    G28/G30 and G28.1, canned cycles G73/G81/G82/G83/G85/G89 with G98/G99 in G17, polar @ ^,
    M70/M72, numbered and named parameters in words. rs274 and vcut must agree on every one:
    the same motions, or both refuse it."""
    import random
    rng = random.Random(seed)
    systems = ["G54", "G55", "G56", "G57", "G58", "G59", "G59.1", "G59.2", "G59.3"]
    planes = {"G17": "XYZ", "G18": "ZXY", "G19": "YZX"}  # first, second, normal
    centre_words = {"X": "I", "Y": "J", "Z": "K"}
    paths = []
    for k in range(n):
        lines = ["G%d G17 G90 G94" % rng.choice([20, 21, 21]), "G0 X0 Y0 Z0", "F500"]
        plane = "G17"
        incremental = False
        saved = False
        # Turned systems (G10 L2 R) or G92/G52 offsets, not both: when a turn changes while a
        # G92 offset is on, rs274 takes the current program point as Rz^-1 (w - G5x - G92),
        # which its own next move maps elsewhere (a known difference, docs/PROGRAMS.md).
        turns = rng.random() < 0.5
        for _ in range(rng.randint(12, 30)):
            kind = rng.random()
            v = lambda: "%.3f" % rng.uniform(-20, 20)
            axes = "".join(a for a in "XYZ" if rng.random() < 0.5) or rng.choice("XYZ")
            words = lambda letters: " ".join("%s%s" % (a, v()) for a in letters)
            if kind < 0.05:
                incremental = not incremental
                lines.append("G91" if incremental else "G90")
            elif kind < 0.35:
                lines.append("G%d %s" % (rng.choice([0, 1]), words(axes)))
            elif kind < 0.42:
                plane = rng.choice(list(planes))
                first, second, normal = planes[plane]
                # a whole circle, the centre off the current point in the plane (G91.1: incremental)
                lines.append("%s G%d %s%s %s%s %s" % (plane, rng.choice([2, 3]), centre_words[first], v(),
                                                      centre_words[second], v(),
                                                      ("%s%s" % (normal, v())) if rng.random() < 0.3 else ""))
            elif kind < 0.47 and not incremental:
                first, second, _ = planes[plane]
                lines.append("G%d %s%s %s%s R%.3f" % (rng.choice([2, 3]), first, v(), second, v(),
                                                      rng.choice([1, -1]) * rng.uniform(25, 40)))
            elif kind < 0.52:
                lines.append("G10 L2 P%d %s%s" % (rng.randint(0, 9), words(axes),
                                                  (" R%.1f" % rng.uniform(-90, 90)) if turns and rng.random() < 0.3
                                                  else ""))
            elif kind < 0.55:
                lines.append("G10 L20 P%d %s" % (rng.randint(0, 9), words(axes)))
            elif kind < 0.6:
                lines.append(rng.choice(systems))
            elif kind < 0.66:
                lines.append(rng.choice(["G92.1", "G92.2"] if turns else
                                        ["G92 %s" % words(axes), "G92.1", "G92.2", "G92.3", "G52 %s" % words(axes)]))
            elif kind < 0.69 and not incremental:
                lines.append("G53 G0 %s" % words(axes))
            elif kind < 0.74:
                code = rng.choice(["G28", "G30", "G28.1"])
                lines.append(code if code == "G28.1" or rng.random() < 0.3 else "%s %s" % (code, words(axes)))
            elif kind < 0.82 and plane == "G17" and not incremental:
                cycle = rng.choice(["G81", "G82 P0.5", "G83 Q%.2f" % rng.uniform(0.5, 3), "G73 Q%.2f" % rng.uniform(0.5, 3),
                                    "G85", "G89 P0.2"])
                z = rng.uniform(-10, 0)
                lines.append("%s %s X%s Y%s Z%.3f R%.3f" % (rng.choice(["G98", "G99"]), cycle, v(), v(), z,
                                                          z + rng.uniform(0.5, 8)))
                lines.append("X%s Y%s" % (v(), v()))
                lines.append("G80")
            elif kind < 0.86 and plane == "G17":  # (rs274 takes polar words in G17 only)
                lines.append("G%d @%.3f ^%.2f" % (rng.choice([0, 1]), rng.uniform(0, 20), rng.uniform(-180, 180)))
            elif kind < 0.9:
                lines.append(rng.choice(["G90.1", "G91.1"]))
            elif kind < 0.93:
                lines.append("M72" if saved else "M70")
                if saved:
                    rng.random()  # a draw the programs measured in docs/PROGRAMS.md depend on
                    # M72 brings back M70's G90/G91; taken as G90 here, so a G53 or an arc in G91
                    # may follow, which rs274 and vcut both refuse.
                    incremental = False
                saved = not saved
            elif kind < 0.97:
                lines.append("#<p%d> = %s" % (k % 3, v()))
                lines.append("G1 X[#<p%d> * 2] Y#5422" % (k % 3))
            else:
                # (#5211.. and #5221.. are in the machine's units, inches for the standalone rs274:
                # only the position, in program units, is read back here)
                lines.append("G0 X#%d Y#%d" % (rng.choice([5420, 5421, 5422]), rng.choice([5420, 5421, 5422])))
        lines.append("M2")
        paths.append(write_program(folder, "mixed-random-%03d.ngc" % k, lines))
    return paths


def main(argv=None):
    ap = argparse.ArgumentParser(
        description="Compare vcut's G-code reader with LinuxCNC's rs274 interpreter.")
    ap.add_argument("programs", nargs="*",
                    help="programs or directories (default: the linuxcnc-uspace samples)")
    ap.add_argument("--vcut", required=True, help="the vcut binary")
    ap.add_argument("--report", help="also write the summary and the details to this file")
    ap.add_argument("--install", action="store_true",
                    help="apt-get install linuxcnc-uspace when rs274 is missing")
    ap.add_argument("--rs274", help="the rs274 binary (default: from PATH)")
    ap.add_argument("--tol", type=float, default=1e-4, help="position tolerance, mm (1e-4)")
    ap.add_argument("--timeout", type=int, default=60, help="seconds per tool run (60)")
    ap.add_argument("--subroutine-path", action="append", default=[],
                    help="more directories for o<name> call files (the program's own directory "
                         "is always searched)")
    ap.add_argument("--no-feed", action="store_true", help="do not compare feeds")
    ap.add_argument("--min-identical", type=int, default=0, metavar="N",
                    help="fail unless at least N of the programs given (or shipped; not the random "
                         "ones) that make a motion under rs274 are identical")
    ap.add_argument("--random-comp", type=int, default=0, metavar="N",
                    help="also N random cutter-compensation programs (seed --seed)")
    ap.add_argument("--random-uvw", type=int, default=0, metavar="N",
                    help="also N random programs moving U V W (LinuxCNC's interpreter module; seed --seed)")
    ap.add_argument("--random-mixed", type=int, default=0, metavar="N",
                    help="also N random programs mixing modes, planes, offsets, cycles and parameters")
    ap.add_argument("--seed", type=int, default=1, help="seed of the random programs (1)")
    ap.add_argument("-v", "--verbose", action="store_true",
                    help="print the details of SKIPPED/REJECTED programs too")
    args = ap.parse_args(argv)

    if not (os.path.isfile(args.vcut) and os.access(args.vcut, os.X_OK)):
        print("rs274_oracle: --vcut %s is not an executable" % args.vcut, file=sys.stderr)
        return 2
    rs274 = find_rs274(args.rs274)
    if not rs274 and args.install and not args.rs274:
        ok, msg = install_rs274()
        print("rs274_oracle: " + msg, file=sys.stderr)
        rs274 = find_rs274()
    if not rs274:
        # make test installs LinuxCNC and sets VCUT_REQUIRE_PEERS: there a missing one fails.
        required = os.environ.get("VCUT_REQUIRE_PEERS") == "1"
        print("rs274_oracle: %s: LinuxCNC's rs274 is not installed (Debian 12: apt-get install "
              "--no-install-recommends linuxcnc-uspace, or pass --install)" % ("FAIL" if required else "SKIP"),
              file=sys.stderr)
        return 1 if required else SKIP_EXIT

    programs = []
    for p in args.programs:
        programs.extend(census.find_programs(p) if os.path.isdir(p) else [p])
    if not args.programs:
        programs = census.default_programs()
        args.subroutine_path = args.subroutine_path + [
            d for d in census.DEFAULT_SUBROUTINE_DIRS if os.path.isdir(d)]
    if not programs:
        required = os.environ.get("VCUT_REQUIRE_PEERS") == "1"
        print("rs274_oracle: %s: no programs (the linuxcnc-uspace samples are not under %s)"
              % ("FAIL" if required else "SKIP", census.NCFILES_DIR), file=sys.stderr)
        return 1 if required else SKIP_EXIT

    random_dir = None
    if args.random_comp > 0:
        random_dir = tempfile.mkdtemp(prefix="rs274-oracle-comp-")
        programs = programs + random_comp_programs(args.random_comp, args.seed, random_dir)
    if args.random_uvw > 0:
        random_dir = random_dir or tempfile.mkdtemp(prefix="rs274-oracle-comp-")
        programs = programs + random_uvw_programs(args.random_uvw, args.seed, random_dir)
    if args.random_mixed > 0:
        random_dir = random_dir or tempfile.mkdtemp(prefix="rs274-oracle-comp-")
        programs = programs + random_mixed_programs(args.random_mixed, args.seed, random_dir)

    results = []
    for p in programs:
        status, motions, detail, more = check_program(p, args, rs274)
        results.append((p, status, motions, detail, more))

    common = os.path.commonpath([os.path.abspath(p) for p in programs]) if len(programs) > 1 else ""
    name_w = 0
    rows = []
    for p, status, motions, detail, more in results:
        name = os.path.relpath(os.path.abspath(p), common) if common else p
        name_w = max(name_w, len(name))
        rows.append((name, status, motions, detail, more))
    lines = ["%-*s  %-8s  %-11s  %s" % (name_w, "program", "status", "rs274/vcut", "detail")]
    for name, status, motions, detail, more in rows:
        lines.append("%-*s  %-8s  %-11s  %s" % (name_w, name, status, motions, detail))
    if random_dir:
        shutil.rmtree(random_dir, ignore_errors=True)
    counts = {}
    for r in results:
        counts[r[1]] = counts.get(r[1], 0) + 1
    # Programs that make at least one motion under rs274 (subroutine and remap files make none
    # standalone: their "identical" is 0 = 0) and how many of those are identical.
    def rs_motions(m):
        try:
            return int(str(m).split("/")[0])
        except ValueError:
            return 0
    moving = [r for r in results if rs_motions(r[2]) > 0]
    moving_pass = sum(1 for r in moving if r[1] == "PASS")
    shipped_pass = sum(1 for r in moving if r[1] == "PASS" and not (random_dir and r[0].startswith(random_dir)))
    lines.append("")
    lines.append("rs274: %s; vcut: %s; %d programs: %s" % (
        rs274, args.vcut, len(results),
        ", ".join("%d %s" % (counts[k], k) for k in ("PASS", "SKIPPED", "REJECTED", "FAIL")
                  if k in counts)))
    lines.append("programs that make a motion under rs274: %d, identical %d (%s)" % (
        len(moving), moving_pass,
        ", ".join("%d %s" % (n, k) for k, n in
                  ((k, sum(1 for r in moving if r[1] == k)) for k in ("SKIPPED", "REJECTED", "FAIL")) if n)))
    details = []
    for name, status, motions, detail, more in rows:
        if status == "FAIL" or (args.verbose and more):
            details.append("%s %s: %s" % (status, name, detail))
            details.extend("    " + m for m in more)
    too_few = shipped_pass < args.min_identical
    if too_few:
        details.append("FAIL: %d programs that make a motion are identical, fewer than --min-identical %d"
                       % (shipped_pass, args.min_identical))
    text = "\n".join(lines) + ("\n\n" + "\n".join(details) if details else "") + "\n"
    sys.stdout.write(text)
    if args.report:
        with open(args.report, "w") as f:
            f.write(text)
    return 1 if counts.get("FAIL") or too_few else 0


if __name__ == "__main__":
    sys.exit(main())
