"""Off-screen rendering of the report picture (EGL)."""
import matplotlib.pyplot as plt
import numpy as np

from ur_glue_planner.report.render import render_paths
from ur_glue_planner.scene.windshield import windshield_pose
from ur_sim_driver.description.params import load_ur_params
from ur_sim_driver.description.tool import get_tool


def test_render_draws_the_path_over_the_windshield(tmp_path):
    from pathlib import Path
    mesh = Path(__file__).resolve().parents[1] / 'meshes' / 'windshield.stl'
    q = np.array([0.0, -1.57, 1.2, -1.2, -1.57, 0.0])
    path = np.column_stack([np.linspace(-0.3, 0.3, 50), np.full(50, 0.6), np.full(50, 0.3)])
    plain = render_paths(load_ur_params('ur5'), get_tool('dispenser'), q, [('windshield', mesh, windshield_pose())], [],
                         tmp_path / 'plain.png', width=480, height=360)
    drawn = render_paths(load_ur_params('ur5'), get_tool('dispenser'), q, [('windshield', mesh, windshield_pose())],
                         [(path, (1.0, 0.0, 0.0, 1.0))], tmp_path / 'drawn.png', width=480, height=360)
    a, b = plt.imread(plain), plt.imread(drawn)
    assert a.shape[:2] == (360, 480)
    changed = np.abs(a[..., :3] - b[..., :3]).sum(axis=2) > 0.1
    assert changed.sum() > 50  # the red path is visible
    red = (b[..., 0] > 0.6) & (b[..., 1] < 0.3) & (b[..., 2] < 0.3)
    assert red.sum() > 20
