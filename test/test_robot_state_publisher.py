"""robot_state_publisher and the tcp_pose_broadcaster's frame over DDS.

No tf2_ros for Python comes from PyPI, so the lookups are done here: the transforms received on /tf_static
and /tf for one stamp are composed along the tree, and compared with Pinocchio's forward kinematics of the
URDF received on /robot_description at the joint positions published on /joint_states with that stamp.
"""
import threading

import numpy as np
import pinocchio as pin
import pytest
from geometry_msgs.msg import WrenchStamped
from sensor_msgs.msg import JointState
from sim_harness import point, running_sim, wait_for
from std_msgs.msg import String
from tf2_msgs.msg import TFMessage

from ur_sim_driver.errors import ConfigError
from ur_sim_driver.robot.sim_config import sim_config_from_params

FK_TOL = 1e-9  # base_link -> tool0 from TF against Pinocchio
# tool0_controller is MuJoCo's tool0 site pose (its own kinematics, rotation matrix -> quaternion) while
# tool0 is composed from URDF origins: both in double precision, they agree to rounding.
TCP_TOL = 1e-12


def stamp_ns(msg) -> int:
    return msg.header.stamp.sec * 1_000_000_000 + msg.header.stamp.nanosec


def matrix(tf) -> np.ndarray:
    t, r = tf.transform.translation, tf.transform.rotation
    out = np.eye(4)
    out[:3, :3] = pin.Quaternion(r.w, r.x, r.y, r.z).toRotationMatrix()
    out[:3, 3] = [t.x, t.y, t.z]
    return out


class TfRecorder:
    """What robot_state_publisher and tcp_pose_broadcaster publish, and the joint states, keyed by stamp."""

    def __init__(self, h) -> None:
        self.lock = threading.Lock()
        self.static: dict[str, tuple[str, np.ndarray]] = {}
        self.tf: dict[int, dict[str, tuple[str, np.ndarray]]] = {}
        self.joint_stamps: list[int] = []  # stamps of /tf messages with the arm joints, in arrival order
        self.frames: set[str] = set()
        self.q: dict[int, np.ndarray] = {}
        self.joint_names: list[str] = []
        self.urdf: str | None = None
        self.wrench_frames: set[str] = set()
        self.tcp_frame = f'{h.sim.cfg.tf_prefix}tool0_controller'
        p = h.sim.cfg.prefixed
        h.listen(TFMessage, '/tf_static', self._on_static, latched=True)
        h.listen(TFMessage, '/tf', self._on_tf)
        h.listen(JointState, p('joint_states'), self._on_js)
        h.listen(String, p('robot_description'), self._on_description, latched=True)
        h.listen(WrenchStamped, p('force_torque_sensor_broadcaster/wrench'),
                 lambda m: self.wrench_frames.add(m.header.frame_id), depth=10)

    def _on_static(self, msg) -> None:
        with self.lock:
            for tf in msg.transforms:
                self.static[tf.child_frame_id] = (tf.header.frame_id, matrix(tf))
                self.frames |= {tf.child_frame_id, tf.header.frame_id}

    def _on_tf(self, msg) -> None:
        with self.lock:
            for tf in msg.transforms:
                self.tf.setdefault(stamp_ns(tf), {})[tf.child_frame_id] = (tf.header.frame_id, matrix(tf))
                self.frames |= {tf.child_frame_id, tf.header.frame_id}
            if len(msg.transforms) > 1:
                self.joint_stamps.append(stamp_ns(msg.transforms[0]))

    def _on_js(self, msg) -> None:
        with self.lock:
            self.q[stamp_ns(msg)] = np.array(msg.position)
            self.joint_names = list(msg.name)

    def _on_description(self, msg) -> None:
        self.urdf = msg.data

    def complete(self) -> list[int]:
        """Stamps of the arm joints' /tf messages whose joint state and tool0_controller (published apart, by
        tcp_pose_broadcaster) have arrived too, oldest first: the publishers' messages of one cycle arrive in any
        order."""
        with self.lock:
            return [s for s in self.joint_stamps if s in self.q and self.tcp_frame in self.tf.get(s, {})]

    def lookup(self, target: str, source: str, stamp: int) -> np.ndarray:
        """Pose (4, 4) of frame `source` in frame `target` at `stamp` (a tf2 lookup, done by hand)."""
        with self.lock:
            edges = {**self.static, **self.tf.get(stamp, {})}
        out, frame = np.eye(4), source
        while frame != target:
            if frame not in edges:
                raise KeyError(f'no transform to {frame} at {stamp} ns')
            parent, t = edges[frame]
            out, frame = t @ out, parent
        return out


