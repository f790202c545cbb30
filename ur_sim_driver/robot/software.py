"""The simulated controller's software: its version (PolyScope / CB3 software), and which dashboard commands that
version's dashboard server knows.

A real CB3 runs software 3.x, an e-series PolyScope 5.x; e-series and UR Series types can run PolyScope X 10.x
instead (from the first release of the type's ``software.polyscope_x`` in config/ur_types). The dashboard server of
each CB3 / PolyScope 5 version knows the commands that version introduced and no others; the driver's client library
(Universal Robots Client Library 2.14, ``dashboard_client_implementation_g5.cpp``) checks the same minimum versions
before it sends a command. :data:`COMMANDS` holds those minima, one table for both sides. PolyScope X has no
dashboard server: its Robot API (HTTP) replaces it (``robot/robot_api.py``). No rclpy here.
"""
from __future__ import annotations

import re
from functools import cache
from typing import NamedTuple

import yaml

from ur_sim_driver.description.params import config_dir, load_ur_params
from ur_sim_driver.errors import ConfigError


class SoftwareVersion(NamedTuple):
    """A controller software version, e.g. 5.12.6 build 0."""

    major: int
    minor: int
    bugfix: int
    build: int = 0

    def __str__(self) -> str:
        # As the client library prints a version in its messages: major.minor.bugfix-build
        return f'{self.major}.{self.minor}.{self.bugfix}-{self.build}'

    @property
    def e_series(self) -> bool:
        """PolyScope 5 or later (the client library's isESeries: major >= 5)."""
        return self.major >= 5

    @property
    def polyscope_x(self) -> bool:
        """PolyScope X (10.x): the Robot API instead of a dashboard server."""
        return self.major >= 10

    def dotted(self) -> str:
        """As the dashboard server's `PolyscopeVersion` answer writes it: major.minor.bugfix.build."""
        return f'{self.major}.{self.minor}.{self.bugfix}.{self.build}'


# Widely used releases: 5.25.1 (the newest PolyScope 5 ur_sim knows, what the driver's tests meet as URSim
# `latest`; the Client Library's CI runs it), 3.15.8 (a late CB3 release, upstream's CB3 dashboard test entry).
# UR's build numbers are not published with them: build 0 marks the version as a simulated one. Each type's default
# and first release are facts of its file in config/ur_types.
E_SERIES_VERSION = SoftwareVersion(5, 25, 1, 0)
CB3_VERSION = SoftwareVersion(3, 15, 8, 0)


def default_version(ur_type: str) -> SoftwareVersion:
    """The version a robot of `ur_type` runs unless told otherwise."""
    return SoftwareVersion(*load_ur_params(ur_type).software_default)


def polyscope_x_minimum(ur_type: str) -> SoftwareVersion | None:
    """The first PolyScope X release that runs `ur_type` (its file's ``software.polyscope_x``), None for a type that
    runs no PolyScope X (the CB3s)."""
    return _polyscope_x(load_ur_params(ur_type).name)


@cache
def _polyscope_x(name: str) -> SoftwareVersion | None:
    # load_ur_params reads the fields every type has; this one only the PolyScope X types have.
    raw = yaml.safe_load((config_dir() / f'{name}.yaml').read_text())
    text = (raw.get('software') or {}).get('polyscope_x')
    return None if text is None else _v(str(text))


def runs(ur_type: str) -> str:
    """What software `ur_type` runs, for messages: e.g. '5.x (PolyScope 5) from 5.0.0 or 10.x (PolyScope X) from
    10.7.0'."""
    params = load_ur_params(ur_type)
    first = SoftwareVersion(*params.software_minimum)
    if params.series == 'cb3':
        return f'3.x (CB3 software) from {first.major}.{first.minor}'
    x = polyscope_x_minimum(ur_type)
    tail = '' if x is None else f' or 10.x (PolyScope X) from {x.major}.{x.minor}.{x.bugfix}'
    return f'5.x (PolyScope 5) from {first.major}.{first.minor}.{first.bugfix}{tail}'


def parse_version(text: str, ur_type: str) -> SoftwareVersion:
    """`software_version` as given ('5.12.6', '3.15.8.0', '10.12.0', or '' for the type's default) for a robot of
    `ur_type`.

    Raises:
        ConfigError: naming the parameter, the value and what the robot type runs.
    """
    if not text:
        return default_version(ur_type)
    params = load_ur_params(ur_type)
    match = re.fullmatch(r'(\d+)\.(\d+)\.(\d+)(?:\.(\d+))?', text.strip())
    if match is None:
        raise ConfigError(f"parameter 'software_version' = {text!r} is not a version: major.minor.bugfix[.build], "
                          f'e.g. {default_version(ur_type).dotted()}')
    version = SoftwareVersion(*(int(g or 0) for g in match.groups()))
    first = SoftwareVersion(*params.software_minimum)
    x_first = polyscope_x_minimum(ur_type)
    if version.major == 10 and x_first is not None and version[:3] >= x_first[:3]:
        return version
    if version.major == (3 if params.series == 'cb3' else 5) and version[:3] >= first[:3]:
        return version
    raise ConfigError(f"parameter 'software_version' = {text!r} does not run on a {ur_type}: it runs "
                      f'{runs(ur_type)}')


