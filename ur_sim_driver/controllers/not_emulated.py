"""The driver's controllers that ur_sim lists but does not emulate yet.

freedrive_mode_controller is loaded by the
driver (inactive). ur_sim reports them in list_controllers with their real types and the command interfaces they
would claim, so that switch requests naming them meet the same conflict and mode rules; activating one is refused
by the controller manager, naming why (:attr:`NotEmulated.unavailable`). They create no node and no interfaces.
When one of them is implemented, its own module replaces the entry here.
"""
from __future__ import annotations

from ur_sim_driver.controllers.base import Component, Host
from ur_sim_driver.sim_config import SimConfig
from ur_sim_driver.ur_hardware import FREEDRIVE

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
        if self.name == 'freedrive_mode_controller':
            return tuple(f'{p}{FREEDRIVE}/{n}' for n in ('async_success', 'enable', 'abort')), ()
        return (), ()


def not_emulated_controllers() -> list[NotEmulated]:
    """The driver's controllers ur_sim lists without emulating them."""
    return [NotEmulated('freedrive_mode_controller', 'ur_controllers/FreedriveModeController')]
