#!/usr/bin/env python3
"""Frame-to-frame peers for ecvo, scored with `ecvo eval`.

Runs, on TUM-layout sequence folders (rgb.txt, depth.txt, rgb/, depth/, camera.json,
groundtruth.txt), at several frame steps:

* opencv-rgbd / opencv-rgb / opencv-depth: OpenCV's RGB-D odometry (cv2.Odometry in
  OpenCV 5, cv2.rgbd.*Odometry_create in OpenCV 4.x contrib) with its default settings,
  naively frame to frame: every frame is aligned to the previous one starting from the
  identity (compute(current, previous), as OpenCV's odometry evaluation sample does; the
  other direction measured worse here: fr1/desk half 0.121 / 0.143 m instead of
  0.101 / 0.061 m for RGB-D / RGB), and the poses are composed. A failed alignment keeps the previous pose
  (counted in `failed`).
* open3d-hybrid / open3d-color: Open3D's RGB-D odometry
  (open3d.pipelines.odometry.compute_rgbd_odometry with the hybrid photometric and
  geometric Jacobian of Park et al., or the photometric one of Steinbrücker et al.),
  default OdometryOption, naively frame to frame like OpenCV's (current frame the
  source, previous frame the target, from the identity). The RGBDImage is made with
  depth_trunc equal to the option's depth_max (4 m), so that the image keeps the depths
  the odometry would use. Open3D runs on one OpenMP thread (OMP_NUM_THREADS=1, set
  before it is imported). It is imported only when asked for: run-peers.sh installs it
  into the venv on first use (a 400 MB wheel).
* vors: the visual-odometry-rs tracker (DSO-style direct tracking against keyframes)
  through scripts/peers/vors-cam, a driver that takes the camera from camera.json.

Colour and depth are paired by nearest timestamp within 0.02 s (greedy, closest pairs
first, each image used once), as TUM's associate.py does; `--frame-steps N` keeps every
Nth associated pair (and `--max-frames N` the first N of those). Each run writes a TUM
trajectory, is scored with `ecvo eval GT EST --json`, and is timed per frame: the cost of
the odometry (OpenCV: making the OdometryFrame from the decoded images, including the
conversion of depth to metres, prepareFrame and compute; Open3D: making the two
RGBDImages' Image objects and RGBDImage, and compute_rgbd_odometry, which builds both
frames' pyramids on every call; vors: Tracker::track). Reading and decoding the PNGs is
not counted for any.

Every frame is timed on three clocks: the CPU time of the whole process
(time.process_time(), every thread's), the CPU time of the calling thread
(time.thread_time()) and the wall clock. `ms_per_frame` is the process CPU time for
OpenCV and Open3D, so that work a library hands to threads of its own is counted (Open3D
0.20 runs its kernels on a oneTBB pool that OMP_NUM_THREADS does not bound), and the
thread CPU time for vors (vors-cam's CLOCK_THREAD_CPUTIME_ID; vors is single-threaded,
which its thread count checks). OMP_NUM_THREADS=1 and cv2.setNumThreads(1) are set;
`--pin-cpu N` also binds the process to CPU N before any library is loaded (as
`taskset -c N`), which makes oneTBB start no workers. Each row of the JSON has all three
clocks' median, mean and p95 (nearest rank, as ecvo's histograms), the threads seen
(/proc/self/task, with each thread's name and CPU seconds at the end) and the CPU
affinity.

Usage: peers.py --ecvo BIN [--vors-cam BIN] [--peers a,b] [--frame-steps 1,2]
                [--max-frames N] [--pin-cpu N] --out DIR SEQ...
Prints a Markdown table and writes DIR/peers.json.
"""

import argparse
import json
import os
import subprocess
import sys
import time

import timing
from assoc import MAX_DT, associate, read_list


def _pin_from_argv(argv):
    """The CPU of `--pin-cpu N` / `--pin-cpu=N` in argv, or None (read before the
    libraries are imported, so that every thread they start inherits the affinity)."""
    for i, a in enumerate(argv):
        if a == "--pin-cpu" and i + 1 < len(argv):
            return int(argv[i + 1])
        if a.startswith("--pin-cpu="):
            return int(a.split("=", 1)[1])
    return None


