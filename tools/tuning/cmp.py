#!/usr/bin/env python3
"""cmp.py A B [FILTER]: geometric means of B/A per metric (RMS roll, pitch, yaw, tilt, total,
wind; tilt max), per group of rows and overall, and the best and worst single rows."""
import sys, os, json, math, collections
D = os.environ.get("TUNE_DIR", os.path.join(os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__)))), "target/tune"))
A = {r["name"]: r for r in json.load(open(os.path.join(D, sys.argv[1] + ".json"))) if "error" not in r}
B = {r["name"]: r for r in json.load(open(os.path.join(D, sys.argv[2] + ".json"))) if "error" not in r}
flt = sys.argv[3] if len(sys.argv) > 3 else ""
def grp(n):
    if n.startswith("random:"):
        return "holdout" if int(n.split(":")[1].split("@")[0]) > 40 else "random"
    if "/realistic" in n: return "realistic"
    if n.startswith("aerobatics"): return n.split("@")[0]
    if "px4_2014" in n or "flight_" in n: return "real"
    if "wind=" in n: return "wind"
    return "still"
def m(r):
    return dict(roll=r["rms"][0], pitch=r["rms"][1], yaw=r["rms"][2], tilt=r["tilt"][0], total=r["total"][0], wind=r["wind"][0], tiltmax=r["tilt"][1])
keys = ["roll", "pitch", "yaw", "tilt", "total", "wind", "tiltmax"]
agg = collections.defaultdict(lambda: collections.defaultdict(list))
worst = []
for n in A:
    if n not in B or flt not in n: continue
    a, b = m(A[n]), m(B[n])
    g = grp(n)
    for k in keys:
        if a[k] > 0 and b[k] > 0 and math.isfinite(a[k]) and math.isfinite(b[k]):
            r = math.log(max(b[k], 1e-3) / max(a[k], 1e-3))
            agg[g][k].append(r); agg["ALL"][k].append(r)
    if a["total"] > 0 and b["total"] > 0:
        worst.append((b["total"] / a["total"], n, a["total"], b["total"]))
print(f"{'group':22s} n  " + " ".join(f"{k:>7s}" for k in keys))
for g in sorted(agg, key=lambda g: (g == "ALL", g)):
    n = len(agg[g]["total"])
    print(f"{g:22s}{n:3d} " + " ".join(f"{math.exp(sum(v)/len(v)):7.3f}" if v else "      -" for v in (agg[g][k] for k in keys)))
worst.sort()
print("best:", [(f"{r:.2f}", n, f"{a:.2f}->{b:.2f}") for r, n, a, b in worst[:3]])
print("worst:", [(f"{r:.2f}", n, f"{a:.2f}->{b:.2f}") for r, n, a, b in worst[-4:]])
