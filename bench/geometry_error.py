#!/usr/bin/env python3
"""Where a run's geometry costs held-out PSNR (issue 19), on a capture with ground truth (`confluent synth`).

1. The scan's offset from the true surface along the truth's normal (the part of the error projective texturing
   sees; a slide along the surface, such as an arm's twist, costs vertex error but hardly any PSNR), per body
   region (each vertex to its heaviest joint in CAPTURE_gt/skin.json), every N-th frame: signed mean (+ = outside)
   and mean of the absolute value, in millimetres.
2. With --evaluate: `confluent evaluate` on copies of the run whose scan is moved onto the true surface in one
   region group at a time (along the truth's normal, weighted by the group's skin weights, so the seams stay
   smooth), and on one whose scan is the truth itself. The PSNR each group gains is what its surface error costs.
   The copies are folders of links to RUN beside a new scan/, under WORK (default RUN.geometry/).

Usage: python3 bench/geometry_error.py --capture CAP --run RUN [--truth CAP_gt] [--every N] [--frames A:B]
                                       [--evaluate all,torso,arms,legs,head,truth] [--confluent EXE] [--work DIR]
Needs python3-numpy and python3-scipy (Debian packages).
"""
import argparse
import glob
import json
import os
import re
import subprocess
import sys

try:
    import numpy as np
    from scipy.spatial import cKDTree
except ImportError:
    sys.exit("geometry_error.py needs numpy and scipy: apt-get install python3-numpy python3-scipy")

REPO = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))

# Body regions by the joint that weighs most (the studio's joint names, core/body_model.h).
REGIONS = {"pelvis": r"^pelvis$", "spine": r"^spine$", "chest": r"^chest$", "head": r"neck|head",
           "upper arm": r"_shoulder$", "forearm": r"_elbow$", "hand": r"_wrist$|_hand_end$",
           "thigh": r"_hip$", "shank": r"_knee$", "foot": r"_ankle$|_toe$"}
# Groups moved onto the truth by --evaluate.
GROUPS = {"all": r".", "torso": r"^(pelvis|spine|chest)$", "arms": r"_(shoulder|elbow|wrist|hand_end)$",
          "legs": r"_(hip|knee|ankle|toe)$", "head": r"neck|head"}
PLY_TYPES = {"char": "i1", "int8": "i1", "uchar": "u1", "uint8": "u1", "short": "<i2", "int16": "<i2",
             "ushort": "<u2", "uint16": "<u2", "int": "<i4", "int32": "<i4", "uint": "<u4", "uint32": "<u4",
             "float": "<f4", "float32": "<f4", "double": "<f8", "float64": "<f8"}


class Ply:
    """A binary little-endian PLY as confluent writes it: vertices first (scalar properties), then triangles."""

    def __init__(self, path):
        data = open(path, "rb").read()
        end = data.find(b"end_header\n")
        if end < 0 or b"binary_little_endian" not in data[:end]:
            sys.exit(f"{path}: not a binary little-endian PLY")
        end += len(b"end_header\n")
        elements = []
        for line in data[:end].decode("ascii", "replace").splitlines():
            t = line.split()
            if t and t[0] == "element":
                elements.append((t[1], int(t[2]), []))
            elif t and t[0] == "property":
                elements[-1][2].append((t[4], None) if t[1] == "list" else (t[2], PLY_TYPES[t[1]]))
        if not elements or elements[0][0] != "vertex" or any(ty is None for _, ty in elements[0][2]):
            sys.exit(f"{path}: expected a vertex element of scalar properties first")
        vertex_type = np.dtype(elements[0][2])
        self.header, count = data[:end], elements[0][1]
        self.vertices = np.frombuffer(data, dtype=vertex_type, count=count, offset=end).copy()
        self.rest = data[end + count * vertex_type.itemsize:]
        self.faces = None
        if len(elements) > 1 and elements[1][0] == "face":
            face_type = np.dtype([("n", "u1"), ("i", "<i4", (3,))] + [p for p in elements[1][2][1:]])
            faces = np.frombuffer(self.rest, dtype=face_type, count=elements[1][1])
            if (faces["n"] == 3).all():
                self.faces = faces["i"].copy()

    def xyz(self):
        return np.stack([self.vertices[c] for c in "xyz"], 1).astype(np.float64)

    def write(self, path, xyz):
        vertices = self.vertices.copy()
        for k, c in enumerate("xyz"):
            vertices[c] = xyz[:, k]
        with open(path, "wb") as f:
            f.write(self.header + vertices.tobytes() + self.rest)


def vertex_normals(xyz, faces):
    face_normals = np.cross(xyz[faces[:, 1]] - xyz[faces[:, 0]], xyz[faces[:, 2]] - xyz[faces[:, 0]])
    normals = np.zeros_like(xyz)
    for k in range(3):
        np.add.at(normals, faces[:, k], face_normals)
    return normals / np.maximum(np.linalg.norm(normals, axis=1, keepdims=True), 1e-12)


def normal_offsets(scan_xyz, truth):
    """Each scan vertex's offset along the normal of its nearest true vertex, and that normal."""
    true_xyz = truth.xyz()
    normals = vertex_normals(true_xyz, truth.faces)
    _, nearest = cKDTree(true_xyz).query(scan_xyz)
    offsets = np.einsum("ij,ij->i", scan_xyz - true_xyz[nearest], normals[nearest])
    return offsets, normals[nearest]


