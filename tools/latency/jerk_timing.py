#!/usr/bin/env python3
"""Where the latency tracker settles on a receiver that smooths its velocity: a forward model.

The tracker (src/mekf/latency.rs) correlates the GPS-acceleration residual with the jerk
between two consecutive IMU windows. That jerk stands at the windows' common edge, half an
interval before the newer window's centre, where the residual stands. For a pure delay the
timing does not matter (the residual vanishes at the right delay); for a receiver with a
first-order velocity filter it does. This replays the tracker's normalised LMS step on an
exact manoeuvre (four sines, no noise, no attitude error) and prints where it settles, with
the residual as shipped and with the residual moved to the jerk's edge (the mean of the two
windows' residuals), beside the least-squares pure delay over the same flight.

python3 tools/latency/jerk_timing.py        (pure Python, no packages)
"""
import math

SINES = [(0.7, 5.0, 0.3), (1.9, 4.0, 1.1), (3.7, 3.0, 2.0), (5.3, 2.0, 0.5)]  # rad/s, m/s², rad


def velocity(t, tau=0.0):
    """North velocity at t, as a receiver with a tau-s first-order filter reports it."""
    v = 0.0
    for w, a, p in SINES:
        gain = 1.0 / math.sqrt(1.0 + (w * tau) ** 2)
        v += -a / w * gain * math.cos(w * t + p - math.atan(w * tau))
    return v


def residual(t, dt, delay, tau, d):
    gps = (velocity(t - delay, tau) - velocity(t - dt - delay, tau)) / dt
    imu = (velocity(t - d) - velocity(t - dt - d)) / dt
    return gps - imu, imu


def track(delay, tau, dt, centred, n=3000):
    """The tracker's step (gain 0.3, clamp 0.02 s, |jerk| at least 2 m/s³); mean of the last 1000."""
    d, jj, prev, late = 0.0, 0.0, None, []
    for k in range(1, n):
        y, f = residual(k * dt, dt, delay, tau, d)
        if prev is not None:
            f0, y0 = prev
            j = (f - f0) / dt
            if j * j >= 4.0:
                jj = jj + 0.05 * (j * j - jj) if jj > 0 else j * j
                yy = 0.5 * (y + y0) if centred else y
                step = max(-0.02, min(0.02, 0.3 * yy * j / max(jj, j * j)))
                d = min(max(d - step, 0.0), 0.3)
        prev = (f, y)
        late.append(d)
    return sum(late[-1000:]) / 1000


def best_fit(delay, tau, dt, n=3000):
    def sse(d):
        return sum(residual(k * dt, dt, delay, tau, d)[0] ** 2 for k in range(n - 1000, n, 2))
    return min((i / 1000 for i in range(301)), key=sse)


print("| receiver | fixes | best pure delay s | tracked, residual at its window s | tracked, residual at the jerk's edge s |")
print("|---|---|---|---|---|")
for delay, tau in [(0.16, 0.0), (0.06, 0.1), (0.0, 0.1)]:
    for dt in [1.0, 0.5, 0.2, 0.1, 0.05]:
        name = f"{delay * 1000:.0f} ms" + (f" + {tau:g} s filter" if tau else "")
        print(f"| {name} | {1 / dt:g} Hz | {best_fit(delay, tau, dt):.3f} | "
              f"{track(delay, tau, dt, False):.3f} | {track(delay, tau, dt, True):.3f} |")
