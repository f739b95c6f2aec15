#!/usr/bin/env python3
"""Writes the seed traces of fuzz_trace (fuzz/seeds/trace/) from docs/trace-format.md, so the seeds
need no tripodal build: one trace with a record of every kind, one with two channels of a kind,
one cut inside a record. Re-run after a format change: python3 fuzz/make_trace_seeds.py"""
import os
import struct
import zlib

HERE = os.path.join(os.path.dirname(os.path.abspath(__file__)), "seeds", "trace")
MAGIC = b"\x89TRPTRC\n"


def header():
    h = MAGIC + struct.pack("<HH", 1, 0)
    return h + struct.pack("<I", zlib.crc32(h))


def frame(body):
    n = len(body)
    return struct.pack("<II", n, n ^ 0xFFFFFFFF) + body + struct.pack("<I", zlib.crc32(body))


def head(kind, channel, stamp):
    return struct.pack("<BHq", kind, channel, stamp)


def s16(text):
    b = text.encode()
    return struct.pack("<H", len(b)) + b


def floats(values):
    return struct.pack("<I", len(values)) + struct.pack("<%df" % len(values), *values)


def declare(channel, kind, name):
    return frame(head(0, channel, 0) + struct.pack("<B", kind) + s16(name))


def every_kind():
    t = 1_700_000_000_000_000_000
    out = header()
    records = [
        (1, "front_laser", struct.pack("<7d", -1.57, 1.57, 0.0175, 0.0, 0.1, 0.05, 30.0)
         + floats([1.0, 2.5, float("nan"), 30.0]) + floats([])),
        (2, "odom", struct.pack("<6d", 1.0, 2.0, 0.5, 0.3, 0.0, 0.1)),
        (3, "sonar", struct.pack("<3d", 0.4, 0.02, 4.0) + floats([0.5, 1.5])),
        (4, "ir", struct.pack("<I", 3) + bytes([0, 1, 0]) + floats([0.2])),
        (5, "bumper", struct.pack("<II", 4, 0b0101)),
        (6, "battery", struct.pack("<3dB", 24.1, -1.2, 87.5, 1)),
        (7, "gyro", struct.pack("<2d", 0.01, 1.2)),
        (8, "cmd_vel", struct.pack("<3d", 0.3, 0.0, 0.2) + s16("BhCleaning")),
        (9, "events", s16("localizer.lost")),
    ]
    for i, (kind, name, payload) in enumerate(records):
        out += declare(i, kind, name)
        out += frame(head(kind, i, t + i * 1000) + payload)
    return out


def two_odometry_channels():
    out = header() + declare(0, 2, "odom") + declare(1, 2, "laser_pose")
    for i in range(3):
        out += frame(head(2, i % 2, 10 * i) + struct.pack("<6d", i, -i, 0.1 * i, 0, 0, 0))
    return out


def main():
    os.makedirs(HERE, exist_ok=True)
    full = every_kind()
    for name, data in [("every-kind.trace", full), ("two-channels.trace", two_odometry_channels()),
                       ("cut.trace", full[: len(full) - 7]), ("empty.trace", header())]:
        with open(os.path.join(HERE, name), "wb") as f:
            f.write(data)


if __name__ == "__main__":
    main()
