#!/usr/bin/env python3
"""Fly an airframe shipped with JSBSim (PyPI `jsbsim`) in JSBSim's own flight dynamics and
write its truth as CSV, one row per 0.01 s:

  t, roll, pitch, yaw (rad, 3-2-1, NED/FRD), p, q, r (rad/s, body FRD),
  fx, fy, fz (m/s^2: specific force at the CG = non-gravitational forces / mass, body FRD),
  vn, ve, vd (m/s, NED ground velocity), lat, lon (deg, geodetic), alt (m, above MSL),
  va (m/s, true airspeed), wind_n, wind_e, wind_d (m/s, NED, turbulence included)

`sim-harness jsbsim NAME` passes it through sim-harness's own sensor models into a flight
log. Usage:  jsbsim_fly.py NAME OUT.csv   (or  jsbsim_fly.py --list)

Flights (NAME):
  c172_turns, c172_wind7, j3cub_turns   scripted turns (the first three, kept as they were)
  t6_aerobatics, t6_aerobatics_wind6   loop, axial roll, 75° bank turns, Immelmann, split-S,
                                        sustained inverted flight, Cuban eight
  randN (N = 1, 2, ...)                 a seeded random flight: airframe, wind 0-10 m/s from
                                        any direction, JSBSim's MIL-spec turbulence (none,
                                        light, moderate), bank and altitude schedule, and on
                                        the aerobatic trainer a loop or an axial roll
A small autopilot written here (not JSBSim's) flies the plan: bank/pitch PD with altitude
hold, and pitch/roll-rate commands for the aerobatic figures.
"""
import math
import random
import sys

import jsbsim

FT = 0.3048
DT = 0.01  # JSBSim integration step and output period, s
G0 = 9.80665

# aircraft: (initial airspeed kts, throttle). Airframes that hold a 40° bank and altitude
# with the autopilot below (c182, pa28 and others tried; pa28 holds bank to 10° only).
AIRFRAMES = {
    "c172x": (100, 0.85), "c172p": (100, 0.85), "c182": (120, 0.85), "J3Cub": (60, 0.9),
    "t6texan2": (180, 0.8),
}
# The aerobatic trainer that flies the figures (pc7 was tried: it enters an inverted spin
# after a stalled loop, which this autopilot does not recover).
AEROBATIC = ("t6texan2",)

# A plan is a list of segments: ("bank", seconds, bank deg[, climb m]), ("dive", airspeed m/s
# to reach), ("loop", fraction of a turn), ("roll", fraction of a turn, direction ±1),
# ("inverted", seconds).
AERO_PLAN = [
    ("bank", 20, 0), ("dive", 105), ("loop", 1.0), ("bank", 10, 0), ("roll", 1.0, 1),
    ("bank", 8, 0), ("bank", 15, 75), ("bank", 8, 0), ("dive", 105), ("loop", 0.5),
    ("roll", 0.5, -1), ("bank", 10, 0), ("roll", 0.5, 1), ("inverted", 10), ("roll", 0.5, 1),
    ("bank", 10, 0), ("bank", 12, -75), ("bank", 8, 0), ("roll", 0.5, -1), ("loop", 0.5),
    ("bank", 10, 0), ("dive", 105), ("loop", 0.625), ("roll", 0.5, 1), ("loop", 0.75),
    ("roll", 0.5, -1), ("loop", 0.125), ("bank", 20, 0),
]

