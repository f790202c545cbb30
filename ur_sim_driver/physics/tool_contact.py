"""What counts as a tool contact: a body of the tool or the flange (the subtree of ``wrist_3_link``) touching something
with more than a force threshold, averaged over the control period's physics steps (``ArmPhysics.contacts``).
Shared by the driver's tool contact controller and the URScript programs that watch for a contact."""
from __future__ import annotations

from collections.abc import Iterable

from ur_sim_driver.physics.physics import Contact

TOOL_CONTACT_FORCE = 2.0  # [N] contact force at the tool or flange that counts as a tool contact
FLANGE_LINK = 'wrist_3_link'


def contact_threshold(protective_stop_force: float) -> float:
    """[N] the tool contact force: TOOL_CONTACT_FORCE, or half the protective stop force [N] when that is lower (so
    that a slow approach ends in a tool contact, never in a protective stop)."""
    return min(TOOL_CONTACT_FORCE, 0.5 * protective_stop_force)


def tool_bodies(model, flange: str) -> frozenset[str]:
    """Names of the bodies in the subtree of body `flange` (flange, tool, payload) of a MuJoCo model."""
    import mujoco

    root = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_BODY, flange)
    if root < 0:
        return frozenset()
    names = set()
    for b in range(model.nbody):
        a = b
        while a > 0 and a != root:
            a = int(model.body_parentid[a])
        if a == root:
            names.add(mujoco.mj_id2name(model, mujoco.mjtObj.mjOBJ_BODY, b))
    return frozenset(names)


def strongest_touch(contacts: Iterable[Contact], bodies: frozenset[str], threshold: float) -> Contact | None:
    """The strongest contact of one of `bodies` over `threshold` [N], or None."""
    touching = [c for c in contacts if c.robot_part in bodies and c.force > threshold]
    return max(touching, key=lambda c: c.force) if touching else None
