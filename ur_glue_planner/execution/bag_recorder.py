"""A glue run recorded as a rosbag2 in MCAP: what the robot did, what was planned and the bead it laid.

:class:`BagRecorder` subscribes (raw: the CDR bytes as received, never decoded) to the driver's topics and the
planner's path on a node of its own, spun by a thread of its own with rclpy's EventsExecutor (a quarter of
the SingleThreadedExecutor's CPU a message: ``python -m bench bag``), and writes them with rosbags' rosbag2 Writer
(MCAP storage, zstd chunks): a directory with ``metadata.yaml`` and ``<name>.mcap``, which Foxglove, ``ros2 bag``
and the ``mcap`` tools read. A topic nothing publishes is absent from the bag. Message definitions come from
rosbags' Jazzy typestore, or else from the installed interface files (``share/<package>/msg/*.msg`` under
``AMENT_PREFIX_PATH``: ur_msgs and the other packages built from interfaces/).

Log times: the simulated clock (``/clock``, ns) where one is published (ur_sim), else the wall clock (a real robot,
whose driver stamps with the wall clock); messages that arrive before the first ``/clock`` message (the latched
ones) take its time. rosbags is imported on start only, so that a planner without it still runs (without a bag).
"""
from __future__ import annotations

import importlib
import os
import shutil
import struct
import threading
import time
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

from rclpy.context import Context
from rclpy.experimental import EventsExecutor
from rclpy.node import Node
from rclpy.qos import DurabilityPolicy, QoSProfile, ReliabilityPolicy

from ur_common.spin_thread import SpinThread
from ur_glue_planner.execution.planned_path import planned_path_topic

STREAM_DEPTH = 2000  # messages a stream's reader queue holds while the recorder's thread is busy (4 s at 500 Hz)
FIRST_MESSAGE_TIMEOUT = 5.0  # [s] of wall time start() waits for the first joint state (the subscriptions matched)


@dataclass(frozen=True)
class RecordedTopic:
    """A topic to record: full name, type ('pkg/msg/Name'), and whether its publisher latches (transient local)."""

    name: str
    type: str
    latched: bool = False


def recorded_topics(prefix: str = '') -> tuple[RecordedTopic, ...]:
    """The run's topics, the driver's under `prefix` ('' or e.g. '/ur10'); /tf and /tf_static are absolute."""
    return (
        RecordedTopic(f'{prefix}/joint_states', 'sensor_msgs/msg/JointState'),
        RecordedTopic('/tf', 'tf2_msgs/msg/TFMessage'),
        RecordedTopic('/tf_static', 'tf2_msgs/msg/TFMessage', latched=True),
        RecordedTopic(f'{prefix}/robot_description', 'std_msgs/msg/String', latched=True),
        RecordedTopic(f'{prefix}/io_and_status_controller/io_states', 'ur_msgs/msg/IOStates'),
        RecordedTopic(f'{prefix}/force_torque_sensor_broadcaster/wrench', 'geometry_msgs/msg/WrenchStamped'),
        RecordedTopic(f'{prefix}/ur_sim/part_scan', 'sensor_msgs/msg/PointCloud2'),
        RecordedTopic(f'{prefix}/ur_sim/glue_bead', 'sensor_msgs/msg/PointCloud2', latched=True),
        RecordedTopic(planned_path_topic(prefix), 'nav_msgs/msg/Path', latched=True),
    )


def subscription_qos(topic: RecordedTopic, offered: list[QoSProfile]) -> QoSProfile:
    """The QoS that matches every publisher seen (`offered`) and gets their latched messages, as ``ros2 bag record``
    chooses it: transient local only if all latch (else volatile, which matches both), reliable only if all are
    reliable (else best effort, which matches both); with no publisher seen yet, the topic's known QoS."""
    latched = all(q.durability == DurabilityPolicy.TRANSIENT_LOCAL for q in offered) if offered else topic.latched
    reliable = all(q.reliability == ReliabilityPolicy.RELIABLE for q in offered) if offered else True
    return QoSProfile(depth=100 if latched else STREAM_DEPTH,
                      durability=DurabilityPolicy.TRANSIENT_LOCAL if latched else DurabilityPolicy.VOLATILE,
                      reliability=ReliabilityPolicy.RELIABLE if reliable else ReliabilityPolicy.BEST_EFFORT)


def clock_ns(cdr: bytes) -> int:
    """The time [ns] in a serialized rosgraph_msgs/Clock (CDR: 4-byte encapsulation header, int32 sec, uint32
    nanosec; byte 1 of the header is 1 for little endian)."""
    sec, nanosec = struct.unpack_from('<iI' if cdr[1] & 1 else '>iI', cdr, 4)
    return sec * 1_000_000_000 + nanosec


