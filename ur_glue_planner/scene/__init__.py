"""Scene: the windshield model (surface, outline, mesh, convex collision pieces) and the bead waypoints on it."""
