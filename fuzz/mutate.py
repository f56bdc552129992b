#!/usr/bin/env python3
"""Deterministic mutation fuzzing for the g++ replay drivers (no libFuzzer needed).

Without clang's libFuzzer the fuzz drivers in fuzz/ are replay programs: they run
LLVMFuzzerTestOneInput once on every file (or every file under every folder) named on the
command line and exit 0. This script makes them fuzz for a while: from the seeds of a corpus
folder it generates N mutants into a temporary folder, runs the driver on them in batches,
and when a batch exits non-zero (abort from a broken invariant, an exception other than
vcut::InputError, a crash, a sanitizer report) or runs past the time limit (a hang), it
runs that batch's files one by one to find the offending inputs, copies them to --out and
reports each with its symptom. With --minimise the first offending input of each kind of
failure (its symptom and the line that says what broke) is also shrunk (lines, then bytes)
while it fails the same way, and the shrunk copy is written next to it as <name>.min.

Mutations, one to four stacked per mutant, chosen by a seeded random generator (the same
--seed gives the same mutants): bit flips, random bytes set, inserted or deleted, a range
duplicated, truncation, lines deleted, duplicated or swapped, a splice of two seeds (the
head of one and the tail of another), a token (a word or a number) replaced by a special
value of the format, a number replaced by an interesting number (0, 1e-9, 1.0000005, 360,
1e9, 1e400, .nan, ...; the file stays readable more often, so that what comes after the
parser runs too), and a special value inserted at a random place. Special values for
YAML (--format yaml): .nan, .inf, ~, [, {, &a, *a, !!binary, merge keys, huge and tiny
numbers, error names, deep nesting, ...; for CSV (--format csv): nan, -nan, inf, 1e400,
quotes, commas, CR, BOM, hex floats, ...

Usage (from the repository root, after building the drivers):
  python3 fuzz/mutate.py build/fuzz/machine_file_fuzz tests/fuzz/corpus/machine --format yaml -n 5000
  python3 fuzz/mutate.py build/fuzz/csv_fuzz tests/fuzz/corpus/csv --format csv -n 5000
  python3 fuzz/mutate.py build/fuzz/sinumerik_fuzz tests/fuzz/corpus/sinumerik --format sinumerik -n 5000
The driver and the project's shared libraries it loads are copied first, so that a rebuild
of the tree during the run does not make mutants fail for no fault of theirs.
Options: --seed S (default 1), --batch B mutants per driver run (default 200), --timeout T
seconds per batch (default 20; a single input gets T too), --memory-mb M address-space
limit of the driver (default 2048, 0 for none: an input that makes it allocate without
bound fails as a crash instead of exhausting the machine; too small for a sanitizer build,
give 0 there), --out DIR for offending inputs (default
$TMPDIR/vcut-fuzz-failures/<driver name>), --minimise, --keep (keep the temporary folder).
Exit status: 0 when every mutant passed, 1 when some failed, 2 on a usage error.
"""

import argparse
import os
import random
import resource
import shutil
import subprocess
import sys
import tempfile