def prepare_bag_dir(path: Path) -> None:
    """Make room for a new bag at `path` (rosbags never overwrites): an earlier bag there (only metadata.yaml and
    .mcap files) is removed, as the run's other report files are replaced; anything else there is an error."""
    if not path.exists():
        path.parent.mkdir(parents=True, exist_ok=True)
        return
    files = list(path.iterdir()) if path.is_dir() else [path]
    if not path.is_dir() or any(f.name != 'metadata.yaml' and f.suffix != '.mcap' for f in files):
        raise FileExistsError(f'{path} exists and is not a bag: not overwriting it')
    shutil.rmtree(path)


def _share_dirs() -> list[Path]:
    return [Path(p) / 'share' for p in os.environ.get('AMENT_PREFIX_PATH', '').split(os.pathsep) if p]


class MessageTypes:
    """Message definitions and RIHS01 hashes for the writer: rosbags' Jazzy typestore, extended with the installed
    .msg files of any type it lacks (and of what those use)."""

    def __init__(self) -> None:
        from rosbags.typesys import Stores, get_typestore

        self.store = get_typestore(Stores.ROS2_JAZZY)

    def ensure(self, typename: str) -> None:
        """Register `typename` ('pkg/msg/Name') and the types it uses, from the installed interface files."""
        from rosbags.interfaces import Nodetype
        from rosbags.typesys import get_types_from_msg

        if typename in self.store.fielddefs:
            return
        pkg, _, name = typename.split('/')
        found = [d / pkg / 'msg' / f'{name}.msg' for d in _share_dirs() if (d / pkg / 'msg' / f'{name}.msg').is_file()]
        if not found:
            raise LookupError(f'no definition of {typename}: not in the Jazzy typestore, no {pkg}/msg/{name}.msg '
                              'under AMENT_PREFIX_PATH')
        types = get_types_from_msg(found[0].read_text(), typename)
        self.store.register(types)
        for _, fields in types.values():
            for _, (kind, detail) in fields:
                while kind in (Nodetype.ARRAY, Nodetype.SEQUENCE):  # arrays and sequences of ...
                    kind, detail = detail[0]
                if kind == Nodetype.NAME:
                    self.ensure(detail)

    def definition(self, typename: str) -> tuple[str, str]:
        """(message definition as rosbag2 stores it, RIHS01 hash) of `typename`."""
        self.ensure(typename)
        return self.store.generate_msgdef(typename, ros_version=2)[0], self.store.hash_rihs01(typename)


def _message_class(typename: str) -> type:
    pkg, kind, name = typename.split('/')
    return getattr(importlib.import_module(f'{pkg}.{kind}'), name)


