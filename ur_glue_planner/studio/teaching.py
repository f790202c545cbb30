"""Teaching state of the studio: the waypoints, their tip orientations, which one is selected, what is saved.

Seed 1's workflow, as pure data: waypoints are clicked on the glass (added after the selected one), selected,
moved, deleted and reordered; each has a tip orientation (ZYX Euler angles, the job file's format) edited with
the keys (Up/Down about X, Left/Right about Y, by ``step``) or set whole (the rotation gizmo). ``C`` saves the
current waypoint's orientation, ``N`` selects the next waypoint. A waypoint whose orientation was edited and not
saved is skipped by the plan, as the seed skips a waypoint left with N and no C; if no waypoint is saved at all,
every waypoint is used with its orientation (the seed's default orientations). Waypoints loaded from a job file
count as saved.

Every operation returns a new :class:`TeachState`; invalid input raises ValueError naming the value and the limit.
"""
from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass

import numpy as np

from ur_glue_planner.defaults import DEFAULT_ORIENTATION_ZYX, DEFAULT_WAYPOINTS
from ur_glue_planner.orientation import rotation_from_zyx_euler, zyx_euler_from_rotation

Vec3 = tuple[float, float, float]

#: Keys of the seed and the orientation edit each makes: (Euler component, sign). The job's ZYX Euler angles are
#: (z, y, x), so component 2 is the rotation about the tip's X axis and component 1 the one about its Y axis.
KEY_EDITS: dict[str, tuple[int, int]] = {'up': (2, +1), 'down': (2, -1), 'right': (1, +1), 'left': (1, -1)}
MAX_STEP_DEG = 45.0


@dataclass(frozen=True)
class TaughtWaypoint:
    """One waypoint: tip position [m] (world), tip orientation as ZYX Euler angles (z, y, x) [rad], saved flag."""

    position: Vec3
    orientation_zyx: Vec3
    saved: bool

    def rotation(self) -> np.ndarray:
        """Tip rotation (3, 3) in the world."""
        return rotation_from_zyx_euler(*self.orientation_zyx)


def _vec3(value, what: str) -> Vec3:
    arr = np.asarray(value, dtype=float)
    if arr.shape != (3,) or not np.all(np.isfinite(arr)):
        raise ValueError(f'{what}: {value!r} is not 3 finite numbers')
    return tuple(float(x) for x in arr)


