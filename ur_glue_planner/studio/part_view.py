"""The part as the cell measured it, on the page: the scanners' points, the measured glass and the bead's line on
the nominal glass beside the corrected bead (the planned bead drawn by speed is the corrected one).

:func:`measured_part` is the planner node's measurement (``execution/part_measure.py``) for the studio: the newest
scan fitted to the job's nominal glass, a line saying what was found, and the reason when the part is refused.
"""
from __future__ import annotations

from collections.abc import Callable

import numpy as np
import viser

from ur_glue_planner.execution.part_measure import describe, measure_part
from ur_glue_planner.job import GlueJob
from ur_glue_planner.motion.plan import GluePlan
from ur_glue_planner.scene.part_variation import move_onto
from ur_glue_planner.scene.registration import Registration
from ur_glue_planner.scene.waypoints import windshield_model
from ur_glue_planner.scene.windshield import build_mesh
from ur_glue_planner.studio.legend import MEASURED_COLOR, NOMINAL_PATH_COLOR, SCAN_COLOR
from ur_glue_planner.studio.scene_view import polyline_segments

SHOW_ABOVE = 0.002  # [m] the nominal line is drawn this far above the glass, as the planned bead


def measured_part(profiles: np.ndarray | None, job: GlueJob, log: Callable[[str], None]
                  ) -> tuple[Registration | None, str | None]:
    """The part fitted to the job's nominal glass (None: no scan) and why it is refused (None: accepted)."""
    if profiles is None:
        return None, None
    found, reason = measure_part(profiles, windshield_model(job.windshield))
    if found is not None:
        log(describe(found))
    return found, reason


def nominal_line(plan: GluePlan) -> np.ndarray:
    """The plan's bead line (P, 3) [m] carried back onto the nominal glass: where the bead would have gone without
    the measurement (the plan's own line when it was planned on the nominal glass)."""
    if plan.part is None:
        return plan.line
    return move_onto(plan.line, plan.part.model, windshield_model(plan.job.windshield))


class PartView:
    """Draws (and clears) the measured part of a plan under ``/part``."""

    def __init__(self, server: viser.ViserServer) -> None:
        self.server = server
        self._handles: list = []

    @property
    def handles(self) -> list:
        """What is drawn now (a copy)."""
        return list(self._handles)

    def clear(self) -> None:
        for handle in self._handles:
            handle.remove()
        self._handles = []

    def show(self, plan: GluePlan) -> bool:
        """Draw the plan's measurement, if it has one; returns whether it did."""
        self.clear()
        found = plan.part
        if found is None:
            return False
        scene = self.server.scene
        points = np.vstack([found.face, found.edges]).astype(np.float32)
        self._handles.append(scene.add_point_cloud('/part/scan', points, SCAN_COLOR, point_size=0.002,
                                                   precision='float32'))  # float16 would round them by 0.5 mm
        glass = build_mesh(found.model, 0.03)
        self._handles.append(scene.add_mesh_simple('/part/measured_glass', glass.vertices, glass.faces,
                                                   color=MEASURED_COLOR, opacity=0.35))
        line = nominal_line(plan)
        _, _, normal = found.model.project(line)
        segments = polyline_segments(line + SHOW_ABOVE * normal)
        self._handles.append(scene.add_line_segments('/part/nominal_line', segments, NOMINAL_PATH_COLOR,
                                                     thickness=0.003))
        return True