class BagRecorder:
    """Records the run's topics into a new rosbag2 (MCAP) at `path` from start() to close().

    Args:
        context: An initialised rclpy context (the run's).
        path: The bag directory to create (an earlier bag there is replaced).
        prefix: The driver's namespace prefix ('' or e.g. '/ur10').
        sim_time: Log times from /clock (True) or the wall clock (False); None: /clock if it has a publisher.
        log: Receives a line on start, on close and for each topic that cannot be recorded.
    """

    def __init__(self, context: Context, path: str | Path, prefix: str = '', sim_time: bool | None = None,
                 log: Callable[[str], None] = print) -> None:
        self.context, self.path, self.prefix, self._log = context, Path(path), prefix, log
        self._sim_time = sim_time
        self.counts: dict[str, int] = {}  # messages written per topic
        self.error: str | None = None  # why writing stopped, if it did
        self._clock: int | None = None  # newest /clock [ns]
        self._pending: list[tuple[RecordedTopic, bytes]] = []  # arrived before the first /clock
        self._connections: dict[str, object] = {}  # rosbags Connection per topic, added on its first message
        self._definitions: dict[str, tuple[str, str]] = {}  # (message definition, RIHS01) per topic
        self._joint_state_seen = False
        self._first = threading.Event()  # a joint state (and with sim_time a /clock) has arrived
        self._writer = self._node = self._spinner = None

    def start(self, first_message_timeout: float = FIRST_MESSAGE_TIMEOUT) -> BagRecorder:
        """Open the bag, subscribe, spin, and wait for the first joint state and /clock (at most
        `first_message_timeout` [s] of wall time): the subscriptions have matched the driver's by then, and only the
        latched messages wait for the clock. Raises on any failure to open (nothing is left running then)."""
        from rosbags.rosbag2 import CompressionFormat, CompressionMode, StoragePlugin, Writer

        self._types = MessageTypes()
        prepare_bag_dir(self.path)
        self._writer = Writer(self.path, version=9, storage_plugin=StoragePlugin.MCAP)
        self._writer.set_compression(CompressionMode.STORAGE, CompressionFormat.ZSTD)
        self._writer.open()
        try:
            self._node = Node('ur_glue_planner_bag', context=self.context)
            if self._sim_time is None:
                self._sim_time = self._node.count_publishers('/clock') > 0
            if self._sim_time:
                clock = _message_class('rosgraph_msgs/msg/Clock')
                self._node.create_subscription(clock, '/clock', self._on_clock, QoSProfile(depth=10), raw=True)
            for topic in recorded_topics(self.prefix):
                try:
                    msg_type = _message_class(topic.type)
                    self._definitions[topic.name] = self._types.definition(topic.type)
                except (ImportError, AttributeError, LookupError) as exc:
                    self._log(f'bag: not recording {topic.name}: {exc}')
                    continue
                offered = [i.qos_profile for i in self._node.get_publishers_info_by_topic(topic.name)]
                self._node.create_subscription(msg_type, topic.name, lambda data, t=topic: self._on_message(t, data),
                                               subscription_qos(topic, offered), raw=True)
            executor = EventsExecutor(context=self.context)
            executor.add_node(self._node)
            self._spinner = SpinThread(executor, 'bag_recorder').start()
        except BaseException:
            self.close()
            raise
        if not self._first.wait(first_message_timeout):
            self._log(f'bag: no joint state{" and clock" if self._sim_time else ""} within '
                      f'{first_message_timeout:.1f} s; recording what arrives')
        self._log(f'bag: recording to {self.path} ({"simulated" if self._sim_time else "wall"} clock)')
        return self

    @property
    def held(self) -> int:
        """Messages received but not yet written: they wait for the first /clock to take its time."""
        return len(self._pending)

    def _on_clock(self, data: bytes) -> None:
        t = clock_ns(data)
        if self._clock is None or t > self._clock:
            self._clock = t
        if self._joint_state_seen:
            self._first.set()
        # What waited for the first clock is written now, not with the next message: DDS keeps each topic's
        # order but not the order across topics, so the first clock can be taken after the last message.
        if self._pending and self.error is None:
            self._guarded(self._flush, self._clock)

    def _on_message(self, topic: RecordedTopic, data: bytes) -> None:
        if self.error is None:
            self._guarded(self._record, topic, data)

    def _guarded(self, write: Callable[..., None], *args) -> None:
        try:
            write(*args)
        except Exception as exc:  # noqa: BLE001 - a bag that cannot be written must not stop the run
            self.error = f'{type(exc).__name__}: {exc}'
            self._log(f'bag: recording stopped: {self.error}')

    def _record(self, topic: RecordedTopic, data: bytes) -> None:
        if not self._joint_state_seen and topic.name == f'{self.prefix}/joint_states':
            self._joint_state_seen = True
            if not self._sim_time or self._clock is not None:
                self._first.set()
        t = self._clock if self._sim_time else time.time_ns()
        if t is None:
            self._pending.append((topic, data))
            return
        self._flush(t)
        self._write(topic, t, data)

    def _flush(self, t: int) -> None:
        pending, self._pending = self._pending, []
        for topic, data in pending:
            self._write(topic, t, data)

    def _write(self, topic: RecordedTopic, t: int, data: bytes) -> None:
        connection = self._connections.get(topic.name)
        if connection is None:
            from rosbags.interfaces import Qos, QosDurability, QosHistory, QosLiveliness, QosReliability, QosTime

            msgdef, rihs01 = self._definitions[topic.name]
            zero = QosTime(0, 0)
            qos = Qos(QosHistory.KEEP_LAST, 1 if topic.latched else 10, QosReliability.RELIABLE,
                      QosDurability.TRANSIENT_LOCAL if topic.latched else QosDurability.VOLATILE, zero, zero,
                      QosLiveliness.AUTOMATIC, zero, False)
            connection = self._writer.add_connection(topic.name, topic.type, msgdef=msgdef, rihs01=rihs01,
                                                     offered_qos_profiles=[qos])
            self._connections[topic.name] = connection
        self._writer.write(connection, t, data)
        self.counts[topic.name] = self.counts.get(topic.name, 0) + 1

    def close(self) -> dict[str, int]:
        """Stop recording, write the bag's index and metadata.yaml; returns the messages written per topic.
        Safe to call twice and after a failed start."""
        if self._spinner is not None:
            if not self._spinner.stop():  # its thread is stuck in a callback: no more writes, the node left alone
                self.error = self.error or 'the recording thread did not stop'
                self._node = None
            self._spinner = None
        if self._node is not None:
            self._node.destroy_node()  # no executor spins it any more
            self._node = None
        if self._writer is not None:
            writer, self._writer = self._writer, None
            if self.error is None:
                try:
                    self._flush(self._clock if self._clock is not None else time.time_ns())
                except Exception as exc:  # noqa: BLE001 - the messages so far are still worth closing
                    self.error = f'{type(exc).__name__}: {exc}'
            writer.close()
            size = sum(f.stat().st_size for f in self.path.glob('*.mcap'))
            self._log(f'bag: {self.path}: {sum(self.counts.values())} messages on {len(self.counts)} topics, '
                      f'{size / 1e6:.1f} MB' + (f' (incomplete: {self.error})' if self.error else ''))
        return dict(self.counts)
