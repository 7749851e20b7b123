# SPDX-License-Identifier: BSD-3-Clause
"""Raw frame logs (`*.cylraw`, version 1; docs/formats.md) from Python: read and write the format
the C++ tools record and replay (`cyl record`, `cyl detect LOG.cylraw`), so that robot logs made
elsewhere (ROS bags, CSV odometry: cyl.robotlog) can be brought to the tools unchanged.

A writer appends records in the order given; readers (C++ and this one) take odometry, truth poses
and truth landmarks as belonging to the frame whose sequence number they carry.
"""
from __future__ import annotations

import struct
from dataclasses import dataclass, field
from typing import Iterator, List, Optional, Tuple

from .output import OutputError, OutputFile

MAGIC = b"CYLRAW\0\0"
VERSION = 1
HEADER_SIZE = 64
REC_MAGIC = b"REC1"
REC_HEADER = struct.Struct("<4sIQqII")        # magic, type, seq, t_ns, size, flags
FILE_HEADER = struct.Struct("<8sIIIIIIII24s")  # magic, version, header size, fourcc, w, h, stride, bytes, flags, source

FRAME, ODOMETRY, TRUTH_POSE, TRUTH_LANDMARK = 1, 2, 3, 4
FLAG_MONOTONIC, FLAG_HAS_TRUTH = 1, 2


def fourcc(code: str) -> int:
    b = code.encode("ascii")
    return b[0] | (b[1] << 8) | (b[2] << 16) | (b[3] << 24)


def fourcc_str(v: int) -> str:
    return bytes([(v >> s) & 255 for s in (0, 8, 16, 24)]).decode("ascii", "replace")


PIXFMT = {"YUYV": 1, "UYVY": 2, "NV12": 3, "YU12": 4, "444P": 5}   # fourcc -> cyl_pixfmt


def frame_bytes(code: str, width: int, height: int, stride: int) -> int:
    """Payload size of one frame: libcyl's own layout (cyl_image_buffer_size), 0 when invalid."""
    from ._cyl import lib
    if code not in PIXFMT:
        raise ValueError(f"pixel format '{code}': one of {', '.join(PIXFMT)}")
    return int(lib.cyl_image_buffer_size(PIXFMT[code], width, height, stride))


class RawLogError(ValueError):
    """A raw log that cannot be read or written as asked; the message names the file."""


@dataclass
class StreamInfo:
    fourcc: str          # 'YUYV', 'UYVY', 'NV12', 'YU12' or '444P'
    width: int           # px
    height: int          # px
    stride: int          # bytes per line of plane 0
    frame_bytes: int
    flags: int = 0       # FLAG_MONOTONIC | FLAG_HAS_TRUTH
    source: str = ""


@dataclass
class Record:
    type: int
    seq: int
    t_ns: int
    payload: bytes
    flags: int = 0

    def odometry(self) -> Tuple[Tuple[float, float, float], Tuple[float, ...]]:
        """(dx_m, dy_m, dtheta_rad), covariance upper triangle (xx xy xt yy yt tt)."""
        v = struct.unpack("<9d", self.payload)
        return v[:3], v[3:]

    def truth_pose(self) -> Tuple[float, float, float]:
        return struct.unpack("<3d", self.payload)

    def truth_landmark(self) -> Tuple[int, int, float, float, float, float]:
        """(id, class index, x_m, y_m, diameter_m, height_m)."""
        return struct.unpack("<II4d", self.payload)


def odometry_payload(d, cov6) -> bytes:
    return struct.pack("<9d", *d, *cov6)


def truth_pose_payload(x, y, th) -> bytes:
    return struct.pack("<3d", x, y, th)


def truth_landmark_payload(lid, cls, x, y, diameter, height) -> bytes:
    return struct.pack("<II4d", lid, cls, x, y, diameter, height)


class Reader:
    """Iterate a raw log's records; a truncated last record ends the iteration (`truncated`)."""

    def __init__(self, path: str):
        self.path = path
        self._f = open(path, "rb")
        h = self._f.read(HEADER_SIZE)
        if len(h) < HEADER_SIZE or h[:8] != MAGIC:
            raise RawLogError(f"{path}: not a libcyl raw frame log")
        _, ver, hsize, fcc, w, hgt, stride, nbytes, flags, src = FILE_HEADER.unpack(h)
        if ver != VERSION or hsize != HEADER_SIZE:
            raise RawLogError(f"{path}: raw log version {ver} (header {hsize} B) is not version 1")
        self.info = StreamInfo(fourcc_str(fcc), w, hgt, stride, nbytes, flags, src.rstrip(b"\0").decode("utf-8", "replace"))
        self.truncated = False

    def __iter__(self) -> Iterator[Record]:
        while True:
            h = self._f.read(REC_HEADER.size)
            if not h:
                return
            if len(h) < REC_HEADER.size:
                self.truncated = True
                return
            magic, typ, seq, t_ns, size, flags = REC_HEADER.unpack(h)
            if magic != REC_MAGIC:
                raise RawLogError(f"{self.path}: record at byte {self._f.tell() - REC_HEADER.size}: bad magic")
            p = self._f.read(size)
            if len(p) < size:
                self.truncated = True
                return
            yield Record(typ, seq, t_ns, p, flags)

    def close(self):
        self._f.close()

    def __enter__(self):
        return self

    def __exit__(self, *a):
        self.close()


class Writer:
    """Write a raw log to `path` (cyl.output.OutputFile: `path`.part renamed by close() over a
    regular file; a device node or FIFO written in place, as the C++ tools do)."""

    def __init__(self, path: str, info: StreamInfo):
        self.path = path
        self.info = info
        want = frame_bytes(info.fourcc, info.width, info.height, info.stride)
        if want == 0:
            raise RawLogError(f"{path}: {info.fourcc} {info.width}x{info.height} stride {info.stride}: invalid frame size")
        if info.frame_bytes != want:
            raise RawLogError(f"{path}: {info.fourcc} {info.width}x{info.height} stride {info.stride} frames are "
                              f"{want} bytes, not {info.frame_bytes}")
        try:
            self._out = OutputFile(path)
        except OutputError as e:
            raise RawLogError(str(e)) from None
        self._f = self._out.f
        src = info.source.encode("utf-8")[:23]
        self._f.write(FILE_HEADER.pack(MAGIC, VERSION, HEADER_SIZE, fourcc(info.fourcc), info.width, info.height,
                                       info.stride, info.frame_bytes, info.flags, src.ljust(24, b"\0")))
        self.records = 0

    def write(self, typ: int, seq: int, t_ns: int, payload: bytes, flags: int = 0):
        if typ == FRAME and len(payload) != self.info.frame_bytes:
            raise RawLogError(f"{self.path}: frame {seq} has {len(payload)} bytes, expected {self.info.frame_bytes}")
        self._f.write(REC_HEADER.pack(REC_MAGIC, typ, seq, t_ns, len(payload), flags))
        self._f.write(payload)
        self.records += 1

    def close(self):
        self._out.close()

    def abort(self):
        """Stop without replacing the target (the partial file is removed)."""
        self._out.abort()

    def __enter__(self):
        return self

    def __exit__(self, exc_type, *a):
        if exc_type is None:
            self.close()
        else:
            self.abort()
