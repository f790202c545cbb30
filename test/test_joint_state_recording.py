"""Recorded joint states resampled on a fixed grid of message time (pure: no ROS)."""
import numpy as np
import pytest

from ur_glue_planner.errors import ClientError
from ur_glue_planner.execution.joint_state_recording import STAMP_TIE, JointStateRecorder, JointStateSample

pytestmark = pytest.mark.timeout(30)
NAMES = ('a', 'b')


def _sample(t: float, value: float) -> JointStateSample:
    return JointStateSample(t, NAMES, np.array([value, -value]), np.array([1.0, 2.0]), np.array([0.5, 0.25]))


def _recorder(stamps, rate: float = 50.0, t0: float | None = None) -> JointStateRecorder:
    recorder = JointStateRecorder(rate, t0)
    recorder.samples.extend(_sample(t, float(k)) for k, t in enumerate(stamps))
    return recorder


def test_each_grid_time_takes_the_newest_message_at_or_before_it():
    # Messages every 8 ms (a CB3 at 125 Hz), sampled at 50 Hz (every 20 ms) from the first message.
    recorder = _recorder([0.008 * k for k in range(13)])
    rec = recorder.resample()
    assert np.allclose(rec.t, [0.0, 0.02, 0.04, 0.06, 0.08])
    # 0.02 s -> the message of 0.016 s (index 2), 0.04 -> 0.040 (5), 0.06 -> 0.056 (7), 0.08 -> 0.080 (10)
    assert rec.q[:, 0].tolist() == [0.0, 2.0, 5.0, 7.0, 10.0]
    assert rec.q[:, 1].tolist() == [-0.0, -2.0, -5.0, -7.0, -10.0]
    assert rec.qd.shape == rec.effort.shape == (5, 2)


def test_a_duration_keeps_the_first_samples_only():
    rec = _recorder([0.008 * k for k in range(13)]).resample(duration=0.05)
    assert len(rec.t) == 2  # k < 0.05 s x 50 Hz, rounded: 2 (N = tf x rate)


def _stamp(ns: int) -> float:
    """A stamp as the client reads it: sec + nanosec x 1e-9."""
    return ns // 1_000_000_000 + (ns % 1_000_000_000) * 1e-9


def test_stamps_on_the_system_clock_land_on_their_own_grid_time():
    # About 1.8e9 s, float seconds resolve 0.24 us: the message exactly on grid time 7 (0.14 s) reads as 0.2 us
    # before it, and without the tie the sample would take the message before.
    start = 1_795_000_000_015_555_554  # [ns]
    stamps = [_stamp(start + 2_000_000 * k) for k in range(81)]  # 500 Hz
    t0 = stamps[0]
    assert stamps[70] < t0 + 7 / 50.0  # the case that needs the tie
    rec = _recorder(stamps, t0=t0).resample()
    assert rec.q[:, 0].tolist() == [10.0 * k for k in range(9)]
    assert STAMP_TIE < 0.5 * 0.002  # far below a control period: no neighbouring message is taken for another


def test_a_start_after_the_newest_message_is_refused_with_both_times():
    recorder = _recorder([0.0, 0.002], t0=1.0)
    with pytest.raises(ClientError, match=r'no joint states at or after the recording start t0 = 1\.000 s '
                                          r'\(newest stamp 0\.002 s\)'):
        recorder.resample()


def test_raw_keeps_every_message_relative_to_the_start_earlier_ones_negative():
    rec = _recorder([0.0, 0.002, 0.004], t0=0.002).raw()
    assert np.allclose(rec.t, [-0.002, 0.0, 0.002])
    assert rec.q[:, 0].tolist() == [0.0, 1.0, 2.0]


def test_nothing_recorded_is_an_error_not_an_empty_recording():
    with pytest.raises(ClientError, match='no joint states were received while recording'):
        JointStateRecorder(50.0).resample()
    with pytest.raises(ClientError, match='no joint states were received while recording'):
        JointStateRecorder(50.0).raw()


class _ArrivingDuringRead(list):
    """Samples to which the spinning thread appends one more message once they have been read through once."""

    def __iter__(self):
        yield from list.__iter__(self)
        if len(self) == 3:
            self.append(_sample(0.024, 3.0))


@pytest.mark.parametrize('read', ['raw', 'resample'])
def test_a_message_arriving_while_the_recording_is_read_does_not_tear_it(read):
    recorder = JointStateRecorder(125.0)
    recorder.samples = _ArrivingDuringRead(_sample(0.008 * k, float(k)) for k in range(3))
    rec = getattr(recorder, read)()
    assert len(rec.t) == len(rec.q) == len(rec.qd) == len(rec.effort) == 3
    assert rec.q[:, 0].tolist() == [0.0, 1.0, 2.0]
