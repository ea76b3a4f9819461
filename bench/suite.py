#!/usr/bin/env python3
"""The motion suite (issue 19, "the yardstick"): capture -> 3D video -> held-out evaluation over many
generated captures, summarised in one Markdown table.

Per capture: `confluent synth` (capture + ground truth), `confluent run` with the studio's held-out
cameras excluded (as `confluent demo` does), `confluent evaluate` against the ground-truth masks and
meshes (evaluate's defaults otherwise), and `confluent track` on the finished run folder with
--gt-joints: its tracking stage finds every frame done and only writes the report
(track_summary.json: the joint error). Flags and the lost-limb test come from RUN/poses.json, seconds
per frame from RUN/timings.csv. The side-by-side pictures of the worst frames are copied into
WORK/<preset>/worst/ and listed in WORK/<preset>/contact_sheet.md.

Usage: ./dev suite [--preset tiny|small|full] [--only NAME,...] [--out DIR] [--threads N]
                   [--table FILE] [--floors FILE --check] [--keep]
"""
import argparse
import datetime
import json
import math
import os
import shutil
import statistics
import subprocess
import sys
import tarfile
import time

REPO = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
DATA = os.path.normpath(os.path.join(REPO, "..", "shared", "data"))
BVH_DIR = os.path.join(DATA, "bvh", "suite")
SAMBA_TAR = os.path.join(DATA, "meshseq", "vlasic_samba.tar.xz")
HELD_OUT = ["holdout0", "holdout1"]  # the studio's held-out cameras (synth --heldout 2)

# Synth arguments per preset; frames and fps are always given, since --bvh without --frames takes
# the whole file. tiny samples 0.8 s at 12.5 fps (at the tiny preset's own 2.5 fps the tracker
# recovers on most frames and the numbers are too noisy for floors); small and full keep 25 fps.
PRESETS = {
    "tiny": ["--preset", "tiny", "--frames", "10", "--fps", "12.5"],
    "small": ["--width", "512", "--height", "384", "--frames", "50", "--fps", "25"],
    "full": ["--width", "1024", "--height", "768", "--frames", "100", "--fps", "25"],
}

# The motion clips of ../shared/data/bvh/suite (README.md there). A number is the start offset in
# seconds (passed as --bvh-start only when `confluent synth --help` lists it); None starts at 0.
# Four clips open with a reference pose: their frame 0 is 77 to 177 degrees (largest channel
# change) away from frame 1, so they start 0.1 s in.
CLIPS = {
    "threejs_pirouette": 0.1, "cmu_05_20_modern_dance": 0.1, "cmu_94_01_indian_dance": None,
    "cmu_01_01_forward_jumps_turn": 0.1, "perfume_B_dance": 0.1, "bvhviewer_jump_from_stand": None,
    "sfu_0007_Cartwheel001": None, "sfu_0005_Jogging001": None, "sfu_0005_JumpRope001": None,
    "sfu_0005_SideSkip001": None, "bandai_kick_normal_001": None, "bandai_punch_normal_002": None,
}

# Clips whose pelvis travels further than the studio's cameras see a performer whole (synth
# refuses them otherwise): performed on the spot, their slow travel removed (--bvh-in-place).
IN_PLACE = {"threejs_pirouette", "cmu_94_01_indian_dance", "cmu_01_01_forward_jumps_turn", "perfume_B_dance",
            "sfu_0007_Cartwheel001", "sfu_0005_Jogging001", "sfu_0005_SideSkip001"}