# name: (aircraft, duration s, wind NED m/s, turbulence severity (0 none, 1 light,
#        3 moderate), start height ft, plan)
FLIGHTS = {
    "c172_turns": ("c172x", 180, (0, 0, 0), 0, 3000,
                   [("bank", 30, 0), ("bank", 30, 30), ("bank", 15, 0), ("bank", 30, -45),
                    ("bank", 15, 0), ("bank", 30, 30), ("bank", 31, 0)]),
    "c172_wind7": ("c172x", 180, (-7 * 0.7071, 7 * 0.7071, 0), 0, 3000,
                   [("bank", 30, 0), ("bank", 30, 30), ("bank", 15, 0), ("bank", 30, -45),
                    ("bank", 15, 0), ("bank", 30, 30), ("bank", 31, 0)]),
    "j3cub_turns": ("J3Cub", 150, (0, 0, 0), 0, 3000,
                    [("bank", 25, 0), ("bank", 30, 35), ("bank", 15, 0), ("bank", 30, -35),
                     ("bank", 15, 0), ("bank", 36, 20)]),
    "t6_aerobatics": ("t6texan2", 220, (0, 0, 0), 0, 12000, AERO_PLAN),
    "t6_aerobatics_wind6": ("t6texan2", 220, (6 * 0.5, 6 * 0.866, 0), 1, 12000, AERO_PLAN),
}


def random_flight(n):
    """The seeded random flight randN: the same N always gives the same flight."""
    rng = random.Random(1000 + n)
    aircraft = rng.choice(sorted(AIRFRAMES))
    speed, direction = rng.uniform(0, 10), rng.uniform(0, 2 * math.pi)
    wind = (-speed * math.cos(direction), -speed * math.sin(direction), 0.0)  # from `direction`
    turb = rng.choice([0, 0, 1, 3])
    plan, t = [("bank", rng.uniform(15, 30), 0)], 0.0
    duration = 150
    figure = aircraft in AEROBATIC and rng.random() < 0.7
    while t < duration - 20:
        if figure and t > 50:
            plan += [rng.choice([("loop", 1.0), ("roll", 1.0, rng.choice([-1, 1]))]),
                     ("bank", 10, 0)]
            figure = False
            t += 25
            continue
        seg = rng.uniform(8, 30)
        bank = 0 if rng.random() < 0.35 else rng.choice([-1, 1]) * rng.uniform(15, 60)
        plan.append(("bank", seg, bank, rng.uniform(-60, 60)))
        t += seg
    plan.append(("bank", 30, 0))
    return aircraft, duration, wind, turb, 3000, plan


def flight(name):
    if name in FLIGHTS:
        return FLIGHTS[name]
    if name.startswith("rand") and name[4:].isdigit() and int(name[4:]) > 0:
        return random_flight(int(name[4:]))
    sys.exit(f"unknown flight {name!r}: use one of {', '.join(FLIGHTS)} or randN (N ≥ 1)")


def wrap(a):
    # Only outside ±π (so the upright flights' commands are the original bits).
    return (a + math.pi) % (2 * math.pi) - math.pi if abs(a) > math.pi else a


