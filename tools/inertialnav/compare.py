#!/usr/bin/env python3
"""A second reference for the real flights a and b: InertialNav's own EKF.

Flights a and b (shared data `real/px4_2014_flight_{a,b}.csv`) are PX4 sdlog2 logs that
InertialNav's `scripts/LoadPX4StackData.m` exported as text (`real/raw/InputFilesPX4_*.zip`).
Their `ref_*` is the PX4 onboard attitude of 2014 (sdlog2 `ATT`), not truth. This builds
InertialNav's C++ test harness (Paul Riseborough's 22-state EKF: GPS, magnetometer, airspeed;
BSD-3-Clause), runs it on the same exports, replays ours (`sim-harness replay`) and prints
the pairwise RMS agreement of the three over the airborne window of docs/real-logs.md.
If two independent estimators agree with each other and both differ from `ATT` the same
way, that difference is the reference's.

    python3 tools/inertialnav/compare.py --inertialnav PATH [--data ../shared/data]

PATH is a checkout of https://github.com/priseborough/InertialNav (measured at 037c5c3).
The build needs g++ and numpy; nothing is written outside a temporary directory.
"""

import argparse
import csv
import os
import shutil
import subprocess
import sys
import tempfile
import zipfile

import numpy as np

# name, export, airborne window of docs/real-logs.md (s)
FLIGHTS = [
    ("flight_a", "InputFilesPX4_search.zip", "px4_2014_flight_a.csv", 40.0, 139.0),
    ("flight_b", "InputFilesPX4_flow.zip", "px4_2014_flight_b.csv", 34.0, 150.0),
]
SOURCES = ["estimator_22states.cpp", "estimator_utilities.cpp", "main_closed_loop_float.cpp"]


def fail(msg):
    print(f"error: {msg}", file=sys.stderr)
    sys.exit(2)


def build(src, work):
    """InertialNav's harness, with its `FILE* > 0` tests made valid C++ for today's g++."""
    code = os.path.join(src, "code")
    for f in os.listdir(code):
        if f.endswith((".cpp", ".h")):
            shutil.copy(os.path.join(code, f), work)
    main = os.path.join(work, "main_closed_loop_float.cpp")
    text = open(main).read()
    for name in ("pOnboardFile", "pInFlowFile", "pInDistFile"):
        text = text.replace(f"({name} > 0)", f"({name} != nullptr)")
        text = text.replace(f"({name} <= 0)", f"({name} == nullptr)")
    open(main, "w").write(text)
    exe = os.path.join(work, "inertialnav")
    cmd = ["g++", "-O2", "-std=c++11", "-I.", '-D__EXPORT=', "-o", exe] + SOURCES + ["-lm"]
    r = subprocess.run(cmd, cwd=work, capture_output=True, text=True)
    if r.returncode != 0:
        fail("InertialNav did not build:\n" + r.stderr[-2000:])
    return exe


def run_inertialnav(exe, export, work):
    d = tempfile.mkdtemp(dir=work)
    with zipfile.ZipFile(export) as z:
        z.extractall(d)
    r = subprocess.run([exe], cwd=d, capture_output=True, text=True)
    if r.returncode != 0 or not os.path.exists(os.path.join(d, "EulDataOut.txt")):
        fail(f"InertialNav failed on {export}: {r.stdout[-500:]}{r.stderr[-500:]}")
    # EulDataOut.txt: t [s], then (estimate, onboard ATT) for roll, pitch, yaw [rad].
    e = np.loadtxt(os.path.join(d, "EulDataOut.txt"))
    return e[:, 0], e[:, [1, 3, 5]], e[:, [2, 4, 6]]


def run_ours(binary, log, work, latency):
    out = os.path.join(work, os.path.basename(log) + f".{latency}.est.csv")
    cmd = [binary, "replay", log, "--out", out, "--gps-latency", latency]
    r = subprocess.run(cmd, capture_output=True, text=True)
    if r.returncode != 0:
        fail(f"sim-harness replay failed: {r.stderr[-1000:]}")
    rows = list(csv.DictReader(open(out)))
    t = np.array([float(r["t"]) for r in rows])
    a = np.array([[float(r[k]) if r[k] else np.nan for k in ("roll", "pitch", "yaw")] for r in rows])
    return t, a


