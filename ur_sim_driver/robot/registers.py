"""The controller's general purpose registers, as RTDE and URScript see them: 128 bits, 48 integers and 48 doubles
each for input (written by a client) and output (written by the robot's program). Mutable; read and write them
under the simulation lock. No ROS here."""
from __future__ import annotations

N_BITS, N_INTS, N_DOUBLES = 128, 48, 48


class Registers:
    """Input and output registers, all zero (False) at start, as after a controller boot."""

    def __init__(self) -> None:
        self.input_bits = [False] * N_BITS
        self.input_ints = [0] * N_INTS
        self.input_doubles = [0.0] * N_DOUBLES
        self.output_bits = [False] * N_BITS
        self.output_ints = [0] * N_INTS
        self.output_doubles = [0.0] * N_DOUBLES


def bits_word(bits: list[bool], first: int) -> int:
    """Bits `first`..`first + 31` as one unsigned 32-bit word (bit 0: register `first`)."""
    return sum(1 << k for k in range(32) if bits[first + k])


def set_bits_word(bits: list[bool], first: int, word: int) -> None:
    """Registers `first`..`first + 31` from the unsigned 32-bit `word`."""
    for k in range(32):
        bits[first + k] = bool(word >> k & 1)
