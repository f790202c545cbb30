"""Messages serialized once and patched in place: the per-cycle topics published as CDR bytes.

rclpy converts a message object to its C form on every publish, about 20-30 us for a JointState; publishing
bytes it already has costs about 3 us. The topics ur_sim publishes every control cycle keep their shape (names,
frame ids, array lengths) from one cycle to the next and only their stamps and float64 values change, so each is
serialized once by rclpy itself, the byte offsets of the changing fields are found, and every cycle writes the new
values into those bytes. What goes on the wire decodes to exactly the message rclpy would have serialized
(``test_cdr_template`` compares them for random values; only CDR's alignment padding may differ, which carries
nothing).

The offsets are found by serializing the prototype with a distinct sentinel in every changing field and searching
the bytes for it (a sentinel must occur exactly once). In CDR every float64 sits 8-aligned counted from the end of
the 4-byte encapsulation header, and every 32-bit integer 4-aligned, so one float64 view (from byte 4) and one
uint32 view (from byte 0) of the buffer reach all of them: a cycle's patch is two fancy-index assignments.

A message no subscription is matched to reaches no one: DDS delivers a sample only to the readers its writer has
matched when it is written, and these topics are volatile (no late joiner gets an old sample). So each cycle asks
DDS (``listened``, 0.13 us) and builds and sends only what someone receives; what that buys is in
``docs/performance.md``.
"""
from __future__ import annotations

import random
import re
import struct
from collections.abc import Callable, Sequence

import numpy as np
from rclpy.publisher import Publisher
from rclpy.qos import DurabilityPolicy
from rclpy.serialization import serialize_message

from ur_sim_driver.errors import UrSimError

_HEADER = 4  # CDR encapsulation header; alignment counts from its end
_STEP = re.compile(r'([A-Za-z_]\w*)(?:\[(\d+)\])?$')


def _resolve(msg: object, path: str) -> tuple[object, str]:
    """(object, attribute) named by a dotted path such as 'transforms[0].header.stamp'."""
    *parents, leaf = path.split('.')
    obj = msg
    for step in parents:
        match = _STEP.match(step)
        if match is None:
            raise UrSimError(f'bad field path {path!r} at {step!r}')
        try:
            obj = getattr(obj, match.group(1))
            if match.group(2) is not None:
                obj = obj[int(match.group(2))]
        except (AttributeError, IndexError):
            raise UrSimError(f'{type(msg).__name__} has no field {path!r}') from None
    if not hasattr(obj, leaf):
        raise UrSimError(f'{type(msg).__name__} has no field {path!r}')
    return obj, leaf


