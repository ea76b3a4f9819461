#!/usr/bin/env python3
"""ctest SuiteTable: bench/suite.py's table replaces the previous generated table of the file it writes and keeps
the dated sections written by hand below it (bench/SUITE.md's history); a new file gets the table alone.
Usage: suite_table_test.py SUITE_PY"""

import importlib.util
import os
import sys
import tempfile

spec = importlib.util.spec_from_file_location("suite", sys.argv[1])
suite = importlib.util.module_from_spec(spec)
spec.loader.exec_module(suite)

RESULT = dict(name="builtin", status="ok", scan_iou_mean=0.99312, scan_iou_min=0.98631, template_iou_mean=0.9392,
              psnr_db=29.243, joint_error_mean_cm=0.41, joint_error_p95_cm=0.83, vertex_error_cm=0.58,
              vertex_error_frame0_mm=1.7, flagged=1, recovered=0, bad=0, seconds_per_frame=5.8, lost_limb=False,
              worst=[])
HISTORY = "## 2026-12-07 (session 60): by hand\n\n| a | b |\n|---|---|\n| 1 | 2 |\n\n## 2026-11-25: the first table\n\ntext\n"
failures = []
with tempfile.TemporaryDirectory() as tmp:
    path = os.path.join(tmp, "SUITE.md")
    suite.write_table(path, [RESULT], "header one", "sheet.md")
    first = open(path).read()
    if "## " in first or "| builtin | ok | 0.9931 | 0.9863 |" not in first:
        failures.append(f"a new file: the table alone expected, got:\n{first}")
    with open(path, "a") as f:
        f.write("\n" + HISTORY)
    suite.write_table(path, [dict(RESULT, name="samba")], "header two", "sheet.md")
    second = open(path).read()
    if not second.endswith(HISTORY):
        failures.append(f"the dated sections are not kept as written:\n{second}")
    if "header one" in second or "| builtin |" in second:
        failures.append(f"the previous table is left in:\n{second}")
    if not second.startswith("# Motion suite\n\nheader two") or "| samba | ok |" not in second:
        failures.append(f"the new table is not on top:\n{second}")
    if second.count("Legend:") != 1:
        failures.append("one legend expected")
for failure in failures:
    print("FAIL:", failure)
sys.exit(1 if failures else 0)
