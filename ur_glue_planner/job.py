"""Glue job files (``config/glue_job.yaml``): loading and validation into a frozen GlueJob.

Every invalid entry raises :class:`~ur_glue_planner.errors.JobError` naming the field (dotted,
e.g. ``path.inset``), the value and the allowed range or choices; unknown keys are errors
too, so that a typo never silently falls back to a default.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
import yaml

from ur_glue_planner.defaults import DEFAULT_ORIENTATION_ZYX, DEFAULT_SAMPLE_TIME, DEFAULT_TCP_SPEED, DEFAULT_WAYPOINTS
from ur_glue_planner.errors import JobError
from ur_sim_driver.description.params import UR_TYPES
from ur_sim_driver.description.tool import TOOL_CHOICES as TOOLS

PATH_SOURCES = ("waypoints", "auto")
METHODS = ("constant_speed", "seed1")
#: UR digital outputs as ur_msgs/SetIO numbers them: 0-7 standard, 8-15 configurable, 16-17 tool.
DIGITAL_OUTPUT_PINS = range(0, 18)


@dataclass(frozen=True)
class WindshieldSpec:
    """Where the glass is: mesh file (for scenes and plots) and world pose of its local frame.

    Attributes:
        mesh: Mesh path as written in the job (relative to the package root or absolute).
        xyz: Position [m]; rpy: URDF roll-pitch-yaw [rad] (seed: (-55 deg, 0, 0)).
    """

    mesh: str
    xyz: tuple[float, float, float]
    rpy: tuple[float, float, float]


@dataclass(frozen=True)
class PathSpec:
    """How the bead is made.

    Attributes:
        source: 'waypoints' (the listed points) or 'auto' (the glass outline, ``inset`` inside).
        waypoints: (K, 3) [m] world frame, for 'waypoints'.
        orientation_zyx: Tip orientation ZYX Euler [rad], one (3,) for all or (K, 3); for
            'auto' it only fixes the roll about the tool axis (the reference orientation).
        closed: The bead is a loop (a last waypoint repeating the first is dropped).
        inset: 'auto': bead distance inside the glass edge [m].
        tilt_deg: 'auto': angle [deg] between the tool axis and the surface normal, the tool
            leaning towards the robot base.
        point_spacing: 'auto': distance [m] between generated waypoints.
        corner_max_deviation: Largest distance [m] of the rounded path from a corner waypoint.
        follow_surface: Lay the path between the waypoints onto the glass (at the standoff), instead of
            straight chords that rise above a curved glass.
    """

    source: str
    waypoints: tuple[tuple[float, float, float], ...]
    orientation_zyx: tuple[tuple[float, float, float], ...]
    closed: bool
    inset: float
    tilt_deg: float
    point_spacing: float
    corner_max_deviation: float
    follow_surface: bool = True


@dataclass(frozen=True)
class Tolerances:
    """Tolerances sent with the FollowJointTrajectory goal.

    Attributes:
        path_position: Per joint (6,) [rad] along the trajectory.
        goal_position: Per joint (6,) [rad] at the end.
        goal_time: goal_time_tolerance [s].
    """

    path_position: tuple[float, ...]
    goal_position: tuple[float, ...]
    goal_time: float


@dataclass(frozen=True)
class DispenserSpec:
    """The glue gun on a digital output; the defaults are ur_sim's (``dispenser.*`` parameters).

    Attributes:
        pin: SetIO digital output pin (0-7 standard, 8-15 configurable, 16-17 tool).
        flow_rate: Material flow once fully open [ml/s].
        nozzle_diameter: [mm].
        on_delay: From the output switching on until material leaves the nozzle [s].
        off_delay: From the output switching off until the flow starts to fall [s].
        time_constant: First-order rise (and fall) of the flow after the delays [s].
        flying_start: Closed loops: the tip runs up along the loop's tail and runs out past the
            closure at cruise speed, so that material starts and stops while the tip moves at
            the commanded speed (else the bead starts and ends with the tip at rest).
    """

    pin: int
    flow_rate: float
    nozzle_diameter: float
    on_delay: float
    off_delay: float
    time_constant: float
    flying_start: bool

    @property
    def kind(self) -> str:
        """'standard', 'configurable' or 'tool' output."""
        return "standard" if self.pin < 8 else "configurable" if self.pin < 16 else "tool"


@dataclass(frozen=True)
class GlueJob:
    """A validated glue job; see ``config/glue_job.yaml`` for the meaning and unit of each field.

    Lengths in metres, speeds in m/s, times in seconds, joint angles in radians (the file
    gives ``home_deg`` and ``ik_seed_deg`` in degrees).
    """

    ur_type: str
    tool: str
    windshield: WindshieldSpec
    path: PathSpec
    standoff: float
    tcp_speed: float
    sample_time: float
    ramp_time: float
    approach_distance: float
    retreat_distance: float
    approach_speed: float
    approach_min_duration: float
    approach_velocity_scale: float
    home: tuple[float, ...]
    ik_seed: tuple[float, ...] | None
    tolerances: Tolerances
    controller_name: str
    namespace: str
    dispenser: DispenserSpec
    method: str = "constant_speed"
    source_file: str = ""


_DEFAULTS: dict[str, Any] = {
    "ur_type": "ur5", "tool": "dispenser", "standoff": 0.0, "tcp_speed": DEFAULT_TCP_SPEED,
    "sample_time": DEFAULT_SAMPLE_TIME, "ramp_time": 0.3, "approach_distance": 0.05, "retreat_distance": 0.05,
    "approach_speed": 0.05, "approach_min_duration": 4.0, "approach_velocity_scale": 0.5,
    "home_deg": [0.0, -90.0, 0.0, -90.0, 0.0, 0.0], "ik_seed_deg": None,
    "controller_name": "scaled_joint_trajectory_controller", "namespace": "", "method": "constant_speed",
}
_DISPENSER_DEFAULTS: dict[str, Any] = {
    "pin": 16, "flow_rate": 6.0, "nozzle_diameter": 6.0, "on_delay": 0.05, "off_delay": 0.03,
    "time_constant": 0.05, "flying_start": True,
}
_WINDSHIELD_DEFAULTS = {"mesh": "meshes/windshield.stl", "pose": {"xyz": [0.0, 0.4, 0.15],
                                                                  "rpy": [math.radians(-55.0), 0.0, 0.0]}}
_PATH_DEFAULTS: dict[str, Any] = {
    "source": "waypoints", "waypoints": None, "orientation_zyx": list(DEFAULT_ORIENTATION_ZYX), "closed": True,
    "inset": 0.03, "tilt_deg": 18.0, "point_spacing": 0.01, "corner_max_deviation": 0.02,
    "follow_surface": True,
}
_TOL_DEFAULTS = {"path_position": 0.1, "goal_position": 0.01, "goal_time_tolerance": 0.5}


def _section(raw: Any, name: str, defaults: dict[str, Any]) -> dict[str, Any]:
    if raw is None:
        raw = {}
    if not isinstance(raw, dict):
        raise JobError(f"{name or 'job'}: must be a mapping, got {raw!r}")
    unknown = sorted(set(raw) - set(defaults))
    if unknown:
        where = f"{name}.{unknown[0]}" if name else unknown[0]
        raise JobError(f"{where}: unknown key; allowed: {', '.join(sorted(defaults))}")
    return {**defaults, **raw}


def _number(value: Any, field: str, lo: float, hi: float, *, lo_open: bool = False) -> float:
    ok = isinstance(value, (int, float)) and not isinstance(value, bool) and math.isfinite(value)
    if ok:
        ok = (value > lo if lo_open else value >= lo) and value <= hi
    if not ok:
        bracket = "(" if lo_open else "["
        raise JobError(f"{field}: {value!r} is not a number in {bracket}{lo:g}, {hi:g}]")
    return float(value)


def _choice(value: Any, field: str, choices: tuple[str, ...]) -> str:
    key = value.strip().lower() if isinstance(value, str) else value
    if key not in choices:
        raise JobError(f"{field}: {value!r} is not one of: {', '.join(choices)}")
    return key


def _array(value: Any, field: str, shape: tuple[int | None, ...], what: str) -> np.ndarray:
    try:
        arr = np.array(value, dtype=float)
    except (TypeError, ValueError):
        arr = np.empty(0)
    good = arr.ndim == len(shape) and all(s is None or s == n for s, n in zip(shape, arr.shape))
    if not good or arr.size == 0 or not np.all(np.isfinite(arr)):
        raise JobError(f"{field}: {value!r} is not {what}")
    return arr


def _per_joint(value: Any, field: str) -> tuple[float, ...]:
    arr = _array(np.broadcast_to(value, (6,)) if np.isscalar(value) else value, field, (6,),
                 "a number or 6 numbers > 0 [rad]")
    if np.any(arr <= 0.0) or np.any(arr > math.pi):
        raise JobError(f"{field}: {value!r} must lie in (0, {math.pi:.4f}] rad")
    return tuple(float(x) for x in arr)


def _pin(value: Any, field: str) -> int:
    if isinstance(value, bool) or not isinstance(value, int) or value not in DIGITAL_OUTPUT_PINS:
        raise JobError(f"{field}: {value!r} is not a digital output pin in [0, 17] "
                       "(0-7 standard, 8-15 configurable, 16-17 tool)")
    return value


def _bool(value: Any, field: str) -> bool:
    if not isinstance(value, bool):
        raise JobError(f"{field}: {value!r} is not true or false")
    return value


def _text(value: Any, field: str, allow_empty: bool = False) -> str:
    if not isinstance(value, str) or (not allow_empty and not value.strip()):
        raise JobError(f"{field}: {value!r} is not a {'' if allow_empty else 'non-empty '}string")
    return value.strip()


def parse_job(raw: Any, source_file: str = "") -> GlueJob:
    """Validate a job given as a mapping (the parsed YAML); missing keys take the defaults.

    Raises:
        JobError: An unknown key or an invalid value (the message names field, value and range).
    """
    top = _section(raw, "", {**_DEFAULTS, "windshield": None, "path": None, "tolerances": None, "dispenser": None})
    disp = _section(top["dispenser"], "dispenser", _DISPENSER_DEFAULTS)
    ws = _section(top["windshield"], "windshield", _WINDSHIELD_DEFAULTS)
    pose = _section(ws["pose"], "windshield.pose", _WINDSHIELD_DEFAULTS["pose"])
    pth = _section(top["path"], "path", _PATH_DEFAULTS)
    tol = _section(top["tolerances"], "tolerances", _TOL_DEFAULTS)

    source = _choice(pth["source"], "path.source", PATH_SOURCES)
    wps = DEFAULT_WAYPOINTS if pth["waypoints"] is None else _array(
        pth["waypoints"], "path.waypoints", (None, 3), "a list of [x, y, z] points [m]")
    if len(wps) < 2:
        raise JobError(f"path.waypoints: {len(wps)} point(s); at least 2 are needed")
    if np.any(np.abs(wps) > 5.0):
        raise JobError(f"path.waypoints: {wps[np.any(np.abs(wps) > 5.0, axis=1)][0].tolist()} lies outside "
                       "[-5, 5] m: waypoints are in metres, world frame")
    ori = _array(pth["orientation_zyx"], "path.orientation_zyx", (None,) * max(np.ndim(pth["orientation_zyx"]), 1),
                 "ZYX Euler angles [rad]")
    if ori.shape != (3,) and ori.shape != (len(wps), 3):
        raise JobError(f"path.orientation_zyx: shape {ori.shape} must be (3,) or ({len(wps)}, 3), "
                       "one per waypoint")
    ori = np.atleast_2d(ori)

    home = _array(top["home_deg"], "home_deg", (6,), "6 joint angles [deg]")
    seed = None if top["ik_seed_deg"] is None else _array(top["ik_seed_deg"], "ik_seed_deg", (6,),
                                                          "null or 6 joint angles [deg]")
    for field, arr in (("home_deg", home), ("ik_seed_deg", seed)):
        if arr is not None and np.any(np.abs(arr) > 360.0):
            raise JobError(f"{field}: {arr.tolist()} has an angle outside [-360, 360] deg")
    namespace = _text(top["namespace"], "namespace", allow_empty=True)
    if namespace and not namespace.startswith("/"):
        raise JobError(f"namespace: {namespace!r} must be '' or start with '/'")

    return GlueJob(
        ur_type=_choice(top["ur_type"], "ur_type", UR_TYPES),
        tool=_choice(top["tool"], "tool", TOOLS),
        windshield=WindshieldSpec(
            mesh=_text(ws["mesh"], "windshield.mesh"),
            xyz=tuple(float(x) for x in _array(pose["xyz"], "windshield.pose.xyz", (3,), "[x, y, z] [m]")),
            rpy=tuple(float(x) for x in _array(pose["rpy"], "windshield.pose.rpy", (3,), "[roll, pitch, yaw] [rad]"))),
        path=PathSpec(
            source=source,
            waypoints=tuple(tuple(float(x) for x in p) for p in wps),
            orientation_zyx=tuple(tuple(float(x) for x in o) for o in ori),
            closed=_bool(pth["closed"], "path.closed"),
            inset=_number(pth["inset"], "path.inset", 0.0, 0.2),
            tilt_deg=_number(pth["tilt_deg"], "path.tilt_deg", 0.0, 60.0),
            point_spacing=_number(pth["point_spacing"], "path.point_spacing", 0.002, 0.1),
            corner_max_deviation=_number(pth["corner_max_deviation"], "path.corner_max_deviation", 0.0, 0.1,
                                         lo_open=True),
            follow_surface=_bool(pth["follow_surface"], "path.follow_surface")),
        standoff=_number(top["standoff"], "standoff", 0.0, 0.05),
        tcp_speed=_number(top["tcp_speed"], "tcp_speed", 0.0, 1.0, lo_open=True),
        sample_time=_number(top["sample_time"], "sample_time", 0.001, 0.1),
        ramp_time=_number(top["ramp_time"], "ramp_time", 0.0, 5.0, lo_open=True),
        approach_distance=_number(top["approach_distance"], "approach_distance", 0.0, 0.3),
        retreat_distance=_number(top["retreat_distance"], "retreat_distance", 0.0, 0.3),
        approach_speed=_number(top["approach_speed"], "approach_speed", 0.0, 0.5, lo_open=True),
        approach_min_duration=_number(top["approach_min_duration"], "approach_min_duration", 0.0, 60.0),
        approach_velocity_scale=_number(top["approach_velocity_scale"], "approach_velocity_scale", 0.0, 1.0,
                                        lo_open=True),
        home=tuple(float(x) for x in np.radians(home)),
        ik_seed=None if seed is None else tuple(float(x) for x in np.radians(seed)),
        tolerances=Tolerances(
            path_position=_per_joint(tol["path_position"], "tolerances.path_position"),
            goal_position=_per_joint(tol["goal_position"], "tolerances.goal_position"),
            goal_time=_number(tol["goal_time_tolerance"], "tolerances.goal_time_tolerance", 0.0, 60.0)),
        controller_name=_text(top["controller_name"], "controller_name"),
        namespace=namespace,
        dispenser=DispenserSpec(
            pin=_pin(disp["pin"], "dispenser.pin"),
            flow_rate=_number(disp["flow_rate"], "dispenser.flow_rate", 0.0, 100.0, lo_open=True),
            nozzle_diameter=_number(disp["nozzle_diameter"], "dispenser.nozzle_diameter", 0.0, 30.0, lo_open=True),
            on_delay=_number(disp["on_delay"], "dispenser.on_delay", 0.0, 2.0),
            off_delay=_number(disp["off_delay"], "dispenser.off_delay", 0.0, 2.0),
            time_constant=_number(disp["time_constant"], "dispenser.time_constant", 0.0, 1.0),
            flying_start=_bool(disp["flying_start"], "dispenser.flying_start")),
        method=_choice(top["method"], "method", METHODS),
        source_file=source_file,
    )


def load_job(path: str | Path) -> GlueJob:
    """Read and validate a job YAML file.

    Raises:
        JobError: Unreadable file, bad YAML, or an invalid field.
    """
    path = Path(path)
    try:
        raw = yaml.safe_load(path.read_text())
    except (OSError, yaml.YAMLError) as exc:
        raise JobError(f"cannot read glue job {path}: {exc}") from exc
    return parse_job(raw, str(path))


def default_job_path() -> Path:
    """``config/glue_job.yaml`` of the source tree, else of the installed share directory."""
    from ur_common.paths import config_dir
    return config_dir() / "glue_job.yaml"