class CdrTemplate:
    """One message's serialized bytes with writable stamps and float64 fields.

    Args:
        prototype: the message as published, with every array at its published length (its other fields, e.g.
            names and frame ids, are serialized as they are).
        stamps: paths of builtin_interfaces/Time fields, e.g. 'header.stamp'.
        floats: paths of float64 fields or float64[] fields, e.g. 'position' or 'pose.position.x'. `render`
            takes their values flattened in this order.
        publisher: the rclpy publisher `publish` sends on (of the prototype's type).

    Raises:
        UrSimError: a path names no field, or a field's sentinel could not be located once.
    """

    def __init__(self, prototype: object, stamps: Sequence[str] = (), floats: Sequence[str] = (),
                 publisher: Publisher | None = None) -> None:
        rng = random.Random(0x5EED)
        slots: list[tuple[object, str, list[float] | float]] = []
        for path in floats:
            obj, leaf = _resolve(prototype, path)
            value = getattr(obj, leaf)
            if isinstance(value, float):
                sentinel: list[float] | float = _sentinel_double(rng)
            else:
                sentinel = [_sentinel_double(rng) for _ in range(len(value))]
            slots.append((obj, leaf, sentinel))
        stamp_slots = []
        for path in stamps:
            obj, leaf = _resolve(prototype, path)
            stamp = getattr(obj, leaf)
            stamp_slots.append((stamp, rng.randrange(1 << 30, 1 << 31), rng.randrange(1, 999_999_999)))
        saved = [(obj, leaf, getattr(obj, leaf)) for obj, leaf, _ in slots]
        saved_stamps = [(s, s.sec, s.nanosec) for s, _, _ in stamp_slots]
        try:
            for obj, leaf, sentinel in slots:
                setattr(obj, leaf, sentinel)
            for stamp, sec, nanosec in stamp_slots:
                stamp.sec, stamp.nanosec = sec, nanosec
            marked = serialize_message(prototype)
        finally:
            for obj, leaf, value in saved:
                setattr(obj, leaf, value)
            for stamp, sec, nanosec in saved_stamps:
                stamp.sec, stamp.nanosec = sec, nanosec
        little = marked[1] == 1
        order = '<' if little else '>'
        double_index: list[int] = []
        for (_, _, sentinel), path in zip(slots, floats):
            for value in (sentinel if isinstance(sentinel, list) else [sentinel]):
                offset = _locate(marked, struct.pack(order + 'd', value), path)
                if (offset - _HEADER) % 8:
                    raise UrSimError(f'field {path!r} is not 8-aligned in the CDR of {type(prototype).__name__}')
                double_index.append((offset - _HEADER) // 8)
        word_index: list[int] = []
        for (_, sec, nanosec), path in zip(stamp_slots, stamps):
            offset = _locate(marked, struct.pack(order + 'iI', sec, nanosec), path)
            word_index += [offset // 4, offset // 4 + 1]
        self.size = len(double_index)
        self.stamp_count = len(stamps)
        self._buffer = bytearray(serialize_message(prototype))
        self._doubles = np.frombuffer(self._buffer, dtype=order + 'f8', offset=_HEADER,
                                      count=(len(self._buffer) - _HEADER) // 8)
        self._words = np.frombuffer(self._buffer, dtype=order + 'u4', count=len(self._buffer) // 4)
        self._double_index = np.array(double_index, dtype=np.intp)
        self._word_index = np.array(word_index, dtype=np.intp)
        self._publish_raw = raw_publish(publisher) if publisher is not None else None
        self.listened = listened(publisher) if publisher is not None else (lambda: False)

    def render(self, values: np.ndarray | Sequence[float], stamp: tuple[int, ...] | None = None) -> bytes:
        """The message's bytes with `values` (the float fields flattened, in order) and every stamp set to `stamp`
        (sec, nanosec), or each to its own pair when `stamp` has one per stamp path (Time or Duration fields); a stamp
        not given keeps its last value."""
        self._patch(values, stamp)
        return bytes(self._buffer)

    def publish(self, values: np.ndarray | Sequence[float], stamp: tuple[int, int] | None = None) -> None:
        """Render (see `render`) and publish on the template's publisher."""
        if self._publish_raw is None:
            raise UrSimError('this CdrTemplate was made without a publisher: use render()')
        self._patch(values, stamp)
        self._publish_raw(bytes(self._buffer))

    def _patch(self, values: np.ndarray | Sequence[float], stamp: tuple[int, int] | None) -> None:
        if self.size:
            self._doubles[self._double_index] = values
        if stamp is not None and self.stamp_count:
            # One (sec, nanosec) for every stamp, or a pair each in the order of `stamps`; a negative Duration's
            # int32 sec goes into its unsigned word as two's complement.
            if len(stamp) == 2 or self.stamp_count == 1:  # one Time for every stamp (non-negative): every cycle
                self._words[self._word_index] = stamp * self.stamp_count
            else:  # a pair each, a Duration possibly negative (controller_state, while someone listens)
                self._words[self._word_index] = [w & 0xFFFFFFFF for w in stamp]


def listened(publisher: Publisher) -> Callable[[], bool]:
    """A call that tells whether a subscription is matched to `publisher` now (DDS's matched readers, asked each
    call). A transient-local publisher counts as always listened to: a late joiner receives what it kept."""
    if publisher.qos_profile.durability == DurabilityPolicy.TRANSIENT_LOCAL:
        return lambda: True
    count = publisher.handle.get_subscription_count
    return lambda: count() > 0


def raw_publish(publisher: Publisher) -> Callable[[bytes], None]:
    """`publisher`'s publish of serialized bytes, without rclpy's wrapper around it (a type dispatch and a guard
    against the publisher's destruction meanwhile: half the cost of a publish). For the simulation loop, which
    has stopped before any node is destroyed."""
    return publisher.handle.publish_raw


def _sentinel_double(rng: random.Random) -> float:
    """A finite double with random bits: it occurs nowhere else in a message by chance."""
    while True:
        (value,) = struct.unpack('<d', rng.getrandbits(64).to_bytes(8, 'little'))
        if np.isfinite(value) and value != 0.0:
            return value


def _locate(data: bytes, pattern: bytes, path: str) -> int:
    first = data.find(pattern)
    if first < 0 or data.find(pattern, first + 1) >= 0:
        raise UrSimError(f'field {path!r} could not be located in the serialized message')
    return first
