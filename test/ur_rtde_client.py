"""A ur_rtde user's program, run by test_rtde_port in a process of its own (ur_rtde's calls hold the GIL): connect
to RTDE at argv[1], read one set of values, set digital output 3 through RTDE, print what it read as JSON."""
import json
import sys
import time

import rtde_io
import rtde_receive

VARIABLES = ['timestamp', 'actual_q', 'actual_TCP_pose', 'robot_mode', 'safety_mode', 'runtime_state',
             'speed_scaling', 'actual_digital_output_bits']

receive = rtde_receive.RTDEReceiveInterface(sys.argv[1], 500.0, VARIABLES)
deadline = time.monotonic() + 30.0
while receive.getTimestamp() == 0.0 and time.monotonic() < deadline:  # the first data package
    time.sleep(0.01)
read = {'connected': receive.isConnected(), 'timestamp': receive.getTimestamp(), 'q': receive.getActualQ(),
        'tcp': receive.getActualTCPPose(), 'robot_mode': receive.getRobotMode(), 'safety_mode': receive.getSafetyMode(),
        'runtime_state': receive.getRuntimeState(), 'speed_scaling': receive.getSpeedScaling()}
io = rtde_io.RTDEIOInterface(sys.argv[1])
read['set_output'] = io.setStandardDigitalOut(3, True)
io.disconnect()
receive.disconnect()
print(json.dumps(read))
