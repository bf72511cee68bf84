#!/usr/bin/env python3
"""An independent check of attitude estimates on real flights: the magnetometer.

None of the compared estimators uses the compass, so how well one attitude turns a single
earth field into each logged MAG sample is evidence its estimators never saw. For each
ArduPilot DataFlash log (.BIN) and each estimate (`sim-harness replay` CSV), over the airborne
part (GPS speed > 8 m/s, every estimate aligned with GPS):

- basic model: MAG_body ≈ Rᵀ m + o (earth field m in NED, hard iron o), linear least squares,
  fitted to each attitude ("own") and, from ATT, applied to all ("ATT-fit");
- full model: MAG_body ≈ W Rᵀ m + o + k·throttle (soft iron W, throttle term k on RCIN C1),
  alternating least squares, with the attitude taken at the MAG time lag that fits ATT best;

and prints the RMS angle between measured and predicted field over all samples and over
high-rate ones (|gyro x| or |gyro y| > 100°/s, and 1 s after), each estimate's difference to
the first one with a 95 % 10-s block bootstrap interval, and the tilt difference to ATT.
ATT (the autopilot's EKF3, which fused this compass) is a reference row, not truth.

    python3 tools/magcheck/magcheck.py LOG.BIN LABEL=EST.csv [LABEL=EST.csv ...] \\
        [LOG2.BIN LABEL=EST.csv ...]

The first LABEL is the baseline; with several logs (same labels each) a pooled summary
follows. Needs numpy and pymavlink; reads the inputs only and prints to stdout.
"""

import csv
import os
import sys

import numpy as np

SPD_MIN = 8.0  # m/s GPS speed: airborne
HR = np.radians(100.0)  # high rate: |gyro x| or |gyro y| above this ...
HR_AFTER = 1.0  # ... and up to this long (s) after
LAGS = np.arange(-0.2, 0.2001, 0.01)  # s, time shifts scanned
FIELD_MG = 480.0  # |m| of the full model (W and m share a scale; fixed by this)
BLOCK = 10.0  # s, bootstrap block
N_BOOT = 2000
VARS = [("own", "basic own"), ("attfit", "ATT-fit"), ("full", "full+lag")]


def fail(msg):
    print(f"error: {msg}", file=sys.stderr)
    sys.exit(2)


# ---------------------------------------------------------------- inputs


def read_bin(path):
    """IMU (instance 0), MAG (instance 0), ATT, GPS (instance 0), RCIN and PARM of a .BIN."""
    try:
        from pymavlink import mavutil
    except ImportError:
        fail("pymavlink is not installed (pip install pymavlink)")
    try:
        m = mavutil.mavlink_connection(path)
    except Exception as e:  # noqa: BLE001 - pymavlink raises anything on a bad file
        fail(f"{path}: not a DataFlash log ({e})")
    d = {k: [] for k in ("IMU", "MAG", "ATT", "GPS", "RCIN")}
    parm = {}
    while True:
        try:
            msg = m.recv_match(type=["IMU", "MAG", "ATT", "GPS", "PARM", "RCIN"])
        except Exception as e:  # noqa: BLE001
            fail(f"{path}: unreadable DataFlash log ({e})")
        if msg is None:
            break
        t = msg.get_type()
        x = msg.to_dict()
        if t == "PARM":
            parm[x["Name"]] = x["Value"]
        elif t == "ATT":
            d[t].append([x["TimeUS"], x["Roll"], x["Pitch"], x["Yaw"]])
        elif t == "RCIN":
            d[t].append([x["TimeUS"], x["C1"]])
        elif x.get("I", 0) != 0:
            continue
        elif t == "IMU":
            d[t].append([x["TimeUS"], x["GyrX"], x["GyrY"], x["GyrZ"]])
        elif t == "MAG":
            d[t].append([x["TimeUS"], x["MagX"], x["MagY"], x["MagZ"]])
        elif t == "GPS":
            d[t].append([x["TimeUS"], x["Spd"]])
    if not parm and not any(d.values()):
        fail(f"{path}: no DataFlash messages (not an ArduPilot .BIN log)")
    for k, why in (
        ("MAG", "no magnetometer logged"),
        ("IMU", "the estimates are per IMU sample"),
        ("ATT", "the reference row"),
        ("GPS", "the airborne part is taken from its speed"),
        ("RCIN", "the throttle term of the full model reads RCIN C1"),
    ):
        if not d[k]:
            fail(f"{path} has no {k} messages ({why})")
    return {k: np.array(v, float) for k, v in d.items()}, parm


