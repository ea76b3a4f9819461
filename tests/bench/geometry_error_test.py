#!/usr/bin/env python3
"""ctest GeometryErrorTool: bench/geometry_error.py on a ground truth built here. Two octahedra, one skinned to
the pelvis and one to the left shoulder; the run's scan has the pelvis one pushed 2 mm out along its normals. The
region table must say +2.0 mm at the pelvis and 0 on the upper arm; --evaluate's copies must hold the scan moved
back onto the truth (a stand-in evaluator records what it was given); bad input gets a one-line error.
Usage: geometry_error_test.py TOOL"""

import json
import os
import struct
import subprocess
import sys
import tempfile

TOOL = sys.argv[1]
try:
    import numpy  # noqa: F401  (the tool's own needs; .ci/install-deps.sh installs both)
    import scipy  # noqa: F401
except ImportError:
    print(f"skipped: {sys.executable} has no numpy or scipy (apt-get install python3-numpy python3-scipy)")
    sys.exit(77)
OCTAHEDRON = [(1, 0, 0), (-1, 0, 0), (0, 1, 0), (0, -1, 0), (0, 0, 1), (0, 0, -1)]
FACES = [(0, 2, 4), (2, 1, 4), (1, 3, 4), (3, 0, 4), (2, 0, 5), (1, 2, 5), (3, 1, 5), (0, 3, 5)]


def write_ply(path, vertices, faces):
    header = (f"ply\nformat binary_little_endian 1.0\nelement vertex {len(vertices)}\nproperty float x\n"
              f"property float y\nproperty float z\nelement face {len(faces)}\nproperty list uchar int vertex_indices\n"
              "end_header\n").encode()
    body = b"".join(struct.pack("<3f", *v) for v in vertices) + b"".join(struct.pack("<B3i", 3, *f) for f in faces)
    with open(path, "wb") as f:
        f.write(header + body)


def bodies(push_m):
    """Octahedron 0 (radius 0.1 m, at the origin) pushed out by push_m, octahedron 1 at x = 1 m."""
    vertices = [tuple(0.1 * c + push_m * c for c in v) for v in OCTAHEDRON]
    vertices += [(1.0 + 0.1 * v[0], 0.1 * v[1], 0.1 * v[2]) for v in OCTAHEDRON]
    return vertices, FACES + [tuple(i + 6 for i in f) for f in FACES]


def run(*args):
    result = subprocess.run([sys.executable, TOOL, *args], capture_output=True, text=True)
    return result.returncode, result.stdout + result.stderr


def check(condition, message):
    if not condition:
        sys.exit("FAIL: " + message)


with tempfile.TemporaryDirectory() as root:
    capture, truth, scan = (os.path.join(root, d) for d in ("capture", "capture_gt", "run/scan"))
    for d in (capture, truth + "/meshes", scan):
        os.makedirs(d)
    true_vertices, faces = bodies(0.0)
    write_ply(truth + "/meshes/000000.ply", true_vertices, faces)
    write_ply(scan + "/000000.ply", *bodies(0.002))

    code, out = run("--capture", capture, "--run", root + "/run")
    check(code != 0 and "skin.json: missing" in out, "a ground truth without skin.json: " + out)

    skin = {"joints": [{"name": "pelvis", "parent": -1, "rest_position": [0, 0, 0]},
                       {"name": "left_shoulder", "parent": 0, "rest_position": [1, 0, 0]}],
            "weights": [[0, 1.0]] * 6 + [[1, 1.0]] * 6}
    with open(truth + "/skin.json", "w") as f:
        json.dump(skin, f)
    code, out = run("--capture", capture, "--run", root + "/run")
    check(code == 0, out)
    row = next(line for line in out.splitlines() if line.startswith("| 0 |")).split(" | ")
    # Columns: frame, all, then the regions in order: pelvis first, upper arm fifth.
    check(row[2] == "+2.0 / 2.0", "pelvis cell " + row[2])
    check(row[6] == "+0.0 / 0.0", "upper arm cell " + row[6])
    check(row[1] == "1.00", "mean over both bodies " + row[1])

    code, out = run("--capture", capture, "--run", root + "/run", "--evaluate", "torso,bogus")
    check(code != 0 and "unknown group 'bogus'" in out, "an unknown group: " + out)

    # A stand-in for `confluent evaluate`: writes the metrics.json the tool reads into the run it is given.
    evaluator = os.path.join(root, "evaluate.sh")
    with open(evaluator, "w") as f:
        f.write('#!/bin/sh\nwhile [ "$1" != --run ]; do shift; done\n'
                'echo \'{"scan": {"psnr_db_mean": 30, "psnr_inside_db_mean": 31, "iou_mean": 0.99}}\' > "$2/metrics.json"\n')
    os.chmod(evaluator, 0o755)
    work = os.path.join(root, "work")
    code, out = run("--capture", capture, "--run", root + "/run", "--evaluate", "torso,arms,truth",
                    "--confluent", evaluator, "--work", work)
    check(code == 0 and "torso: PSNR 30.00 dB" in out, out)
    sys.path.insert(0, os.path.dirname(TOOL))
    import geometry_error
    truth_xyz = geometry_error.Ply(truth + "/meshes/000000.ply").xyz()
    scan_xyz = geometry_error.Ply(scan + "/000000.ply").xyz()
    for group, expected in (("torso", truth_xyz), ("arms", scan_xyz), ("truth", truth_xyz)):
        moved = geometry_error.Ply(os.path.join(work, group, "scan", "000000.ply")).xyz()
        check(abs(moved - expected).max() < 1e-6, f"{group}: the copy's scan is not the expected one")
    check(os.path.islink(os.path.join(work, "torso", "scan")) is False, "the copy's scan/ must be its own")

    os.rename(scan, scan + ".gone")
    code, out = run("--capture", capture, "--run", root + "/run")
    check(code != 0 and "no animated scan" in out, "a run without scan/: " + out)
print("geometry_error.py: all checks passed")