def captures(work):
    """The suite: name, synth args, the path it needs (skipped when absent), optional BVH start."""
    caps = [dict(name="builtin", args=[])]
    for clip, start in CLIPS.items():
        path = os.path.join(BVH_DIR, clip + ".bvh")
        args = ["--bvh", path] + (["--bvh-in-place"] if clip in IN_PLACE else [])
        caps.append(dict(name=clip, args=args, needs=path, bvh_start=start))
    caps += [
        dict(name="body_heavy", args=["--girth", "1.3"]),
        dict(name="body_small", args=["--actor-height", "1.55", "--girth", "0.9"]),
        dict(name="rig_6cams", args=["--cameras", "6"]),
        dict(name="rig_k1", args=["--k1", "-0.05"]),
    ]
    # Scans taken in the performer's own first pose (--scan-frame 0), for the frame-0 vertex
    # error (issue 19: <= 5 mm): the built-in A-pose, arms against the body (Perfume's first
    # pose) and crouched (the Indian dance's plie).
    caps.append(dict(name="scan_pose_a", args=["--scan-frame", "0"]))
    for name, clip in (("scan_pose_arms_in", "perfume_B_dance"), ("scan_pose_crouched", "cmu_94_01_indian_dance")):
        path = os.path.join(BVH_DIR, clip + ".bvh")
        args = ["--bvh", path] + (["--bvh-in-place"] if clip in IN_PLACE else []) + ["--scan-frame", "0"]
        caps.append(dict(name=name, args=args, needs=path, bvh_start=CLIPS[clip]))
    caps += [
        # Samba ships as a tarball; it is unpacked once into WORK/data/samba (Y up).
        dict(name="samba", args=["--actor-sequence", os.path.join(work, "data", "samba"), "--up", "y"],
             needs=SAMBA_TAR, unpack=SAMBA_TAR),
    ]
    return caps


class StepFailed(Exception):
    pass


def log(msg):
    print(msg, flush=True)


def step(tag, name, cmd, logfile):
    """Runs one command with its output appended to logfile; prints the step and its seconds."""
    start = time.time()
    log(f"{tag} {name} ...")
    with open(logfile, "a") as out:
        out.write(f"\n$ {' '.join(cmd)}\n")
        out.flush()
        rc = subprocess.run(cmd, stdout=out, stderr=subprocess.STDOUT, stdin=subprocess.DEVNULL).returncode
    seconds = time.time() - start
    if rc != 0:
        with open(logfile, errors="replace") as f:
            lines = [l.strip() for l in f.read().replace("\r", "\n").splitlines() if l.strip()]
        why = next((l for l in reversed(lines) if l.startswith("confluent")), lines[-1] if lines else "")
        log(f"{tag} {name} FAILED after {seconds:.1f} s (exit {rc}): {why}")
        why = why.split(": error: ", 1)[-1]  # drop "confluent X: error: " and a leading path
        why = why.split(": ", 1)[1] if "/" in why.split(": ", 1)[0] and ": " in why else why
        raise StepFailed(f"{name} failed: {why[:120] + ('...' if len(why) > 120 else '')} (see log.txt)")
    log(f"{tag} {name} done, {seconds:.1f} s")
    return seconds


def longest_stretch(flags, min_frames=6):
    """The longest run of >= min_frames consecutive true flags, as (first, last), or None."""
    best, start = None, None
    for i, flag in enumerate(list(flags) + [False]):
        if flag and start is None:
            start = i
        elif not flag and start is not None:
            if i - start >= min_frames and (best is None or i - start > best[1] - best[0] + 1):
                best = (start, i - 1)
            start = None
    return best


def lost_limb(ious, min_frames=6, drop=0.05):
    """The longest stretch of >= min_frames frames whose tracking-camera IoU is more than `drop`
    below the median, as (first, last), or None."""
    if not ious:
        return None
    limit = statistics.median(ious) - drop
    return longest_stretch([iou < limit for iou in ious], min_frames)


# The limbs' articulation joints, for the joint-error companion of the lost-limb test.
LIMB_OFF_CM = 10.0
LIMB_JOINTS = [f"{side}_{joint}" for side in ("left", "right") for joint in ("elbow", "wrist", "knee", "ankle")]


def limb_joint_errors(frames, joint_names, joints_path):
    """Per tracked frame (poses.json's, whose joints are `joint_names`), the largest error (cm) of a
    limb's elbow, wrist, knee or ankle against the studio's joints (joints.json of `confluent synth`),
    with the joint's name; None without that file."""
    if not joints_path or not os.path.exists(joints_path):
        return None
    truth = json.load(open(joints_path))
    true_index = {n: i for i, n in enumerate(truth["joint_names"])}
    tracked_index = {n: i for i, n in enumerate(joint_names)}
    joints = [j for j in LIMB_JOINTS if j in true_index and j in tracked_index]
    true_frames = {f["frame"]: f["positions"] for f in truth["frames"]}
    errors = []
    for f in frames:
        true = true_frames.get(f["frame"])
        errors.append(max(((100 * math.dist(f["joint_positions"][tracked_index[j]], true[true_index[j]]), j)
                           for j in joints if true), default=(0.0, "")))
    return errors


