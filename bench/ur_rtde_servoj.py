"""`python -m bench.ur_rtde_servoj HOST SECONDS`: a ur_rtde user's servoJ loop, for the URScript benchmark.

RTDEControlInterface uploads ur_rtde's control script (ur_sim's interpreter runs it) and the loop streams servoJ at
500 Hz in real time, wrist_3 on a slow sine, for SECONDS; then servoStop and stopScript. Prints one JSON line: the
commands sent, their rate and how far the arm lagged. The loop sleeps to its next 2 ms deadline: ur_rtde's own
waitPeriod spins, and on a 2-core machine that core would be taken from ur_sim, which is what is measured.
"""
from __future__ import annotations

import json
import math
import sys
import time

import rtde_control
import rtde_receive

READY = [0.0, -1.2, 1.2, -1.57, -1.57, 0.0]
DT = 0.002  # [s] 500 Hz


def main() -> int:
    host, seconds = sys.argv[1], float(sys.argv[2])
    receive = rtde_receive.RTDEReceiveInterface(host)
    control = rtde_control.RTDEControlInterface(host)
    control.moveJ(READY, 1.0, 1.0)
    lag = 0.0
    start = time.monotonic()
    k = 0
    deadline = start
    while time.monotonic() - start < seconds:
        q = list(READY)
        q[5] = 0.3 * math.sin(0.5 * k * DT)  # [rad] 0.15 rad/s at most
        control.servoJ(q, 0.5, 0.5, DT, 0.1, 300)
        if k % 50 == 0:
            lag = max(lag, abs(receive.getActualQ()[5] - q[5]))
        k += 1
        deadline += DT
        time.sleep(max(0.0, deadline - time.monotonic()))
    control.servoStop()
    control.stopScript()
    print(json.dumps({'commands': k, 'rate_hz': k / (time.monotonic() - start), 'max_lag_rad': lag}))
    return 0


if __name__ == '__main__':
    sys.exit(main())
