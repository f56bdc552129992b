#!/usr/bin/env python3
"""Reads every program of a corpus with `vcut program` and compares the outcome with EXPECTED.

Usage: run_corpus.py --vcut PATH [--expected EXPECTED.tsv] [--jobs N] FOLDER

Each program runs as a user would run it: `vcut program FILE --tools tools.yaml
--subroutine-path FOLDER` (dialect auto). Outcomes:
  ok        exit 0 and at least one motion
  still     exit 0 and no motion (a parameter check, a macro that only computes): read, and
            left out of the rate, as a user counts programs that cut
  refused   exit 2 with one "file:line:column: message" line
  other     anything else (a crash, a hang, an error without a place): always a failure
EXPECTED (tab-separated: file, "ok" or "refused", the fragment the refusal names, the reason)
lists every program kept in the repository; a program whose outcome differs fails the test.
Without --expected the counts are printed only (for programs kept out of the repository).
Exit status: 1 if any program differs from EXPECTED or is "other", else 0.
"""
import argparse
import concurrent.futures
import os
import re
import subprocess
import sys

HERE = os.path.dirname(os.path.abspath(__file__))
PLACE = re.compile(r"^vcut: error: (.+?):(\d+):(\d+): (.*)$")


def run(vcut, folder, name, timeout):
    cmd = [vcut, "program", os.path.join(folder, name), "--tools", os.path.join(HERE, "tools.yaml"),
           "--subroutine-path", folder]
    try:
        r = subprocess.run(cmd, stdin=subprocess.DEVNULL, stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                           timeout=timeout)
    except subprocess.TimeoutExpired:
        return name, "other", "timed out after %d s" % timeout, 0
    motions = r.stdout.count(b"\n")
    errors = [l for l in r.stderr.decode("utf-8", "replace").splitlines() if l.startswith("vcut: error:")]
    if r.returncode == 0:
        return name, ("ok" if motions > 0 else "still"), "" if motions else "no motion", motions
    if r.returncode == 2 and len(errors) == 1 and PLACE.match(errors[0]):
        return name, "refused", PLACE.match(errors[0]).group(4), motions
    return name, "other", "exit %d: %s" % (r.returncode, " | ".join(errors) or r.stderr[-200:]), motions


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("folder")
    ap.add_argument("--vcut", required=True)
    ap.add_argument("--expected")
    ap.add_argument("--jobs", type=int, default=2)
    ap.add_argument("--timeout", type=int, default=120)
    args = ap.parse_args()
    expected = {}
    unlisted = []
    if args.expected:
        with open(args.expected) as f:
            for line in f:
                if not line.strip() or line.startswith("#") or line.startswith("file\t"):
                    continue
                parts = line.rstrip("\n").split("\t")
                expected[parts[0]] = (parts[1], parts[2] if len(parts) > 2 else "", parts[3] if len(parts) > 3 else "")
        names = sorted(expected)
        # Every program kept in the folder is listed: one added without its expectation fails.
        unlisted = sorted(n for n in os.listdir(args.folder)
                          if os.path.isfile(os.path.join(args.folder, n)) and n not in expected)
        for n in unlisted:
            print("%-70s not in %s: FAIL" % (n, args.expected))
    else:
        names = sorted(n for n in os.listdir(args.folder) if os.path.isfile(os.path.join(args.folder, n)))
    with concurrent.futures.ThreadPoolExecutor(max_workers=args.jobs) as pool:
        results = list(pool.map(lambda n: run(args.vcut, args.folder, n, args.timeout), names))
    bad = 0
    counts = {}
    for name, outcome, message, motions in results:
        counts[outcome] = counts.get(outcome, 0) + 1
        verdict = ""
        if outcome == "other":
            verdict = "FAIL"
        elif name in expected:
            want, fragment, _ = expected[name]
            if want != outcome or (outcome == "refused" and fragment not in message):
                verdict = "FAIL (expected %s%s)" % (want, ": " + fragment if fragment else "")
        if verdict:
            bad += 1
        print("%-70s %-8s %7d  %s %s" % (name, outcome, motions, message[:150], verdict))
    total = len(results) - counts.get("still", 0)
    print("\n%d programs that make a motion (and %d that make none): %d read (%.0f %%), %d refused with "
          "file:line:column and the feature, %d other; %d differ from the expectations"
          % (total, counts.get("still", 0), counts.get("ok", 0), 100.0 * counts.get("ok", 0) / max(total, 1),
             counts.get("refused", 0), counts.get("other", 0), bad))
    return 1 if bad or (args.expected and unlisted) else 0


if __name__ == "__main__":
    sys.exit(main())
