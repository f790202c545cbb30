"""Reading a serialized trajectory_msgs/JointTrajectory (CDR, as it arrives on a raw subscription) into arrays.

rclpy turns a received message into one Python object per point and per array, about 10 us a point while
holding the GIL; for 100,000 points that is a second in which no other thread of the process runs. Taking
the message raw and reading the CDR bytes here costs a few microseconds a point and yields the flat arrays
validation works on (:class:`command_arrays.CommandArrays`).

Layout (OMG CDR, XCDR1 as ROS 2's DDS implementations send it): a 4-byte encapsulation header whose second
byte gives the byte order, then the fields in declaration order, each aligned to its size counted from the
end of the header; a string is a uint32 length (with its terminating NUL) and the bytes; a sequence a uint32
count and the elements.
"""
from __future__ import annotations

import struct

import numpy as np

from ur_sim_driver.errors import TrajectoryError
from ur_sim_driver.motion.command_arrays import CommandArrays

_HEADER = 4  # encapsulation header; alignment counts from its end


def parse_joint_trajectory(data: bytes) -> CommandArrays:
    """CommandArrays of a serialized JointTrajectory.

    Raises:
        TrajectoryError: the bytes are not a well-formed JointTrajectory.
    """
    try:
        return _parse(data)
    except (struct.error, ValueError, IndexError) as exc:
        raise TrajectoryError(f'malformed JointTrajectory message ({len(data)} bytes): {exc}') from None


def align(pos: int, size: int) -> int:
    """`pos` rounded up to a multiple of `size` [bytes], counted from the end of the encapsulation header."""
    return pos + (-(pos - _HEADER)) % size


def read_prefix(data: bytes, order: str) -> tuple[int, int, list[str], int, int]:
    """What precedes the points of a serialized JointTrajectory in byte order `order` ('<' or '>'):
    header.stamp (sec, nanosec), joint_names, the point count and the byte offset of the first point."""
    u32 = struct.Struct(order + 'I').unpack_from
    sec, nanosec = struct.Struct(order + 'iI').unpack_from(data, _HEADER)
    (length,) = u32(data, _HEADER + 8)  # header.frame_id (not kept)
    pos = align(_HEADER + 12 + length, 4)
    (name_count,) = u32(data, pos)
    pos += 4
    names = []
    for _ in range(name_count):
        pos = align(pos, 4)
        (length,) = u32(data, pos)
        names.append(bytes(data[pos + 4:pos + 3 + length]).decode())
        pos += 4 + length
    pos = align(pos, 4)
    (count,) = u32(data, pos)
    return sec, nanosec, names, count, pos + 4


def _parse(data: bytes) -> CommandArrays:
    if len(data) < _HEADER or data[1] not in (0, 1):
        raise ValueError('not CDR: unknown encapsulation header')
    order = '<' if data[1] == 1 else '>'
    u32 = struct.Struct(order + 'I').unpack_from
    time = struct.Struct(order + 'iI').unpack_from
    f8 = np.dtype(order + 'f8')
    sec, nanosec, names, count, pos = read_prefix(data, order)
    sizes = np.zeros((count, 4), dtype=np.int64)
    starts = np.zeros((count, 4), dtype=np.int64)  # byte offset of each array's first element
    stamps = np.zeros((count, 2), dtype=np.int64)
    for k in range(count):
        for field in range(4):
            pos = align(pos, 4)
            (m,) = u32(data, pos)
            pos += 4
            if m:
                pos = align(pos, 8)
                starts[k, field] = pos
                sizes[k, field] = m
                pos += 8 * m
        pos = align(pos, 4)
        stamps[k] = time(data, pos)
        pos += 8
    if pos > len(data):
        raise ValueError(f'the message ends at byte {len(data)}, before its last point (byte {pos})')
    raw = np.frombuffer(data, dtype=np.uint8)
    values = tuple(_gather(raw, starts[:, f], sizes[:, f], f8) for f in range(4))
    times = stamps[:, 0] + stamps[:, 1] * 1e-9
    return CommandArrays(tuple(names), sec + nanosec * 1e-9, times, sizes, values)


def _gather(raw: np.ndarray, starts: np.ndarray, sizes: np.ndarray, dtype: np.dtype) -> np.ndarray:
    """Concatenate the float64 runs (start byte, element count) of one field, point after point."""
    total = int(sizes.sum())
    if total == 0:
        return np.zeros(0)
    # Byte index of every element: each run's start repeated, plus 8 x the element's index in its run.
    run_of = np.repeat(np.arange(len(sizes)), sizes)
    first = np.cumsum(sizes) - sizes
    within = np.arange(total) - first[run_of]
    byte = starts[run_of] + 8 * within
    idx = byte[:, None] + np.arange(8)
    return raw[idx].view(dtype).reshape(total).astype(np.float64)
