"""Taking FollowJointTrajectory goal requests straight into arrays, without a Python object per point.

rclpy's ActionServer converts every goal request into Python messages in C, one object per point and per
array: for 100,000 points that is 600,000 objects, about 1.5 s here with the GIL held (the garbage collector
walks them again and again while they are made), and tens of MB that the process keeps afterwards.

rclpy looks the conversion function up on the message class it is handed (the metaclass attribute
``_CONVERT_TO_PY``, a capsule holding a C function pointer), and a ctypes callback is a C function pointer. So
:class:`ArrayGoalActionServer` takes goal requests through rclpy's own call with a stand-in class whose
conversion is :meth:`GoalIntake._convert`. Handed the taken C request, that

1. serializes the goal's trajectory (the C struct inside the request) with the rmw's serializer and reads the
   points from those bytes with numpy (``trajectory_cdr.py``), tens of milliseconds for 100,000 points;
2. converts the request with the generated function while the point count reads 0, so the goal the callbacks
   get is a real message whose trajectory has no points (everything else as sent);
3. keeps the points' :class:`CommandArrays` for the goal callback (:meth:`ArrayGoalActionServer.arrays_of`).

The C layout this relies on (a request is the goal id, 16 bytes, then the goal, whose first member is the
trajectory) is checked once per process against rclpy's own conversion of a probe request
(:func:`goal_intake`); if it does not hold, or a conversion fails, goals are converted by rclpy as before.

Why it reaches into rclpy's private parts (the metaclass capsules, ``ActionServer._handle`` and
``_is_goal_request_ready``): rclpy converts nested message arrays to Python one object at a time, which is slow
for large messages (https://github.com/ros2/rclpy/issues/836, open), and unlike subscriptions (``raw=True``) its
ActionServer has no way to take a request serialized. What it buys is measured in ``bench/bench_tricks.py``
(docs/performance.md): without it a 100,000-point goal is not accepted within the 1 s the driver's users need.
"""
from __future__ import annotations

import ctypes
import threading
from collections.abc import Callable

import numpy as np
from control_msgs.action import FollowJointTrajectory
from control_msgs.msg import JointTolerance
from rclpy.action import ActionServer
from rclpy.logging import get_logger
from rclpy.utilities import get_rmw_implementation_identifier
from trajectory_msgs.msg import JointTrajectory, JointTrajectoryPoint

from ur_sim_driver.gateway.trajectory_cdr import read_joint_trajectory
from ur_sim_driver.motion import conversions as conv
from ur_sim_driver.motion.command_arrays import CommandArrays, from_points

_log = get_logger('ur_sim.goal_intake')
Request = FollowJointTrajectory.Impl.SendGoalService.Request
# Arrays of goals whose callback never came (rclpy drops a request whose goal id is in use) are let go beyond this.
_KEEP = 8


# ---- the C structs, as rosidl_generator_c lays them out ------------------------------------------------------------
class _Sequence(ctypes.Structure):
    """rosidl_runtime_c sequences and strings: data, size, capacity."""

    _fields_ = [('data', ctypes.c_void_p), ('size', ctypes.c_size_t), ('capacity', ctypes.c_size_t)]


class _Time(ctypes.Structure):
    _fields_ = [('sec', ctypes.c_int32), ('nanosec', ctypes.c_uint32)]


class _Header(ctypes.Structure):
    _fields_ = [('stamp', _Time), ('frame_id', _Sequence)]


class _JointTrajectory(ctypes.Structure):
    _fields_ = [('header', _Header), ('joint_names', _Sequence), ('points', _Sequence)]


class _SendGoalRequest(ctypes.Structure):
    """The request's leading part: goal_id, then the goal, whose first member is the trajectory."""

    _fields_ = [('goal_id', ctypes.c_uint8 * 16), ('trajectory', _JointTrajectory)]


class _Allocator(ctypes.Structure):
    """rcutils_allocator_t."""

    _fields_ = [('allocate', ctypes.c_void_p), ('deallocate', ctypes.c_void_p), ('reallocate', ctypes.c_void_p),
                ('zero_allocate', ctypes.c_void_p), ('state', ctypes.c_void_p)]


class _Bytes(ctypes.Structure):
    """rcutils_uint8_array_t (rmw_serialized_message_t)."""

    _fields_ = [('buffer', ctypes.c_void_p), ('buffer_length', ctypes.c_size_t),
                ('buffer_capacity', ctypes.c_size_t), ('allocator', _Allocator)]


