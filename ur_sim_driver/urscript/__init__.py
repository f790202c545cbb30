"""URScript, the UR controller's language, as ur_sim runs it: the parser (``grammar.py``, lark; never ``eval``),
values and pose arithmetic (``values.py``), operators and argument binding (``operators.py``), the interpreter
(``interpreter.py``) and its threads as the controller schedules them (``threads.py``), the built-in functions by
family (``builtins.py``: motion, IO, registers, text, maths; ``state_functions.py``: state, kinematics, dynamics,
payload; ``mode_functions.py``: force mode, direct torque, freedrive, teach mode, sensor zero, gravity, protective
stop, RTDE watchdog, interpreter mode's end; ``socket_functions.py``: sockets), interpreter mode's queue
(``interpreter_session.py``), the motions a script commands as inspectable profiles sampled in time (``moves.py``), a
running program as the robot's commander (``program.py``) and what it reads and sets on the robot
(``robot_access.py``), and the controller's program slot (``runner.py``). No ROS and no networking: a program's
sockets are handed to it (``ports/script_sockets.py``). May import motion, robot, physics and description."""
