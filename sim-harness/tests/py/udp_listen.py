"""Ground-station side of the MAVLink UDP test: pymavlink listens on 127.0.0.1:PORT,
prints `ready`, then counts messages until SECONDS pass with nothing new; prints
`TYPE count` lines. Usage: udp_listen.py PORT SECONDS"""
import socket
import sys
import time

from pymavlink import mavutil

port, quiet = int(sys.argv[1]), float(sys.argv[2])
m = mavutil.mavlink_connection("udpin:127.0.0.1:%d" % port)
# A 4 MiB receive buffer: this Python loop is slower than QEMU sends on a busy CI machine,
# and the default ~200 kB overflowed there (9 % of the datagrams dropped by the kernel).
for opt in (getattr(socket, "SO_RCVBUFFORCE", None), socket.SO_RCVBUF):
    if opt is None:
        continue
    try:
        m.port.setsockopt(socket.SOL_SOCKET, opt, 4 << 20)
        break
    except OSError:
        pass
print("ready", flush=True)
counts = {}
last = time.time()
first_att = None
while time.time() - last < quiet:
    msg = m.recv_match(blocking=True, timeout=0.2)
    if msg is None:
        continue
    last = time.time()
    t = msg.get_type()
    counts[t] = counts.get(t, 0) + 1
    if t == "ATTITUDE" and first_att is None:
        first_att = msg
    if t == "GPS_RAW_INT":
        gps = msg
for t, n in sorted(counts.items()):
    print(t, n)
if "GPS_RAW_INT" in counts:
    print("gps_lat_e7", gps.lat)
