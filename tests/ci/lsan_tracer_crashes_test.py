#!/usr/bin/env python3
"""ctest CiLsanTracerCrashes: .ci/lsan_tracer_crashes.py picks the tests that failed only by
LeakSanitizer's tracer crash, and refuses when any failure has another cause.

The logs are written in ctest's LastTest.log layout; the crash text is the one CI printed
(MeshRenderer.BackFaceCullingKeepsClosedMeshImagesIdentical, session 47).
Usage: lsan_tracer_crashes_test.py SCRIPT"""

import os
import re
import subprocess
import sys
import tempfile

GTEST_PASSED = "[==========] 1 test from 1 test suite ran. (1209 ms total)\n[  PASSED  ] 1 test.\n"
TRACER_CRASH = ("Tracer caught signal 11: addr=0x2b10 pc=0x56314a71ac1a sp=0x7f80d39c3d40\n"
                "==983==LeakSanitizer has encountered a fatal error.\n"
                "==983==HINT: LeakSanitizer does not work under ptrace (strace, gdb, etc)\n")
LEAK = "==12==ERROR: LeakSanitizer: detected memory leaks\n\nDirect leak of 8 byte(s) in 1 object(s)\n"
GTEST_FAILED = "[  FAILED  ] Suite.Case (3 ms)\n"


SKIPPED_VERDICT = "Test Pass Reason:\nSkip regular expression found in output. Regex=[\\[  PASSED  \\] 0 tests\\.]"


def entry(index, name, output, passed, verdict=None):
    verdict = verdict or ("Test Passed." if passed else "Test Failed.")
    return (f"{index}/9 Testing: {name}\n{index}/9 Test: {name}\n"
            f"Command: \"/b/tests/test_x\" \"--gtest_filter={name}\"\nDirectory: /b/tests\n"
            f"\"{name}\" start time: Dec 05 17:09 UTC\nOutput:\n" + "-" * 58 + "\n" + output +
            "<end of output>\nTest time =   2.25 sec\n" + "-" * 58 + f"\n{verdict}\n"
            f"\"{name}\" end time: Dec 05 17:09 UTC\n\"{name}\" time elapsed: 00:00:02\n" + "-" * 58 + "\n\n")


def run(script, entries):
    with tempfile.TemporaryDirectory() as folder:
        path = os.path.join(folder, "LastTest.log")
        with open(path, "w") as log:
            log.write("Start testing: Dec 05 17:09 UTC\n" + "-" * 58 + "\n" + "".join(entries))
        done = subprocess.run([sys.executable, script, path], capture_output=True, text=True)
        return done.returncode, done.stdout.strip()


def main():
    script = sys.argv[1]
    failures = []

    def expect(what, condition):
        if not condition:
            failures.append(what)

    passing = entry(1, "Quick.Passes", GTEST_PASSED, True)
    crashed = entry(2, "MeshRenderer.BackFaceCullingKeepsClosedMeshImagesIdentical", GTEST_PASSED + TRACER_CRASH, False)
    crashed_param = entry(3, "Suite/Clip.Moves/threejs_pirouette", GTEST_PASSED + TRACER_CRASH, False)

    code, pattern = run(script, [passing, crashed, crashed_param])
    expect(f"two tracer crashes are both rerun (exit {code})", code == 0)
    names = ["MeshRenderer.BackFaceCullingKeepsClosedMeshImagesIdentical", "Suite/Clip.Moves/threejs_pirouette",
             "Quick.Passes", "MeshRenderer.BackFaceCullingKeepsClosedMeshImagesIdenticalX", "Suite/Clip.Moves"]
    # ctest's regular expressions agree with Python's on these escapes (\. and plain text).
    matched = [name for name in names if code == 0 and re.fullmatch(pattern, name)]
    expect(f"the pattern {pattern!r} matches exactly the two crashed tests, got {matched}", matched == names[:2])

    cases = {
        "a leak report is a real failure": GTEST_PASSED + TRACER_CRASH + LEAK,
        "a failed assertion is a real failure": GTEST_FAILED + TRACER_CRASH,
        "a crash without the test having passed is a real failure": TRACER_CRASH,
        "a failure without the tracer crash is a real failure": GTEST_PASSED + "Segmentation fault\n",
    }
    for what, output in cases.items():
        code, _ = run(script, [crashed, entry(4, "Other.Case", output, False)])
        expect(f"{what} (exit {code})", code == 1)

    # A test skipped (no shared data) beside a tracer crash is no failure (CI, session 59: MeshRenderer crashed
    # while Suite/BvhSuiteClip skipped, and the skip was taken for a real failure).
    skipped = entry(5, "Suite/BvhSuiteClip", "[  SKIPPED ] 1 test, listed below:\n[  PASSED  ] 0 tests.\n", True,
                    SKIPPED_VERDICT)
    code, pattern = run(script, [skipped, crashed])
    expect(f"a skipped test beside a tracer crash: only the crash is rerun (exit {code}, {pattern!r})",
           code == 0 and re.fullmatch(pattern, names[0]) and not re.fullmatch(pattern, "Suite/BvhSuiteClip"))

    code, _ = run(script, [passing])
    expect(f"a log with no failure asks for no rerun (exit {code})", code == 1)

    for failure in failures:
        print("FAILED:", failure)
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