def collect(run_dir, worst_dir, name, joints_path=None):
    """Reads the metrics of one finished capture into a flat dict (`joints_path`: the studio's
    joints.json, for the limb-joint test; None or absent: no such test)."""
    m = {}
    metrics = json.load(open(os.path.join(run_dir, "metrics.json")))
    m["scan_iou_mean"] = metrics["scan"]["iou_mean"]
    m["scan_iou_min"] = metrics["scan"]["iou_min"]
    m["template_iou_mean"] = metrics["template"]["iou_mean"]
    m["psnr_db"] = metrics["scan"]["psnr_db_mean"]
    if "scan_vertex_error_mean_m" in metrics:
        m["vertex_error_cm"] = 100 * metrics["scan_vertex_error_mean_m"]
    first = [row["scan_vertex_error_m"] for row in metrics["rows"] if row["frame"] == 0 and "scan_vertex_error_m" in row]
    if first:
        m["vertex_error_frame0_mm"] = 1000 * first[0]
    summary_path = os.path.join(run_dir, "track_summary.json")
    if os.path.exists(summary_path):
        summary = json.load(open(summary_path))
        if "joint_error_mean_m" in summary:
            m["joint_error_mean_cm"] = 100 * summary["joint_error_mean_m"]
            m["joint_error_p95_cm"] = 100 * summary["joint_error_p95_m"]
    # Tracking flags and the per-frame IoU on the tracking cameras (poses.json).
    poses = json.load(open(os.path.join(run_dir, "poses.json")))
    frames = sorted(poses["frames"], key=lambda f: f["frame"])
    flags = [f.get("flags", []) for f in frames]
    m["flagged"] = sum(any(x != "initialized" for x in fl) for fl in flags)
    m["recovered"] = sum("recovered" in fl for fl in flags)
    m["bad"] = sum("bad" in fl for fl in flags)
    ious = [f["mean_iou"] for f in frames]
    m["tracking_iou_median"] = statistics.median(ious)
    stretch = lost_limb(ious)
    m["lost_limb"] = stretch is not None
    m["lost_limb_frames"] = f"{frames[stretch[0]]['frame']}-{frames[stretch[1]]['frame']}" if stretch else ""
    # Beside it (not instead of it), the same question asked of the joints: a limb's elbow, wrist,
    # knee or ankle more than LIMB_OFF_CM from the truth for more than 5 frames. Overlap also falls
    # where the template's surface cannot follow a pose (a cartwheel's handstand) with every limb in place.
    limb_errors = limb_joint_errors(frames, poses.get("joint_names", []), joints_path)
    if limb_errors:
        m["limb_joint_max_cm"], m["limb_joint_max_name"] = max(limb_errors)
        stretch = longest_stretch([e > LIMB_OFF_CM for e, _ in limb_errors])
        m["limb_off"] = stretch is not None
        m["limb_off_frames"] = f"{frames[stretch[0]]['frame']}-{frames[stretch[1]]['frame']}" if stretch else ""
    # Seconds per frame of the run: every row of timings.csv (once-per-run rows included).
    with open(os.path.join(run_dir, "timings.csv")) as f:
        total = sum(float(line.split(",")[2]) for line in f.readlines()[1:] if line.count(",") == 2)
    m["seconds_per_frame"] = total / max(1, len(frames))
    # The worst 4 frames by held-out scan IoU (each frame's worst camera) and their pictures.
    worst = {}
    for row in metrics["rows"]:
        if "scan" in row and row["scan"]["iou"] < worst.get(row["frame"], (2, ""))[0]:
            worst[row["frame"]] = (row["scan"]["iou"], row["camera"])
    m["worst"] = []
    for frame, (iou, camera) in sorted(worst.items(), key=lambda kv: kv[1][0])[:4]:
        src = os.path.join(run_dir, "evaluation", camera, f"{frame:06d}.png")
        picture = ""
        if os.path.exists(src):
            os.makedirs(worst_dir, exist_ok=True)
            picture = os.path.join(worst_dir, f"{name}_{frame:06d}_{camera}.png")
            shutil.copyfile(src, picture)
        m["worst"].append(dict(frame=frame, camera=camera, iou=iou, picture=picture))
    return m


