"""ur_common: the ground that ur_sim_driver and ur_glue_planner share, importing neither.

- ``action_client``: rclpy's ActionClient without its lost-response race (both packages send goals with it).
- ``spin_thread``: an rclpy executor spun by a thread that stops at once and without a race.
- ``paths``: where the package's data lives (config/, meshes/): the source tree, or the installed share directory.

ur_glue_planner depends on the simulator's package only for ``ur_sim_driver.description`` (the robot and scene
models, which both must agree on); everything else they share is here or a ROS interface.
"""