class Pilot:
    """Flies the plan's segments one after another; the last one is held to the end."""

    def __init__(self, plan, h0):
        self.plan, self.k, self.t0, self.turned, self.h_ref = plan, 0, 0.0, 0.0, h0
        # Plans with figures fly at full power throughout; others at the cruise throttle.
        self.full_power = any(seg[0] != "bank" or abs(seg[2]) >= 50 for seg in plan)
        self.plane = None  # the loop's plane normal (body y at the loop's entry), NED

    def segment(self, t, rates, va, h):
        seg = self.plan[self.k]
        if seg[0] in ("loop", "roll"):
            self.turned += (rates[1] if seg[0] == "loop" else abs(rates[0])) * DT
            done = self.turned >= 2 * math.pi * seg[1]
        elif seg[0] == "dive":
            done = va >= seg[1]
        else:
            done = t - self.t0 >= seg[1] - 1e-9
        if done and self.k < len(self.plan) - 1:
            if seg[0] != "bank":
                self.h_ref = h  # after a figure, hold the height it ended at
            self.k, self.t0, self.turned, self.plane = self.k + 1, t, 0.0, None
            seg = self.plan[self.k]
            if seg[0] == "bank" and len(seg) > 3:
                self.h_ref += seg[3]  # the segment climbs or descends by seg[3] m
        return seg

    def command(self, fdm, t):
        phi, theta = fdm["attitude/phi-rad"], fdm["attitude/theta-rad"]
        p, q, r = (fdm[f"velocities/{a}-rad_sec"] for a in "pqr")
        h = fdm["position/h-sl-ft"] * FT
        vd = fdm["velocities/v-down-fps"] * FT
        va = fdm["velocities/vt-fps"] * FT
        seg = self.segment(t, (p, q, r), va, h)
        kind = seg[0]
        rudder = 0.8 * fdm["aero/beta-rad"] - 0.2 * r
        throttle = 1.0
        if kind == "loop":
            # A constant pitch rate for 4.5 g of turn (5.5 g at the bottom) at the current
            # speed; the wings are held in the loop's plane: body y kept on its direction at
            # entry (valid at any attitude).
            x_b, y_b, _ = body_axes(phi, theta, fdm["attitude/psi-rad"])
            if self.plane is None:
                self.plane = y_b
            off = dot(cross(y_b, self.plane), x_b)
            q_c = 4.5 * G0 / max(va, 30.0)
            aileron, elevator = 3.0 * off - 0.3 * p, -0.4 - 2.0 * (q_c - q)
        elif kind == "roll":
            aileron, elevator = seg[2] * 1.0, -0.5 * (0.0 - q)
        else:
            if kind == "bank":
                bank = math.radians(seg[2])
            else:
                bank = math.pi if kind == "inverted" else 0.0  # "dive": wings level
            # Pitch target from altitude and climb rate, plus the load-factor pitch of a
            # level turn; the body pitch rate that brings it, sign-correct inverted.
            c = math.cos(bank)
            theta_t = math.radians(2.0) + 0.004 * (self.h_ref - h) + 0.01 * vd \
                + math.radians(4.0) * (1.0 / max(abs(c), 0.3) - 1.0)
            if kind == "dive":
                theta_t = math.radians(-25.0)
            q_c = 6.0 * (theta_t - theta) * (1.0 if c >= 0 else -1.0)
            aileron = 1.5 * wrap(bank - phi) - 0.3 * p
            elevator = -0.5 * (q_c - q)
            if not self.full_power:
                throttle = None  # the airframe's cruise throttle
        return aileron, elevator, rudder, throttle


def body_axes(phi, theta, psi):
    """The body x, y, z axes in NED (rows of the 3-2-1 direction cosine matrix R_BN)."""
    cf, sf, ct, st, cp, sp = (math.cos(phi), math.sin(phi), math.cos(theta), math.sin(theta),
                              math.cos(psi), math.sin(psi))
    return ((ct * cp, ct * sp, -st),
            (sf * st * cp - cf * sp, sf * st * sp + cf * cp, sf * ct),
            (cf * st * cp + sf * sp, cf * st * sp - sf * cp, cf * ct))


def dot(a, b):
    return sum(x * y for x, y in zip(a, b))


def cross(a, b):
    return (a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0])


def clamp(x):
    return max(-1.0, min(1.0, x))


