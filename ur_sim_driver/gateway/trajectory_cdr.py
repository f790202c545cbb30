"""Reading a serialized trajectory_msgs/JointTrajectory whose points all have one shape, with a few numpy steps.

``cdr.parse_joint_trajectory`` walks the points one by one in Python: about 3 us a point, a third of a second for
100,000. Almost every trajectory a client sends gives every point the same number of positions, velocities,
accelerations and efforts; such points then lie at a fixed stride in the CDR bytes from the third point on (the
padding before a point's first value depends on where the point starts modulo 8, and where a point of a given
shape ends modulo 8 does not), so every field is a strided view of the bytes. :func:`read_joint_trajectory`
reads the header and the first three points, checks every further point's four lengths against that stride at
once, and copies the values out of the views. Any other message (ragged points, few points, malformed bytes) is
read the general way, with the same result and the same errors.
"""
from __future__ import annotations

import struct

import numpy as np

from ur_sim_driver.gateway.cdr import align, parse_joint_trajectory, read_prefix
from ur_sim_driver.motion.command_arrays import CommandArrays

_HEADER = 4  # encapsulation header; alignment counts from its end
_MIN_POINTS = 4  # below this the general reader is as fast


def read_joint_trajectory(data: bytes) -> CommandArrays:
    """CommandArrays of a serialized JointTrajectory (as ``cdr.parse_joint_trajectory``, faster when regular).

    Raises:
        TrajectoryError: the bytes are not a well-formed JointTrajectory.
    """
    try:
        regular = _read_regular(data)
    except (struct.error, ValueError, IndexError, UnicodeDecodeError):
        regular = None  # the general reader words the error
    return regular if regular is not None else parse_joint_trajectory(data)




class _Layout:
    """Where one point's parts lie, relative to its first byte."""

    def __init__(self, data: bytes, start: int, u32) -> None:
        pos = start
        self.sizes = [0, 0, 0, 0]
        self.count_at = [0, 0, 0, 0]  # offset of each field's uint32 length
        self.values_at = [0, 0, 0, 0]  # offset of each field's first value (when it has any)
        for field in range(4):
            pos = align(pos, 4)
            self.count_at[field] = pos - start
            (m,) = u32(data, pos)
            pos += 4
            if m:
                pos = align(pos, 8)
                self.values_at[field] = pos - start
                self.sizes[field] = m
                pos += 8 * m
        pos = align(pos, 4)
        self.time_at = pos - start
        self.end = pos + 8


def _read_regular(data: bytes) -> CommandArrays | None:
    if len(data) < _HEADER or data[1] not in (0, 1):
        return None
    order = '<' if data[1] == 1 else '>'
    u32 = struct.Struct(order + 'I').unpack_from
    stamp = struct.Struct(order + 'iI').unpack_from
    sec, nanosec, names, count, pos = read_prefix(data, order)
    if count < _MIN_POINTS:
        return None
    # The first two points are read one by one: where the first ends decides the padding of the second; from
    # the third on, every point of the same shape starts at the same offset modulo 8.
    head = [_Layout(data, pos, u32)]
    head.append(_Layout(data, head[0].end, u32))
    base = head[1].end
    block = _Layout(data, base, u32)
    stride = block.end - base
    rest = count - len(head)
    if stride % 8 or base + rest * stride > len(data):
        return None
    u32_dtype, i32_dtype, f8_dtype = np.dtype(order + 'u4'), np.dtype(order + 'i4'), np.dtype(order + 'f8')

    def column(offset: int, dtype: np.dtype, width: int = 1) -> np.ndarray:
        """(rest, width) view of one part of the points from the third on."""
        return np.ndarray((rest, width), dtype=dtype, buffer=data, offset=base + offset,
                          strides=(stride, dtype.itemsize))

    for field in range(4):
        if not (column(block.count_at[field], u32_dtype) == block.sizes[field]).all():
            return None
    sizes = np.empty((count, 4), dtype=np.int64)
    sizes[:len(head)] = [h.sizes for h in head]
    sizes[len(head):] = block.sizes
    values = []
    for field in range(4):
        m = block.sizes[field]
        out = np.empty(sum(h.sizes[field] for h in head) + rest * m, dtype=np.float64)
        at = 0
        for h, start in zip(head, (pos, head[0].end)):
            n = h.sizes[field]
            if n:
                out[at:at + n] = np.frombuffer(data, dtype=f8_dtype, count=n, offset=start + h.values_at[field])
            at += n
        if m:
            out[at:].reshape(rest, m)[:] = column(block.values_at[field], f8_dtype, m)
        values.append(out)
    stamps = np.empty((count, 2), dtype=np.int64)
    for k, (h, start) in enumerate(zip(head, (pos, head[0].end))):
        stamps[k] = stamp(data, start + h.time_at)
    stamps[len(head):, 0] = column(block.time_at, i32_dtype)[:, 0]
    stamps[len(head):, 1] = column(block.time_at + 4, u32_dtype)[:, 0]
    times = stamps[:, 0] + stamps[:, 1] * 1e-9
    return CommandArrays(tuple(names), sec + nanosec * 1e-9, times, sizes, tuple(values))