def run_capture(cap, i, n, args, build, preset_dir, synth_help):
    """synth -> run -> evaluate -> track report for one capture; returns a result dict."""
    name = cap["name"]
    tag = f"[{i}/{n} {name}]"
    result = dict(name=name, status="ok", seconds=0.0)
    if cap.get("needs") and not os.path.exists(cap["needs"]):
        log(f"{tag} skipped: {cap['needs']} is absent")
        return dict(result, status="skipped (no " + os.path.relpath(cap["needs"], REPO) + ")")
    start = time.time()
    root = os.path.join(preset_dir, name)
    capture, truth, run = os.path.join(root, "capture"), os.path.join(root, "capture_gt"), os.path.join(root, "run")
    logfile = os.path.join(root, "log.txt")
    if not args.keep and os.path.exists(root):
        shutil.rmtree(root)
    os.makedirs(root, exist_ok=True)
    exe = os.path.join(build, "app", "confluent")
    threads = ["--threads", str(args.threads)] if args.threads else []
    try:
        if cap.get("unpack") and not os.path.isdir(cap["args"][1]):
            log(f"{tag} unpacking {cap['unpack']}")
            scratch = cap["args"][1] + ".unpacking"  # renamed when complete
            shutil.rmtree(scratch, ignore_errors=True)
            with tarfile.open(cap["unpack"]) as tar:
                tar.extractall(scratch)  # the archive holds one folder, samba/
            os.rename(os.path.join(scratch, "samba"), cap["args"][1])
            shutil.rmtree(scratch)
        # 1. Synthesis, once (a finished capture has CAPTURE_gt/synth.json, as `confluent demo` checks).
        if not os.path.exists(os.path.join(truth, "synth.json")):
            extra = []
            if cap.get("bvh_start") is not None:
                if "--bvh-start" in synth_help:
                    extra = ["--bvh-start", str(cap["bvh_start"])]
                else:
                    log(f"{tag} note: this synth has no --bvh-start; the clip starts at 0 s")
            shutil.rmtree(capture, ignore_errors=True)
            shutil.rmtree(truth, ignore_errors=True)
            step(tag, "synth", [exe, "synth", "--out", capture, "--gt", truth] + PRESETS[args.preset] + cap["args"] +
                 extra + threads, logfile)
        else:
            log(f"{tag} synth: reusing {capture}")
        # 2. The run with the held-out cameras excluded (resumes by itself).
        excluded = [a for c in HELD_OUT for a in ("--exclude-camera", c)]
        step(tag, "run", [exe, "run", capture, "--out", run] + excluded + threads + args.run_option, logfile)
        # 3. Held-out evaluation against the ground truth; a side-by-side picture of every frame,
        #    so that the worst frames have one.
        step(tag, "evaluate", [exe, "evaluate", capture, "--run", run, "--masks", os.path.join(truth, "masks"),
                               "--gt-meshes", os.path.join(truth, "meshes"), "--side-by-side-every", "1"], logfile)
        # 4. Joint error: the tracking report of the finished run (tracking itself is all skipped).
        joints = os.path.join(truth, "joints.json")
        if os.path.exists(joints):
            step(tag, "joint error", [exe, "track", capture, "--out", run, "--masks", os.path.join(run, "masks"),
                                      "--gt-joints", joints, "--overlay-every", "0"] + excluded, logfile)
        result.update(collect(run, os.path.join(preset_dir, "worst"), name, joints))
    except StepFailed as e:
        result["status"] = str(e)
    except (OSError, ValueError, KeyError, IndexError, tarfile.TarError) as e:
        result["status"] = f"error reading results: {type(e).__name__}: {e}"
        log(f"{tag} {result['status']}")
    result["seconds"] = time.time() - start
    log(f"{tag} {result['status']}, {result['seconds']:.0f} s")
    return result


def fmt(r, key, spec):
    return format(r[key], spec) if isinstance(r.get(key), (int, float)) else "-"


