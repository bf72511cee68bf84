"""Decode a raw MAVLink v2 capture with pymavlink (the reference implementation)
and print every ATTITUDE as `time_boot_ms roll pitch yaw` with the f32 bit
patterns in hex, plus a final `crc_errors N` line. With COMPONENT, only that
sender's (25: the per-sample HIL records). Usage: decode_attitude.py FILE [COMPONENT]"""
import os
import struct
import sys

os.environ.setdefault("MAVLINK20", "1")
from pymavlink.dialects.v20 import common as mav  # noqa: E402

data = open(sys.argv[1], "rb").read()
component = int(sys.argv[2]) if len(sys.argv) > 2 else None
m = mav.MAVLink(None)
m.robust_parsing = True
bad = 0
for i in range(0, len(data), 4096):
    try:
        msgs = m.parse_buffer(data[i:i + 4096]) or []
    except mav.MAVError:
        msgs = []
    for msg in msgs:
        t = msg.get_type()
        if t == "BAD_DATA":
            bad += 1
        elif t == "ATTITUDE" and component in (None, msg.get_srcComponent()):
            h = lambda x: struct.pack("<f", x).hex()
            print(msg.time_boot_ms, h(msg.roll), h(msg.pitch), h(msg.yaw))
print("crc_errors", bad)
