#!/usr/bin/env python3
"""How correlated two cameras' pixel errors of one feature are (docs/stereo.md, "Monte-Carlo NEES in stereo").

From a stereo run's residual logs (`ovton run --residual-log res.csv` on a rendered folder: res.csv, res_cam1.csv):
each accepted (update, feature) window is refitted with the ground-truth poses (t_imu = t_cam + t_d,true) to both
cameras' undistorted observations, so the errors left are the tracker's; prints their RMS, the cross-camera
correlation at the same image and at lags, and each camera's lag-one correlation. The point fit itself correlates the
errors (negatively across cameras: a common shift is a moved point), so CONTROL_RHO [RHO_CAM] replaces the
observations by the fitted point's projections plus synthetic AR(1) errors (rho over images, rho_cam between the
cameras, 0.3 px) and reports the same statistics: the RHO_CAM that reproduces the measured numbers is the model's.
Without a control it also regresses the errors on the true image velocity per camera (a camera-specific time shift
would show as a slope) and compares the rows' tracked velocities with the true ones.
Usage: stereo_error_correlation.py DATASET res.csv res_cam1.csv [CONTROL_RHO [RHO_CAM]]   (numpy)
"""
import sys, numpy as np, csv, re
ds, res0, res1 = sys.argv[1], sys.argv[2], sys.argv[3]
CTRL = float(sys.argv[4]) if len(sys.argv) > 4 else None
RX = float(sys.argv[5]) if len(sys.argv) > 5 else 0.0
rng = np.random.default_rng(7)
def refine_point(X, obs, Rs, ps, iterations=8):
    """Gauss-Newton on the landmark's position X against its normalised observations; returns X and the residuals."""
    for _ in range(iterations):
        J, e = [], []
        for (cam, t, x, y), R, p in zip(obs, Rs, ps):
            c = R.T @ (X - p); e += [x - c[0]/c[2], y - c[1]/c[2]]
            J += [R.T[0]/c[2] - c[0]/c[2]**2 * R.T[2], R.T[1]/c[2] - c[1]/c[2]**2 * R.T[2]]
        J, e = np.array(J), np.array(e); X = X + np.linalg.lstsq(J, e, rcond=None)[0]
    return X, e


def T_BS(path):
    txt = open(path).read(); m = re.search(r'T_BS:.*?data:\s*\[([^\]]*)\]', txt, re.S)
    T = np.array([float(x) for x in m.group(1).replace('\n', ' ').split(',')]).reshape(4, 4)
    fx = float(re.search(r'intrinsics:\s*\[([^,]*)', txt).group(1)); return T[:3, :3], T[:3, 3], fx
R0, p0, fx = T_BS(ds + '/mav0/cam0/sensor.yaml'); R1, p1, _ = T_BS(ds + '/mav0/cam1/sensor.yaml')
gt = np.loadtxt(ds + '/mav0/state_groundtruth_estimate0/data.csv', delimiter=',', comments='#')
td = np.loadtxt(ds + '/mav0/td_truth/data.csv', delimiter=',', comments='#')
def quat2R(q):
    w, x, y, z = q / np.linalg.norm(q)
    return np.array([[1-2*(y*y+z*z), 2*(x*y-w*z), 2*(x*z+w*y)], [2*(x*y+w*z), 1-2*(x*x+z*z), 2*(y*z-w*x)],
                     [2*(x*z-w*y), 2*(y*z+w*x), 1-2*(x*x+y*y)]])
def pose(tc):
    tdv = np.interp(tc, td[:, 0], td[:, 1]); ti = tc + tdv * 1e9
    i = np.searchsorted(gt[:, 0], ti); a = (ti - gt[i-1, 0]) / (gt[i, 0] - gt[i-1, 0])
    p = (1-a) * gt[i-1, 1:4] + a * gt[i, 1:4]; q0, q1 = gt[i-1, 4:8], gt[i, 4:8]
    if q0 @ q1 < 0: q1 = -q1
    return quat2R((1-a) * q0 + a * q1), p
VEL = {}
def load(f, cam):
    rows = {}
    for r in csv.DictReader(open(f)):
        if r['status'] != '0': continue  # accepted only
        k = (int(r['update_id']), int(r['feature_id']))
        rows.setdefault(k, []).append((cam, int(r['t_cam_ns']), float(r['x_norm']), float(r['y_norm'])))
        VEL[(cam, k[1], int(r['t_cam_ns']))] = (float(r['vel_u_px_s']), float(r['vel_v_px_s']), int(r['td_column']))
    return rows
