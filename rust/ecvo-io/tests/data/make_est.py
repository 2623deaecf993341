"""Make a perturbed, drifting estimate of a TUM ground truth at the rgb frame times."""
import sys
import numpy as np

def read_tum(path):
    rows = [l.split() for l in open(path) if l.strip() and not l.startswith('#')]
    return np.array([[float(x) for x in r] for r in rows])

def quat_to_mat(q):  # x y z w
    x, y, z, w = q / np.linalg.norm(q)
    return np.array([[1-2*(y*y+z*z), 2*(x*y-z*w), 2*(x*z+y*w)],
                     [2*(x*y+z*w), 1-2*(x*x+z*z), 2*(y*z-x*w)],
                     [2*(x*z-y*w), 2*(y*z+x*w), 1-2*(x*x+y*y)]])

def mat_to_quat(R):
    w = np.sqrt(max(0.0, 1 + R[0,0] + R[1,1] + R[2,2])) / 2
    x = np.sqrt(max(0.0, 1 + R[0,0] - R[1,1] - R[2,2])) / 2
    y = np.sqrt(max(0.0, 1 - R[0,0] + R[1,1] - R[2,2])) / 2
    z = np.sqrt(max(0.0, 1 - R[0,0] - R[1,1] + R[2,2])) / 2
    x = np.copysign(x, R[2,1] - R[1,2]); y = np.copysign(y, R[0,2] - R[2,0]); z = np.copysign(z, R[1,0] - R[0,1])
    return np.array([x, y, z, w])

def axis_angle(axis, ang):
    a = np.asarray(axis, float); a /= np.linalg.norm(a)
    K = np.array([[0, -a[2], a[1]], [a[2], 0, -a[0]], [-a[1], a[0], 0]])
    return np.eye(3) + np.sin(ang) * K + (1 - np.cos(ang)) * K @ K

gt_path, rgb_list, out_gt, out_est, t_max, gt_step, est_step, seed = sys.argv[1:9]
t_max, gt_step, est_step = float(t_max), int(gt_step), int(est_step)
rng = np.random.default_rng(int(seed))
gt = read_tum(gt_path)
t0 = gt[0, 0]
gt = gt[gt[:, 0] <= t0 + t_max]
gt_sub = gt[::gt_step]
with open(out_gt, 'w') as f:
    f.write('# timestamp tx ty tz qx qy qz qw\n')
    for r in gt_sub:
        f.write('%.4f %.4f %.4f %.4f %.4f %.4f %.4f %.4f\n' % tuple(r))

stamps = np.array([float(l.split()[0]) for l in open(rgb_list) if l.strip() and not l.startswith('#')])
stamps = stamps[(stamps >= gt[0, 0]) & (stamps <= gt[-1, 0])][::est_step]
R_w = axis_angle([1, 2, 3], np.radians(40)); t_w = np.array([0.5, -1.2, 0.3])
drift_t = np.zeros(3); drift_R = np.eye(3)
with open(out_est, 'w') as f:
    f.write('# perturbed, drifting estimate\n')
    for t in stamps:
        k = np.searchsorted(gt[:, 0], t)
        k = min(max(k, 1), len(gt) - 1)
        a, b = gt[k - 1], gt[k]
        s = (t - a[0]) / (b[0] - a[0])
        p = (1 - s) * a[1:4] + s * b[1:4]
        qa, qb = a[4:8], b[4:8]
        if np.dot(qa, qb) < 0: qb = -qb
        q = (1 - s) * qa + s * qb
        R = quat_to_mat(q)
        drift_t = drift_t + np.array([0.0004, -0.0002, 0.0001]) + rng.normal(0, 0.0008, 3)
        drift_R = drift_R @ axis_angle(rng.normal(size=3), np.radians(rng.normal(0, 0.05)))
        Rd = R @ drift_R
        pd = p + drift_t + rng.normal(0, 0.003, 3)
        Re = R_w @ Rd; pe = R_w @ pd + t_w
        q = mat_to_quat(Re)
        f.write('%.6f %.9f %.9f %.9f %.9f %.9f %.9f %.9f\n' % ((t,) + tuple(pe) + tuple(q)))
