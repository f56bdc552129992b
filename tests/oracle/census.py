#!/usr/bin/env python3
"""Feature census of RS274/NGC programs (LinuxCNC dialect).

Usage: census.py [--json] [PROGRAMS or DIRECTORIES...]

Without arguments it scans the sample programs that Debian's linuxcnc-uspace package installs
(see default_programs()). For each program it prints which rs274ngc features it uses, so that
a reader implementing them knows which samples exercise what. Standard library only.

The scan is textual, line by line: comments are removed (after noting (print,...), (debug,...),
(msg,...) and (log,...)), bracketed expressions are reduced to a placeholder, named-parameter
and o-word names are blanked so that their letters are not read as words. It answers "does
the text use X", not "does execution reach X".
"""
import argparse
import gzip
import json
import os
import re
import sys

# Where the linuxcnc-uspace package (Debian 12, 2.9.0~pre1) puts its sample programs.
NCFILES_DIR = "/usr/share/linuxcnc/ncfiles"
FIVE_AXIS_DEMOS_DIR = ("/usr/share/doc/linuxcnc/examples/sample-configs/sim/axis/vismach/"
                       "5axis/table-rotary-tilting/demos")
PROGRAM_SUFFIXES = (".ngc", ".ngc.gz", ".nc", ".nc.gz")
# Where the sample configurations look for o<name> call files (their ini's SUBROUTINE_PATH).
DEFAULT_SUBROUTINE_DIRS = (os.path.join(os.path.dirname(FIVE_AXIS_DEMOS_DIR), "remap_subs"),)


def default_programs():
    """Every program under NCFILES_DIR (recursively) and FIVE_AXIS_DEMOS_DIR, sorted."""
    found = []
    for root in (NCFILES_DIR, FIVE_AXIS_DEMOS_DIR):
        found.extend(find_programs(root))
    return found


def find_programs(root):
    out = []
    if os.path.isfile(root):
        return [root]
    for dirpath, dirnames, filenames in os.walk(root):
        dirnames.sort()
        for name in sorted(filenames):
            if name.lower().endswith(PROGRAM_SUFFIXES):
                out.append(os.path.join(dirpath, name))
    return out


def read_text(path):
    if path.endswith(".gz"):
        with gzip.open(path, "rb") as f:
            data = f.read()
    else:
        with open(path, "rb") as f:
            data = f.read()
    return data.decode("utf-8", errors="replace")


# ---------------------------------------------------------------------------------------------
# Line preparation

_COMMENT = re.compile(r"\(([^)]*)\)")
_ACTIVE_COMMENT = re.compile(r"^\s*(print|debug|msg|log|logopen|logappend|logclose|probeopen|"
                             r"probeclose|abort)\s*,", re.I)
_OWORD = re.compile(r"^\s*(?:/\s*)?(?:N\s*\d+\s*)?O\s*(<[^>]*>|\d+|\[[^\]]*\]|#\s*<[^>]*>|#\s*\d+)"
                    r"\s*([A-Z]+)?(.*)$", re.I)


def strip_brackets(s):
    """Replaces every outermost [...] by ' 0 ' and returns (text, had_brackets)."""
    out = []
    depth = 0
    had = False
    for ch in s:
        if ch == "[":
            if depth == 0:
                out.append(" 0 ")
                had = True
            depth += 1
        elif ch == "]":
            depth = max(0, depth - 1)
        elif depth == 0:
            out.append(ch)
    return "".join(out), had


def g_number(text):
    """'01' -> '1', '59.10' -> '59.1', '5' -> '5'."""
    if "." in text:
        whole, frac = text.split(".", 1)
        frac = frac.rstrip("0")
        whole = str(int(whole)) if whole else "0"
        return whole + ("." + frac if frac else "")
    return str(int(text))


# ---------------------------------------------------------------------------------------------
# The census of one program

BASIC_M = {0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 30}


