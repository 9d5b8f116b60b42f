#!/usr/bin/env python3
"""Copies an LCM log with every time shifted by SHIFT microseconds: the event timestamps and the utime of
the raw sensor messages (imu_t, lidar_scan_t, image_t: their first field after the 8-byte fingerprint),
so that a log replayed again after itself looks like one longer drive (scripts/bench-suite --soak).
Other channels are copied unchanged.

  scripts/lcm_log_shift.py IN OUT SHIFT_US [--from US] [--to US]
      copies the events with FROM <= timestamp < TO (before the shift; default: all)
  scripts/lcm_log_shift.py --span IN      prints first and last event timestamps and the median IMU step (us)
  scripts/lcm_log_shift.py --lap GT.tum   prints T_A T_B (us): a time after the first quarter of the ground
      truth and the time near its end where the path is closest to that pose again, for a seamless loop
"""
import struct
import sys

SYNC = 0xEDA1DA01
HEADER = struct.Struct(">IqqII")  # sync, event number, timestamp, channel length, data length


def events(path):
    with open(path, "rb") as f:
        while True:
            head = f.read(HEADER.size)
            if not head:
                return
            if len(head) < HEADER.size:
                raise SystemExit(f"{path}: truncated event header")
            sync, num, ts, clen, dlen = HEADER.unpack(head)
            if sync != SYNC:
                raise SystemExit(f"{path}: bad sync word at event {num}")
            channel = f.read(clen)
            data = f.read(dlen)
            if len(channel) < clen or len(data) < dlen:
                raise SystemExit(f"{path}: truncated event {num}")
            yield num, ts, channel.decode(), data


def span(path, imu_channel="LIVO_IMU"):
    first = last = None
    imu_times = []
    for _, ts, ch, data in events(path):
        first = ts if first is None else first
        last = ts
        if ch == imu_channel and len(imu_times) < 2000:
            imu_times.append(struct.unpack(">q", data[8:16])[0])
    steps = sorted(b - a for a, b in zip(imu_times, imu_times[1:]) if b > a)
    step = steps[len(steps) // 2] if steps else 5000
    return first, last, step


def lap(gt_path):
    """(T_A, T_B, gap m): the pair of ground-truth times, A in the first 40 % and B in the last 40 % of the
    path, where the position is closest and the velocity agrees within 2 % (a seamless lap)."""
    rows = []
    for line in open(gt_path):
        if line.startswith("#") or not line.strip():
            continue
        rows.append([float(x) for x in line.split()[:4]])
    n = len(rows)
    if n < 1000:
        raise SystemExit(f"{gt_path}: too few poses for a lap")

    def vel(i):
        i0, i1 = max(0, i - 5), min(n - 1, i + 5)
        dt = rows[i1][0] - rows[i0][0]
        return [(rows[i1][k] - rows[i0][k]) / dt for k in (1, 2, 3)]

    best = None
    step_a = max(1, n // 2000)
    for i in range(0, n * 2 // 5, step_a):
        a = rows[i]
        va = vel(i)
        speed = sum(x * x for x in va) ** 0.5
        if speed < 0.5:
            continue  # at rest or starting: not a seam
        for j in range(n * 3 // 5, n - 6):
            b = rows[j]
            d2 = (b[1] - a[1]) ** 2 + (b[2] - a[2]) ** 2 + (b[3] - a[3]) ** 2
            if best is not None and d2 >= best[0]:
                continue
            vb = vel(j)
            if sum((x - y) ** 2 for x, y in zip(va, vb)) ** 0.5 > 0.02 * speed:
                continue
            best = (d2, a[0], b[0])
    if best is None or best[0] ** 0.5 > 0.5:
        raise SystemExit(f"{gt_path}: the path never comes back to an earlier pose at the same velocity: not a loop")
    return int(round(best[1] * 1e6)), int(round(best[2] * 1e6)), best[0] ** 0.5


def shift(src, dst, shift_us, channels, t_from=None, t_to=None):
    with open(dst, "wb") as out:
        for num, ts, ch, data in events(src):
            if (t_from is not None and ts < t_from) or (t_to is not None and ts >= t_to):
                continue
            if ch in channels and len(data) >= 16:
                utime = struct.unpack(">q", data[8:16])[0]
                data = data[:8] + struct.pack(">q", utime + shift_us) + data[16:]
            c = ch.encode()
            out.write(HEADER.pack(SYNC, num, ts + shift_us, len(c), len(data)))
            out.write(c)
            out.write(data)


def main(argv):
    if len(argv) == 3 and argv[1] == "--span":
        print(*span(argv[2]))
        return 0
    if len(argv) == 3 and argv[1] == "--lap":
        a, b, gap = lap(argv[2])
        print(a, b, f"{gap:.4f}")
        return 0
    if len(argv) < 4:
        print(__doc__, file=sys.stderr)
        return 2
    opts = dict(zip(argv[4::2], argv[5::2]))
    unknown = set(opts) - {"--from", "--to"}
    if unknown or len(argv[4:]) % 2:
        print(__doc__, file=sys.stderr)
        return 2
    t_from = int(opts["--from"]) if "--from" in opts else None
    t_to = int(opts["--to"]) if "--to" in opts else None
    shift(argv[1], argv[2], int(argv[3]), {"LIVO_IMU", "LIVO_LIDAR", "LIVO_CAMERA"}, t_from, t_to)
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