def read_estimate(path):
    """t, Euler angles [roll, pitch, yaw] (rad) and flags of a `sim-harness replay` CSV."""
    try:
        f = open(path, newline="")
    except OSError as e:
        fail(f"{path}: {e.strerror}")
    with f:
        r = csv.reader(f)
        head = next(r, [])
        need = ["t", "roll", "pitch", "yaw", "flags"]
        missing = [c for c in need if c not in head]
        if missing:
            fail(f"{path} lacks the column(s) {', '.join(missing)} (a `sim-harness replay` CSV has them)")
        cols = [head.index(c) for c in need]
        t, e, fl = [], [], []
        for n, row in enumerate(r, 2):
            try:
                t.append(float(row[cols[0]]))
                e.append([float(row[c]) for c in cols[1:4]])
                fl.append(row[cols[4]])
            except (ValueError, IndexError):
                fail(f"{path}:{n}: t, roll, pitch or yaw is not a number")
    return np.array(t), np.array(e), np.array(fl)


def parse_args(argv):
    """[(log, [(label, csv), ...]), ...] from LOG.BIN LABEL=EST.csv ... [LOG2.BIN ...]."""
    if not argv or argv[0] in ("-h", "--help"):
        print(__doc__)
        sys.exit(0 if argv else 2)
    runs = []
    for a in argv:
        if "=" in a:
            if not runs:
                fail(f"{a}: give the log (LOG.BIN) before its estimates")
            label, path = a.split("=", 1)
            if not label or not path:
                fail(f"{a}: expected LABEL=EST.csv")
            if label == "ATT" or label in [x[0] for x in runs[-1][1]]:
                fail(f"{a}: label {label} is taken")
            runs[-1][1].append((label, path))
        else:
            runs.append((a, []))
    labels = [x[0] for x in runs[0][1]]
    for log, ests in runs:
        if not ests:
            fail(f"{log}: no estimates (LABEL=EST.csv) given")
        if [x[0] for x in ests] != labels:
            fail(f"{log}: every log needs the same labels in the same order ({', '.join(labels)})")
        for p in [log] + [x[1] for x in ests]:
            if not os.path.isfile(p):
                fail(f"{p} not found")
    return runs


# ---------------------------------------------------------------- geometry


def quat(e):
    """3-2-1 Euler angles [roll, pitch, yaw] (rad) → quaternions body → NED."""
    r, p, y = e[:, 0] / 2, e[:, 1] / 2, e[:, 2] / 2
    cr, sr, cp, sp, cy, sy = np.cos(r), np.sin(r), np.cos(p), np.sin(p), np.cos(y), np.sin(y)
    return np.stack(
        [
            cr * cp * cy + sr * sp * sy,
            sr * cp * cy - cr * sp * sy,
            cr * sp * cy + sr * cp * sy,
            cr * cp * sy - sr * sp * cy,
        ],
        1,
    )


def dcm(q):
    """Quaternions → rotation matrices body → NED, shape (n, 3, 3)."""
    w, x, y, z = q.T
    return np.stack(
        [
            np.stack([1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)], -1),
            np.stack([2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)], -1),
            np.stack([2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)], -1),
        ],
        1,
    )


def interp_q(ts, q, t):
    """nlerp (sign-fixed) of a quaternion series to times t; NaN outside or across gaps > 0.5 s."""
    i = np.clip(np.searchsorted(ts, t) - 1, 0, len(ts) - 2)
    a = (t - ts[i]) / (ts[i + 1] - ts[i])
    q0, q1 = q[i], q[i + 1].copy()
    q1[np.sum(q0 * q1, 1) < 0] *= -1
    out = q0 * (1 - a)[:, None] + q1 * a[:, None]
    out /= np.linalg.norm(out, axis=1)[:, None]
    out[(t < ts[0]) | (t > ts[-1]) | (ts[i + 1] - ts[i] > 0.5)] = np.nan
    return out


