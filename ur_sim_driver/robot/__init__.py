"""The simulated robot as its controller box sees it: the arm simulation (``simulator.py``), robot and safety
state, protective stops, the controller's software version (``software.py``), the dashboard's command interpreter,
the IO bank, payload, speed scaling and the glue gun with its bead. No ROS. May import physics and description."""