_TRAJECTORY_AT = _SendGoalRequest.trajectory.offset
_PYTHON = ctypes.PyDLL(None)  # the interpreter's C API (own function objects: ctypes.pythonapi's are shared)
_PYTHON.PyCapsule_GetName.restype = ctypes.c_void_p
_PYTHON.PyCapsule_GetName.argtypes = (ctypes.py_object,)
_PYTHON.PyCapsule_GetPointer.restype = ctypes.c_void_p
_PYTHON.PyCapsule_GetPointer.argtypes = (ctypes.py_object, ctypes.c_void_p)
_PYTHON.PyCapsule_New.restype = ctypes.py_object
_PYTHON.PyCapsule_New.argtypes = (ctypes.c_void_p, ctypes.c_char_p, ctypes.c_void_p)
_TO_PY = ctypes.CFUNCTYPE(ctypes.py_object, ctypes.c_void_p)  # rosidl's convert_to_py, as rclpy calls it


def _pointer(capsule: object) -> int:
    return _PYTHON.PyCapsule_GetPointer(capsule, _PYTHON.PyCapsule_GetName(capsule))


class GoalIntake:
    """The stand-in request class and its conversion (one per process: :func:`goal_intake`)."""

    def __init__(self) -> None:
        for cls in (Request, JointTrajectory):
            type(cls).__import_type_support__()
        meta = type(Request)
        # Calling the generated conversion must keep the GIL (it makes Python objects): PYFUNCTYPE.
        self._standard = ctypes.PYFUNCTYPE(ctypes.py_object, ctypes.c_void_p)(_pointer(meta._CONVERT_TO_PY))
        self._trajectory_type = _pointer(type(JointTrajectory)._TYPE_SUPPORT)
        rmw = ctypes.CDLL(f'lib{get_rmw_implementation_identifier()}.so')
        self._serialize = rmw.rmw_serialize
        self._serialize.restype = ctypes.c_int
        self._serialize.argtypes = (ctypes.c_void_p, ctypes.c_void_p, ctypes.POINTER(_Bytes))
        rcutils = ctypes.CDLL('librcutils.so')
        self._allocator = rcutils.rcutils_get_default_allocator
        self._allocator.restype = _Allocator
        self._init = rcutils.rcutils_uint8_array_init
        self._init.restype = ctypes.c_int
        self._init.argtypes = (ctypes.POINTER(_Bytes), ctypes.c_size_t, ctypes.POINTER(_Allocator))
        self._fini = rcutils.rcutils_uint8_array_fini
        self._fini.restype = ctypes.c_int
        self._fini.argtypes = (ctypes.POINTER(_Bytes),)
        self._callback = _TO_PY(self._convert)  # kept: rclpy holds only its address
        stand_in_meta = type('ArrayGoalRequestMeta', (type,), {
            '_CREATE_ROS_MESSAGE': meta._CREATE_ROS_MESSAGE, '_DESTROY_ROS_MESSAGE': meta._DESTROY_ROS_MESSAGE,
            '_CONVERT_FROM_PY': meta._CONVERT_FROM_PY, '_TYPE_SUPPORT': meta._TYPE_SUPPORT,
            '_CONVERT_TO_PY': _PYTHON.PyCapsule_New(ctypes.cast(self._callback, ctypes.c_void_p), None, None)})
        self.request_class = stand_in_meta('ArrayGoalRequest', (), {})
        self._lock = threading.Lock()
        self._taken: dict[int, tuple[object, CommandArrays]] = {}
        self.failed: str | None = None  # the last conversion that fell back to rclpy's, and why

    def _convert(self, address: int) -> object:
        """A taken C request to a Python request without points; called by rclpy in C, holding the GIL."""
        try:
            request, cmd = self.split(address)
        except Exception as exc:  # never leave rclpy without a message: convert it the standard way
            self.failed = f'{type(exc).__name__}: {exc}'
            _log.warning(f'goal request converted by rclpy instead: {self.failed}')
            try:
                return self._standard(address)
            except Exception:
                return None  # rclpy then drops the request, as for a failed take
        with self._lock:
            self._taken[id(request.goal)] = (request.goal, cmd)  # the goal held: its id stays its own
            while len(self._taken) > _KEEP:
                del self._taken[next(iter(self._taken))]
        return request

    def split(self, address: int) -> tuple[object, CommandArrays]:
        """The request at `address` as a Python message without points, and the points as arrays."""
        cmd = read_joint_trajectory(self._trajectory_bytes(address + _TRAJECTORY_AT))
        points = _SendGoalRequest.from_address(address).trajectory.points
        count = points.size
        points.size = 0  # the generated conversion reads the count; the points stay for the destroy function
        try:
            request = self._standard(address)
        finally:
            points.size = count
        return request, cmd

    def _trajectory_bytes(self, address: int) -> bytes:
        """The C JointTrajectory at `address`, serialized (CDR)."""
        buffer = _Bytes()
        allocator = self._allocator()
        if self._init(ctypes.byref(buffer), 0, ctypes.byref(allocator)):
            raise MemoryError('rcutils_uint8_array_init failed')
        try:
            ret = self._serialize(address, self._trajectory_type, ctypes.byref(buffer))
            if ret:
                raise RuntimeError(f'rmw_serialize returned {ret}')
            return ctypes.string_at(buffer.buffer, buffer.buffer_length)
        finally:
            self._fini(ctypes.byref(buffer))

    def arrays_of(self, goal: object) -> CommandArrays | None:
        """The points of `goal` (a request's goal this intake converted), once; None if it did not."""
        with self._lock:
            entry = self._taken.pop(id(goal), None)
        return entry[1] if entry is not None and entry[0] is goal else None

    def check(self) -> None:
        """Convert a probe request both ways and compare (ValueError on a difference)."""
        probe = _probe_request()
        meta = type(Request)
        create = ctypes.CFUNCTYPE(ctypes.c_void_p)(_pointer(meta._CREATE_ROS_MESSAGE))
        destroy = ctypes.CFUNCTYPE(None, ctypes.c_void_p)(_pointer(meta._DESTROY_ROS_MESSAGE))
        from_py = ctypes.PYFUNCTYPE(ctypes.c_bool, ctypes.py_object, ctypes.c_void_p)(
            _pointer(meta._CONVERT_FROM_PY))
        address = create()
        if not address:
            raise MemoryError('could not create a C goal request')
        try:
            if not from_py(probe, address):
                raise ValueError('the probe request did not convert to C')
            request, cmd = self.split(address)
            standard = self._standard(address)
        finally:
            destroy(address)
        traj = standard.goal.trajectory
        expected = from_points(traj.joint_names, conv.time_to_sec(traj.header.stamp), traj.points)
        request.goal.trajectory.points = traj.points
        if request != standard or standard != probe:
            raise ValueError('the request without points differs from the standard conversion')
        if not _same(cmd, expected):
            raise ValueError('the points read from the serialized trajectory differ from the message')