PIN_CPU = _pin_from_argv(sys.argv[1:]) if __name__ == "__main__" else None
if PIN_CPU is not None:
    os.sched_setaffinity(0, {PIN_CPU})

# One thread for every peer, as ecvo's ms_per_frame is measured (OpenMP and OpenBLAS
# read this when they are loaded; Open3D's oneTBB pool does not).
os.environ["OMP_NUM_THREADS"] = "1"

import numpy as np  # noqa: E402 (after the affinity and OMP_NUM_THREADS)
import cv2  # noqa: E402


# One thread, as ecvo's ms_per_frame.total is measured.
cv2.setNumThreads(1)


def load_sequence(seq):
    with open(os.path.join(seq, "camera.json")) as f:
        cam = json.load(f)
    rgb = sorted(read_list(os.path.join(seq, "rgb.txt")))
    depth = sorted(read_list(os.path.join(seq, "depth.txt")))
    return cam, associate(rgb, depth)


def read_gray(path):
    img = cv2.imread(path, cv2.IMREAD_UNCHANGED)
    if img is None:
        raise RuntimeError(f"cannot read {path}")
    if img.ndim == 3:
        code = cv2.COLOR_BGRA2GRAY if img.shape[2] == 4 else cv2.COLOR_BGR2GRAY
        img = cv2.cvtColor(img, code)
    if img.dtype != np.uint8:
        raise RuntimeError(f"{path}: 8-bit colour expected, got {img.dtype}")
    return img


def read_depth(path):
    d = cv2.imread(path, cv2.IMREAD_UNCHANGED)
    if d is None or d.dtype != np.uint16 or d.ndim != 2:
        raise RuntimeError(f"{path}: 16-bit depth expected")
    return d


def quat_from_matrix(r):
    """(qx, qy, qz, qw) of a rotation matrix (Shepperd's method)."""
    t = np.trace(r)
    if t > 0:
        s = 2.0 * np.sqrt(t + 1.0)
        return ((r[2, 1] - r[1, 2]) / s, (r[0, 2] - r[2, 0]) / s,
                (r[1, 0] - r[0, 1]) / s, 0.25 * s)
    i = int(np.argmax(np.diag(r)))
    j, k = (i + 1) % 3, (i + 2) % 3
    s = 2.0 * np.sqrt(1.0 + r[i, i] - r[j, j] - r[k, k])
    q = [0.0, 0.0, 0.0, 0.0]
    q[i] = 0.25 * s
    q[j] = (r[j, i] + r[i, j]) / s
    q[k] = (r[k, i] + r[i, k]) / s
    q[3] = (r[k, j] - r[j, k]) / s
    return tuple(q)


def write_tum(path, stamps, poses):
    with open(path, "w") as f:
        f.write("# timestamp tx ty tz qx qy qz qw\n")
        for t, p in zip(stamps, poses):
            q = quat_from_matrix(p[:3, :3])
            x, y, z = p[:3, 3]
            f.write(f"{t:.6f} {x:.9f} {y:.9f} {z:.9f} "
                    f"{q[0]:.9f} {q[1]:.9f} {q[2]:.9f} {q[3]:.9f}\n")


