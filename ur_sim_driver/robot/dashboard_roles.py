"""Who may control the robot: the CB3's user role and the e-series' operational mode and remote control, as state
that restricts what the robot accepts. No rclpy here.

CB3 (``setUserRole``, from 3.1): the role restricts the teach pendant, not the dashboard server (UR's dashboard
server documentation for the CB-series): NONE (also ``setUserRole`` without a role) leaves every button enabled,
PROGRAMMER disables "SETUP Robot", OPERATOR enables only "RUN Program" and "SHUTDOWN Robot", LOCKED disables every
button. Expert mode is available as NONE and PROGRAMMER only. ur_sim has no teach pendant: :meth:`pendant_allows`
answers what it would allow (flight reports record the role); dashboard commands are accepted in every role, as on
the robot.

PolyScope 5 (``set operational mode``, from 5.0): the dashboard takes over the operational mode until ``clear
operational mode``. A robot in MANUAL mode is in local control (remote control needs AUTOMATIC mode): the dashboard
server refuses the commands that act on the robot with its remote-control answer (:data:`REMOTE_REFUSAL`), while
queries, popups and the operational mode commands themselves stay available.
"""
from __future__ import annotations

USER_ROLES = ('PROGRAMMER', 'OPERATOR', 'NONE', 'LOCKED', 'RESTRICTED')  # CB3's setUserRole
OPERATIONAL_MODES = ('MANUAL', 'AUTOMATIC')  # e-series: set by the dashboard or the teach pendant
REMOTE_REFUSAL = ('Command is not allowed due to safety reasons, please switch robot to Remote Control mode and '
                  'reconnect to port 29999')
# Dashboard commands (keys of software.COMMANDS) that act on the robot: an e-series refuses them in local control.
REMOTE_ONLY = frozenset({'power on', 'power off', 'brake release', 'unlock protective stop', 'restart safety',
                         'load', 'load installation', 'play', 'pause', 'stop', 'shutdown'})
# Teach pendant actions by user role. RESTRICTED is not described by UR: ur_sim restricts it as OPERATOR.
PENDANT_ACTIONS = ('run program', 'shutdown robot', 'program robot', 'setup robot', 'expert mode')
_PENDANT = {
    'NONE': frozenset(PENDANT_ACTIONS),
    'PROGRAMMER': frozenset(PENDANT_ACTIONS) - {'setup robot'},
    'OPERATOR': frozenset({'run program', 'shutdown robot'}),
    'RESTRICTED': frozenset({'run program', 'shutdown robot'}),
    'LOCKED': frozenset(),
}


class OperatorControls:
    """The user role (CB3) and operational mode (e-series) of one simulated robot.

    Args:
        e_series: the robot runs PolyScope 5 (it has remote control and operational modes), else CB3 software.
    """

    def __init__(self, e_series: bool) -> None:
        self.e_series = e_series
        self.user_role = 'PROGRAMMER'
        self.operational_mode = 'AUTOMATIC'
        self.mode_by_dashboard = False  # set operational mode took over the mode (clear operational mode ends it)

    @property
    def remote_control(self) -> bool:
        """The robot accepts dashboard commands that act on it (an e-series in AUTOMATIC mode; a CB3 always)."""
        return not self.e_series or self.operational_mode != 'MANUAL'

    def refusal(self, command: str) -> str | None:
        """Why the robot refuses dashboard `command` (a key of software.COMMANDS) now, or None when it accepts it."""
        if command in REMOTE_ONLY and not self.remote_control:
            return f'the robot is in local control (operational mode {self.operational_mode}): {command} needs ' \
                   'remote control'
        return None

    def pendant_allows(self, action: str) -> bool:
        """The teach pendant offers `action` (one of PENDANT_ACTIONS) in the current user role."""
        if action not in PENDANT_ACTIONS:
            raise ValueError(f'pendant action {action!r} is not one of {", ".join(PENDANT_ACTIONS)}')
        return action in _PENDANT[self.user_role]

    def set_user_role(self, role: str) -> str | None:
        """`role` as sent (any case; '' means NONE); None when set, else why not."""
        name = role.strip().upper() or 'NONE'
        if name not in USER_ROLES:
            return f'user role {role!r} is not one of {", ".join(r.lower() for r in USER_ROLES)}'
        self.user_role = name
        return None

    def set_operational_mode(self, mode: str) -> str | None:
        """`mode` as sent (any case); None when set (the dashboard now holds the mode), else why not."""
        if mode.strip().upper() not in OPERATIONAL_MODES:
            return f'operational mode {mode!r} is not one of {", ".join(m.lower() for m in OPERATIONAL_MODES)}'
        self.operational_mode = mode.strip().upper()
        self.mode_by_dashboard = True
        return None

    def clear_operational_mode(self) -> None:
        """The teach pendant may change the mode again; the mode itself stays."""
        self.mode_by_dashboard = False
