"""The studio page (viser): scene, teaching, preview, save/load, run and live view, wired to the pure modules.

Everything here is the thin edge: state changes go through :class:`~ur_glue_planner.studio.teaching.TeachState`,
files through :mod:`~ur_glue_planner.studio.job_file`, picking through :mod:`~ur_glue_planner.studio.surface_pick`,
IK through :mod:`~ur_glue_planner.studio.reach`, playback through :mod:`~ur_glue_planner.studio.playback`, the plan
through :func:`~ur_glue_planner.motion.plan.plan_job` and running through :mod:`~ur_glue_planner.studio.ros_link`.
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
from ur_glue_planner.motion.plan import GluePlan, plan_job
from ur_glue_planner.motion.ur_arm_kinematics import ur_kinematics
from ur_glue_planner.orientation import rotation_from_zyx_euler
from ur_glue_planner.path.glue_path import build_glue_path
from ur_glue_planner.scene.waypoints import windshield_model
from ur_glue_planner.studio import scene_view as sv
from ur_glue_planner.studio.figures import FIGURES, plan_figures, speed_summary
from ur_glue_planner.studio.job_file import StudioJob, read_job, studio_job, teach_state, write_job
from ur_glue_planner.studio.playback import Clock, Timeline, bead_segments
from ur_glue_planner.studio.reach import GlassCollision, Reach, ReachResult, waypoint_pose
from ur_glue_planner.studio.robot_geometry import RobotModel, ur_shapes
from ur_glue_planner.studio.ros_link import LiveRobot, RunResult
from ur_glue_planner.studio.scene_assets import glass_mesh_path, glass_pieces, glass_pose
from ur_glue_planner.studio.surface_pick import onto_surface, ray_hit
from ur_glue_planner.studio.teaching import TeachState
from ur_sim_driver.description.params import joint_names, load_ur_params
from ur_sim_driver.description.tool import get_tool
from ur_sim_driver.description.urdf import build_urdf

LOOP_RATE = 60.0  # [Hz] page updates: playback, live robot
# [m] camera position and look-at for a new page: from beyond the glass, looking back at the robot (the look-at
# lies beside the cell so that the cell shows left of the control panel)
INITIAL_CAMERA = ((0.45, 1.5, 1.0), (-0.3, 0.4, 0.28))
SHOW_ABOVE = 0.002  # [m] paths are drawn this far above the glass so that it does not hide them
KEYS = {'arrowup': 'up', 'arrowdown': 'down', 'arrowleft': 'left', 'arrowright': 'right', 'C': 'c', 'N': 'n'}
HELP = ('**Keys** (seed 1): Up/Down rotate the tool about X, Left/Right about Y, by the step; '
        '**C** saves the orientation of the current waypoint, **N** goes to the next. A waypoint left without C '
        'is skipped by the plan. Click the glass to add a waypoint after the selected one; click a marker to '
        'select it; drag the gizmo to move it on the glass or turn it.')


class Studio:
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
        self._namespace, self._controller = namespace, controller_name
        self._save_default = str(save_path)
        self.messages: list[str] = []
        self.sjob: StudioJob | None = None
        self.tip_frame = 'tool0'  # the loaded job's tool tip: the live trail follows it
        self.teach = TeachState()
        self.reach_results: list[ReachResult | None] = []
        self.plan: GluePlan | None = None
        self.timeline: Timeline | None = None
        self.clock: Clock | None = None
        self.mode = 'teach'
        self.run_result: RunResult | None = None
        self.run_progress = (None, 0.0, 0.0)
        self._q_ref: np.ndarray | None = None
        self._reach_dirty = False
        self._markers: list = []
        self._model_view: sv.RobotView | None = None
        self._live_view: sv.RobotView | None = None
        self._live_urdf: str | None = None
        self._live_stamp = None
        self._trail: list[np.ndarray] = []
        self._trail_drawn = 0
        self._trail_pieces: list = []
        self._gizmo = None
        self.live_updates = 0
        self._bead_count = 0
        self._bead_cloud = None
        self.bead_points_drawn = 0  # deposit points of the simulated bead shown in the page
        self._build_gui(job_path is not None)
        self.server.on_client_connect(self._on_connect)
        if job_path is not None:
            self.load(job_path)
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._loop, daemon=True, name='ur_glue_studio_loop')
        self._thread.start()

    # ---- status ------------------------------------------------------------------------------------------------
    def say(self, text: str) -> None:
        """Show a line in the status box (newest first) and keep it in ``messages``."""
        with self._lock:
            self.messages.append(text)
            self._status.content = '  \n'.join(reversed(self.messages[-6:]))

    def _on_connect(self, client) -> None:
        # A view of the cell from the front left, above the glass (the default view looks from far away).
        client.camera.up_direction = (0.0, 0.0, 1.0)
        client.camera.position = INITIAL_CAMERA[0]
        client.camera.look_at = INITIAL_CAMERA[1]

    # ---- GUI ---------------------------------------------------------------------------------------------------
    def _build_gui(self, with_job: bool) -> None:
        gui = self.server.gui
        self._status = gui.add_markdown('')
        if not with_job:
            gui.add_markdown('**Live viewer**: any robot publishing joint_states and robot_description.')
            self._clear_trail = gui.add_button('Clear tip path')
            self._clear_trail.on_click(lambda _: self._reset_trail())
            return
        tabs = gui.add_tab_group()
        with tabs.add_tab('Teach'):
            self._wp_info = gui.add_markdown('')
            self._wp_select = gui.add_number('Waypoint', 1, min=1, step=1)
            self._wp_select.on_update(self._on_select_number)
            self._click_adds = gui.add_checkbox('Click on glass adds a waypoint', True)
            self._step = gui.add_number('Step [deg]', 5.0, min=0.1, max=45.0, step=0.5)
            self._step.on_update(lambda e: self._edit(lambda s: s.with_step(float(self._step.value))))
            buttons = gui.add_button_group('Orientation', ('C: save', 'N: next'))
            buttons.on_click(lambda e: self.key('c' if e.target.value.startswith('C') else 'n'))
            edits = gui.add_button_group('Waypoint', ('earlier', 'later', 'delete', 'defaults'))
            edits.on_click(lambda e: self._on_edit_button(e.target.value))
            gui.add_markdown(HELP)
        with tabs.add_tab('Plan'):
            self._plan_button = gui.add_button('Plan', color='blue')
            self._plan_button.on_click(lambda _: threading.Thread(target=self.plan_now, daemon=True).start())
            self._plan_info = gui.add_markdown('')
            play = gui.add_button_group('Playback', ('play', 'pause'))
            play.on_click(lambda e: self._on_play(e.target.value))
            self._time = gui.add_slider('Time [s]', 0.0, 1.0, 0.01, 0.0)
            self._time.on_update(self._on_scrub)
            self._speed = gui.add_slider('Speed', 0.1, 4.0, 0.1, 1.0)
            self._speed.on_update(self._on_speed)
            self._images = {name: gui.add_image(np.full((8, 8, 3), 255, np.uint8), label=name, visible=False)
                            for name in FIGURES}
        with tabs.add_tab('Run'):
            self._run_button = gui.add_button('Run', color='green')
            self._run_button.on_click(lambda _: self.run())
            self._stop_button = gui.add_button('Stop', color='red')
            self._stop_button.on_click(lambda _: threading.Thread(target=self.stop_run, daemon=True).start())
            self._progress = gui.add_progress_bar(0.0)
            self._run_info = gui.add_markdown('')
        with tabs.add_tab('File'):
            self._save_path = gui.add_text('Save as', self._save_default)
            save = gui.add_button('Save')
            save.on_click(lambda _: self.save(self._save_path.value))
            self._load_path = gui.add_text('Load', '')
            load = gui.add_button('Load')
            load.on_click(lambda _: self.load(self._load_path.value))
        for hotkey, key in KEYS.items():
            command = gui.add_command(f'key {key}', hotkey=hotkey)
            command.on_trigger(lambda _, k=key: self.key(k))

    # ---- loading and the job scene -----------------------------------------------------------------------------
    def load(self, path: str | Path) -> None:
        """Load a job file and show its scene and waypoints."""
        try:
            sjob = read_job(path)
        except JobError as exc:
            self.say(f'load failed: {exc}')
            return
        with self._lock:
            self.sjob = sjob
            job = sjob.job
            self.teach = teach_state(job, step_deg=float(self._step.value))
            self.glass = windshield_model(job.windshield)
            robot, tool = load_ur_params(job.ur_type), get_tool(job.tool)  # the job's names, resolved once
            self.tip_frame = tool.tip_name if tool is not None else 'tool0'
            self.kin = ur_kinematics(robot, tool)
            self.reach = Reach(self.kin, GlassCollision(robot, tool, glass_pieces(job.windshield)))
            # The page loop checks every waypoint with its own Pinocchio and MuJoCo workspaces (not thread-safe).
            self._reach_all = Reach(ur_kinematics(robot, tool),
                                    GlassCollision(robot, tool, glass_pieces(job.windshield)))
            urdf = build_urdf(robot, tool=tool)
            if self._model_view is not None:
                self._model_view.remove()
            opacity = 0.55 if self.live is not None else None
            self._model_view = sv.RobotView(self.server, '/model', RobotModel(urdf, ur_shapes(robot, tool)),
                                            opacity=opacity)
            self._show_glass()
            self.plan = self.timeline = self.clock = None
            self._q_ref = self._bead_branch()
            self.reach_results = [None] * len(self.teach.waypoints)
            self._reach_dirty = True
            self._refresh_teach()
        self.say(f'loaded {sjob.path} ({len(self.teach.waypoints)} waypoints, {job.ur_type}, tool {job.tool})')

    def _show_glass(self) -> None:
        mesh = trimesh.load(glass_mesh_path(self.sjob.job.windshield), force='mesh')
        pose = glass_pose(self.sjob.job.windshield)
        self._glass = self.server.scene.add_mesh_simple('/glass', mesh.vertices, mesh.faces, color=(150, 190, 230),
                                                        opacity=0.7, side='double', wxyz=sv.wxyz(pose[:3, :3]),
                                                        position=pose[:3, 3], cast_shadow=False,
                                                        receive_shadow=False)
        self._glass.on_click(self._on_glass_click)

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

    # ---- teaching ----------------------------------------------------------------------------------------------
    def _edit(self, change) -> None:
        """Apply a TeachState change; errors are shown, not raised."""
        with self._lock:
            if self.sjob is None:
                return
            try:
                self.teach = change(self.teach)
            except ValueError as exc:
                self.say(str(exc))
                return
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
        if self._click_adds.value:
            self.add_at_ray(event.ray_origin, event.ray_direction)

    def _on_select_number(self, event) -> None:
        if event.client is None:
            return
        n = len(self.teach.waypoints)
        self._edit(lambda s: s.select(int(min(max(self._wp_select.value, 1), n)) - 1))

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
                self._wp_info.content = 'No waypoint: click the glass to add one.'
                return
            if self._gizmo is None:
                self._gizmo = self.server.scene.add_transform_controls('/gizmo', scale=0.12, line_width=2.0)
                self._gizmo.on_update(self._on_gizmo)
            self._gizmo.visible = True
            self._gizmo.position = cur.position
            self._gizmo.wxyz = sv.wxyz(cur.rotation())
            self._wp_select.max = max(1, len(self.teach.waypoints))
            self._wp_select.value = self.teach.selected + 1
            self._wp_info.content = self._describe_selected(res)
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

    def _check_all_reach(self) -> None:
        """IK of every waypoint, each from its predecessor's solution, for the red markers."""
        with self._lock:
            if not self._reach_dirty or self.sjob is None:
                return
            self._reach_dirty = False
            teach, q = self.teach, self._q_ref
            job, reach = self.sjob.job, self._reach_all
        results = []
        for wp in teach.waypoints:
            _, _, normal = self.glass.project(np.array(wp.position)[None])
            res = reach.solve(waypoint_pose(wp.position, wp.rotation(), normal[0], job.standoff), q)
            results.append(res)
            q = res.q if res.reachable else q
        with self._lock:
            if self.teach is teach:
                changed = [(r.reachable if r else None) for r in self.reach_results] != [r.reachable for r in results]
                self.reach_results = results
                if changed:
                    self._refresh_teach()

    # ---- plan and playback -------------------------------------------------------------------------------------
    def start_state(self) -> np.ndarray:
        """Where the plan starts: the live robot's joint positions if it is this arm, else the job's home."""
        state = self.live.state() if self.live is not None else None
        if state is not None and tuple(state.names[:6]) == tuple(joint_names()):
            return np.array(state.q[:6])
        return np.array(self.sjob.job.home)

    def plan_now(self) -> GluePlan | None:
        """Plan the taught job (the planner's plan_job), draw the bead by speed, show the figures."""
        with self._lock:
            if self.sjob is None:
                return None
            try:
                job = studio_job(self.sjob, self.teach).job
            except JobError as exc:
                self.say(f'cannot plan: {exc}')
                return None
        self.say('planning ...')
        try:
            plan = plan_job(job, self.start_state())
        except GluePlannerError as exc:
            self.say(f'planning failed: {exc}')
            return None
        figures = plan_figures(plan)
        with self._lock:
            self.plan, self.timeline = plan, Timeline.from_plan(plan)
            self.clock = Clock(self.timeline.duration, speed=float(self._speed.value))
            self._q_ref = plan.bead.q[0]
            segs, colors = bead_segments(plan)
            _, _, normal = self.glass.project(segs.reshape(-1, 3))
            lifted = segs + SHOW_ABOVE * normal.reshape(segs.shape)  # drawn just above the glass, not inside it
            self.server.scene.add_line_segments('/bead', lifted, colors, thickness=0.005)
            self._time.max = round(self.timeline.duration, 2)
            self._time.value = 0.0
            for name, image in figures.items():
                self._images[name].image = image
                self._images[name].visible = True
            self._plan_info.content = speed_summary(plan)
            self.mode = 'preview'
            self._model_view.set_visible(True)
            self._model_view.show(joint_names(), self.timeline.q_at(0.0))
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

    def _on_scrub(self, event) -> None:
        if event.client is None:
            return
        with self._lock:
            if self.clock is not None:
                self.mode = 'preview'
                self.clock = self.clock.seek(float(self._time.value))
                self._model_view.show(joint_names(), self.timeline.q_at(self.clock.t))

    def _on_speed(self, event) -> None:
        with self._lock:
            if self.clock is not None:
                self.clock = self.clock.with_speed(float(self._speed.value))

    # ---- save ----------------------------------------------------------------------------------------------------
    def save(self, path: str | Path) -> Path | None:
        """Write the taught job (the waypoints the plan uses) to ``path``."""
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

    # ---- run -------------------------------------------------------------------------------------------------------
    def run(self) -> None:
        """Plan from the robot's current state and execute through FollowJointTrajectory (as ur_glue_planner)."""
        with self._lock:
            if self.live is None:
                self.say('run: no ROS connection')
                return
            if self.live.running:
                self.say('run: already running')
                return
            try:
                job = studio_job(self.sjob, self.teach).job
            except JobError as exc:
                self.say(f'run: {exc}')
                return
            self.run_result = None
            self.run_progress = (None, 0.0, 0.0)
            self._run_info.content = 'connecting ...'
            self._reset_trail()
            self.mode = 'run'
            self._model_view.set_visible(False)  # the live robot is the one to watch
        self.live.start_run(job, self._namespace or job.namespace, self._controller or job.controller_name,
                            log=self._run_log, on_progress=self._on_run_progress, on_done=self._on_run_done)
        self.say('run started')

    def stop_run(self) -> None:
        if self.live is not None and self.live.running:
            self.say('stop: cancelling the goal')
            self.live.stop_run()

    def _run_log(self, text: str) -> None:
        if not text.lstrip().startswith('['):
            self.say(text.strip())

    def _on_run_progress(self, segment: str, fraction: float, error: float) -> None:
        self.run_progress = (segment, fraction, error)

    def _on_run_done(self, result: RunResult, plan: GluePlan | None) -> None:
        with self._lock:
            self.run_result = result
            word = 'succeeded' if result.succeeded else 'failed'
            self._run_info.content = f'**Run {word}**: {result.message}'
        self.say(f'run {word}: {result.message}')

    # ---- live robot and the page loop ------------------------------------------------------------------------------
    def _reset_trail(self) -> None:
        self._trail = []
        self._trail_drawn = 0
        for piece in self._trail_pieces:
            piece.remove()
        self._trail_pieces = []

    def _update_live(self) -> None:
        urdf = self.live.urdf()
        if urdf is not None and urdf != self._live_urdf:
            if self._live_view is not None:
                self._live_view.remove()
            self._live_urdf = urdf
            self._live_view = sv.RobotView(self.server, '/live', RobotModel(urdf))
        state = self.live.state()
        if self._live_view is None or state is None or state.stamp == self._live_stamp:
            return
        self._live_stamp = state.stamp
        self._live_view.show(state.names, state.q)
        self.live_updates += 1
        self._draw_bead()
        tip = self._live_view.robot.frame_position(self.tip_frame, state.names, state.q)
        if tip is not None and (not self._trail or np.linalg.norm(tip - self._trail[-1]) > 5e-4):
            self._trail.append(tip)

    def _draw_bead(self) -> None:
        """The simulated bead as it grows: one point per deposit, amber, sized to the bead's mean width."""
        count, bead = self.live.bead()
        if count == self._bead_count or bead is None:
            return
        self._bead_count = count
        if len(bead.points) == 0:
            if self._bead_cloud is not None:
                self._bead_cloud.remove()
                self._bead_cloud = None
            return
        colors = np.tile(np.array([[240, 160, 20]], dtype=np.uint8), (len(bead.points), 1))
        self._bead_cloud = self.server.scene.add_point_cloud(
            '/bead', points=bead.points.astype(np.float32), colors=colors,
            point_size=float(np.mean(bead.widths)), point_shape='circle')
        self.bead_points_drawn = len(bead.points)


    def _draw_trail(self) -> None:
        # Only the new part is sent, as its own piece: the page keeps the earlier pieces.
        if len(self._trail) < 2 or len(self._trail) == self._trail_drawn:
            return
        start = max(self._trail_drawn - 1, 0)
        points = np.array(self._trail[start:])
        if self.sjob is not None:  # drawn above the glass, where the bead line is, not hidden in it
            points = points + 1.5 * SHOW_ABOVE * self.glass.project(points)[2]
        segs = sv.polyline_segments(points)
        self._trail_pieces.append(self.server.scene.add_line_segments(
            f'/executed/piece_{len(self._trail_pieces)}', segs, (230, 30, 30), thickness=0.004))
        self._trail_drawn = len(self._trail)

    def _update_run_gui(self) -> None:
        # A run's thread lives on after its result (it closes its client): the result, once set, stays shown.
        if self.sjob is None or self.live is None or not self.live.running or self.run_result is not None:
            return
        segment, fraction, error = self.run_progress
        if segment is not None:
            self._progress.value = 100.0 * fraction
            self._run_info.content = (f'running **{segment}**: {100 * fraction:.0f} %, max joint tracking error '
                                      f'{error * 1e3:.2f} mrad')

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
                            self._time.value = round(self.clock.t, 2)
                    if self.live is not None:
                        self._update_live()
                        if ticks % 6 == 0:
                            self._draw_trail()
                            self._update_run_gui()
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