class OpenCvOdometry:
    """OpenCV's odometry in one of its modes, behind one interface for 5.x and 4.x."""

    def __init__(self, mode, cam):
        self.mode = mode
        self.k = np.array([[cam["fx"], 0, cam["cx"]], [0, cam["fy"], cam["cy"]],
                           [0, 0, 1]], dtype=np.float64)
        self.scale = float(cam["depth_scale"])
        if hasattr(cv2, "Odometry") and hasattr(cv2, "OdometrySettings"):
            self.api = "cv2.Odometry (OpenCV 5)"
            settings = cv2.OdometrySettings()
            settings.setCameraMatrix(self.k.astype(np.float32))
            otype = {"rgbd": cv2.OdometryType_RGB_DEPTH, "rgb": cv2.OdometryType_RGB,
                     "depth": cv2.OdometryType_DEPTH}[mode]
            self.odo = cv2.Odometry(otype, settings, cv2.OdometryAlgoType_COMMON)
        elif hasattr(cv2, "rgbd"):
            self.api = "cv2.rgbd (OpenCV 4 contrib)"
            make = {"rgbd": cv2.rgbd.RgbdICPOdometry_create,
                    "rgb": cv2.rgbd.RgbdOdometry_create,
                    "depth": cv2.rgbd.ICPOdometry_create}[mode]
            self.odo = make(self.k)
        else:
            raise RuntimeError("this OpenCV has neither cv2.Odometry nor cv2.rgbd")

    def frame(self, gray, depth_raw):
        """A prepared frame from decoded images (timed by the caller)."""
        depth = depth_raw.astype(np.float32) * np.float32(1.0 / self.scale)
        if self.api.startswith("cv2.Odometry"):
            f = cv2.OdometryFrame(depth=depth, image=gray)
            self.odo.prepareFrame(f)
            return f
        f = cv2.rgbd.OdometryFrame_create(gray, depth, (depth > 0).astype(np.uint8))
        self.odo.prepareFrameCache(f, cv2.rgbd.OdometryFrame_CACHE_ALL)
        return f

    def compute(self, src, dst):
        """(ok, Rt) with Rt mapping points of src's camera frame into dst's."""
        if self.api.startswith("cv2.Odometry"):
            ok, rt = self.odo.compute(src, dst)
        else:
            ok, rt = self.odo.compute2(src, dst)
        return bool(ok), np.asarray(rt, dtype=np.float64)


class Open3dOdometry:
    """Open3D's RGB-D odometry with the hybrid or the photometric Jacobian."""

    def __init__(self, mode, cam):
        import open3d as o3d

        self.o3d = o3d
        odometry = o3d.pipelines.odometry
        self.api = f"open3d {o3d.__version__} compute_rgbd_odometry ({mode})"
        self.intrinsic = o3d.camera.PinholeCameraIntrinsic(
            int(cam["width"]), int(cam["height"]), cam["fx"], cam["fy"], cam["cx"],
            cam["cy"])
        self.jacobian = {"hybrid": odometry.RGBDOdometryJacobianFromHybridTerm,
                         "color": odometry.RGBDOdometryJacobianFromColorTerm}[mode]()
        self.option = odometry.OdometryOption()
        self.scale = float(cam["depth_scale"])
        self.init = np.eye(4)

    def frame(self, gray, depth_raw):
        """An RGBDImage from decoded images (timed by the caller)."""
        g = self.o3d.geometry
        return g.RGBDImage.create_from_color_and_depth(
            g.Image(gray), g.Image(depth_raw), depth_scale=self.scale,
            depth_trunc=self.option.depth_max, convert_rgb_to_intensity=True)

    def compute(self, src, dst):
        """(ok, T) with T mapping points of src's camera frame into dst's."""
        ok, t, _info = self.o3d.pipelines.odometry.compute_rgbd_odometry(
            src, dst, self.intrinsic, self.init, self.jacobian, self.option)
        return bool(ok), np.asarray(t, dtype=np.float64)


def threads_now():
    """This process's threads now (/proc/self/task): [{"tid", "name", "cpu_s"}]."""
    out = []
    tick = os.sysconf("SC_CLK_TCK")
    for t in sorted(os.listdir("/proc/self/task"), key=int):
        try:
            with open(f"/proc/self/task/{t}/comm") as f:
                name = f.read().strip()
            with open(f"/proc/self/task/{t}/stat") as f:
                # Fields after the parenthesised name: utime and stime are the 12th
                # and 13th.
                st = f.read().rsplit(")", 1)[1].split()
        except OSError:  # the thread ended meanwhile
            continue
        out.append({"tid": int(t), "name": name,
                    "cpu_s": (int(st[11]) + int(st[12])) / tick})
    return out


