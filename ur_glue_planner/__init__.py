"""ur_glue_planner: windshield glue path planning and execution through FollowJointTrajectory."""