def tilt(Ra, Rb):
    """Angle between the body-frame gravity directions (deg)."""
    return np.degrees(np.arccos(np.clip(np.sum(Ra[:, 2, :] * Rb[:, 2, :], 1), -1, 1)))


def rms(x):
    return np.sqrt(np.mean(x**2)) if len(x) else np.nan


# ---------------------------------------------------------------- field models


def fit(R, mb):
    """Basic model mb ≈ Rᵀ m + o → (m, o)."""
    n = len(R)
    A = np.zeros((3 * n, 6))
    A[:, :3] = np.transpose(R, (0, 2, 1)).reshape(3 * n, 3)
    A[:, 3:] = np.tile(np.eye(3), (n, 1))
    x, *_ = np.linalg.lstsq(A, mb.reshape(-1), rcond=None)
    return x[:3], x[3:]


def resid(R, mb, m, o):
    """Angle (deg) and magnitude (mG) of the basic model's residual."""
    pred = np.einsum("nji,j->ni", R, m)
    meas = mb - o
    c = np.sum(pred * meas, 1) / np.linalg.norm(pred, axis=1) / np.linalg.norm(meas, axis=1)
    return np.degrees(np.arccos(np.clip(c, -1, 1))), np.linalg.norm(meas - pred, axis=1)


def fit_full(R, mb, thr, iters=30):
    """Full model mb ≈ W Rᵀ m + o + k·thr (soft iron W, hard iron o, throttle k); alternating LS."""
    m, o = fit(R, mb)
    n = len(R)
    for _ in range(iters):
        v = np.einsum("nji,j->ni", R, m)
        X = np.hstack([v, np.ones((n, 1)), thr[:, None]])
        B, *_ = np.linalg.lstsq(X, mb, rcond=None)
        W, o, k = B[:3].T, B[3], B[4]
        A = np.einsum("ab,nbc->nac", W, np.transpose(R, (0, 2, 1))).reshape(3 * n, 3)
        m, *_ = np.linalg.lstsq(A, (mb - o - thr[:, None] * k).reshape(-1), rcond=None)
        s = np.linalg.norm(m) / FIELD_MG
        m /= s
        W *= s
    return W, m, o, k


def resid_full(R, mb, thr, par):
    """Angle (deg) and magnitude (mG) of the full model's residual."""
    W, m, o, k = par
    pred = np.einsum("ab,nb->na", W, np.einsum("nji,j->ni", R, m))
    meas = mb - o - thr[:, None] * k
    c = np.sum(pred * meas, 1) / np.linalg.norm(pred, axis=1) / np.linalg.norm(meas, axis=1)
    return np.degrees(np.arccos(np.clip(c, -1, 1))), np.linalg.norm(meas - pred, axis=1)


def boot_diff(a2, b2, t, rng):
    """RMS(b) − RMS(a) (deg) from squared residuals, with a 95 % block bootstrap interval."""
    blk = np.floor((t - t[0]) / BLOCK).astype(int)
    idx = [np.where(blk == u)[0] for u in np.unique(blk)]
    d0 = np.sqrt(b2.mean()) - np.sqrt(a2.mean())
    ds = []
    for _ in range(N_BOOT):
        s = np.concatenate([idx[k] for k in rng.integers(0, len(idx), len(idx))])
        ds.append(np.sqrt(b2[s].mean()) - np.sqrt(a2[s].mean()))
    lo, hi = np.percentile(ds, [2.5, 97.5])
    return d0, lo, hi


def lagscan(f):
    r = [f(L) for L in LAGS]
    return LAGS[int(np.argmin(r))], r


# ---------------------------------------------------------------- one log


