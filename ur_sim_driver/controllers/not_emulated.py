"""The driver's controllers that ur_sim lists but does not emulate yet.

passthrough_trajectory_controller, freedrive_mode_controller and tool_contact_controller are loaded by the
driver (inactive). ur_sim reports them in list_controllers with their real types and the command interfaces they
would claim, so that switch requests naming them meet the same conflict and mode rules; activating one is refused
by the controller manager, naming why (:attr:`NotEmulated.unavailable`). They create no node and no interfaces.
When one of them is implemented, its own module replaces the entry here.
"""
from __future__ import annotations

from ur_sim_driver.controllers.base import Component, Host
from ur_sim_driver.sim_config import SimConfig
from ur_sim_driver.ur_hardware import FREEDRIVE, PASSTHROUGH, TOOL_CONTACT, joint_interfaces, prefixed_joints

UNAVAILABLE = 'ur_sim does not emulate this controller yet'


class NotEmulated(Component):
    """A loaded, inactive controller without behaviour."""

    initially_active = False
    unavailable = UNAVAILABLE

    def __init__(self, name: str, type_name: str) -> None:
        super().__init__()
        self.name = name
        self.type_name = type_name

    def configure(self, host: Host) -> None:
        self.host = host  # no node: nothing to serve

    def activate(self) -> None:
        raise RuntimeError(f'{self.name}: {UNAVAILABLE}')

    def interfaces(self, cfg: SimConfig) -> tuple[tuple[str, ...], tuple[str, ...]]:
        p = cfg.tf_prefix
        joints = prefixed_joints(cfg.joints, p)
        if self.name == 'passthrough_trajectory_controller':
            command = tuple(f'{p}{PASSTHROUGH}/setpoint_{kind}_{i}' for i in range(len(joints))
                            for kind in ('positions', 'velocities', 'accelerations'))
            command += tuple(f'{p}{PASSTHROUGH}/{n}' for n in ('abort', 'transfer_state', 'time_from_start',
                                                                'trajectory_size'))
            state = joint_interfaces(joints, 'position', 'velocity') + (f'{p}speed_scaling/speed_scaling_factor',)
            return command, state
        if self.name == 'freedrive_mode_controller':
            return tuple(f'{p}{FREEDRIVE}/{n}' for n in ('async_success', 'enable', 'abort')), ()
        if self.name == 'tool_contact_controller':
            return (f'{p}{TOOL_CONTACT}/tool_contact_set_state',), \
                tuple(f'{p}{TOOL_CONTACT}/{n}' for n in ('tool_contact_result', 'tool_contact_state'))
        return (), ()


def not_emulated_controllers() -> list[NotEmulated]:
    """The driver's controllers ur_sim lists without emulating them."""
    return [NotEmulated('passthrough_trajectory_controller', 'ur_controllers/PassthroughTrajectoryController'),
            NotEmulated('freedrive_mode_controller', 'ur_controllers/FreedriveModeController'),
            NotEmulated('tool_contact_controller', 'ur_controllers/ToolContactController')]
