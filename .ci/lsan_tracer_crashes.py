#!/usr/bin/env python3
"""Names the failed tests of a ctest run whose only fault was LeakSanitizer's own crash.

LeakSanitizer stops every thread with a ptrace "tracer" before it scans for leaks; that tracer
now and then dies with SIGSEGV on its own ("Tracer caught signal 11 ... LeakSanitizer has
encountered a fatal error", google/sanitizers#1353), after the test itself has passed. Such a
failure says nothing about the code, so `./dev test --sanitize` runs those tests once more.

Usage: lsan_tracer_crashes.py LastTest.log
Prints one ctest regular expression matching exactly those tests and exits 0 when every failed
test is such a crash; exits 1 (printing why) when any failure has another cause, or none failed.
"""

import re
import sys

TRACER_CRASH = "LeakSanitizer has encountered a fatal error"
# Any of these in a test's output is a real fault that a rerun must not hide.
REAL_FAULTS = (
    "ERROR: AddressSanitizer",
    "ERROR: LeakSanitizer",
    "runtime error:",
    "[  FAILED  ]",
    "Timeout",
)


def failed_tests(log_text):
    """(name, output) of each test that the log records as failed."""
    results = []
    pattern = re.compile(
        r"^\d+/\d+ Test: (?P<name>.+?)\n.*?^Output:\n-+\n(?P<output>.*?)^<end of output>\n"
        r"(?P<tail>.*?)^-{10,}\n(?P<verdict>[^\n]*)\n",
        re.S | re.M)
    for match in pattern.finditer(log_text):
        # A skipped test passes too: ctest writes "Test Pass Reason:" and the skip regex it found.
        if not match.group("verdict").strip().startswith(("Test Passed.", "Test Pass Reason:")):
            results.append((match.group("name"), match.group("output") + match.group("verdict")))
    return results


def ctest_literal(name):
    """`name` as a CMake regular expression that matches only itself."""
    return "".join("\\" + c if c in ".^$*+?()[]{}|\\" else c for c in name)


def main(argv):
    if len(argv) != 2:
        print("usage: lsan_tracer_crashes.py LastTest.log", file=sys.stderr)
        return 2
    try:
        with open(argv[1], encoding="utf-8", errors="replace") as log:
            text = log.read()
    except OSError as error:
        print(f"cannot read the ctest log {argv[1]}: {error}", file=sys.stderr)
        return 1
    failures = failed_tests(text)
    if not failures:
        print(f"{argv[1]}: no failed test recorded", file=sys.stderr)
        return 1
    names = []
    for name, output in failures:
        real_fault = any(fault in output for fault in REAL_FAULTS)
        if TRACER_CRASH not in output or "[  PASSED  ]" not in output or real_fault:
            print(f"{name}: failed for a reason other than LeakSanitizer's tracer crash", file=sys.stderr)
            return 1
        names.append(name)
    print("^(" + "|".join(ctest_literal(name) for name in names) + ")$")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