def dcm(e):
    """Body → NED rotations of 3-2-1 Euler angles [roll, pitch, yaw] (rad), shape (n, 3, 3)."""
    cr, sr = np.cos(e[:, 0]), np.sin(e[:, 0])
    cp, sp = np.cos(e[:, 1]), np.sin(e[:, 1])
    cy, sy = np.cos(e[:, 2]), np.sin(e[:, 2])
    m = np.empty((len(e), 3, 3))
    m[:, 0] = np.stack([cp * cy, sr * sp * cy - cr * sy, cr * sp * cy + sr * sy], 1)
    m[:, 1] = np.stack([cp * sy, sr * sp * sy + cr * cy, cr * sp * sy - sr * cy], 1)
    m[:, 2] = np.stack([-sp, sr * cp, cr * cp], 1)
    return m


def agreement(a, b):
    """RMS and mean of the Euler differences (deg), and RMS tilt / total angle (deg)."""
    d = np.degrees((a - b + np.pi) % (2 * np.pi) - np.pi)
    ma, mb = dcm(a), dcm(b)
    cos_tot = (np.einsum("nij,nij->n", ma, mb) - 1.0) / 2.0
    total = np.degrees(np.arccos(np.clip(cos_tot, -1, 1)))
    tilt = np.degrees(np.arccos(np.clip(np.einsum("nj,nj->n", ma[:, 2], mb[:, 2]), -1, 1)))
    rms = lambda x: float(np.sqrt(np.mean(x**2)))
    return [rms(d[:, i]) for i in range(3)], list(d.mean(0)), rms(tilt), rms(total)


def main():
    p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    p.add_argument("--inertialnav", required=True, help="a checkout of priseborough/InertialNav")
    p.add_argument("--data", default=os.environ.get("WING_AHRS_DATA", "../shared/data"))
    p.add_argument("--bin", default=os.environ.get("BIN", "target/release/sim-harness"))
    a = p.parse_args()
    if not os.path.exists(os.path.join(a.inertialnav, "code", "estimator_22states.cpp")):
        fail(f"{a.inertialnav} is not an InertialNav checkout (no code/estimator_22states.cpp)")
    if not os.path.exists(a.bin):
        fail(f"{a.bin} not found: cargo build --release -p sim-harness")
    work = tempfile.mkdtemp(prefix="inertialnav-")
    try:
        exe = build(a.inertialnav, work)
        print("| flight | pair | roll / pitch / yaw RMS | mean roll / pitch / yaw | tilt / total RMS |")
        print("|---|---|---|---|---|")
        for name, export, log, t0, t1 in FLIGHTS:
            export = os.path.join(a.data, "real", "raw", export)
            log = os.path.join(a.data, "real", log)
            if not (os.path.exists(export) and os.path.exists(log)):
                fail(f"{export} or {log} missing (shared data)")
            te, inav, att = run_inertialnav(exe, export, work)
            t, ours = run_ours(a.bin, log, work, "auto")
            w = (te >= t0) & (te <= t1)
            te, inav, att = te[w], inav[w], att[w]
            ours = ours[np.clip(np.searchsorted(t, te), 0, len(t) - 1)]
            for pair, x, y in (
                ("ours − ATT", ours, att),
                ("InertialNav − ATT", inav, att),
                ("ours − InertialNav", ours, inav),
            ):
                rms, mean, tilt, total = agreement(x, y)
                print(
                    f"| {name} | {pair} | {rms[0]:.1f}° / {rms[1]:.1f}° / {rms[2]:.1f}° "
                    f"| {mean[0]:+.1f}° / {mean[1]:+.1f}° / {mean[2]:+.1f}° | {tilt:.2f}° / {total:.2f}° |"
                )
    finally:
        shutil.rmtree(work, ignore_errors=True)


if __name__ == "__main__":
    main()
