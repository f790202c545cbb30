"""The Teach tab of the studio: editing the waypoints from the page and drawing them with their reach.

A part of :class:`~ur_glue_planner.studio.app.Studio` (a mixin: it works on the studio's state under its lock).
State changes go through :class:`~ur_glue_planner.studio.teaching.TeachState`, picking through
:mod:`~ur_glue_planner.studio.surface_pick`, IK through :mod:`~ur_glue_planner.studio.reach`.
"""
from __future__ import annotations

import numpy as np

from ur_glue_planner.studio import scene_view as sv
from ur_glue_planner.studio.reach import ReachResult, waypoint_pose
from ur_glue_planner.studio.surface_pick import onto_surface, ray_hit
from ur_glue_planner.studio.teaching import TeachState
from ur_sim_driver.description.params import joint_names


class TeachView:
    """Waypoint editing, markers, gizmo, the selected waypoint's text and IK robot, and the reach of all."""

    # ---- editing ---------------------------------------------------------------------------------------------
    def _edit(self, change) -> None:
        """Apply a TeachState change; errors are shown, not raised. The model robot shows the selected IK again."""
        with self._lock:
            if self.sjob is None:
                return
            try:
                self.teach = change(self.teach)
            except ValueError as exc:
                self.say(str(exc))
                return
            self.show_ik()

    def show_ik(self) -> None:
        """Teach mode: the model robot visible at the selected waypoint's IK, the markers and texts redrawn."""
        with self._lock:
            self.mode = 'teach'
            self._model_view.set_visible(True)
            self.reach_results = (self.reach_results + [None] * len(self.teach.waypoints))[:len(self.teach.waypoints)]
            self._reach_dirty = True
            self._refresh_teach()

    def key(self, name: str) -> None:
        """One of the seed's keys: 'up', 'down', 'left', 'right', 'c', 'n'."""
        self._edit(lambda s: s.key(name))

    def add_at_ray(self, origin, direction) -> bool:
        """Add a waypoint where the ray hits the glass (after the selected one); False if it misses."""
        with self._lock:
            hit = ray_hit(self.glass, origin, direction)
            if hit is None:
                self.say('the click missed the glass')
                return False
            self._edit(lambda s: s.add(hit.position))
            return True

    def _on_glass_click(self, event) -> None:
        if self.panel.click_adds.value:
            self.add_at_ray(event.ray_origin, event.ray_direction)

    def _on_select_number(self, event) -> None:
        if event.client is None:
            return
        n = len(self.teach.waypoints)
        self._edit(lambda s: s.select(int(min(max(self.panel.wp_select.value, 1), n)) - 1))

    def _on_edit_button(self, what: str) -> None:
        sel = self.teach.selected
        if what == 'defaults':
            self._edit(lambda s: s.restore_defaults())
        elif sel is not None and what == 'delete':
            self._edit(lambda s: s.delete(sel))
        elif sel is not None and what in ('earlier', 'later'):
            target = sel - 1 if what == 'earlier' else sel + 1
            if 0 <= target < len(self.teach.waypoints):
                self._edit(lambda s: s.reorder(sel, target))

    def _on_gizmo(self, event) -> None:
        # Applied at release: re-posing the gizmo from here while the user drags it would fight the drag.
        if event.client is None or event.phase != 'end' or self.teach.selected is None:
            return
        self.gizmo_released(self.teach.selected, np.asarray(event.target.position), np.asarray(event.target.wxyz))

    def gizmo_released(self, index: int, position: np.ndarray, wxyz: np.ndarray) -> bool:
        """The gizmo of waypoint ``index`` was let go at ``position`` [m] with orientation ``wxyz``: the waypoint
        moves to the nearest glass point (refused off the glass) and takes the new orientation if it turned."""
        rotation = sv.rotation_of(wxyz)
        on_glass = onto_surface(self.glass, position)
        if on_glass is None:
            self.say('a waypoint must stay on the glass')
            self._refresh_teach()
            return False

        def change(s: TeachState) -> TeachState:
            turned = not np.allclose(rotation, s.waypoints[index].rotation(), atol=1e-9)
            moved = s.move(index, on_glass.position)
            return moved.set_rotation(index, rotation) if turned else moved

        self._edit(change)
        return True

    # ---- drawing -----------------------------------------------------------------------------------------------
    def _refresh_teach(self) -> None:
        """Markers, labels, the gizmo, the selected waypoint's text and the model robot at its IK."""
        with self._lock:
            res = self._solve_selected() if self.teach.current() is not None else None  # before colouring
            for handle in self._markers:
                handle.remove()
            self._markers = []
            skipped = set(self.teach.skipped_indices())
            for k, wp in enumerate(self.teach.waypoints):
                known = self.reach_results[k] if k < len(self.reach_results) else None
                unreachable = known is not None and not known.reachable
                color = sv.RED if unreachable else sv.GREY if k in skipped else sv.GREEN
                selected = k == self.teach.selected
                marker = self.server.scene.add_icosphere(
                    f'/waypoints/wp_{k}', radius=sv.MARKER_RADIUS * (1.6 if selected else 1.0),
                    color=sv.SELECTED if selected and color == sv.GREEN else color, position=wp.position,
                    subdivisions=2, cast_shadow=False, receive_shadow=False)
                marker.on_click(lambda _, i=k: self._edit(lambda s: s.select(i)))
                label = self.server.scene.add_label(f'/waypoints/label_{k}', str(k + 1),
                                                    position=np.array(wp.position) + [0.0, 0.0, 0.02])
                self._markers += [marker, label]
            cur = self.teach.current()
            if cur is None:
                if self._gizmo is not None:
                    self._gizmo.visible = False
                self.panel.wp_info.content = 'No waypoint: click the glass to add one.'
                return
            if self._gizmo is None:
                self._gizmo = self.server.scene.add_transform_controls('/gizmo', scale=0.12, line_width=2.0)
                self._gizmo.on_update(self._on_gizmo)
            self._gizmo.visible = True
            self._gizmo.position = cur.position
            self._gizmo.wxyz = sv.wxyz(cur.rotation())
            self.panel.wp_select.max = max(1, len(self.teach.waypoints))
            self.panel.wp_select.value = self.teach.selected + 1
            self.panel.wp_info.content = self._describe_selected(res)
            if self.mode == 'teach' and res is not None:
                self._model_view.show(joint_names(), res.q)

    def _solve_selected(self) -> ReachResult | None:
        sel = self.teach.selected
        job = self.sjob.job
        wp = self.teach.waypoints[sel]
        _, _, normal = self.glass.project(np.array(wp.position)[None])
        res = self.reach.solve(waypoint_pose(wp.position, wp.rotation(), normal[0], job.standoff), self._q_ref)
        self.reach_results[sel] = res
        return res

    def _describe_selected(self, res: ReachResult | None) -> str:
        sel = self.teach.selected
        wp = self.teach.waypoints[sel]
        zyx = np.degrees(wp.orientation_zyx)
        state = 'saved' if wp.saved else 'not saved: skipped by the plan (press C)'
        planned = self.teach.planned_indices()
        reach = '' if res is None else ('**reachable**' if res.reachable else f'**unreachable**: {res.reason}')
        others = [f'{k + 1}' for k, r in enumerate(self.reach_results) if r is not None and not r.reachable]
        red = f'  \nunreachable (red): {", ".join(others)}' if others else ''
        return (f'**Waypoint {sel + 1}** of {len(self.teach.waypoints)} ({state})  \n'
                f'position [m] {np.round(wp.position, 4).tolist()}  \n'
                f'orientation ZYX [deg] {np.round(zyx, 2).tolist()}, step {self.teach.step_deg:g} deg  \n'
                f'{reach}  \nthe plan uses {len(planned)} of {len(self.teach.waypoints)} waypoints{red}')

    # ---- reach of every waypoint ---------------------------------------------------------------------------------
    def reach_of(self, teach: TeachState) -> list[ReachResult]:
        """IK of every waypoint of ``teach``, each from its predecessor's solution (the first from the bead branch).

        Its own Pinocchio and MuJoCo workspaces (not thread-safe), used by one thread at a time.
        """
        with self._lock:
            q, job, reach, glass = self._q_ref, self.sjob.job, self._reach_all, self.glass
        results = []
        with self._reach_lock:
            for wp in teach.waypoints:
                _, _, normal = glass.project(np.array(wp.position)[None])
                res = reach.solve(waypoint_pose(wp.position, wp.rotation(), normal[0], job.standoff), q)
                results.append(res)
                q = res.q if res.reachable else q
        return results

    def _check_all_reach(self) -> None:
        """The reach of every waypoint for the red markers, when the waypoints changed."""
        with self._lock:
            if not self._reach_dirty or self.sjob is None:
                return
            self._reach_dirty = False
            teach = self.teach
        results = self.reach_of(teach)
        self._keep_reach(teach, results)

    def _keep_reach(self, teach: TeachState, results: list[ReachResult]) -> None:
        """Store ``results`` if the waypoints are still ``teach``'s; redraw the markers if a colour changed."""
        with self._lock:
            if self.teach is teach:
                changed = [(r.reachable if r else None) for r in self.reach_results] != [r.reachable for r in results]
                self.reach_results = results
                if changed:
                    self._refresh_teach()
