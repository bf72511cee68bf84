#!/usr/bin/env python3
"""run.py LABEL SET...: fly the tuning table's rows through `sim-harness report --models quat
--from 20` and save their RMS figures in $TUNE_DIR/LABEL.json (default target/tune).
Sets: wind random holdout aero turb realistic real (159 rows in all), and jsbsim (18 JSBSim
flights, rand1-16 and the T-6 aerobatics: a validation set, flown into $TUNE_DIR/jsbsim
when missing; no default was tuned on it). Environment: BIN (the sim-harness binary), EXTRA
(more report options, e.g. --white-fix-noise), J (parallel jobs)."""
import sys, os, json, subprocess, concurrent.futures as cf, tempfile
HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(os.path.dirname(HERE))
BIN = os.environ.get("BIN", os.path.join(ROOT, "target/release/sim-harness"))
TUNE_DIR = os.environ.get("TUNE_DIR", os.path.join(ROOT, "target/tune"))
os.makedirs(TUNE_DIR, exist_ok=True)
EXTRA = os.environ.get("EXTRA", "").split()
R = os.path.join(os.environ.get("WING_AHRS_DATA", os.path.join(ROOT, "../shared/data")), "real/")
def sets(name):
    if name == "wind":
        return [(i, 1, None) for i in ["wind", "flight1", "flight2", "aggressive", "level"]]
    if name == "random":
        return [(f"random:{s}", 1, None) for s in range(1, 41)]
    if name == "holdout":
        return [(f"random:{s}", 1, None) for s in range(41, 81)]
    if name == "aero":
        return [(a, s, None) for a in ["aerobatics", "aerobatics_realistic", "aerobatics_wind5"] for s in range(2, 9)]
    if name == "turb":
        return [(f"{b}+wind=6@0,turb=moderate", s, None) for b in ["flight1", "flight2", "coordinated_turn"] for s in (2, 3)]
    if name == "realistic":
        its = ["flight1", "flight2", "aggressive", "level", "coordinated_turn",
               "flight1+wind=6@90", "flight2+wind=6@270,turb=light", "aggressive+wind=3@45",
               "coordinated_turn+wind=10@135", "flight2+wind=10@315,turb=moderate",
               "flight1+wind=3@225,turb=light", "coordinated_turn+wind=6@180,shear=0.05,gust=3",
               "aggressive+wind=6@0,turb=moderate", "level+wind=6@90"]
        return [(i, 1, "realistic") for i in its]
    if name == "jsbsim":
        d = os.path.join(TUNE_DIR, "jsbsim")
        names = [f"rand{n}" for n in range(1, 17)] + ["t6_aerobatics", "t6_aerobatics_wind6"]
        missing = [n for n in names if not os.path.exists(os.path.join(d, n + ".csv"))]
        if missing:
            env = dict(os.environ, WING_AHRS_JSBSIM_DIR=d)
            subprocess.run([BIN, "jsbsim"] + missing, env=env, check=True, capture_output=True)
        return [(os.path.join(d, n + ".csv"), 1, None) for n in names]
    if name == "real":
        return [(R + "px4_2014_flight_a.csv", 1, None), (R + "px4_2014_flight_b.csv", 1, None)]
    raise SystemExit("unknown set " + name)

def parse(out):
    rows = []
    for line in out.splitlines():
        c = [x.strip() for x in line.strip().strip("|").split("|")]
        # Accuracy rows of the quaternion filter (against truth, or a log's reference).
        if len(c) >= 11 and c[1] == "quat":
            try:
                rms = [float(x) for x in c[5].split("/")]
                mx = [float(x) for x in c[6].split("/")]
            except ValueError:
                continue
            def two(s):
                try: return [float(x) for x in s.split("(")[0].split("/")]
                except ValueError: return [float("nan")]*2
            rows.append(dict(name=c[0], rms=rms, max=mx, tilt=two(c[8]), total=two(c[9]), wind=two(c[10])))
    return rows

def job(item):
    it, seed, spec = item
    d = tempfile.mkdtemp(prefix="tune")
    cmd = [BIN, "report", it, "--models", "quat", "--from", "20", "--no-figures", "--seed", str(seed), "--out", d] + EXTRA
    if spec: cmd += ["--spec", spec]
    p = subprocess.run(cmd, capture_output=True, text=True)
    subprocess.run(["rm", "-rf", d])
    if p.returncode != 0:
        return [dict(name=f"{it}@{seed}", error=p.stderr[-300:])]
    rows = parse(p.stdout)
    for r in rows:
        r["name"] = f"{r['name']}@{seed}" + (f"/{spec}" if spec else "")
    return rows

label = sys.argv[1]
items = [x for s in sys.argv[2:] for x in sets(s)]
res = []
with cf.ThreadPoolExecutor(int(os.environ.get("J", "2"))) as ex:
    for rows in ex.map(job, items):
        res += rows
json.dump(res, open(os.path.join(TUNE_DIR, label + ".json"), "w"), indent=0)
errs = [r for r in res if "error" in r]
print(f"{label}: {len(res)} rows, {len(errs)} errors")
for e in errs[:5]: print(e)