def census_text(text):
    """Returns a dict: feature name -> count (lines using it), plus details."""
    feats = {}
    g_codes = {}
    m_codes = {}
    subs_defined = set()
    subs_called = set()
    axes = set()

    def hit(name, n=1):
        feats[name] = feats.get(name, 0) + n

    for raw in text.splitlines():
        line = raw.rstrip("\r")
        # ';' starts a comment to the end of the line (LinuxCNC), unless inside ( ).
        code = []
        depth = 0
        for ch in line:
            if ch == "(":
                depth += 1
            elif ch == ")":
                depth = max(0, depth - 1)
            elif ch == ";" and depth == 0:
                break
            code.append(ch)
        line = "".join(code)
        for c in _COMMENT.findall(line):
            m = _ACTIVE_COMMENT.match(c)
            if m:
                hit("comment:" + m.group(1).lower())
        line = _COMMENT.sub(" ", line)
        if not line.strip():
            continue
        if line.lstrip().startswith("/"):
            hit("block delete /")

        o = _OWORD.match(line)
        if o and o.group(2):
            name = o.group(1).lower().replace(" ", "")
            kw = o.group(2).lower()
            if kw in ("sub",):
                subs_defined.add(name)
                hit("o-word sub")
            elif kw == "endsub":
                pass
            elif kw == "call":
                subs_called.add(name)
                hit("o-word call")
            elif kw in ("if", "elseif", "else", "endif"):
                hit("o-word if")
            elif kw in ("while", "endwhile"):
                hit("o-word while")
            elif kw == "do":
                hit("o-word do/while")
            elif kw in ("repeat", "endrepeat"):
                hit("o-word repeat")
            elif kw == "return":
                hit("o-word return")
            elif kw in ("break", "continue"):
                hit("o-word break/continue")
            else:
                hit("o-word " + kw)
            rest = o.group(3) or ""
            if "[" in rest:
                hit("expressions [..]")
            if re.search(r"#\s*<", rest):
                hit("named params #<..>")
            if re.search(r"#\s*\d", rest):
                hit("numbered params #n")
            continue
        if o and not o.group(2):
            hit("o-word (bare program number)")

        if re.search(r"#\s*<", line):
            hit("named params #<..>")
            if re.search(r"#\s*<\s*_", line):
                hit("global named params #<_..>")
        if re.search(r"#\s*\d", line):
            hit("numbered params #n")
            for num in re.findall(r"#\s*(\d+)", line):
                if int(num) >= 5000:
                    hit("system params #5xxx")
                    break
        if re.search(r"#\s*\[", line):
            hit("indirect params #[..]")
        if re.search(r"(?i)(?<![A-Z])[GM]\s*[\[#]", line):
            hit("computed G/M code")
        line = re.sub(r"#\s*<[^>]*>", " #0 ", line)
        line, had = strip_brackets(line)
        if had:
            hit("expressions [..]")
        up = line.upper()
        if re.search(r"#\s*\d+\s*=", up):
            hit("param assignment")
        # Words: a letter and a number (or a parameter / placeholder from strip_brackets).
        for letter, value in re.findall(r"([A-Z])\s*([-+]?\s*(?:\d+\.?\d*|\.\d+|#\s*\d+))", up):
            value = value.replace(" ", "")
            if letter == "G" and not value.startswith("#") and not value.startswith("-"):
                try:
                    g = g_number(value.lstrip("+"))
                except ValueError:
                    continue
                g_codes[g] = g_codes.get(g, 0) + 1
            elif letter == "M" and not value.startswith("#"):
                try:
                    m = int(float(value))
                except ValueError:
                    continue
                m_codes[m] = m_codes.get(m, 0) + 1
            elif letter in "UVWABC":
                axes.add(letter)

    def g_has(*codes):
        return sum(g_codes.get(c, 0) for c in codes)

    groups = [
        ("canned cycles", ("73", "74", "76", "81", "82", "83", "84", "85", "86", "87", "88", "89")),
        ("G98/G99", ("98", "99")),
        ("G10 L1/L10/L11 (tool table)", ()),  # filled below
        ("G92 family", ("92", "92.1", "92.2", "92.3")),
        ("G52", ("52",)),
        ("G53", ("53",)),
        ("G28/G30", ("28", "28.1", "30", "30.1")),
        ("G43/G43.1/G43.2/G49", ("43", "43.1", "43.2", "49")),
        ("cutter comp G41/G42", ("41", "41.1", "42", "42.1")),
        ("G40", ("40",)),
        ("inverse time G93", ("93",)),
        ("feed per rev G95", ("95",)),
        ("CSS G96", ("96",)),
        ("threading G33/G33.1/G76", ("33", "33.1", "76")),
        ("splines G5/G5.1/G5.2", ("5", "5.1", "5.2", "5.3")),
        ("lathe G7/G8", ("7", "8")),
        ("lathe cycles G70-G72", ("70", "71", "71.1", "71.2", "72", "72.1", "72.2")),
        ("probing G38.x", ("38.2", "38.3", "38.4", "38.5")),
        ("G64 blending", ("64",)),
        ("G61/G61.1 exact", ("61", "61.1")),
        ("inches G20", ("20",)),
        ("arcs G2/G3", ("2", "3")),
        ("plane G18/G19", ("18", "19")),
        ("UVW planes G17.1-G19.1", ("17.1", "18.1", "19.1")),
        ("incremental G91", ("91",)),
        ("arc centre mode G90.1/G91.1", ("90.1", "91.1")),
        ("work offsets G54-G59.3", ("54", "55", "56", "57", "58", "59", "59.1", "59.2", "59.3")),
        ("dwell G4", ("4",)),
        ("G80", ("80",)),
    ]
    for name, codes in groups:
        if codes and g_has(*codes):
            hit(name, g_has(*codes))
    if g_codes.get("10"):
        ls = set(re.findall(r"G\s*0*10\b[^\n]*?L\s*(\d+)", text.upper()))
        hit("G10 " + "/".join("L" + l for l in sorted(ls, key=int)) if ls else "G10")
    extra_m = sorted(m for m in m_codes if m not in BASIC_M)
    for m in extra_m:
        if 62 <= m <= 68:
            hit("M62-M68 I/O")
        elif 100 <= m <= 199:
            hit("user M100-M199")
        else:
            hit("M%d" % m)
    for a in sorted(axes):
        hit(("ABC" if a in "ABC" else "UVW") + " axes")
    if "ABC axes" in feats:
        feats["ABC axes"] = "".join(sorted(a for a in axes if a in "ABC"))
    if "UVW axes" in feats:
        feats["UVW axes"] = "".join(sorted(a for a in axes if a in "UVW"))
    external = sorted(c for c in subs_called if c not in subs_defined)
    if external:
        feats["calls subs in other files"] = " ".join(external)
    return {
        "features": feats,
        "g_codes": sorted(g_codes, key=lambda g: float(g)),
        "m_codes": sorted(m_codes),
        "subs_defined": sorted(subs_defined),
        "subs_called": sorted(subs_called),
    }


