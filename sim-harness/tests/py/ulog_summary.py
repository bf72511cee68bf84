"""Independent read of a ULog with pyulog: column sums the Rust importer must match.
Prints `key value` lines. Usage: ulog_summary.py FILE"""
import math
import sys

from pyulog import ULog

u = ULog(sys.argv[1], ["sensor_combined", "vehicle_gps_position", "vehicle_attitude"])
d = {x.name: x.data for x in u.data_list if x.multi_id == 0}
sc = d["sensor_combined"]
print("imu_n", len(sc["timestamp"]))
for k in ["gyro_rad[0]", "gyro_rad[1]", "gyro_rad[2]", "accelerometer_m_s2[0]",
          "accelerometer_m_s2[1]", "accelerometer_m_s2[2]"]:
    print("sum", k, float(sum(float(v) for v in sc[k])))
g = d.get("vehicle_gps_position")
if g is not None:
    ok = [i for i in range(len(g["timestamp"])) if g["fix_type"][i] >= 3
          and ("vel_ned_valid" not in g or g["vel_ned_valid"][i])]
    print("gps_3d", len(ok))
    print("gps_sum_vn", float(sum(float(g["vel_n_m_s"][i]) for i in ok)))
a = d["vehicle_attitude"]
# Roll of the first attitude sample, 3-2-1 from the quaternion (w, x, y, z).
w, x, y, z = (float(a["q[%d]" % i][0]) for i in range(4))
print("att0_t", int(a["timestamp"][0]))
print("att0_roll", math.atan2(2 * (w * x + y * z), 1 - 2 * (x * x + y * y)))