def check_log(log, ests, rng, pool):
    d, P = read_bin(log)
    if P.get("AHRS_ORIENTATION", 0) != 0:
        fail(f"{log}: AHRS_ORIENTATION {P['AHRS_ORIENTATION']:g} is not supported (IMU and MAG assumed in the board frame)")
    # ATT (EKF3) Euler angles are the IMU's minus AHRS_TRIM, angle by angle: added back, as
    # the importer does. AHRS_ORIENTATION 0: IMU and MAG (COMPASS_ORIENT and offsets applied
    # by the autopilot) are both in the board frame.
    trim = np.array([P.get("AHRS_TRIM_X", 0), P.get("AHRS_TRIM_Y", 0), P.get("AHRS_TRIM_Z", 0)])
    imu, mag, att, gps, rcin = d["IMU"], d["MAG"], d["ATT"], d["GPS"], d["RCIN"]
    t0 = imu[0, 0]  # the importer's time base: t = (TimeUS − first IMU TimeUS) / 1e6

    def sec(us):
        return (us - t0) / 1e6

    ti, tm, ta, tg = sec(imu[:, 0]), sec(mag[:, 0]), sec(att[:, 0]), sec(gps[:, 0])
    mb = mag[:, 1:4]
    q_att = quat(np.radians(att[:, 1:4]) + trim)
    labels = [lab for lab, _ in ests]
    keys = ["ATT"] + labels
    base = labels[0]
    est = {}
    for lab, path in ests:
        t, e, fl = read_estimate(path)
        if len(t) != len(imu) or np.max(np.abs(t - ti)) >= 1e-5:
            fail(f"{path}: {len(t)} rows, {log} has {len(imu)} IMU samples at other times — not a replay of this log")
        est[lab] = (t, quat(e), fl)

    # The baseline against ATT at the IMU samples, and the time shift that fits best.
    air_i = np.interp(ti, tg, gps[:, 1]) > SPD_MIN
    R_base_i = dcm(est[base][1])[air_i]

    def tilt_lag(L):
        Rl = dcm(interp_q(ta, q_att, ti[air_i] + L))
        ok = ~np.isnan(Rl[:, 0, 0])
        return rms(tilt(R_base_i[ok], Rl[ok]))

    att_lag, _ = lagscan(tilt_lag)

    # MAG samples used: airborne, every estimate aligned with GPS, all attitudes defined.
    use = np.interp(tm, tg, gps[:, 1]) > SPD_MIN
    for t, q, fl in est.values():
        j = np.clip(np.searchsorted(t, tm), 0, len(t) - 1)
        use &= ~np.array([("not_aligned" in f) or ("no_gps" in f) for f in fl])[j]
    hr_t = ti[(np.abs(imu[:, 1]) > HR) | (np.abs(imu[:, 2]) > HR)]
    k_ = np.searchsorted(hr_t, tm, side="right") - 1
    hr = (k_ >= 0) & (tm - hr_t[np.clip(k_, 0, None)] <= HR_AFTER)

    def series(k):
        return (ta, q_att) if k == "ATT" else est[k][:2]

    def attitudes(L):
        return {k: dcm(interp_q(*series(k), tm + L)) for k in keys}

    Rs0 = attitudes(0.0)
    for R in Rs0.values():
        use &= ~np.isnan(R[:, 0, 0])
    if use.sum() < 2:
        fail(f"{log}: no airborne MAG samples with every estimate aligned")
    use &= (tm > tm[use][0] + 0.25) & (tm < tm[use][-1] - 0.25)  # room for the lag scan
    hru, mbu, tt = hr[use], mb[use], tm[use]
    thr = (np.interp(tt, sec(rcin[:, 0]), rcin[:, 1]) - 1000.0) / 1000.0

    # MAG time lag (basic model, ATT attitude): the attitude at t + lag fits best.
    def basic_rms(k, L):
        R = dcm(interp_q(*series(k), tt + L))
        return rms(resid(R, mbu, *fit(R, mbu))[0])

    mag_lag, r_mag = lagscan(lambda L: basic_rms("ATT", L))
    RsL = attitudes(mag_lag)

    print(
        f"\n=== {log}: AHRS_TRIM {np.degrees(trim).round(2)} deg (added back to ATT); "
        f"{base} vs ATT tilt RMS {rms(tilt(R_base_i, dcm(interp_q(ta, q_att, ti[air_i])))):.2f} deg, "
        f"best time shift {att_lag:+.2f} s"
    )
    print(
        f"  MAG: {use.sum()} samples airborne+aligned, {hru.sum()} high-rate; "
        f"mean |B| {np.linalg.norm(mbu, axis=1).mean():.0f} mG; MAG vs ATT best shift {mag_lag:+.2f} s "
        f"(basic RMS {min(r_mag):.2f} vs {r_mag[len(LAGS) // 2]:.2f} deg at 0)"
    )
    R_att = Rs0["ATT"][use]
    m_c, o_c = fit(R_att, mbu)
    th_corr = np.corrcoef(resid(R_att, mbu, m_c, o_c)[0], thr)[0, 1]
    w = max(4, max(len(k) for k in keys))
    print(
        f"  {'':{w}s} {'basic own':>9s} {'mG':>5s} {'HR':>6s} | {'ATT-fit':>7s} {'HR':>6s} | "
        f"{'full+lag':>8s} {'mG':>5s} {'HR':>6s} | {'tilt-ATT':>8s} {'HR':>5s} | best lag (s)"
    )
    res = {v: {} for v, _ in VARS}
    for k in keys:
        R, RL = Rs0[k][use], RsL[k][use]
        a1, g1 = resid(R, mbu, *fit(R, mbu))
        a2, _ = resid(R, mbu, m_c, o_c)
        a3, g3 = resid_full(RL, mbu, thr, fit_full(RL, mbu, thr))
        tl = tilt(R, R_att)
        lk, _ = lagscan(lambda L: basic_rms(k, L))
        for (v, _), a in zip(VARS, (a1, a2, a3)):
            res[v][k] = a
            pool[v][k]["all"].append(a)
            pool[v][k]["hr"].append(a[hru])
        pool["tilt"][k]["all"].append(tl)
        pool["tilt"][k]["hr"].append(tl[hru])
        print(
            f"  {k:{w}s} {rms(a1):9.2f} {rms(g1):5.1f} {rms(a1[hru]):6.2f} | {rms(a2):7.2f} {rms(a2[hru]):6.2f} | "
            f"{rms(a3):8.2f} {rms(g3):5.1f} {rms(a3[hru]):6.2f} | {rms(tl):8.2f} {rms(tl[hru]):5.2f} | {lk:+.2f}"
        )
    for k in labels[1:]:
        for lab, sel in (("all", np.ones_like(hru)), ("HR", hru)):
            out = []
            for v, _ in VARS:
                dd, lo, hi = boot_diff(res[v][base][sel] ** 2, res[v][k][sel] ** 2, tt[sel], rng)
                out.append(f"{v} {dd:+.3f} [{lo:+.3f},{hi:+.3f}]")
            print(f"  {k}-{base} RMS diff {lab:3s} deg (95% 10-s block bootstrap): " + "; ".join(out))
    print(f"  corr(basic ATT residual angle, throttle RCIN C1) = {th_corr:+.2f}")


def main():
    runs = parse_args(sys.argv[1:])
    keys = ["ATT"] + [lab for lab, _ in runs[0][1]]
    pool = {v: {k: {"all": [], "hr": []} for k in keys} for v in [v for v, _ in VARS] + ["tilt"]}
    rng = np.random.default_rng(0)  # one stream for the whole run, drawn in order
    for log, ests in runs:
        check_log(log, ests, rng, pool)
    if len(runs) > 1:
        print(f"\n=== pooled over {len(runs)} logs, RMS residual angle (deg): all / high-rate")
        for v in [v for v, _ in VARS] + ["tilt"]:
            name = "tilt-ATT" if v == "tilt" else v
            cells = [
                f"{k} {rms(np.concatenate(pool[v][k]['all'])):.3f}/{rms(np.concatenate(pool[v][k]['hr'])):.3f}"
                for k in keys
            ]
            print(f"  {name:8s}: " + "  ".join(cells))


if __name__ == "__main__":
    main()
