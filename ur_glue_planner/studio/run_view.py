"""Running the taught job from the studio on the live robot (through ``ros_link``, as ur_glue_planner runs it):
start, stop, progress and the result on the page.

A part of :class:`~ur_glue_planner.studio.app.Studio` (a mixin, as :mod:`~ur_glue_planner.studio.teach_view`: it
works on the studio's state under its lock).
"""
from __future__ import annotations

from ur_glue_planner.errors import JobError
from ur_glue_planner.motion.plan import GluePlan
from ur_glue_planner.studio.job_file import studio_job
from ur_glue_planner.studio.ros_link import RunResult


class RunView:
    """Run and Stop, the run's progress line and its result."""

    def run(self) -> None:
        """Plan from the robot's current state and execute through FollowJointTrajectory (as ur_glue_planner)."""
        with self._lock:
            if self.live is None:
                self.say('run: no ROS connection')
                return
            if self.live.running:
                self.say('run: already running')
                return
            self.begin('run: planning from the robot\'s state ...')
            try:
                job = studio_job(self.sjob, self.teach).job
            except JobError as exc:
                self.say(f'run: {exc}')
                return
            self.run_result = None
            self.run_progress = (None, 0.0, 0.0)
            self.panel.progress.value = 0.0
            self.panel.run_info.content = 'connecting ...'
            self._reset_trail()
            self.mode = 'run'
            self._model_view.set_visible(False)  # the live robot is the one to watch
        self.live.start_run(job, self._namespace or job.namespace, self._controller or job.controller_name,
                            log=self._run_log, on_progress=self._on_run_progress, on_done=self._on_run_done)

    def stop_run(self) -> None:
        """Stop the run: its goal is cancelled first, the message and the wait for the run's end come after.

        The request takes no lock of the studio's: the Stop click's thread used to say its message first, under the
        studio's lock, which the page loop holds while it draws the moving robot and the bead (and a plan while it
        draws itself), so whatever held it delayed the cancel.
        """
        live = self.live
        if live is None or not live.running:
            return
        live.request_stop()
        self.say('stop: cancelling the goal')
        live.stop_run()

    def _run_log(self, text: str) -> None:
        if not text.lstrip().startswith('['):
            self.say(text.strip())

    def _on_run_progress(self, segment: str, fraction: float, error: float) -> None:
        self.run_progress = (segment, fraction, error)

    def _on_run_done(self, result: RunResult, plan: GluePlan | None) -> None:
        message = self.explain_failure(result.message) if result.planning_failed else result.message
        with self._lock:
            self.run_result = result
            if plan is not None:
                self.part_view.show(plan)  # the part as measured for this run
            word = 'succeeded' if result.succeeded else 'failed'
            self.panel.run_info.content = f'**Run {word}**: {message}'
            if self.mode == 'run':  # the IK robot again, beside the live one
                self.show_ik()
        self.say(f'run {word}: {message}')

    def _update_run_gui(self) -> None:
        # The progress line until the run's result: once set, the result stays shown.
        if self.sjob is None or self.live is None or not self.live.running or self.run_result is not None:
            return
        segment, fraction, error = self.run_progress
        if segment is not None:
            self.panel.progress.value = 100.0 * fraction
            self.panel.run_info.content = (f'running **{segment}**: {100 * fraction:.0f} %, max joint tracking '
                                           f'error {error * 1e3:.2f} mrad')