def make_odometry(peer, cam):
    """The Python-driven peer `peer` (opencv-* or open3d-*)."""
    family, mode = peer.split("-", 1)
    if family == "open3d":
        return Open3dOdometry(mode, cam)
    return OpenCvOdometry(mode, cam)


def run_python_peer(peer, seq, cam, pairs, out_path):
    """Runs an OpenCV or Open3D peer naively frame to frame."""
    odo = make_odometry(peer, cam)
    at_start = len(os.listdir("/proc/self/task"))
    most = at_start
    pose = np.eye(4)
    stamps, poses, proc, thread, wall, failed = [], [], [], [], [], 0
    prev = None
    for (t, rgb_rel), (_, depth_rel) in pairs:
        gray = read_gray(os.path.join(seq, rgb_rel))
        depth = read_depth(os.path.join(seq, depth_rel))
        start, cpu, pcpu = time.perf_counter(), time.thread_time(), time.process_time()
        cur = odo.frame(gray, depth)
        if prev is not None:
            # As OpenCV's own odometry evaluation sample does: the current frame is the
            # source, the previous one the destination.
            ok, rt = odo.compute(cur, prev)
        pcpu, cpu = time.process_time() - pcpu, time.thread_time() - cpu
        wall.append((time.perf_counter() - start) * 1e3)
        proc.append(pcpu * 1e3)
        thread.append(cpu * 1e3)
        most = max(most, len(os.listdir("/proc/self/task")))
        if prev is not None:
            if ok and np.all(np.isfinite(rt)):
                # Rt * p_cur = p_prev: Rt is the current camera's pose in the previous
                # camera's frame.
                pose = pose @ rt
            else:
                failed += 1
        prev = cur
        stamps.append(t)
        poses.append(pose.copy())
    write_tum(out_path, stamps, poses)
    # The first frame is only prepared; its cost is part of every later frame's.
    return {"clock": "process_cpu", "process_ms": proc[1:], "thread_ms": thread[1:],
            "wall_ms": wall[1:], "failed": failed, "api": odo.api,
            "threads": {"at_start": at_start, "max_seen": most, "at_end": threads_now()}}


def run_vors(vors_cam, seq, pairs, out_path, work):
    assoc = os.path.join(work, "vors-associations.txt")
    with open(assoc, "w") as f:
        # vors_track's format: depth first.
        for (t_rgb, rgb_rel), (t_d, depth_rel) in pairs:
            f.write(f"{t_d:.6f} {os.path.abspath(os.path.join(seq, depth_rel))} "
                    f"{t_rgb:.6f} {os.path.abspath(os.path.join(seq, rgb_rel))}\n")
    r = subprocess.run([vors_cam, os.path.join(seq, "camera.json"), assoc],
                       capture_output=True, text=True)
    if r.returncode != 0:
        raise RuntimeError(f"vors-cam failed: {r.stderr[-2000:]}")
    with open(out_path, "w") as f:
        f.write("# timestamp tx ty tz qx qy qz qw (vors, depth stamps)\n")
        f.write(r.stdout)
    timed = [line.split() for line in r.stderr.splitlines()
             if line.startswith("vors-cam-ms ")]
    most = [int(line.split()[1]) for line in r.stderr.splitlines()
            if line.startswith("vors-cam-threads ")]
    failed = sum(1 for line in r.stderr.splitlines()
                 if line and not line.startswith(("vors-cam", "Optical_flow",
                                                  "Changing keyframe")))
    keyframes = sum(1 for line in r.stderr.splitlines()
                    if line.startswith("Changing keyframe"))
    return {"clock": "thread_cpu", "thread_ms": [float(x[2]) for x in timed],
            "wall_ms": [float(x[3]) for x in timed],
            "process_ms": [float(x[4]) for x in timed if len(x) > 4],
            "failed": failed, "keyframes": keyframes,
            "threads": {"max_seen": most[0] if most else None}}


