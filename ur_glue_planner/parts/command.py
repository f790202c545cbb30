"""The ``ur_glue_planner`` command: one job (``--ros-args -p job:=...``, ``execution/node.py``) or, with
``--parts N``, the job on N generated parts (``runner.py``). It lives here, in the last stage, because it may
start either."""
from __future__ import annotations

import sys

from ur_glue_planner.execution.node import main as job_main
from ur_glue_planner.parts.runner import main as parts_main


def main(argv: list[str] | None = None) -> int:
    """Entry point of ``ur_glue_planner`` (and ``ros2 run ur_sim_driver ur_glue_planner``)."""
    args = sys.argv[1:] if argv is None else argv
    if any(a == '--parts' or a.startswith('--parts=') for a in args):
        return parts_main(args)
    return job_main(argv)


if __name__ == '__main__':
    sys.exit(main())