YAML_TOKENS = [
    b".nan", b".NaN", b"-.nan", b".inf", b"-.inf", b".Inf", b"~", b"null", b"Null", b"", b"[",
    b"]", b"{", b"}", b"[]", b"{}", b"&a", b"*a", b"&a [*a]", b"&a {x: *a}", b"*undefined",
    b"!!binary", b"!!binary aGVsbG8=", b"!!str", b"!!float", b"!!int", b"!!map", b"!!seq",
    b"!custom", b"<<", b"<<: *a", b"? ", b"- ", b": ", b":", b",", b"---", b"...", b"|", b">",
    b"|-", b'"', b"'", b"#", b"%YAML 1.2\n---\n", b"%TAG ! tag:x,2000:\n", b"\t", b"\n",
    b"\r\n", b"\r", b"\x00", b"\xef\xbb\xbf", b"\xff\xfe", b"\xc3", b"\xe2\x80\xa8", b"1e400",
    b"-1e400", b"1e-400", b"1e308", b"1e9", b"1000000001", b"-1e9", b"999999999.9999999",
    b"4.9e-324", b"0", b"-0", b"0.0", b"1", b"-1", b"0x10", b"0o17", b"1_000", b"+1", b"1.",
    b".5", b"1e", b"--1", b"yes", b"no", b"true", b"NaN", b"inf", b"2147483648",
    b"99999999999999999999", b"E_XX", b"E_YX", b"E_BX", b"E_C0Y", b"E_X0C", b"E_A0C",
    b"E_CC", b"E_Q0", b"E_0", b"E_XXX", b"{table: [[0, 1], [1, 2]]}", b"{table: [[0, 1]]}",
    b"{table: [[1, 0], [0, 1]]}", b"{table: []}", b"linear", b"rotary", b"kind", b"axis",
    b"center", b"direction", b"limits", b"limits: null", b"[0, 0, 0]", b"[1, 0, 0]",
    b"[0, 0, 1]", b"[1e-7, 0, 1]", b"[1.0000001, 0, 0]", b"[1, 1, 1]", b"[-360, 360]",
    b"[-1e9, 1e9]", b"[0, 0]", b"[1, 2, 3, 4]", b"W", b"T", b"F", b"WXYZT", b"WCAFXYZT",
    b"WYXZCAT", b"WFXYZCAT", b"WABXYZT", b"X", b"Y", b"Z", b"A", b"B", b"C", b"models",
    b"errors", b"singularity_deg", b"spindle", b"workpiece", b"file: /", b"file: .",
    b"[" * 64, b"{a: " * 32, b"- " * 32,
]

CSV_TOKENS = [
    b",", b",,", b'"', b'""', b'"1"', b"'", b"\r", b"\n", b"\r\n", b"\n\n", b"#", b"# c\n",
    b" ", b"\t", b"\x00", b"\xef\xbb\xbf", b"\xff", b"\xc3\xa9", b"nan", b"-nan", b"NaN",
    b"nan(0x1)", b"inf", b"-inf", b"Infinity", b"1e400", b"-1e400", b"1e-400", b"4.9e-324",
    b"2.2250738585072014e-308", b"1e308", b"1.7976931348623157e308", b"0x1p3", b"0x", b"0x1p",
    b"0X1P-1074", b"1e", b"1e+", b".", b"-", b"+", b"+.5", b"-0", b"0", b"1", b"12345678901234567890",
    b"1_000", b"1,5", b"1.5e3", b"e5", b"x", b"X", b"a", b"A", b"tip_x", b"axis_z", b"q1",
    b"x,y,z", b"1,2,3", b"1" * 400, b"9" * 4000,
]

# Numbers that stay numbers: a number of a seed replaced by one keeps the file readable more
# often, so that the code behind the parser (for machines: validation and kinematics) runs.
NUMBERS = [
    b"0", b"-0", b"0.0", b"1", b"-1", b"2", b"0.5", b"1e-12", b"1e-9", b"-1e-9", b"1e-7",
    b"1e-6", b"0.999999", b"0.9999995", b"1.0000005", b"1.000001", b"0.7071067811865476",
    b"0.57735", b"3.141592653589793", b"90", b"-90", b"180", b"-180", b"360", b"-360", b"720",
    b"3600", b"36000", b"1e5", b"1e6", b"-1e6", b"1e9", b"-1e9", b"999999999", b"1000000001",
    b"1e300", b"1e-300", b"4.9e-324", b"1e400", b"-1e400", b".nan", b".inf", b"-.inf", b"nan",
    b"inf", b"0x1p3", b"1_0", b"12345678901234567890",
]

