"""URScript, the UR controller's language, in the subset ur_sim runs: the parser (``grammar.py``, lark; never
``eval``), values and pose arithmetic (``values.py``), the built-in functions (``builtins.py``), the motions a script
commands as inspectable profiles sampled in time (``moves.py``), the interpreter (``interpreter.py``), a running
program as the robot's commander (``program.py``) and the controller's program slot (``runner.py``). No ROS, no
sockets. May import motion, robot, physics and description."""