def main():
    if len(sys.argv) == 2 and sys.argv[1] == "--list":
        print(" ".join(FLIGHTS))
        return
    if len(sys.argv) != 3:
        sys.exit(f"usage: {sys.argv[0]} NAME OUT.csv  (NAME: {', '.join(FLIGHTS)}, randN)")
    name, out = sys.argv[1], sys.argv[2]
    aircraft, duration, wind, turb, h_ft, plan = flight(name)
    kts, cruise = AIRFRAMES[aircraft]
    fdm = jsbsim.FGFDMExec(jsbsim.get_default_root_dir())
    fdm.set_debug_level(0)
    if not fdm.load_model(aircraft):
        sys.exit(f"JSBSim cannot load {aircraft}")
    fdm.set_dt(DT)
    fdm["ic/h-sl-ft"] = h_ft
    fdm["ic/vc-kts"] = kts
    fdm["ic/psi-true-deg"] = 0
    fdm["ic/lat-geod-deg"] = 47.397742
    fdm["ic/long-gc-deg"] = 8.545594
    fdm.run_ic()
    # The wind after run_ic (set before it, JSBSim's initialisation clears it): the
    # aircraft starts air-relative at the commanded airspeed and the wind then carries it.
    fdm["atmosphere/wind-north-fps"] = wind[0] / FT
    fdm["atmosphere/wind-east-fps"] = wind[1] / FT
    fdm["atmosphere/wind-down-fps"] = wind[2] / FT
    if turb:
        fdm["atmosphere/turb-type"] = 3  # MIL-F-8785C / MIL-HDBK-1797 (Dryden)
        fdm["atmosphere/turbulence/milspec/windspeed_at_20ft_AGL-fps"] = (15 if turb == 1 else 30) / 0.5925
        fdm["atmosphere/turbulence/milspec/severity"] = turb
    fdm["propulsion/set-running"] = -1
    fdm["fcs/mixture-cmd-norm"] = 1.0
    fdm["fcs/throttle-cmd-norm"] = cruise
    pilot = Pilot(plan, fdm["position/h-sl-ft"] * FT)
    t = 0.0
    rows = []
    while t <= duration + 1e-9:
        aileron, elevator, rudder, throttle = pilot.command(fdm, t)
        fdm["fcs/aileron-cmd-norm"] = clamp(aileron)
        fdm["fcs/elevator-cmd-norm"] = clamp(elevator)
        fdm["fcs/rudder-cmd-norm"] = clamp(rudder)
        fdm["fcs/throttle-cmd-norm"] = cruise if throttle is None else throttle
        m = fdm["inertia/weight-lbs"] / (G0 / FT)  # slug
        f = [fdm[f"forces/fb{a}-total-lbs"] / m * FT for a in "xyz"]
        rows.append((
            t, fdm["attitude/phi-rad"], fdm["attitude/theta-rad"], fdm["attitude/psi-rad"],
            *(fdm[f"velocities/{a}-rad_sec"] for a in "pqr"), *f,
            fdm["velocities/v-north-fps"] * FT, fdm["velocities/v-east-fps"] * FT,
            fdm["velocities/v-down-fps"] * FT,
            fdm["position/lat-geod-deg"], fdm["position/long-gc-deg"], fdm["position/h-sl-ft"] * FT,
            fdm["velocities/vt-fps"] * FT,
            fdm["atmosphere/total-wind-north-fps"] * FT, fdm["atmosphere/total-wind-east-fps"] * FT,
            fdm["atmosphere/total-wind-down-fps"] * FT,
        ))
        if not fdm.run():
            sys.exit(f"JSBSim stopped at t = {t:.2f} s")
        if fdm["position/h-agl-ft"] < 100:
            sys.exit(f"{name}: {aircraft} reached the ground at t = {t:.2f} s")
        t = round(t + DT, 9)
    with open(out, "w") as fh:
        fh.write("t,roll,pitch,yaw,p,q,r,fx,fy,fz,vn,ve,vd,lat,lon,alt,va,wind_n,wind_e,wind_d\n")
        for row in rows:
            fh.write(",".join(repr(float(x)) for x in row) + "\n")
    turb_name = {0: "none", 1: "light", 3: "moderate"}[turb]
    print(f"{name}: {len(rows)} rows, {aircraft}, wind {math.hypot(wind[0], wind[1]):.1f} m/s "
          f"from {math.degrees(math.atan2(-wind[1], -wind[0])) % 360:.0f}°, turbulence {turb_name}, "
          f"{sum(seg[0] != 'bank' for seg in plan)} aerobatic segments, written to {out}")


if __name__ == "__main__":
    main()