def evaluate(ecvo, gt, est):
    r = subprocess.run([ecvo, "eval", gt, est, "--json"], capture_output=True, text=True)
    if r.returncode != 0:
        raise RuntimeError(f"ecvo eval failed: {r.stderr.strip()}")
    return json.loads(r.stdout)["ate_rmse_m"]


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("seqs", nargs="+", metavar="SEQ")
    ap.add_argument("--ecvo", required=True)
    ap.add_argument("--vors-cam")
    ap.add_argument("--peers", default="opencv-rgbd,opencv-rgb,vors")
    ap.add_argument("--frame-steps", default="1")
    ap.add_argument("--max-frames", type=int, default=0,
                    help="keep the first N pairs of each frame step (0: all)")
    ap.add_argument("--pin-cpu", type=int, metavar="N",
                    help="bind the process to CPU N before loading any library")
    ap.add_argument("--out", required=True)
    a = ap.parse_args()
    steps = [int(s) for s in a.frame_steps.split(",")]
    peers = a.peers.split(",")
    for p in peers:
        if p not in ("opencv-rgbd", "opencv-rgb", "opencv-depth", "open3d-hybrid",
                     "open3d-color", "vors"):
            ap.error(f"unknown peer {p}")
    if "vors" in peers and not a.vors_cam:
        ap.error("the vors peer needs --vors-cam")
    os.makedirs(a.out, exist_ok=True)
    rows = []
    print("| sequence | frame step | peer | frames | ATE RMSE (m) | clock | ms/frame median "
          "/ mean / p95 | wall ms/frame median / mean / p95 | threads | failed |")
    print("|---|---|---|---|---|---|---|---|---|---|")
    for seq in a.seqs:
        seq = seq.rstrip("/")
        name = os.path.basename(seq)
        cam, pairs = load_sequence(seq)
        gt = os.path.join(seq, "groundtruth.txt")
        for step in steps:
            sel = pairs[::step]
            if a.max_frames > 0:
                sel = sel[:a.max_frames]
            work = os.path.join(a.out, name, f"step{step}")
            os.makedirs(work, exist_ok=True)
            for peer in peers:
                est = os.path.join(work, f"{peer}.txt")
                if peer == "vors":
                    info = run_vors(a.vors_cam, seq, sel, est, work)
                else:
                    info = run_python_peer(peer, seq, cam, sel, est)
                ate = evaluate(a.ecvo, gt, est)
                row = {"sequence": name, "path": seq, "frame_step": step, "peer": peer,
                       "frames": len(sel), "ate_rmse_m": ate}
                row.update(timing.row_timing(info))
                row.update({"failed": info["failed"], "threads": info["threads"],
                            "trajectory": est})
                for k in ("api", "keyframes"):
                    if k in info:
                        row[k] = info[k]
                rows.append(row)
                most = info["threads"].get("max_seen")
                print(f"| {name} | {step} | {peer} | {len(sel)} | {ate:.4f} | "
                      f"{row['clock']} | {timing.fmt3(row['ms_per_frame'])} | "
                      f"{timing.fmt3(row['wall_ms_per_frame'])} | {most} | "
                      f"{info['failed']} |", flush=True)
    meta = {"opencv": cv2.__version__, "numpy": np.__version__,
            "open3d": sys.modules["open3d"].__version__ if "open3d" in sys.modules
            else None,
            "association_max_dt_s": MAX_DT, "max_frames": a.max_frames,
            "cpu_affinity": sorted(os.sched_getaffinity(0)), "pin_cpu": a.pin_cpu,
            "env": {k: os.environ.get(k) for k in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS",
                                                   "TCM_ENABLE")},
            "cv2_threads": cv2.getNumThreads(), "load_average": os.getloadavg(),
            "rows": rows}
    with open(os.path.join(a.out, "peers.json"), "w") as f:
        json.dump(meta, f, indent=2)
    print(f"\nwrote {os.path.join(a.out, 'peers.json')}", file=sys.stderr)


if __name__ == "__main__":
    main()
