"""Robot description benchmark: wall time to generate and load each UR type's model, with the dispenser, as ur_sim
does at start-up (the MJCF into MuJoCo, the URDF into Pinocchio). Writes out/bench/description.json (through
`python -m bench`). These bounds were asserts in test_description_mjcf.py and test_description_urdf.py."""
from __future__ import annotations

import os
import platform
import time

import mujoco
import numpy as np
import pinocchio as pin

from ur_sim_driver.description.mjcf import build_mjcf
from ur_sim_driver.description.params import UR_TYPES, load_ur_params
from ur_sim_driver.description.tool import DISPENSER
from ur_sim_driver.description.urdf import build_urdf

TARGET_MS = 1000.0  # generate and load one model


def _ms(fn, repeats: int) -> dict:
    """Wall time [ms] of ``repeats`` calls of ``fn``, the first (cold) one included."""
    times = []
    for _ in range(repeats):
        t0 = time.perf_counter()
        fn()
        times.append(1e3 * (time.perf_counter() - t0))
    return {'first': times[0], 'median': float(np.median(times)), 'max': float(np.max(times))}


def run(repeats: int = 5) -> dict:
    base_pose = np.eye(4)
    base_pose[:3, 3] = (0.1, 0.2, 0.5)
    models = {}
    for ur_type in UR_TYPES:
        p = load_ur_params(ur_type)
        models[ur_type] = {
            'mjcf_build_and_load_ms': _ms(lambda p=p: mujoco.MjModel.from_xml_string(
                build_mjcf(p, 'r_', DISPENSER, base_pose, timestep=0.001)), repeats),
            'urdf_build_and_load_ms': _ms(lambda p=p: pin.buildModelFromXML(build_urdf(p, tool=DISPENSER)),
                                              repeats),
        }
    worst = max(m[k]['max'] for m in models.values() for k in m)
    return {'repeats': repeats, 'models': models, 'target_ms': TARGET_MS, 'meets_target': worst <= TARGET_MS,
            'load_average_1min': os.getloadavg()[0],
            'machine': {'cpus': os.cpu_count(), 'python': platform.python_version(),
                        'processor': platform.processor() or platform.machine()}}


if __name__ == '__main__':
    import json
    print(json.dumps(run(), indent=2))
