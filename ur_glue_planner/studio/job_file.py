"""The studio's job file round trip: a job YAML -> teaching state, and teaching state -> a job YAML.

The written file has the layout of ``config/glue_job.yaml``: every key of the loaded file is kept as it was, and
only ``path.source`` ('waypoints'), ``path.waypoints`` and ``path.orientation_zyx`` (one per waypoint) take the
taught values, those the plan uses (unsaved waypoints are skipped, as in the plan). Floats are written with their
shortest round-trip representation, so loading the file gives back the same job, bit for bit.
"""
from __future__ import annotations

import copy
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
import yaml

from ur_glue_planner.errors import JobError
from ur_glue_planner.job import GlueJob, default_job_path, parse_job
from ur_glue_planner.orientation import zyx_euler_from_rotation
from ur_glue_planner.scene.waypoints import job_waypoints, windshield_model
from ur_glue_planner.studio.teaching import TeachState

HEADER = ('# Glue job written by ur_glue_studio (layout of config/glue_job.yaml; see that file for every key).\n'
          '# Units: m, m/s, s, rad, except the *_deg fields.\n')


@dataclass(frozen=True)
class StudioJob:
    """A job as the studio holds it: the file's raw mapping (kept for saving), the validated job, the file path."""

    raw: dict[str, Any]
    job: GlueJob
    path: Path | None


def read_job(path: str | Path | None) -> StudioJob:
    """Load and validate a job file (None: the package's config/glue_job.yaml).

    Raises:
        JobError: Unreadable file, bad YAML or an invalid field.
    """
    path = Path(path) if path is not None else default_job_path()
    try:
        raw = yaml.safe_load(path.read_text()) or {}
    except (OSError, yaml.YAMLError) as exc:
        raise JobError(f'cannot read glue job {path}: {exc}') from exc
    return StudioJob(raw, parse_job(raw, str(path)), path)


def teach_state(job: GlueJob, **kwargs) -> TeachState:
    """The job's waypoints (on the glass, before the stand-off) and orientations, saved.

    An 'auto' job's generated waypoints are brought back onto the glass and their rotations turned into ZYX angles.
    """
    default = tuple(job.path.orientation_zyx[0])
    if job.path.source == 'waypoints':
        ori = np.array(job.path.orientation_zyx)
        return TeachState.from_arrays(np.array(job.path.waypoints), ori if len(ori) > 1 else ori[0],
                                      default_orientation_zyx=default, **kwargs)
    points, rots = job_waypoints(job)
    _, on_glass, _ = windshield_model(job.windshield).project(points)
    zyx = np.array([zyx_euler_from_rotation(r) for r in rots])
    return TeachState.from_arrays(on_glass, zyx, default_orientation_zyx=default, **kwargs)


def job_mapping(raw: dict[str, Any], state: TeachState) -> dict[str, Any]:
    """``raw`` with the path taken from the teaching state (the waypoints the plan uses).

    Raises:
        JobError: Fewer than 2 planned waypoints.
    """
    positions, zyx = state.planned_arrays()
    if len(positions) < 2:
        raise JobError(f'path.waypoints: {len(positions)} waypoint(s) to plan; at least 2 are needed')
    out = copy.deepcopy(raw) if raw else {}
    path = dict(out.get('path') or {})
    path['source'] = 'waypoints'
    path['waypoints'] = [[float(x) for x in p] for p in positions]
    path['orientation_zyx'] = [[float(x) for x in o] for o in zyx]
    out['path'] = path
    return out


def studio_job(current: StudioJob, state: TeachState) -> StudioJob:
    """The job to plan and save: ``current`` with the taught path, validated like a loaded file."""
    raw = job_mapping(current.raw, state)
    return StudioJob(raw, parse_job(raw, str(current.path or '')), current.path)


def _flow_lists(dumper: yaml.SafeDumper, data: list) -> yaml.Node:
    # Lists of numbers on one line each, like config/glue_job.yaml (- [x, y, z]).
    flow = all(isinstance(x, (int, float)) and not isinstance(x, bool) for x in data)
    return dumper.represent_sequence('tag:yaml.org,2002:seq', data, flow_style=flow)


class _Dumper(yaml.SafeDumper):
    pass


_Dumper.add_representer(list, _flow_lists)


def dump_job(raw: dict[str, Any]) -> str:
    """YAML text of a job mapping, keys in the file's order."""
    return HEADER + yaml.dump(raw, Dumper=_Dumper, sort_keys=False, default_flow_style=False, width=120)


def write_job(path: str | Path, current: StudioJob, state: TeachState) -> StudioJob:
    """Write the taught job to ``path`` and return it as loaded back from there (validated)."""
    job = studio_job(current, state)
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(dump_job(job.raw))
    return read_job(path)
