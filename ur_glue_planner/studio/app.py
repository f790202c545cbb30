"""The studio page (viser): scene, teaching, preview, save/load, run and live view, wired to the pure modules.

Everything here is the thin edge: the panel's controls are :mod:`~ur_glue_planner.studio.panel`'s, teaching is
:class:`~ur_glue_planner.studio.teach_view.TeachView`'s, planning and preview
:class:`~ur_glue_planner.studio.plan_view.PlanView`'s, running :class:`~ur_glue_planner.studio.run_view.RunView`'s
(through :mod:`~ur_glue_planner.studio.ros_link`), the live robot :class:`~ur_glue_planner.studio.live_view.
LiveView`'s; files go through :mod:`~ur_glue_planner.studio.job_file`. This module loads a job and its scene, and
runs the page loop.
"""
from __future__ import annotations

import threading
import time
from pathlib import Path

import numpy as np
import trimesh
import viser

from ur_glue_planner.errors import GluePlannerError, JobError
from ur_glue_planner.motion.ik_branch import choose_branch
from ur_glue_planner.motion.plan import GluePlan
from ur_glue_planner.motion.ur_arm_kinematics import ur_kinematics
from ur_glue_planner.orientation import rotation_from_zyx_euler
from ur_glue_planner.path.glue_path import build_glue_path
from ur_glue_planner.scene.waypoints import windshield_model
from ur_glue_planner.studio import scene_view as sv
from ur_glue_planner.studio.job_file import StudioJob, read_job, teach_state, write_job
from ur_glue_planner.studio.legend import MODEL_OPACITY, MODEL_TINT, legend_entries, legend_html
from ur_glue_planner.studio.live_view import LiveView
from ur_glue_planner.studio.messages import MessageLog, log_html
from ur_glue_planner.studio.panel import LIVE_TEXT, build_panel
from ur_glue_planner.studio.part_view import PartView
from ur_glue_planner.studio.plan_view import SHOW_ABOVE, PlanView
from ur_glue_planner.studio.playback import Clock, Timeline
from ur_glue_planner.studio.reach import GlassCollision, Reach, ReachResult
from ur_glue_planner.studio.robot_geometry import RobotModel, ur_shapes
from ur_glue_planner.studio.robot_status import no_ros_status, status_html
from ur_glue_planner.studio.ros_link import LiveRobot, RunResult
from ur_glue_planner.studio.run_view import RunView
from ur_glue_planner.studio.scene_assets import glass_mesh_path, glass_pieces, glass_pose
from ur_glue_planner.studio.teach_view import TeachView
from ur_glue_planner.studio.teaching import TeachState
from ur_sim_driver.description.params import joint_names, load_ur_params
from ur_sim_driver.description.tool import get_tool
from ur_sim_driver.description.urdf import build_urdf