def _same(a: CommandArrays, b: CommandArrays) -> bool:
    return (a.joint_names == b.joint_names and a.header_stamp == b.header_stamp
            and np.array_equal(a.times, b.times) and np.array_equal(a.sizes, b.sizes)
            and all(np.array_equal(x, y) for x, y in zip(a.values, b.values)))


def _probe_request() -> object:
    probe = Request()
    probe.goal_id.uuid = list(range(1, 17))
    traj = probe.goal.trajectory
    traj.header.stamp.sec, traj.header.stamp.nanosec = 12, 345_678_901
    traj.header.frame_id = 'probe'
    traj.joint_names = [f'joint_{i}' for i in range(6)]
    for k in range(5):
        p = JointTrajectoryPoint(positions=[0.1 * k + i for i in range(6)], velocities=[0.01 * i for i in range(6)])
        p.time_from_start.sec, p.time_from_start.nanosec = k, 250_000_000
        traj.points.append(p)
    probe.goal.goal_tolerance = [JointTolerance(name='joint_0', position=0.1, velocity=-1.0)]
    probe.goal.goal_time_tolerance.sec = 2
    return probe


_intake: GoalIntake | None = None
_intake_error: str | None = None
_intake_lock = threading.Lock()


def goal_intake() -> GoalIntake | None:
    """The process's intake, checked on first use; None where it cannot work here (see :func:`intake_error`)."""
    global _intake, _intake_error
    with _intake_lock:
        if _intake is None and _intake_error is None:
            try:
                intake = GoalIntake()
                intake.check()
                _intake = intake
            except Exception as exc:
                _intake_error = f'{type(exc).__name__}: {exc}'
        return _intake


def intake_error() -> str | None:
    """Why :func:`goal_intake` is None (None while it works)."""
    return _intake_error


class ArrayGoalActionServer(ActionServer):
    """rclpy's ActionServer for FollowJointTrajectory whose goal requests arrive without points; the goal
    callback gets their arrays from :meth:`arrays_of` (None when rclpy converted the request: then the points
    are in the message). Same arguments as ActionServer, without the action type."""

    def __init__(self, node, action_name: str, execute_callback: Callable, **kwargs) -> None:
        self._intake = goal_intake()
        super().__init__(node, FollowJointTrajectory, action_name, execute_callback, **kwargs)

    def arrays_of(self, goal: object) -> CommandArrays | None:
        return self._intake.arrays_of(goal) if self._intake is not None else None

    def take_data(self):
        intake = self._intake
        mine = intake is not None and self._is_goal_request_ready
        if mine:
            self._is_goal_request_ready = False  # rclpy takes the other requests as ever
        data = super().take_data()
        if mine:
            with self._lock:
                taken = self._handle.take_goal_request(intake.request_class)
            if all(taken):
                data['goal'] = taken
        return data
