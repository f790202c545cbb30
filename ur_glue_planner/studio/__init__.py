"""Studio: the glue job in the browser (viser): teach waypoints and orientations, preview, run, watch live.

Pure modules (teaching state, job file round trip, surface picking, reachability, playback, figures, robot
geometry) are tested with plain pytest; ``app`` (viser) and ``ros_link``/``node`` (rclpy) are the thin edges.
"""
