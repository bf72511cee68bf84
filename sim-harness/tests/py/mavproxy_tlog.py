"""What MAVProxy (a ground station nobody here wrote) logged of a flight, decoded with
pymavlink: bad data in its telemetry log and in its raw log, each message's rate on its
own receive clock, the STATUSTEXTs with their severity and flight time, the HEARTBEAT
states, SYS_STATUS' AHRS health bit and ESTIMATOR_STATUS' attitude flag.
Usage: mavproxy_tlog.py TLOG   (TLOG.raw beside it)
Prints `key value…` lines (see sim-harness/tests/qemu_mavproxy.rs)."""
import os
import sys

os.environ.setdefault("MAVLINK20", "1")
from pymavlink import mavutil  # noqa: E402
from pymavlink.dialects.v20 import common as mav  # noqa: E402

AHRS = mav.MAV_SYS_STATUS_AHRS
tlog = sys.argv[1]

# The raw log: the bytes MAVProxy read, as it read them.
raw = open(tlog + ".raw", "rb").read()
p = mav.MAVLink(None)
p.robust_parsing = True
bad_raw = frames_raw = 0
for i in range(0, len(raw), 4096):
    for m in p.parse_buffer(raw[i:i + 4096]) or []:
        if m.get_type() == "BAD_DATA":
            bad_raw += 1
        else:
            frames_raw += 1
print("raw_bytes", len(raw))
print("raw_frames", frames_raw)
print("raw_bad_data", bad_raw)

# The telemetry log: every message with MAVProxy's receive time.
m = mavutil.mavlink_connection(tlog, robust_parsing=True, dialect="common")
times = {}
components = {}
bad = 0
flight_t = None  # flight time of the latest timed message, s
states = []
att = []  # (flight time s, receive time s) of each ATTITUDE
ahrs = [0, 0]
est = [0, 0]
while True:
    msg = m.recv_match()
    if msg is None:
        break
    t = msg.get_type()
    if t == "BAD_DATA":
        bad += 1
        continue
    if msg.get_srcSystem() != 1:
        continue  # MAVProxy's own messages
    comp = msg.get_srcComponent()
    components[comp] = components.get(comp, 0) + 1
    if comp != 1:
        continue
    wall = msg._timestamp
    if hasattr(msg, "time_boot_ms"):
        flight_t = msg.time_boot_ms / 1e3
    elif hasattr(msg, "time_usec"):
        flight_t = msg.time_usec / 1e6
    key = t
    if t in ("DEBUG_VECT", "NAMED_VALUE_INT"):
        key = t + ":" + msg.name.rstrip("\0")
    times.setdefault(key, []).append(wall)
    if t == "ATTITUDE":
        att.append((flight_t, wall))
    if t == "STATUSTEXT":
        print("text", msg.severity, "%.3f" % (flight_t or 0.0), "%.3f" % wall, msg.text)
    elif t == "HEARTBEAT":
        if not states or states[-1] != msg.system_status:
            print("state", msg.system_status, "%.3f" % (flight_t or 0.0))
        states.append(msg.system_status)
    elif t == "SYS_STATUS":
        ahrs[0] += 1
        if msg.onboard_control_sensors_health & AHRS:
            ahrs[1] += 1
    elif t == "ESTIMATOR_STATUS":
        est[0] += 1
        if msg.flags & mav.ESTIMATOR_ATTITUDE:
            est[1] += 1
print("tlog_bad_data", bad)
if len(att) > 1:
    # Real time: the flight time the stream covers against MAVProxy's receive clock.
    print("clock flight_s %.3f received_s %.3f" % (att[-1][0] - att[0][0], att[-1][1] - att[0][1]))
for c, n in sorted(components.items()):
    print("component", c, n)
print("sys_status", ahrs[0], "ahrs_healthy", ahrs[1])
print("estimator_status", est[0], "attitude_good", est[1])
for key, ts in sorted(times.items()):
    span = ts[-1] - ts[0]
    hz = (len(ts) - 1) / span if span > 0 else 0.0
    print("rate", key, "%.3f" % hz, len(ts), "%.3f" % span)