def census_file(path):
    try:
        text = read_text(path)
    except OSError as e:
        return {"error": str(e), "features": {}}
    c = census_text(text)
    c["lines"] = text.count("\n") + (0 if text.endswith("\n") or not text else 1)
    # A file that only defines subroutines and never calls anything at top level is a library.
    c["library_only"] = bool(c["subs_defined"]) and not _has_top_level_code(text)
    return c


def _has_top_level_code(text):
    depth = 0
    for raw in text.splitlines():
        line = _COMMENT.sub(" ", raw.split(";", 1)[0]).strip()
        if not line or line == "%":
            continue
        o = _OWORD.match(line)
        if o and o.group(2):
            kw = o.group(2).lower()
            if kw == "sub":
                depth += 1
                continue
            if kw == "endsub":
                depth = max(0, depth - 1)
                continue
        if depth == 0:
            if re.fullmatch(r"(?i)M\s*0*(2|30)", line):
                continue
            return True
    return False


def short_features(c):
    items = []
    for k, v in sorted(c["features"].items()):
        items.append(k if isinstance(v, int) else "%s(%s)" % (k, v))
    return items


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("paths", nargs="*", help="programs or directories (default: the LinuxCNC samples)")
    ap.add_argument("--json", action="store_true", help="print one JSON object instead of a table")
    args = ap.parse_args(argv)
    programs = []
    for p in args.paths:
        programs.extend(find_programs(p))
    if not args.paths:
        programs = default_programs()
        if not programs:
            print("census: no programs found under %s or %s (is linuxcnc-uspace installed?)"
                  % (NCFILES_DIR, FIVE_AXIS_DEMOS_DIR), file=sys.stderr)
            return 1
    result = {p: census_file(p) for p in programs}
    if args.json:
        json.dump(result, sys.stdout, indent=1, sort_keys=True)
        print()
        return 0
    common = os.path.commonpath(programs) if len(programs) > 1 else ""
    totals = {}
    for p, c in result.items():
        name = os.path.relpath(p, common) if common else p
        feats = short_features(c)
        for k in c["features"]:
            totals[k] = totals.get(k, 0) + 1
        tag = " [sub library]" if c.get("library_only") else ""
        print("%s%s: %s" % (name, tag, ", ".join(feats) if feats else "(plain G-code)"))
    print()
    print("programs using each feature (%d programs):" % len(result))
    for k, n in sorted(totals.items(), key=lambda kv: (-kv[1], kv[0])):
        print("  %4d  %s" % (n, k))
    return 0


if __name__ == "__main__":
    sys.exit(main())