LOOP_RATE = 60.0  # [Hz] page updates: playback, live robot
# [m] camera position and look-at for a new page: from beyond the glass, looking back at the robot (the look-at
# lies beside the cell so that the cell shows left of the control panel)
INITIAL_CAMERA = ((0.45, 1.5, 1.0), (-0.3, 0.4, 0.28))
class Studio(TeachView, PlanView, RunView):
    """The glue studio served on http://host:port.

    Args:
        job_path: Job YAML to teach and run; None: live viewer only.
        host, port: Where to serve.
        live: The live robot link (None: no ROS, teaching and preview only).
        namespace, controller_name: Override the job's (for Run); '' keeps the job's.
        save_path: Default path of Save.
    """

    def __init__(self, job_path: str | Path | None, host: str = '127.0.0.1', port: int = 8080,
                 live: LiveRobot | None = None, namespace: str = '', controller_name: str = '',
                 save_path: str | Path = 'out/studio/glue_job.yaml') -> None:
        self.server = viser.ViserServer(host=host, port=port, verbose=False)
        self.server.gui.configure_theme(control_width='large', show_logo=False, show_share_button=False)
        self.live = live
        self._lock = threading.RLock()
        self._reach_lock = threading.Lock()  # the reach check of all waypoints: one thread at a time
        self._namespace, self._controller = namespace, controller_name
        self._save_default = str(save_path)
        self.log = MessageLog()
        self.sjob: StudioJob | None = None
        self.teach = TeachState()
        self.reach_results: list[ReachResult | None] = []
        self.plan: GluePlan | None = None
        self.timeline: Timeline | None = None
        self.clock: Clock | None = None
        self.mode = 'teach'  # what the model robot shows: 'teach' (IK), 'preview' (playback), 'run' (hidden)
        self.run_result: RunResult | None = None
        self.run_progress = (None, 0.0, 0.0)
        self._q_ref: np.ndarray | None = None
        self._reach_dirty = False
        self._markers: list = []
        self._model_view: sv.RobotView | None = None
        self._planned_bead = None
        self._gizmo = None
        self._status_shown = None
        self.live_view = LiveView(self.server, live, self._lift) if live is not None else None
        self.part_view = PartView(self.server)  # the part as measured by the cell's scanners, with a plan on it
        self.panel = build_panel(self.server.gui, job_path is not None, live is not None, self._save_default)
        self._wire(job_path is not None)
        self.server.on_client_connect(self._on_connect)
        if job_path is not None:
            self.load(job_path)
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._loop, daemon=True, name='ur_glue_studio_loop')
        self._thread.start()

    # ---- messages ----------------------------------------------------------------------------------------------
    @property
    def messages(self) -> list[str]:
        """Every line said so far, oldest first."""
        return self.log.history

    def say(self, text: str) -> None:
        """Add a line to the message box (newest first)."""
        with self._lock:
            self.log.say(text)
            self.panel.log.content = log_html(self.log.lines())

    def begin(self, text: str) -> None:
        """A new action (load, plan, run, save): what earlier ones said leaves the box, ``text`` starts it."""
        with self._lock:
            self.log.begin(text)
            self.panel.log.content = log_html(self.log.lines())

    @property
    def live_updates(self) -> int:
        """Live robot poses sent to the page."""
        return self.live_view.updates if self.live_view is not None else 0

    @property
    def bead_points_drawn(self) -> int:
        """Deposit points of the simulated bead shown in the page."""
        return self.live_view.bead_points_drawn if self.live_view is not None else 0

    def _on_connect(self, client) -> None:
        """A new page: its camera at :meth:`reset_view`'s pose."""
        self.reset_view(client)

    def reset_view(self, client) -> None:
        """A page's camera where a new page has it (the Reset view button): the cell from the front left,
        above the glass (the default view looks from far away)."""
        client.camera.up_direction = (0.0, 0.0, 1.0)
        client.camera.position = INITIAL_CAMERA[0]
        client.camera.look_at = INITIAL_CAMERA[1]

    # ---- GUI ---------------------------------------------------------------------------------------------------
    def _wire(self, with_job: bool) -> None:
        p = self.panel
        p.reset_view.on_click(lambda e: e.client is not None and self.reset_view(e.client))
        if not with_job:
            p.clear_trail.on_click(lambda _: self._reset_trail())
            return
        p.wp_select.on_update(self._on_select_number)
        p.step.on_update(lambda e: self._edit(lambda s: s.with_step(float(p.step.value))))
        p.orientation.on_click(lambda e: self.key('c' if e.target.value.startswith('C') else 'n'))
        p.edits.on_click(lambda e: self._on_edit_button(e.target.value))
        # The user's wait counts from the click's arrival (before a thread is made for the plan).
        p.plan_button.on_click(lambda _: threading.Thread(target=self.plan_now, args=(time.monotonic(),),
                                                          daemon=True).start())
        p.play.on_click(lambda e: self._on_play(e.target.value))
        p.time.on_update(self._on_scrub)
        p.speed.on_update(self._on_speed)
        p.run_button.on_click(lambda _: self.run())
        p.stop_button.on_click(lambda _: threading.Thread(target=self.stop_run, daemon=True).start())
        p.save_button.on_click(lambda _: self.save(p.save_path.value))
        p.load_button.on_click(lambda _: self.load(p.load_path.value))
        for key, command in p.commands.items():
            command.on_trigger(lambda _, k=key: self.key(k))

    # ---- loading and the job scene -----------------------------------------------------------------------------
    def load(self, path: str | Path) -> None:
        """Load a job file and show its scene and waypoints; what showed the previous job's plan is cleared."""
        self.begin(f'loading {path} ...')
        try:
            sjob = read_job(path)
        except JobError as exc:
            self.say(f'load failed: {exc}')
            return
        with self._lock:
            self.sjob = sjob
            job = sjob.job
            self.teach = teach_state(job, step_deg=float(self.panel.step.value))
            self.glass = windshield_model(job.windshield)
            robot, tool = load_ur_params(job.ur_type), get_tool(job.tool)  # the job's names, resolved once
            self.kin = ur_kinematics(robot, tool)
            self.reach = Reach(self.kin, GlassCollision(robot, tool, glass_pieces(job.windshield)))
            # The page loop checks every waypoint with its own Pinocchio and MuJoCo workspaces (not thread-safe).
            self._reach_all = Reach(ur_kinematics(robot, tool),
                                    GlassCollision(robot, tool, glass_pieces(job.windshield)))
            urdf = build_urdf(robot, tool=tool)
            if self._model_view is not None:
                self._model_view.remove()
            self._model_view = sv.RobotView(self.server, '/model', RobotModel(urdf, ur_shapes(robot, tool)),
                                            opacity=MODEL_OPACITY if self.live is not None else None,
                                            tint=MODEL_TINT)
            self._show_glass()
            self._clear_plan()
            self.panel.legend.content = legend_html(legend_entries(True, self.live is not None, job.tcp_speed))
            self._q_ref = self._bead_branch()
            self.reach_results = [None] * len(self.teach.waypoints)
            self.show_ik()
        self.say(f'loaded {sjob.path} ({len(self.teach.waypoints)} waypoints, {job.ur_type}, tool {job.tool})')

    def _show_glass(self) -> None:
        mesh = trimesh.load(glass_mesh_path(self.sjob.job.windshield), force='mesh')
        pose = glass_pose(self.sjob.job.windshield)
        self._glass = self.server.scene.add_mesh_simple('/glass', mesh.vertices, mesh.faces, color=(150, 190, 230),
                                                        opacity=0.7, side='double', wxyz=sv.wxyz(pose[:3, :3]),
                                                        position=pose[:3, 3], cast_shadow=False,
                                                        receive_shadow=False)
        self._glass.on_click(self._on_glass_click)

    def _lift(self, points: np.ndarray) -> np.ndarray:
        """Path points (K, 3) [m] moved above the glass along its normal (where the bead line is), if a job is
        loaded: the glass would hide them."""
        if self.sjob is None:
            return points
        return points + 1.5 * SHOW_ABOVE * self.glass.project(points)[2]

    def _bead_branch(self) -> np.ndarray:
        """IK reference for the waypoints: the plan's bead branch (the branch chosen from home), else home."""
        job = self.sjob.job
        if job.ik_seed is not None:
            return np.array(job.ik_seed)
        try:
            points, zyx = self.teach.planned_arrays()
            rots = np.array([rotation_from_zyx_euler(*o) for o in zyx])
            path = build_glue_path(points, rots, max_deviation=job.path.corner_max_deviation, closed=job.path.closed)
            return choose_branch(path, self.kin, np.array(job.home), job.tcp_speed)[0].q
        except (GluePlannerError, ValueError):
            return np.array(job.home)

    # ---- save ----------------------------------------------------------------------------------------------------
    def save(self, path: str | Path) -> Path | None:
        """Write the taught job (the waypoints the plan uses) to ``path``."""
        self.begin(f'saving to {path} ...')
        with self._lock:
            try:
                written = write_job(path, self.sjob, self.teach)
            except (JobError, OSError) as exc:
                self.say(f'save failed: {exc}')
                return None
            skipped = len(self.teach.skipped_indices())
        self.say(f'saved {len(written.job.path.waypoints)} waypoints to {Path(path).resolve()}'
                 + (f' ({skipped} unsaved skipped)' if skipped else ''))
        return Path(path)

    # ---- live robot and the page loop ------------------------------------------------------------------------------
    def _reset_trail(self) -> None:
        if self.live_view is not None:
            self.live_view.reset_trail()

    def _update_status(self) -> None:
        """The robot status line (sent only when its text changes) and the live viewer's traced frame."""
        state, text = self.live_view.status() if self.live_view is not None else no_ros_status()
        if (state, text) != self._status_shown:
            self._status_shown = (state, text)
            self.panel.robot_status.content = status_html(state, text)
            if self.panel.live_text is not None and self.live_view.tip_frame is not None:
                self.panel.live_text.content = f'{LIVE_TEXT} The red path traces `{self.live_view.tip_frame}`.'

    def _loop(self) -> None:
        period = 1.0 / LOOP_RATE
        last = time.monotonic()
        ticks = 0
        while not self._stop.is_set():
            now = time.monotonic()
            dt, last = now - last, now
            ticks += 1
            try:
                with self._lock:
                    if self.clock is not None and self.clock.playing and self.mode == 'preview':
                        self.clock = self.clock.advance(dt)
                        self._model_view.show(joint_names(), self.timeline.q_at(self.clock.t))
                        if ticks % 6 == 0 or not self.clock.playing:
                            self.panel.time.value = round(self.clock.t, 2)
                    if self.live_view is not None:
                        self.live_view.update()
                        if ticks % 6 == 0:
                            self.live_view.draw_trail()
                            self._update_run_gui()
                    if ticks % 6 == 1:
                        self._update_status()
                if ticks % 15 == 0:
                    self._check_all_reach()
            except Exception as exc:  # keep the page alive; show what went wrong
                self.say(f'internal error: {type(exc).__name__}: {exc}')
            self._stop.wait(max(0.0, period - (time.monotonic() - now)))

    def close(self) -> None:
        """Stop the page loop and the server."""
        self._stop.set()
        self._thread.join(timeout=5.0)
        self.server.stop()