def check_frames_against_fk(rec: TfRecorder, prefix: str, count: int, after: int) -> float:
    """Compare base_link -> tool0 (and -> tool0_controller) with Pinocchio at the first `count` stamps after
    `after` [ns] (the motion's start: the arm moves through them however late the check runs); the largest
    tool0_controller - tool0 difference."""
    model = pin.buildModelFromXML(rec.urdf)
    data = model.createData()
    tool0 = model.getFrameId(f'{prefix}tool0')
    order = [model.getJointId(n) for n in rec.joint_names]  # published order -> Pinocchio's q index
    stamps = [s for s in rec.complete() if s > after][:count]
    assert len(stamps) == count
    tcp_diff = 0.0
    moved = set()
    for s in stamps:
        q = np.zeros(model.nq)
        for k, jid in enumerate(order):
            q[model.joints[jid].idx_q] = rec.q[s][k]
        moved.add(tuple(np.round(q, 6)))
        pin.framesForwardKinematics(model, data, q)
        fk = data.oMf[tool0].homogeneous
        np.testing.assert_allclose(rec.lookup(f'{prefix}base_link', f'{prefix}tool0', s), fk, rtol=0, atol=FK_TOL)
        tcp = rec.lookup(f'{prefix}base_link', f'{prefix}tool0_controller', s)
        tcp_diff = max(tcp_diff, float(np.abs(tcp - fk).max()))
    assert len(moved) > 1, 'the arm did not move between the stamps compared'
    return tcp_diff


def assert_published_every(stamps_ns: np.ndarray, period: float) -> None:
    """The arm joints' /tf stamps [ns] (arrival order) are `period` [s] of simulated time apart: every gap a whole
    number of periods and the shortest one period. A real-time listener on a loaded machine can lose messages (its
    queue overflows; /tf carries tool0_controller every cycle too), which leaves a gap of several periods."""
    gaps = np.diff(np.sort(np.unique(stamps_ns))) * 1e-9
    assert len(gaps) >= 5, f'only {len(gaps) + 1} /tf messages of the arm joints'
    periods = gaps / period
    np.testing.assert_allclose(periods, np.round(periods), atol=1e-4)
    assert gaps.min() == pytest.approx(period, abs=1e-6), gaps


def move_and_record(h, rec: TfRecorder, target, duration: float, count: int) -> int:
    """Move to `target` in `duration` [s] and record until `count` complete stamps after the goal's acceptance have
    come; returns the acceptance's stamp [ns]."""
    wait_for(lambda: rec.urdf is not None and rec.static, what='/robot_description and /tf_static')
    handle = h.send(h.goal([point(target, duration, np.zeros(6))]))
    assert handle.accepted
    # Counted by stamp, not by arrival: the listeners' threads may still be delivering older /tf messages.
    accepted_ns = h.sim.clock.origin_ns + round(h.sim.sim.time * 1e9)  # in real time on the system clock

    wait_for(lambda: sum(s > accepted_ns for s in rec.complete()) >= count,
             what=f'{count} /tf messages of the arm joints, with their joint states and tool0_controller, after the '
                  'goal was accepted')
    return accepted_ns


def test_tf_equals_forward_kinematics_of_the_joint_states():
    with running_sim(real_time_factor=1.0) as h:
        rec = TfRecorder(h)
        accepted = move_and_record(h, rec, h.q + np.array([0.4, -0.3, 0.5, 0.3, -0.4, 0.6]), 1.0, 12)
        tcp_diff = check_frames_against_fk(rec, '', 10, accepted)
        print(f'tool0_controller vs tool0: largest difference {tcp_diff:.2e}')
        assert tcp_diff < TCP_TOL
        with rec.lock:
            stamps = np.array(rec.joint_stamps)
            frames = set(rec.frames)
        # 20 Hz of simulated time (the default publish_frequency).
        assert_published_every(stamps, 0.05)
        assert {'base_link', 'base', 'base_link_inertia', 'shoulder_link', 'wrist_3_link', 'flange', 'tool0',
                'ft_frame', 'ee_link', 'tool0_controller'} <= frames


def test_tf_prefix_on_every_frame_and_publish_frequency():
    prefix = 'my_ur_'
    with running_sim(tf_prefix=prefix, publish_frequency=50.0, tool='dispenser', real_time_factor=1.0) as h:
        rec = TfRecorder(h)
        accepted = move_and_record(h, rec, h.q + np.array([-0.3, 0.2, -0.2, 0.4, 0.3, -0.5]), 1.0, 12)
        check_frames_against_fk(rec, prefix, 10, accepted)
        wait_for(lambda: rec.wrench_frames, what='a wrench')
        with rec.lock:
            stamps = np.array(rec.joint_stamps)
            frames = set(rec.frames)
        assert all(f.startswith(prefix) for f in frames), sorted(frames)
        assert {f'{prefix}dispenser', f'{prefix}dispenser_tip', f'{prefix}tool0_controller'} <= frames
        assert rec.wrench_frames == {f'{prefix}tool0_controller'}
        assert all(n.startswith(prefix) for n in rec.joint_names)
        assert_published_every(stamps, 0.02)


@pytest.mark.parametrize('value', [0.0, -20.0, float('nan'), 'fast', 2000.0])
def test_publish_frequency_is_validated(value):
    with pytest.raises(ConfigError, match='publish_frequency'):
        sim_config_from_params({'publish_frequency': value})
