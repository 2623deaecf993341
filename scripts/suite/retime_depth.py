#!/usr/bin/env python3
"""Writes a copy of a TUM sequence whose depth images are moved to their colour
images' time: the experiment behind docs/accuracy.md's "colour/depth time offset".

    retime_depth.py SRC DST [--trajectory TRAJ]

Pairs colour and depth images as ecvo does (nearest timestamps within 20 ms, greedy
by smallest gap, each image used once). Each depth image is back-projected, moved by
the camera motion from its timestamp to its colour image's, splatted to the nearest
pixel (nearest surface wins) and written with the colour image's timestamp, so the
pair has no offset left. The motion comes from the ground truth (the best a tracker
could know), or with --trajectory from an estimated TUM trajectory of the same
sequence: the constant-velocity motion of the two frames before (what a tracker
knows when it prepares the frame). Needs numpy and opencv (the peers' venv,
scripts/peers/setup.sh).
"""
import argparse, json, os, shutil

import cv2
import numpy as np


def read_list(path):
    out = []
    for line in open(path):
        if line.strip() and not line.startswith('#'):
            f = line.split()
            out.append((float(f[0]), f[1]))
    return out


def quat_to_mat(q):
    x, y, z, w = q / np.linalg.norm(q)
    return np.array([[1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
                     [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
                     [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)]])


def pose(row):
    m = np.eye(4)
    m[:3, :3] = quat_to_mat(np.asarray(row[4:8]))
    m[:3, 3] = row[1:4]
    return m


def gt_pose(gt, t):
    """Linear interpolation of position, normalised linear interpolation of the
    quaternion (the samples are 10 ms apart)."""
    k = int(np.clip(np.searchsorted(gt[:, 0], t), 1, len(gt) - 1))
    a = (t - gt[k - 1, 0]) / (gt[k, 0] - gt[k - 1, 0])
    q0, q1 = gt[k - 1, 4:8], gt[k, 4:8]
    if np.dot(q0, q1) < 0:
        q1 = -q1
    row = np.concatenate([[t], (1 - a) * gt[k - 1, 1:4] + a * gt[k, 1:4], (1 - a) * q0 + a * q1])
    return pose(row)


def rot_log(r):
    c = np.clip((np.trace(r) - 1) / 2, -1, 1)
    th = np.arccos(c)
    if th < 1e-9:
        return np.zeros(3)
    return th / (2 * np.sin(th)) * np.array([r[2, 1] - r[1, 2], r[0, 2] - r[2, 0], r[1, 0] - r[0, 1]])


def rot_exp(w):
    th = np.linalg.norm(w)
    if th < 1e-12:
        return np.eye(3)
    k = w / th
    kx = np.array([[0, -k[2], k[1]], [k[2], 0, -k[0]], [-k[1], k[0], 0]])
    return np.eye(3) + np.sin(th) * kx + (1 - np.cos(th)) * kx @ kx


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument('src')
    ap.add_argument('dst')
    ap.add_argument('--trajectory')
    a = ap.parse_args()
    cam = json.load(open(os.path.join(a.src, 'camera.json')))
    rgb = read_list(os.path.join(a.src, 'rgb.txt'))
    dep = read_list(os.path.join(a.src, 'depth.txt'))
    cand = sorted((abs(x - y), i, j) for i, (x, _) in enumerate(rgb) for j, (y, _) in enumerate(dep)
                  if abs(x - y) < 0.02)
    used_r, used_d, pairs = set(), set(), []
    for _, i, j in cand:
        if i not in used_r and j not in used_d:
            used_r.add(i)
            used_d.add(j)
            pairs.append((i, j))
    pairs.sort()
    gt = np.loadtxt(os.path.join(a.src, 'groundtruth.txt'))
    est = np.loadtxt(a.trajectory) if a.trajectory else None
    os.makedirs(os.path.join(a.dst, 'rgb'), exist_ok=True)
    os.makedirs(os.path.join(a.dst, 'depth'), exist_ok=True)
    for f in ('groundtruth.txt', 'camera.json'):
        shutil.copy(os.path.join(a.src, f), a.dst)
    fx, fy, cx, cy, s = (cam[k] for k in ('fx', 'fy', 'cx', 'cy', 'depth_scale'))
    w, h = cam['width'], cam['height']
    u, v = np.meshgrid(np.arange(w), np.arange(h))
    with open(os.path.join(a.dst, 'rgb.txt'), 'w') as rf, open(os.path.join(a.dst, 'depth.txt'), 'w') as df:
        for k, (i, j) in enumerate(pairs):
            tc, td = rgb[i][0], dep[j][0]
            shutil.copy(os.path.join(a.src, rgb[i][1]), os.path.join(a.dst, rgb[i][1]))
            d = cv2.imread(os.path.join(a.src, dep[j][1]), cv2.IMREAD_UNCHANGED).astype(np.float64) / s
            m = None
            if est is None:
                if gt[0, 0] <= min(tc, td) and max(tc, td) <= gt[-1, 0]:
                    m = np.linalg.inv(gt_pose(gt, tc)) @ gt_pose(gt, td)
            elif k >= 2:
                rel = np.linalg.inv(pose(est[k - 2])) @ pose(est[k - 1])
                dt = est[k - 1, 0] - est[k - 2, 0]
                f = (td - tc) / dt
                m = np.eye(4)
                m[:3, :3] = rot_exp(rot_log(rel[:3, :3]) * f)
                m[:3, 3] = rel[:3, 3] * f
            if m is not None:
                ok = d > 0
                z = d[ok]
                p = np.stack([(u[ok] - cx) / fx * z, (v[ok] - cy) / fy * z, z])
                q = m[:3, :3] @ p + m[:3, 3:4]
                uu = np.round(q[0] / q[2] * fx + cx).astype(int)
                vv = np.round(q[1] / q[2] * fy + cy).astype(int)
                keep = (uu >= 0) & (uu < w) & (vv >= 0) & (vv < h) & (q[2] > 0)
                out = np.full((h, w), np.inf)
                np.minimum.at(out, (vv[keep], uu[keep]), q[2][keep])
                out[np.isinf(out)] = 0
                d = out
            name = 'depth/%.6f.png' % tc
            cv2.imwrite(os.path.join(a.dst, name), np.round(d * s).astype(np.uint16))
            rf.write('%.6f %s\n' % (tc, rgb[i][1]))
            df.write('%.6f %s\n' % (tc, name))
    print('%d pairs written to %s' % (len(pairs), a.dst))


if __name__ == '__main__':
    main()