# SINUMERIK part programs (--format sinumerik): words, expressions and their edge cases.
SINUMERIK_TOKENS = [
    b"=", b"==", b"(", b")", b"((", b"AC(", b"IC(", b"AC(1", b"=AC(", b"=IC(", b"R1", b"R999",
    b"R1000", b"R1=", b"R2=R1*2", b"/0", b"*1EX300", b"1EX", b"1EX-400", b"SIN(", b"ATAN2(0,0)",
    b"SQRT(-1)", b"ASIN(2)", b"POT(1EX200)", b"TRUNC(", b"CR=", b"CR=-", b"CR=0", b"CR=1EX9",
    b"G0", b"G1", b"G2", b"G3", b"G4", b"G9", b"G17", b"G18", b"G19", b"G54", b"G500", b"G60",
    b"G64", b"G642", b"G70", b"G700", b"G91", b"G93", b"G94", b"I", b"J0", b"K=AC(0)", b"F0",
    b"F-1", b"F1EX6", b"S-1", b"T=\"", b"T=\"A\"", b"T99999", b"T100000", b"M6", b"M30", b"M3",
    b"TRAORI", b"TRAORI(1)", b"TRAORI(", b"TRAFOOF", b"ORIVECT", b"ORIAXES", b"ORIPLANE",
    b"ORICONCW", b"ORICONCCW", b"ORIMKS", b"ORIWKS", b"A3=", b"B3=0", b"C3=1", b"A3=-1 C3=0",
    b"A6=0 B6=0 C6=1", b"A6=0", b"NUT=", b"A7=", b"ADIS=", b"ADISPOS=-1", b"MSG(\"", b"\"",
    b";", b"%", b"$", b"$P_X", b"N", b"N7 X -1320", b" ", b"\t", b"\r", b"\n", b"\r\n",
    b"\x00", b"\xef\xbb\xbf", b"\xff", b"X", b"Y", b"Z", b"A", b"C", b"-", b"+", b".", b"-.",
    b"(" * 80, b"-" * 200, b"X=" + b"(" * 70, b"9" * 400, b"1" * 4000,
]

FORMATS = {"yaml": YAML_TOKENS, "csv": CSV_TOKENS, "sinumerik": SINUMERIK_TOKENS}


def read_seeds(folder):
    seeds = []
    for root, _, files in os.walk(folder):
        for name in sorted(files):
            with open(os.path.join(root, name), "rb") as f:
                seeds.append(f.read())
    return seeds


def token_spans(data):
    """Start and end of every word or number (letters, digits, _ . + -) in data."""
    spans, i, n = [], 0, len(data)
    while i < n:
        c = data[i]
        if chr(c).isalnum() or c in b"_.+-":
            j = i
            while j < n and (chr(data[j]).isalnum() or data[j] in b"_.+-"):
                j += 1
            spans.append((i, j))
            i = j
        else:
            i += 1
    return spans


def mutate_once(rng, data, seeds, tokens):
    data = bytearray(data)
    kind = rng.randrange(16)
    n = len(data)
    if n == 0 and kind not in (12, 13):
        kind = 12  # nothing to flip or cut: insert a token
    if kind == 0:  # bit flips
        for _ in range(rng.randint(1, 4)):
            i = rng.randrange(n)
            data[i] ^= 1 << rng.randrange(8)
    elif kind == 1:  # random bytes set
        for _ in range(rng.randint(1, 4)):
            data[rng.randrange(n)] = rng.randrange(256)
    elif kind == 2:  # random bytes inserted
        i = rng.randrange(n + 1)
        data[i:i] = bytes(rng.randrange(256) for _ in range(rng.randint(1, 8)))
    elif kind == 3:  # a range deleted
        i = rng.randrange(n)
        del data[i:i + rng.randint(1, max(1, min(64, n - i)))]
    elif kind == 4:  # a range duplicated
        i = rng.randrange(n)
        j = min(n, i + rng.randint(1, 64))
        k = rng.randrange(n + 1)
        data[k:k] = data[i:j] * rng.randint(1, 3)
    elif kind == 5:  # truncated
        del data[rng.randrange(n):]
    elif kind in (6, 7):  # lines: deleted, duplicated, swapped
        lines = bytes(data).split(b"\n")
        i, j = rng.randrange(len(lines)), rng.randrange(len(lines))
        op = rng.randrange(3)
        if op == 0:
            del lines[i]
        elif op == 1:
            lines.insert(j, lines[i])
        else:
            lines[i], lines[j] = lines[j], lines[i]
        data = bytearray(b"\n".join(lines))
    elif kind in (8, 9, 10, 11):  # a token replaced by a special value
        spans = token_spans(data)
        if spans:
            i, j = rng.choice(spans)
            data[i:j] = rng.choice(tokens)
        else:
            i = rng.randrange(n + 1)
            data[i:i] = rng.choice(tokens)
    elif kind == 12:  # a special value inserted
        i = rng.randrange(n + 1)
        data[i:i] = rng.choice(tokens)
    elif kind in (14, 15):  # a number replaced by another
        spans = [(i, j) for i, j in token_spans(data) if data[i:j].lstrip(b"+-.")[:1].isdigit()]
        if spans:
            i, j = rng.choice(spans)
            data[i:j] = rng.choice(NUMBERS)
    else:  # a splice of two seeds, cut at line boundaries half of the time
        other = rng.choice(seeds)
        a, b = rng.randrange(n + 1), rng.randrange(len(other) + 1)
        if rng.randrange(2):
            a = data.rfind(b"\n", 0, a) + 1
            b = other.rfind(b"\n", 0, b) + 1
        data = data[:a] + bytearray(other[b:])
    return bytes(data[:1 << 20])


