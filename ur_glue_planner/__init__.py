"""ur_glue_planner: windshield glue path planning and execution through FollowJointTrajectory.

The subpackages follow the pipeline, each stage using only the ones before it:

- ``job``, ``defaults``: the input, a validated job file and seed 1's data; ``errors``, ``orientation``: shared.
- ``scene``: where the bead goes: the windshield model, its mesh and collision pieces, the job's waypoints.
- ``path``: the bead's geometry (corners blended) and its time law (constant speed, ramps, slowdowns).
- ``motion``: joint space: kinematics, IK branch, the bead's joint trajectory, the moves around it, ``plan_job``.
- ``execution``: the ROS boundary: the client API, FollowJointTrajectory execution and the planner node.
- ``report``: metrics, figures, the rendered picture and summary.json.
- ``parts``: the job on many generated parts, with and without the measurement's correction (``ur_glue_planner
  --parts N``); also the ``ur_glue_planner`` command's entry (``parts/command.py``), which starts either.
"""
