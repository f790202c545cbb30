"""Array types of the compiled kernels' signatures (servo, torque control, MjData readout).

Signatures are given explicitly so that each kernel is compiled (or loaded from numba's disk cache) when its module
is imported, never in the middle of a control cycle. Inputs are typed read-only, any layout: a writable array is
accepted where a read-only one is declared, and the trajectory's frozen arrays are read-only.
"""
from numba import types

IN1 = types.Array(types.float64, 1, 'A', readonly=True)  # (n,) input
IN2 = types.Array(types.float64, 2, 'A', readonly=True)  # (n, m) input
INDEX = types.Array(types.int64, 1, 'A', readonly=True)  # (n,) indices
OUT1 = types.Array(types.float64, 1, 'A')  # (n,) written
OUT2 = types.Array(types.float64, 2, 'A')  # (n, m) written
FLAGS = types.Array(types.boolean, 1, 'A')  # (n,) written
F8, I8, B1, VOID = types.float64, types.int64, types.boolean, types.void