def make_mutant(rng, seeds, tokens):
    data = rng.choice(seeds)
    for _ in range(rng.choice((1, 1, 1, 2, 2, 3, 4))):
        data = mutate_once(rng, data, seeds, tokens)
    return data


MEMORY_MB = 2048


def limit_memory():
    limit = MEMORY_MB << 20
    resource.setrlimit(resource.RLIMIT_AS, (limit, limit))


def snapshot(driver, folder):
    """Copies the driver and its project libraries (those outside /lib and /usr) to folder, so
    that a rebuild of the tree while this runs cannot swap libraries under it. Returns the
    copy of the driver and an environment that loads the copied libraries (the drivers find
    theirs by RUNPATH, which LD_LIBRARY_PATH overrides)."""
    lib_dir = os.path.join(folder, "lib")
    os.makedirs(lib_dir)
    try:
        ldd = subprocess.run(["ldd", driver], stdout=subprocess.PIPE, stderr=subprocess.DEVNULL,
                             check=True).stdout.decode()
    except (OSError, subprocess.CalledProcessError):
        return driver, None
    for line in ldd.splitlines():
        parts = line.split("=>")
        if len(parts) != 2 or not parts[1].strip() or parts[1].split()[0] == "not":
            continue
        path = parts[1].split()[0]
        if not path.startswith(("/lib", "/usr")):
            shutil.copy2(path, os.path.join(lib_dir, os.path.basename(path)))
    copy = os.path.join(folder, os.path.basename(driver))
    shutil.copy2(driver, copy)
    env = dict(os.environ)
    env["LD_LIBRARY_PATH"] = lib_dir + (":" + env["LD_LIBRARY_PATH"] if env.get("LD_LIBRARY_PATH") else "")
    return copy, env


ENV = None


def run_driver(driver, paths, timeout):
    """(symptom or None, output tail) for one run of the driver on paths."""
    try:
        p = subprocess.run([driver] + paths, stdout=subprocess.PIPE, stderr=subprocess.STDOUT,
                           timeout=timeout, env=ENV, preexec_fn=limit_memory if MEMORY_MB else None)
    except subprocess.TimeoutExpired as e:
        out = (e.output or b"").decode("utf-8", "replace")
        return "timeout after %gs" % timeout, out[-2000:]
    out = p.stdout.decode("utf-8", "replace")
    if p.returncode == 0:
        return None, out
    if p.returncode < 0:
        return "killed by signal %d" % -p.returncode, out[-2000:]
    return "exit status %d" % p.returncode, out[-2000:]


def signature(symptom, output):
    """What identifies a failure: the symptom's kind and the line that says what broke."""
    if symptom is None:
        return None
    for line in output.splitlines():
        if any(k in line for k in ("broken invariant", "what():", "Sanitizer", "runtime error")):
            return symptom.split()[0], line.split("/")[0].strip()
    return symptom.split()[0], ""


