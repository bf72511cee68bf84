#!/usr/bin/env python3
"""Fly an airframe shipped with JSBSim (PyPI `jsbsim`) through scripted turns and winds in
JSBSim's own flight dynamics and write its truth as CSV, one row per 0.01 s:

  t, roll, pitch, yaw (rad, 3-2-1, NED/FRD), p, q, r (rad/s, body FRD),
  fx, fy, fz (m/s^2: specific force at the CG = non-gravitational forces / mass, body FRD),
  vn, ve, vd (m/s, NED ground velocity), lat, lon (deg, geodetic), alt (m, above MSL),
  va (m/s, true airspeed), wind_n, wind_e, wind_d (m/s, NED)

`sim-harness jsbsim NAME` passes it through sim-harness's own sensor models into a flight
log. Flights (NAME): c172_turns, c172_wind7, j3cub_turns. Usage:
  jsbsim_fly.py NAME OUT.csv
A bank/pitch PD autopilot written here (not JSBSim's) holds the bank schedule and altitude.
"""
import math
import sys

import jsbsim

FT = 0.3048
DT = 0.01  # JSBSim integration step and output period, s

# name: (aircraft, initial airspeed kts, throttle, duration s, wind NED m/s,
#        bank schedule [(until t s, bank deg)])
FLIGHTS = {
    "c172_turns": ("c172x", 100, 0.85, 180, (0, 0, 0),
                   [(30, 0), (60, 30), (75, 0), (105, -45), (120, 0), (150, 30), (180, 0)]),
    "c172_wind7": ("c172x", 100, 0.85, 180, (-7 * 0.7071, 7 * 0.7071, 0),
                   [(30, 0), (60, 30), (75, 0), (105, -45), (120, 0), (150, 30), (180, 0)]),
    "j3cub_turns": ("J3Cub", 60, 0.9, 150, (0, 0, 0),
                    [(25, 0), (55, 35), (70, 0), (100, -35), (115, 0), (150, 20)]),
}


def bank_at(schedule, t):
    for until, bank in schedule:
        if t < until:
            return math.radians(bank)
    return math.radians(schedule[-1][1])


def main():
    if len(sys.argv) != 3 or sys.argv[1] not in FLIGHTS:
        sys.exit(f"usage: {sys.argv[0]} {{{'|'.join(FLIGHTS)}}} OUT.csv")
    name, out = sys.argv[1], sys.argv[2]
    aircraft, kts, throttle, duration, wind, schedule = FLIGHTS[name]
    fdm = jsbsim.FGFDMExec(jsbsim.get_default_root_dir())
    fdm.set_debug_level(0)
    if not fdm.load_model(aircraft):
        sys.exit(f"JSBSim cannot load {aircraft}")
    fdm.set_dt(DT)
    fdm["ic/h-sl-ft"] = 3000
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
    fdm["propulsion/set-running"] = -1
    fdm["fcs/mixture-cmd-norm"] = 1.0
    fdm["fcs/throttle-cmd-norm"] = throttle
    h_ref = fdm["position/h-sl-ft"] * FT
    g0 = 9.80665
    t = 0.0
    rows = []
    while t <= duration + 1e-9:
        phi, theta = fdm["attitude/phi-rad"], fdm["attitude/theta-rad"]
        p, q, r = fdm["velocities/p-rad_sec"], fdm["velocities/q-rad_sec"], fdm["velocities/r-rad_sec"]
        h = fdm["position/h-sl-ft"] * FT
        vd = fdm["velocities/v-down-fps"] * FT
        # Bank and altitude hold (PD on attitude; pitch target from altitude and climb rate,
        # plus the load-factor pitch a level turn needs).
        bank = bank_at(schedule, t)
        theta_t = math.radians(2.0) + 0.004 * (h_ref - h) + 0.01 * vd \
            + math.radians(4.0) * (1.0 / max(math.cos(bank), 0.3) - 1.0)
        fdm["fcs/aileron-cmd-norm"] = max(-1, min(1, 1.5 * (bank - phi) - 0.3 * p))
        fdm["fcs/elevator-cmd-norm"] = max(-1, min(1, -(3.0 * (theta_t - theta) - 0.5 * q)))
        fdm["fcs/rudder-cmd-norm"] = max(-1, min(1, 0.8 * fdm["aero/beta-rad"] - 0.2 * r))
        m = fdm["inertia/weight-lbs"] / (g0 / FT)  # slug
        f = [fdm[f"forces/fb{a}-total-lbs"] / m * FT for a in "xyz"]
        rows.append((
            t, phi, theta, fdm["attitude/psi-rad"], p, q, r, *f,
            fdm["velocities/v-north-fps"] * FT, fdm["velocities/v-east-fps"] * FT, vd,
            fdm["position/lat-geod-deg"], fdm["position/long-gc-deg"], h,
            fdm["velocities/vt-fps"] * FT,
            fdm["atmosphere/total-wind-north-fps"] * FT, fdm["atmosphere/total-wind-east-fps"] * FT,
            fdm["atmosphere/total-wind-down-fps"] * FT,
        ))
        if not fdm.run():
            sys.exit(f"JSBSim stopped at t = {t:.2f} s")
        t = round(t + DT, 9)
    with open(out, "w") as fh:
        fh.write("t,roll,pitch,yaw,p,q,r,fx,fy,fz,vn,ve,vd,lat,lon,alt,va,wind_n,wind_e,wind_d\n")
        for row in rows:
            fh.write(",".join(repr(float(x)) for x in row) + "\n")
    print(f"{name}: {len(rows)} rows, {aircraft}, written to {out}")


if __name__ == "__main__":
    main()