A, B = load(res0, 0), load(res1, 1)
pc = {}
pairs, lag0, lag1, cross = [], [], [], {}
allvar = {0: [], 1: []}
VS = {0: [], 1: []}
for k in A:
    if k not in B: continue
    obs = A[k] + B[k]
    Rs, ps = [], []
    for cam, t, x, y in obs:
        if t not in pc: pc[t] = pose(t)
        Rw, pw = pc[t]; Rc, pcb = (R0, p0) if cam == 0 else (R1, p1)
        Rs.append(Rw @ Rc); ps.append(pw + Rw @ pcb)
    # linear triangulation then Gauss-Newton
    M = np.zeros((3, 3)); v = np.zeros(3)
    for (cam, t, x, y), R, p in zip(obs, Rs, ps):
        b = R @ np.array([x, y, 1.0]); b /= np.linalg.norm(b); P = np.eye(3) - np.outer(b, b); M += P; v += P @ p
    X = np.linalg.solve(M, v)
    X, e = refine_point(X, obs, Rs, ps)
    if CTRL is not None:  # control: exact projections of the fitted point + independent AR(1) per camera
        tsu = sorted(set(o[1] for o in obs)); ix = {t: i for i, t in enumerate(tsu)}
        noise = {}
        for cam in (0, 1):
            n = np.zeros((len(tsu), 2)); n[0] = rng.standard_normal(2)
            for i in range(1, len(tsu)): n[i] = CTRL * n[i-1] + np.sqrt(1 - CTRL**2) * rng.standard_normal(2)
            noise[cam] = n * 0.3 / fx
        noise[1] = RX * noise[0] + np.sqrt(1 - RX**2) * noise[1]
        new = []
        for (cam, t, x, y), R, p in zip(obs, Rs, ps):
            c = R.T @ (X - p); z = c[:2] / c[2] + noise[cam][ix[t]]; new.append((cam, t, z[0], z[1]))
        obs = new
        X, e = refine_point(X, obs, Rs, ps)
    e = e.reshape(-1, 2) * fx
    if np.abs(e).max() > 5: continue
    E = {(cam, t): ei for (cam, t, x, y), ei in zip(obs, e)}
    if CTRL is None:
      for (cam, t, x, y), R, p, ei in zip(obs, Rs, ps, e):
        # true image velocity (normalised -> px/s via fx) by central difference of the ground-truth pose
        def proj(tt):
            Rw, pw = pose(tt); Rc, pcb = (R0, p0) if cam == 0 else (R1, p1); Rr = Rw @ Rc; pp = pw + Rw @ pcb
            c = Rr.T @ (X - pp); return c[:2] / c[2]
        vt = (proj(t + 2.5e6) - proj(t - 2.5e6)) / 5e-3 * fx
        vu, vv, tdc = VEL[(cam, k[1], t)]
        if tdc: VS[cam].append((vt, np.array([vu, vv]), ei))
    ts = sorted(set(t for _, t, _, _ in obs)); idx = {t: i for i, t in enumerate(ts)}
    for (cam, t), ei in E.items(): allvar[cam].append(ei)
    for (cam, t), ei in E.items():
        if cam == 0 and (1, t) in E: pairs.append((ei, E[(1, t)]))
        for lag in (1, 2, 3, 5):
            j = idx[t] + lag
            if j < len(ts):
                t2 = ts[j]
                if cam == 0 and (0, t2) in E and lag == 1: lag0.append((ei, E[(0, t2)]))
                if cam == 1 and (1, t2) in E and lag == 1: lag1.append((ei, E[(1, t2)]))
                if (1 - cam, t2) in E: cross.setdefault(lag, []).append((ei, E[(1 - cam, t2)]))
def corr(P):
    P = np.array(P); return [np.corrcoef(P[:, 0, a], P[:, 1, a])[0, 1] for a in (0, 1)], len(P)
print('features in both cameras (accepted windows):', sum(1 for k in A if k in B))
for c in (0, 1):
    a = np.array(allvar[c]); print(f'cam{c} error rms u,v [px]: {np.sqrt((a**2).mean(0))}  n={len(a)}')
print('cross-camera same instant corr (u, v), n:', corr(pairs))
print('cam0 lag-1 corr:', corr(lag0)); print('cam1 lag-1 corr:', corr(lag1))
for lag in sorted(cross): print(f'cross-camera lag {lag} corr:', corr(cross[lag]))

for cam in (0, 1):
    if not VS[cam]: continue
    vt = np.array([a for a, b, c in VS[cam]]); vm = np.array([b for a, b, c in VS[cam]]); ee = np.array([c for a, b, c in VS[cam]])
    k = (vt.ravel() @ ee.ravel()) / (vt.ravel() @ vt.ravel())
    rel = np.linalg.norm(vm - vt, axis=1).mean() / np.linalg.norm(vt, axis=1).mean()
    g = (vt.ravel() @ vm.ravel()) / (vt.ravel() @ vt.ravel())
    print(f'cam{cam}: rows with t_d column {len(vt)}: error-vs-true-velocity slope {1e3*k:.3f} ms; tracked velocity: gain vs truth {g:.3f}, mean |V-Vtrue|/mean|Vtrue| {rel:.3f}')