def minimise(driver, data, target, timeout, scratch):
    """Shrinks data (whole lines, then bytes) while the driver fails the same way (target:
    the failure's signature)."""
    path = os.path.join(scratch, "minimise.input")

    def fails(candidate):
        with open(path, "wb") as f:
            f.write(candidate)
        return signature(*run_driver(driver, [path], timeout)) == target

    for unit in ("lines", "bytes"):
        chunk = None
        while True:
            parts = data.split(b"\n") if unit == "lines" else [bytes([c]) for c in data]
            join = (lambda ps: b"\n".join(ps)) if unit == "lines" else (lambda ps: b"".join(ps))
            if chunk is None:
                chunk = max(1, len(parts) // 2)
            progress = False
            i = 0
            while i < len(parts):
                candidate = join(parts[:i] + parts[i + chunk:])
                if len(parts) > 1 and fails(candidate):
                    parts = parts[:i] + parts[i + chunk:]
                    data = candidate
                    progress = True
                else:
                    i += chunk
            if not progress:
                if chunk == 1:
                    break
                chunk = max(1, chunk // 2)
            if unit == "bytes" and len(data) > 4096 and chunk == 1:
                break  # byte-wise shrinking of a big input takes too long
    return data


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("driver")
    ap.add_argument("corpus")
    ap.add_argument("--format", choices=sorted(FORMATS), required=True)
    ap.add_argument("-n", type=int, default=2000, help="number of mutants")
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--batch", type=int, default=200)
    ap.add_argument("--timeout", type=float, default=20.0)
    ap.add_argument("--out")
    ap.add_argument("--minimise", action="store_true")
    ap.add_argument("--keep", action="store_true")
    ap.add_argument("--memory-mb", type=int, default=2048)
    args = ap.parse_args()
    global MEMORY_MB
    MEMORY_MB = args.memory_mb

    driver = os.path.abspath(args.driver)
    if not os.access(driver, os.X_OK):
        print("mutate.py: no driver program %s (build it first)" % driver, file=sys.stderr)
        return 2
    seeds = read_seeds(args.corpus)
    if not seeds:
        print("mutate.py: no seeds under %s" % args.corpus, file=sys.stderr)
        return 2
    out_dir = args.out or os.path.join(tempfile.gettempdir(), "vcut-fuzz-failures",
                                       os.path.basename(driver))
    rng = random.Random(args.seed)
    tokens = FORMATS[args.format]
    scratch = tempfile.mkdtemp(prefix="vcut-mutate-")
    global ENV
    driver, ENV = snapshot(driver, os.path.join(scratch, "driver"))
    # The drivers write each input to a temporary file; one left by a crash goes with scratch.
    ENV = dict(ENV if ENV is not None else os.environ)
    ENV["TMPDIR"] = os.path.join(scratch, "tmp")
    os.makedirs(ENV["TMPDIR"])
    failures = []
    minimised = set()  # signatures of the failures already shrunk
    done = 0
    try:
        while done < args.n:
            count = min(args.batch, args.n - done)
            batch_dir = os.path.join(scratch, "batch")
            shutil.rmtree(batch_dir, ignore_errors=True)
            os.makedirs(batch_dir)
            paths = []
            for k in range(count):
                path = os.path.join(batch_dir, "mutant-%07d" % (done + k))
                with open(path, "wb") as f:
                    f.write(make_mutant(rng, seeds, tokens))
                paths.append(path)
            symptom, tail = run_driver(driver, paths, args.timeout)
            if symptom is not None:
                # Find the offending inputs one by one.
                for path in paths:
                    one, one_tail = run_driver(driver, [path], args.timeout)
                    if one is None:
                        continue
                    os.makedirs(out_dir, exist_ok=True)
                    kept = os.path.join(out_dir, os.path.basename(path))
                    shutil.copyfile(path, kept)
                    report = "%s: %s\n  %s" % (kept, one, one_tail.strip().replace("\n", "\n  ")[-600:])
                    sig = signature(one, one_tail)
                    if args.minimise and sig not in minimised:
                        minimised.add(sig)
                        with open(path, "rb") as f:
                            small = minimise(driver, f.read(), sig, args.timeout, scratch)
                        with open(kept + ".min", "wb") as f:
                            f.write(small)
                        report += "\n  minimised (%d bytes): %s.min" % (len(small), kept)
                    print(report, flush=True)
                    failures.append(kept)
                if not failures:
                    print("batch at %d failed (%s) but no single input does:\n%s" % (done, symptom, tail[-600:]))
                    failures.append("batch at %d" % done)
            done += count
            print("mutate.py: %d/%d mutants, %d failing" % (done, args.n, len(failures)), flush=True)
    finally:
        if args.keep:
            print("mutate.py: mutants kept in %s" % scratch)
        else:
            shutil.rmtree(scratch, ignore_errors=True)
    print("mutate.py: %s on %d mutants of %d seeds (seed %d): %s" %
          (os.path.basename(driver), args.n, len(seeds), args.seed,
           "no failures" if not failures else "%d failing input(s) in %s" % (len(failures), out_dir)))
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