@dataclass(frozen=True)
class TeachState:
    """Waypoints in bead order, the selected one (index or None) and the key step [deg]."""

    waypoints: tuple[TaughtWaypoint, ...] = ()
    selected: int | None = None
    step_deg: float = 5.0
    default_orientation_zyx: Vec3 = DEFAULT_ORIENTATION_ZYX

    # ---- construction ----------------------------------------------------------------------------------------
    @classmethod
    def from_arrays(cls, positions: np.ndarray, orientations_zyx: np.ndarray, saved: bool = True,
                    **kwargs) -> TeachState:
        """Waypoints (K, 3) [m] with orientations (K, 3) or one (3,) ZYX Euler [rad]."""
        pos = np.asarray(positions, dtype=float).reshape(-1, 3)
        ori = np.broadcast_to(np.asarray(orientations_zyx, dtype=float), pos.shape)
        wps = tuple(TaughtWaypoint(_vec3(p, f'waypoint {k}'), _vec3(o, f'orientation {k}'), saved)
                    for k, (p, o) in enumerate(zip(pos, ori)))
        return cls(wps, 0 if wps else None, **kwargs)

    @classmethod
    def defaults(cls, **kwargs) -> TeachState:
        """Seed 1's 22 waypoints with its orientation, saved."""
        return cls.from_arrays(DEFAULT_WAYPOINTS, np.array(DEFAULT_ORIENTATION_ZYX), **kwargs)

    def restore_defaults(self) -> TeachState:
        """Seed 1's waypoints again, keeping the step setting."""
        return TeachState.defaults(step_deg=self.step_deg, default_orientation_zyx=self.default_orientation_zyx)

    # ---- queries ---------------------------------------------------------------------------------------------
    def _index(self, index: int) -> int:
        if not isinstance(index, (int, np.integer)) or not 0 <= index < len(self.waypoints):
            raise ValueError(f'waypoint index {index!r} is not in [0, {len(self.waypoints) - 1}]')
        return int(index)

    def current(self) -> TaughtWaypoint | None:
        """The selected waypoint, or None."""
        return None if self.selected is None else self.waypoints[self.selected]

    def planned_indices(self) -> tuple[int, ...]:
        """Indices of the waypoints the plan uses: the saved ones, or all if none is saved."""
        saved = tuple(k for k, w in enumerate(self.waypoints) if w.saved)
        return saved if saved else tuple(range(len(self.waypoints)))

    def skipped_indices(self) -> tuple[int, ...]:
        """Indices left out of the plan (orientation edited or added, and not saved)."""
        used = set(self.planned_indices())
        return tuple(k for k in range(len(self.waypoints)) if k not in used)

    def planned_arrays(self) -> tuple[np.ndarray, np.ndarray]:
        """Positions (K, 3) [m] and ZYX orientations (K, 3) [rad] of the planned waypoints."""
        idx = self.planned_indices()
        return (np.array([self.waypoints[k].position for k in idx]).reshape(-1, 3),
                np.array([self.waypoints[k].orientation_zyx for k in idx]).reshape(-1, 3))

    # ---- editing waypoints -----------------------------------------------------------------------------------
    def _with(self, waypoints, selected) -> TeachState:
        return dataclasses.replace(self, waypoints=tuple(waypoints), selected=selected)

    def add(self, position, orientation_zyx=None) -> TeachState:
        """Insert a waypoint after the selected one (at the end if none) and select it.

        Its orientation is ``orientation_zyx``, else the selected waypoint's, else the default; it is not saved.
        """
        if orientation_zyx is None:
            cur = self.current()
            orientation_zyx = cur.orientation_zyx if cur is not None else self.default_orientation_zyx
        wp = TaughtWaypoint(_vec3(position, 'position'), _vec3(orientation_zyx, 'orientation_zyx'), False)
        at = len(self.waypoints) if self.selected is None else self.selected + 1
        wps = list(self.waypoints)
        wps.insert(at, wp)
        return self._with(wps, at)

    def select(self, index: int | None) -> TeachState:
        """Select waypoint ``index`` (None: no selection)."""
        return self._with(self.waypoints, None if index is None else self._index(index))

    def move(self, index: int, position) -> TeachState:
        """Put waypoint ``index`` at ``position`` [m] (the caller keeps it on the surface); orientation unchanged."""
        i = self._index(index)
        wps = list(self.waypoints)
        wps[i] = dataclasses.replace(wps[i], position=_vec3(position, 'position'))
        return self._with(wps, self.selected)

    def delete(self, index: int) -> TeachState:
        """Remove waypoint ``index``; the one before it (or the new first) becomes selected."""
        i = self._index(index)
        wps = list(self.waypoints)
        del wps[i]
        return self._with(wps, min(max(i - 1, 0), len(wps) - 1) if wps else None)

    def reorder(self, index: int, new_index: int) -> TeachState:
        """Move waypoint ``index`` to position ``new_index`` in the bead order; it stays selected."""
        i, j = self._index(index), self._index(new_index)
        wps = list(self.waypoints)
        wps.insert(j, wps.pop(i))
        return self._with(wps, j)

    # ---- orientations ----------------------------------------------------------------------------------------
    def with_step(self, step_deg: float) -> TeachState:
        """Key step [deg] in (0, MAX_STEP_DEG]."""
        ok = isinstance(step_deg, (int, float)) and math.isfinite(step_deg) and 0.0 < step_deg <= MAX_STEP_DEG
        if not ok:
            raise ValueError(f'step: {step_deg!r} deg is not in (0, {MAX_STEP_DEG:g}]')
        return dataclasses.replace(self, step_deg=float(step_deg))

    def set_orientation(self, index: int, orientation_zyx) -> TeachState:
        """Set waypoint ``index``'s orientation (ZYX Euler [rad]); it becomes unsaved until ``save``."""
        i = self._index(index)
        wps = list(self.waypoints)
        wps[i] = dataclasses.replace(wps[i], orientation_zyx=_vec3(orientation_zyx, 'orientation_zyx'), saved=False)
        return self._with(wps, self.selected)

    def set_rotation(self, index: int, rotation: np.ndarray) -> TeachState:
        """Set waypoint ``index``'s orientation from a rotation matrix (3, 3) (the gizmo)."""
        return self.set_orientation(index, zyx_euler_from_rotation(rotation))

    def key(self, name: str) -> TeachState:
        """The seed's keys on the selected waypoint: 'up', 'down', 'left', 'right' rotate by the step, 'c' saves,
        'n' selects the next waypoint (wrapping to the first)."""
        key = name.lower()
        cur = self.selected
        if key not in (*KEY_EDITS, 'c', 'n'):
            raise ValueError(f"key {name!r} is not one of: {', '.join((*KEY_EDITS, 'c', 'n'))}")
        if cur is None:
            return self if key != 'n' or not self.waypoints else self.select(0)
        if key == 'n':
            return self.select((cur + 1) % len(self.waypoints))
        if key == 'c':
            wps = list(self.waypoints)
            wps[cur] = dataclasses.replace(wps[cur], saved=True)
            return self._with(wps, cur)
        component, sign = KEY_EDITS[key]
        zyx = list(self.waypoints[cur].orientation_zyx)
        zyx[component] += sign * math.radians(self.step_deg)
        return self.set_orientation(cur, zyx)
