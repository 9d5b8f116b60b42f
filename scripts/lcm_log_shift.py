#!/usr/bin/env python3
"""Copies an LCM log with every time shifted by SHIFT microseconds: the event timestamps and the utime of
the raw sensor messages (imu_t, lidar_scan_t, image_t: their first field after the 8-byte fingerprint),
so that a log replayed again after itself looks like one longer drive (scripts/bench-suite --soak).
Other channels are copied unchanged.

  scripts/lcm_log_shift.py IN OUT SHIFT_US [--channels LIVO_IMU,LIVO_LIDAR,LIVO_CAMERA]
  scripts/lcm_log_shift.py --span IN      prints first and last event timestamps and the median IMU step (us)
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


def shift(src, dst, shift_us, channels):
    with open(dst, "wb") as out:
        for num, ts, ch, data in events(src):
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
    if len(argv) not in (4, 6):
        print(__doc__, file=sys.stderr)
        return 2
    channels = {"LIVO_IMU", "LIVO_LIDAR", "LIVO_CAMERA"}
    if len(argv) == 6 and argv[4] == "--channels":
        channels = set(argv[5].split(","))
    shift(argv[1], argv[2], int(argv[3]), channels)
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