def write_table(path, results, header, contact_sheet):
    lines = [f"# Motion suite", "", header, "",
             "| capture | status | scan IoU mean | scan IoU min | template IoU mean | PSNR dB | joint err cm (mean / p95) "
             "| scan vertex err cm (frame 0: mm) | flagged (recovered / bad) | s/frame | lost limb | limb joint off (worst cm) | worst frames (IoU) |",
             "|---|---|---|---|---|---|---|---|---|---|---|---|---|"]
    for r in results:
        ok = r["status"] == "ok"
        joint = f"{fmt(r, 'joint_error_mean_cm', '.1f')} / {fmt(r, 'joint_error_p95_cm', '.1f')}" if ok else "-"
        flagged = f"{r['flagged']} ({r['recovered']} / {r['bad']})" if ok else "-"
        lost = ("yes, " + r["lost_limb_frames"] if r["lost_limb"] else "no") if ok else "-"
        limb_off = "-"
        if ok and "limb_off" in r:
            limb_off = (("yes, " + r["limb_off_frames"]) if r["limb_off"] else "no") + \
                f" ({r['limb_joint_max_cm']:.1f} {r['limb_joint_max_name'].replace('_', ' ')})"
        worst = ", ".join(f"{w['frame']} ({w['iou']:.3f})" for w in r.get("worst", []))
        lines.append(f"| {r['name']} | {r['status']} | {fmt(r, 'scan_iou_mean', '.4f')} | {fmt(r, 'scan_iou_min', '.4f')} "
                     f"| {fmt(r, 'template_iou_mean', '.4f')} | {fmt(r, 'psnr_db', '.2f')} | {joint} "
                     f"| {fmt(r, 'vertex_error_cm', '.2f')} ({fmt(r, 'vertex_error_frame0_mm', '.1f')}) | {flagged} | {fmt(r, 'seconds_per_frame', '.2f')} | {lost} | {limb_off} | {worst} |")
    lines += ["", "Legend: IoU and PSNR are `confluent evaluate`'s on the two held-out cameras (holdout0, holdout1) "
              "against the ground-truth masks, every frame, views over the clean plates (its defaults); PSNR is the "
              "scan's, inside the union of the silhouettes. Joint error: `confluent track --gt-joints` on the finished "
              "run (articulation joints, 95th percentile over joint-frames). Scan vertex error: mean over frames "
              "against the ground-truth meshes (in brackets: frame 0, mm; the scan_pose_* captures' scan is the actor's frame-0 mesh). Flagged: frames the tracker marked (recovered, bad, low overlap ...). "
              "s/frame: every stage of `confluent run` (RUN/timings.csv) over the frames. Lost limb: a stretch of "
              "more than 5 frames whose tracking-camera IoU (poses.json) is more than 0.05 below the capture's "
              f"median. Limb joint off, beside it: a stretch of more than 5 frames where an elbow, wrist, knee or ankle is "
              f"more than {LIMB_OFF_CM:.0f} cm from the studio's joint (in brackets: the largest such error over the frames, "
              f"and its joint). Worst frames: by held-out scan IoU (worst camera); their side-by-side pictures are in {contact_sheet}.",
              ""]
    kept = kept_sections(path)
    with open(path, "w") as f:
        f.write("\n".join(lines) + ("\n" + kept if kept else ""))


def kept_sections(path):
    """The dated sections written by hand below the generated table (from the first '## ' heading on):
    a new table replaces the old one and keeps them."""
    try:
        with open(path) as f:
            text = f.read()
    except FileNotFoundError:
        return ""
    start = text.find("\n## ")
    return text[start + 1:] if start >= 0 else ""


def write_contact_sheet(path, results):
    lines = ["# Worst frames by held-out scan IoU", "", "real | scan | template | difference (`confluent evaluate`)", ""]
    for r in results:
        for w in r.get("worst", []):
            if w["picture"]:
                lines.append(f"**{r['name']}** frame {w['frame']}, {w['camera']}, scan IoU {w['iou']:.3f}  ")
                lines.append(f"![]({os.path.relpath(w['picture'], os.path.dirname(path))})\n")
    with open(path, "w") as f:
        f.write("\n".join(lines) + "\n")


