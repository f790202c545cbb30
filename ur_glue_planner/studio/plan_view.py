"""Plan and preview in the studio: the taught job planned (the planner's plan_job), its bead drawn by speed, its
figures shown, and the plan played on the model robot.

A part of :class:`~ur_glue_planner.studio.app.Studio` (a mixin, as :mod:`~ur_glue_planner.studio.teach_view`: it
works on the studio's state under its lock). Playback is :mod:`~ur_glue_planner.studio.playback`'s, the figures
:mod:`~ur_glue_planner.studio.figures`', why a plan failed :mod:`~ur_glue_planner.studio.plan_failure`'s.
"""
from __future__ import annotations

import time

import numpy as np

from ur_glue_planner.errors import GluePlannerError, JobError
from ur_glue_planner.motion.plan import GluePlan, plan_job
from ur_glue_planner.studio.figures import plan_figures, speed_summary
from ur_glue_planner.studio.job_file import studio_job
from ur_glue_planner.studio.legend import SPEED_SCALE
from ur_glue_planner.studio.part_view import measured_part
from ur_glue_planner.studio.plan_failure import plan_failure
from ur_glue_planner.studio.playback import Clock, Timeline, bead_segments
from ur_sim_driver.description.params import joint_names

SHOW_ABOVE = 0.002  # [m] paths are drawn this far above the glass so that it does not hide them


class PlanView:
    """Plan, the planned bead and figures, and playback of the plan on the model robot."""

    def start_state(self) -> np.ndarray:
        """Where the plan starts: the live robot's joint positions if it is this arm, else the job's home."""
        state = self.live.state() if self.live is not None else None
        if state is not None and tuple(state.names[:6]) == tuple(joint_names()):
            return np.array(state.q[:6])
        return np.array(self.sjob.job.home)

    def explain_failure(self, planner_message: str) -> str:
        """Why planning the taught waypoints failed, in the Teach tab's words (plan_failure.py)."""
        with self._lock:
            teach = self.teach
        results = self.reach_of(teach)
        self._keep_reach(teach, results)
        return plan_failure(planner_message, results, teach.planned_indices())

    def plan_now(self, clicked: float | None = None) -> GluePlan | None:
        """Plan the taught job (the planner's plan_job), draw the bead by speed, show the figures.

        The model robot then shows the selected waypoint's IK again; play or the slider play the plan on it.
        ``clicked``: when Plan was pressed (``time.monotonic()`` [s] in the click's handler; None: now), from which
        the plan's text counts the user's wait.
        """
        clicked = time.monotonic() if clicked is None else clicked
        self.begin('planning ...')
        with self._lock:
            if self.sjob is None:
                return None
            try:
                job = studio_job(self.sjob, self.teach).job
            except JobError as exc:
                self.say(f'cannot plan: {exc}')
                return None
        found, reason = measured_part(self.live.scan() if self.live is not None else None, job, self.say)
        if reason is not None:
            self.say(f'part refused: {reason}')
            return None
        try:
            plan = plan_job(job, self.start_state(), part=found)
        except GluePlannerError as exc:
            self.say(f'planning failed: {self.explain_failure(str(exc))}')
            return None
        figures = plan_figures(plan)
        with self._lock:
            self._clear_plan()
            self.plan, self.timeline = plan, Timeline.from_plan(plan)
            self.clock = Clock(self.timeline.duration, speed=float(self.panel.speed.value))
            self._q_ref = plan.bead.q[0]
            segs, colors = bead_segments(plan, v_max=SPEED_SCALE * plan.job.tcp_speed)
            _, _, normal = self.glass.project(segs.reshape(-1, 3))
            lifted = segs + SHOW_ABOVE * normal.reshape(segs.shape)  # drawn just above the glass, not inside it
            self._planned_bead = self.server.scene.add_line_segments('/planned_bead', lifted, colors, thickness=0.005)
            self.panel.time.max = round(self.timeline.duration, 2)
            for name, image in figures.items():
                self.panel.images[name].image = image
                self.panel.images[name].visible = True
            self.part_view.show(plan)
            self.show_ik()
            # Last, so that the wait it states includes the drawing above (the IK robot and markers too).
            self.panel.plan_info.content = speed_summary(plan, time.monotonic() - clicked)
        self.say(f'planned: bead {plan.summary.bead_length:.3f} m, {plan.summary.total_duration:.2f} s')
        return plan

    def _on_play(self, what: str) -> None:
        with self._lock:
            if self.clock is None:
                self.say('press Plan first')
                return
            self.mode = 'preview'
            self._model_view.set_visible(True)
            self.clock = self.clock.play() if what == 'play' else self.clock.pause()
            self._model_view.show(joint_names(), self.timeline.q_at(self.clock.t))

    def _on_scrub(self, event) -> None:
        if event.client is None:
            return
        with self._lock:
            if self.clock is not None:
                self.mode = 'preview'
                self._model_view.set_visible(True)
                self.clock = self.clock.seek(float(self.panel.time.value))
                self._model_view.show(joint_names(), self.timeline.q_at(self.clock.t))

    def _on_speed(self, event) -> None:
        with self._lock:
            if self.clock is not None:
                self.clock = self.clock.with_speed(float(self.panel.speed.value))

    def _clear_plan(self) -> None:
        """No plan: its bead line, figures, text, slider, the executed path and the bead deposited on the part leave
        the page."""
        self.plan = self.timeline = self.clock = None
        if self._planned_bead is not None:
            self._planned_bead.remove()
            self._planned_bead = None
        for image in self.panel.images.values():
            image.visible = False
        self.panel.plan_info.content = 'No plan yet: press **Plan**.'
        self.panel.time.max = 1.0
        self.panel.time.value = 0.0
        self.part_view.clear()
        self._reset_trail()
        if self.live_view is not None:
            self.live_view.clear_bead()