class Minimum(NamedTuple):
    """The first version of each series whose dashboard server knows a command."""

    cb3: SoftwareVersion
    e_series: SoftwareVersion

    def of(self, version: SoftwareVersion) -> SoftwareVersion:
        return self.e_series if version.e_series else self.cb3


def _v(text: str) -> SoftwareVersion:
    return SoftwareVersion(*(int(x) for x in (text.split('.') + ['0', '0'])[:3]))


def _minimum(cb3: str, e_series: str) -> Minimum:
    return Minimum(_v(cb3), _v(e_series))


# Command (lower case, as keyed in the client library) -> the first versions that know it. A CB3 minimum of 3.99
# or 5.x, or an e-series minimum of 5.99, means the command does not exist in that series.
COMMANDS: dict[str, Minimum] = {
    **dict.fromkeys(('load', 'play', 'stop', 'pause', 'quit', 'shutdown'), _minimum('1.4', '5.0.0')),
    **dict.fromkeys(('running', 'robotmode', 'get loaded program', 'popup', 'close popup'), _minimum('1.6', '5.0.0')),
    **dict.fromkeys(('addtolog', 'isprogramsaved', 'programstate', 'polyscopeversion'), _minimum('1.8', '5.0.0')),
    **dict.fromkeys(('power on', 'power off', 'brake release', 'safetymode'), _minimum('3.0', '5.0.0')),
    **dict.fromkeys(('unlock protective stop', 'close safety popup'), _minimum('3.1', '5.0.0')),
    'load installation': _minimum('3.2', '5.0.0'),
    'restart safety': _minimum('3.7', '5.1.0'),
    **dict.fromkeys(('get serial number', 'get robot model'), _minimum('3.12', '5.6.0')),
    **dict.fromkeys(('generate flight report', 'generate support file', 'savelog'), _minimum('3.13', '5.8.0')),
    **dict.fromkeys(('setuserrole', 'getuserrole'), _minimum('3.1.0', '5.99.0')),
    'set operational mode': _minimum('3.99.0', '5.0.0'),
    'clear operational mode': _minimum('5.0.0', '5.0.0'),
    'safetystatus': _minimum('5.4.0', '5.4.0'),
    **dict.fromkeys(('get operational mode', 'is in remote control'), _minimum('5.6.0', '5.6.0')),
    'version': _minimum('5.0.0', '5.0.0'),
}


# PolyScope X: the driver's dashboard client connects from 10.11.0 on (dashboard_client_ros.cpp exits on older
# versions); the Robot API 3.1.4 of 10.12.0 adds the state queries and the program services (the client library's
# DashboardClientImplX refuses them on an older Robot API).
DASHBOARD_X = _v('10.11.0')
ROBOT_API_QUERIES = _v('10.12.0')


def required(command: str, version: SoftwareVersion) -> SoftwareVersion | None:
    """The version `command` needs on this robot's series when `version` is older, else None (it is known)."""
    minimum = COMMANDS[command].of(version)
    return minimum if version[:3] < minimum[:3] else None


# Features of the driver that need a minimum robot software (PolyScope 5, PolyScope X), as the driver and its client
# library check them: torque control (hardware_interface.cpp, prepare_command_mode_switch) and friction scales for
# it (ScriptCommandInterface::setFrictionScales).
TORQUE_CONTROL = (_v('5.23.0'), _v('10.10.0'))
# RTDE actual_current_as_torque, which the driver's use_currents_as_efforts: false reads (its on_configure check)
CURRENT_AS_TORQUE = (_v('5.23.0'), _v('10.11.0'))
FRICTION_SCALES = (_v('5.25.1'), _v('10.12.1'))
# URScript's optimovej / optimovel, as the Client Library's External Control program guards its calls of them
OPTIMOVE = (_v('5.21.0'), _v('10.8.0'))


def supports(version: SoftwareVersion, minima: tuple[SoftwareVersion, SoftwareVersion]) -> bool:
    """`version` has a feature whose first versions are `minima` (PolyScope 5, PolyScope X); never on a CB3."""
    polyscope5, polyscope_x = minima
    if version.major < 5:
        return False
    return version[:3] >= (polyscope5 if version.major == 5 else polyscope_x)[:3]