def check_floors(results, floors):
    """Floors: {capture: {metric: floor, "max_<metric>": ceiling}}. Returns the failures."""
    failures = []
    for r in results:
        if r["name"] not in floors or r["status"].startswith("skipped"):
            continue
        if r["status"] != "ok":
            failures.append(f"{r['name']}: {r['status']}")
            continue
        for key, limit in floors[r["name"]].items():
            metric, ceiling = (key[4:], True) if key.startswith("max_") else (key, False)
            value = r.get(metric)
            if not isinstance(value, (int, float)):
                failures.append(f"{r['name']}: {metric} missing")
            elif (value > limit) if ceiling else (value < limit):
                failures.append(f"{r['name']}: {metric} = {value:.4g} {'above its ceiling' if ceiling else 'below its floor'} {limit}")
    return failures


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0], formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--build", default=os.path.join(REPO, "build"), help="build folder (build/app/confluent)")
    parser.add_argument("--preset", choices=sorted(PRESETS), default="small")
    parser.add_argument("--only", help="comma-separated capture names")
    parser.add_argument("--out", default="/tmp/confluent-suite", help="work folder")
    parser.add_argument("--threads", "--jobs", type=int, help="passed to synth and run as --threads")
    parser.add_argument("--table", help="Markdown table (default bench/SUITE.md; tiny: WORK/tiny/SUITE.md); "
                        "the file's dated '## ' sections below the table are kept")
    parser.add_argument("--floors", help="JSON of per-capture floors (default bench/suite_floors_<preset>.json)")
    parser.add_argument("--check", action="store_true",
                        help="exit 1 when a metric is below its floor; without --only, only the captures the floors file names")
    parser.add_argument("--keep", action="store_true", help="reuse finished captures and runs")
    parser.add_argument("--run-option", action="append", default=[], metavar="OPTION",
                        help="passed to every `confluent run` (repeatable; e.g. --run-option=--girth-inflation=0.1)")
    args = parser.parse_args()

    work = os.path.abspath(args.out)
    preset_dir = os.path.join(work, args.preset)
    exe = os.path.join(args.build, "app", "confluent")
    if not os.access(exe, os.X_OK):
        sys.exit(f"suite: {exe} not found (build first: ./dev build)")
    caps = captures(work)
    if args.only:
        wanted = args.only.split(",")
        unknown = [w for w in wanted if w not in [c["name"] for c in caps]]
        if unknown:
            sys.exit(f"suite: unknown capture(s) {', '.join(unknown)}; known: {', '.join(c['name'] for c in caps)}")
        caps = [c for c in caps if c["name"] in wanted]
    floors_path = args.floors or os.path.join(REPO, "bench", f"suite_floors_{args.preset}.json")
    if args.check and not os.path.exists(floors_path):
        sys.exit(f"suite: --check needs a floors file ({floors_path} is absent)")
    if args.check and not args.only:  # the captures that have floors
        floored = json.load(open(floors_path))
        caps = [c for c in caps if c["name"] in floored]
    table = args.table or (os.path.join(preset_dir, "SUITE.md") if args.preset == "tiny" else os.path.join(REPO, "bench", "SUITE.md"))
    synth_help = subprocess.run([exe, "synth", "--help"], capture_output=True, text=True).stdout
    os.makedirs(preset_dir, exist_ok=True)
    shutil.rmtree(os.path.join(preset_dir, "worst"), ignore_errors=True)

    try:
        commit = subprocess.check_output(["git", "-C", REPO, "rev-parse", "--short", "HEAD"], text=True).strip()
    except (OSError, subprocess.CalledProcessError):
        commit = "unknown"
    contact_sheet = os.path.join(preset_dir, "contact_sheet.md")
    os.makedirs(os.path.dirname(os.path.abspath(table)), exist_ok=True)

    def write_outputs(results, total):
        """The table, contact sheet and JSON so far (rewritten after every capture)."""
        done = f"{len(results)} captures" if len(results) == len(caps) else f"{len(results)} of {len(caps)} captures so far"
        header = (f"{datetime.datetime.now():%Y-%m-%d %H:%M}, commit {commit}, preset {args.preset} "
                  f"(synth {' '.join(PRESETS[args.preset])}), {done} in {total / 60:.1f} min "
                  f"on {os.cpu_count()} cores. Work folder {work}.")
        write_contact_sheet(contact_sheet, results)
        write_table(table, results, header, contact_sheet)
        with open(os.path.join(preset_dir, "suite_results.json"), "w") as f:
            json.dump(dict(header=header, results=results), f, indent=1)

    start = time.time()
    results = []
    for i, cap in enumerate(caps):
        results.append(run_capture(cap, i + 1, len(caps), args, args.build, preset_dir, synth_help))
        write_outputs(results, time.time() - start)
    total = time.time() - start
    log(f"suite: {len(results)} captures in {total:.0f} s; table {table}; contact sheet {contact_sheet}")

    if args.check:
        failures = check_floors(results, json.load(open(floors_path)))
        for failure in failures:
            log(f"suite check FAILED: {failure}")
        if failures:
            return 1
        log(f"suite check passed ({floors_path})")
    return 0


if __name__ == "__main__":
    sys.exit(main())