def joint_weights(skin, pattern):
    """Per vertex, the skin weight of the joints whose names match `pattern`."""
    chosen = [bool(re.search(pattern, j["name"])) for j in skin["joints"]]
    return np.array([sum(row[k + 1] for k in range(0, len(row), 2) if chosen[int(row[k])]) for row in skin["weights"]])


def heaviest_joint_names(skin):
    names = [j["name"] for j in skin["joints"]]
    return [names[int(max((row[k + 1], row[k]) for k in range(0, len(row), 2))[1])] for row in skin["weights"]]


def frame_files(run, frames, every):
    files = sorted(glob.glob(os.path.join(run, "scan", "*.ply")))
    if not files:
        sys.exit(f"{run}/scan: no animated scan (*.ply)")
    numbered = [(int(os.path.splitext(os.path.basename(f))[0]), f) for f in files]
    first, last = frames
    return [(n, f) for n, f in numbered if first <= n < last and (n - first) % every == 0]


def linked_copy(run, out):
    """OUT: links to RUN's entries but scan/ and evaluate's outputs, and an empty scan/."""
    os.makedirs(os.path.join(out, "scan"), exist_ok=True)
    for entry in os.listdir(run):
        if entry in ("scan", "metrics.json", "metrics.csv", "plots", "evaluation", "report.html"):
            continue
        link = os.path.join(out, entry)
        if not os.path.lexists(link):
            os.symlink(os.path.abspath(os.path.join(run, entry)), link)


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--capture", required=True)
    parser.add_argument("--run", required=True)
    parser.add_argument("--truth", help="ground truth folder (default CAPTURE_gt)")
    parser.add_argument("--every", type=int, default=5, help="every N-th frame in the region table (default 5)")
    parser.add_argument("--frames", help="A:B, B exclusive (default all)")
    parser.add_argument("--evaluate", default="", help="comma-separated groups: " + ",".join(GROUPS) + ",truth")
    parser.add_argument("--confluent", default=os.path.join(REPO, "build", "app", "confluent"))
    parser.add_argument("--work", help="folder for the evaluated copies (default RUN.geometry)")
    args = parser.parse_args()
    groups = [g for g in args.evaluate.split(",") if g]
    for group in groups:
        if group != "truth" and group not in GROUPS:
            sys.exit(f"--evaluate: unknown group '{group}' (known: {', '.join(GROUPS)}, truth)")
    truth_dir = args.truth or args.capture.rstrip("/") + "_gt"
    skin_path = os.path.join(truth_dir, "skin.json")
    if not os.path.exists(skin_path):
        sys.exit(f"{skin_path}: missing (regions need the actor's skin weights; synth writes them)")
    skin = json.load(open(skin_path))
    first, last = (int(x) for x in args.frames.split(":")) if args.frames else (0, 1 << 30)
    heaviest = heaviest_joint_names(skin)
    region_masks = {r: np.array([bool(re.search(p, n)) for n in heaviest]) for r, p in REGIONS.items()}

    # One pass over the frames: each frame's offsets are measured once, for the table (every N-th frame) and for
    # every group's copy (each frame).
    work = args.work or args.run.rstrip("/") + ".geometry"
    group_weights = {g: None if g == "truth" else joint_weights(skin, GROUPS[g]) for g in groups}
    for group in groups:
        linked_copy(args.run, os.path.join(work, group))
    print("| frame | all | " + " | ".join(REGIONS) + " |")
    print("|---" * (len(REGIONS) + 2) + "|")
    means = []
    for frame, path in frame_files(args.run, (first, last), 1 if groups else args.every):
        in_table = (frame - first) % args.every == 0
        scan = Ply(path)
        truth = Ply(os.path.join(truth_dir, "meshes", os.path.basename(path)))
        scan_xyz = scan.xyz()
        offsets, normals = normal_offsets(scan_xyz, truth)
        if in_table:
            mm = 1000.0 * offsets
            means.append(np.abs(mm).mean())
            cells = [f"{mm[m].mean():+.1f} / {np.abs(mm[m]).mean():.1f}" for m in region_masks.values()]
            print(f"| {frame} | {means[-1]:.2f} | " + " | ".join(cells) + " |", flush=True)
        for group, weights in group_weights.items():
            xyz = truth.xyz() if weights is None else scan_xyz - (weights * offsets)[:, None] * normals
            scan.write(os.path.join(work, group, "scan", os.path.basename(path)), xyz)
    print(f"\nmean |offset along the true normal| {np.mean(means):.2f} mm (cells: signed mean / mean of |offset|, mm; "
          "+ = the scan outside the truth)")

    for group in groups:
        out = os.path.join(work, group)
        command = [args.confluent, "evaluate", args.capture, "--run", out, "--masks", os.path.join(truth_dir, "masks"),
                   "--side-by-side-every", "0"] + (["--frames", args.frames] if args.frames else [])
        with open(os.path.join(work, group + ".log"), "w") as log:
            if subprocess.run(command, stdout=log, stderr=subprocess.STDOUT).returncode != 0:
                sys.exit(f"evaluate failed on {out} (see {work}/{group}.log)")
        scan = json.load(open(os.path.join(out, "metrics.json")))["scan"]
        print(f"{group}: PSNR {scan['psnr_db_mean']:.2f} dB, inside both silhouettes "
              f"{scan['psnr_inside_db_mean']:.2f} dB, IoU {scan['iou_mean']:.4f}", flush=True)


if __name__ == "__main__":
    main()
