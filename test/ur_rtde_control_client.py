"""A ur_rtde user's program, run by test_ur_rtde_control in a process of its own (ur_rtde's calls hold the GIL):
against argv[1], the robot started from the DashboardClient (power off, on, brake release, load, play), the speed
slider set through RTDEIOInterface, then RTDEControlInterface with its defaults and each motion command in turn;
prints what ur_rtde returned and read as one JSON line."""
import json
import sys
import time

import dashboard_client
import rtde_control
import rtde_io
import rtde_receive

READY = [0.0, -1.2, 1.2, -1.57, -1.57, 0.0]

host = sys.argv[1]
receive = rtde_receive.RTDEReceiveInterface(host)  # every output variable, as by default
out = {}


def wait_mode(mode: int) -> bool:
    deadline = time.monotonic() + 30.0
    while receive.getRobotMode() != mode and time.monotonic() < deadline:
        time.sleep(0.01)
    return receive.getRobotMode() == mode


dashboard = dashboard_client.DashboardClient(host)  # the robot from its dashboard, as a user starts a cell
dashboard.connect()
dashboard.powerOff()
out['power_off'] = wait_mode(3) and 'POWER_OFF' in dashboard.robotmode()
dashboard.powerOn()
dashboard.brakeRelease()
out['running_mode'] = wait_mode(7) and 'RUNNING' in dashboard.robotmode()
dashboard.loadURP('wait_program.urp')
out['loaded'] = dashboard.getLoadedProgram()
dashboard.play()
out['playing'] = dashboard.running()
io = rtde_io.RTDEIOInterface(host)
out['slider'] = io.setSpeedSlider(0.5)
# RTDE inputs have no answer: the slider shows once the robot has taken the package (deadline: 2 s of robot
# time; 30 s of wall time guards against a stream that stops)
t, hang = receive.getTimestamp(), time.monotonic() + 30.0
while abs(receive.getTargetSpeedFraction() - 0.5) > 1e-9 and receive.getTimestamp() < t + 2.0 \
        and time.monotonic() < hang:
    time.sleep(0.001)
out['slider_read'] = receive.getTargetSpeedFraction()
io.setSpeedSlider(1.0)
io.disconnect()

control = rtde_control.RTDEControlInterface(host)  # stops the program that plays and runs its own
out.update(connected=control.isConnected() and receive.isConnected(), running=control.isProgramRunning())


def settled() -> list[float]:
    """The actual joints once a newer RTDE package than the command's answer has come."""
    t = receive.getTimestamp()
    while receive.getTimestamp() <= t + 0.004:
        time.sleep(0.001)
    return receive.getActualQ()


out['movej'] = control.moveJ(READY, 1.0, 2.0)
out['movej_q'] = settled()
pose = receive.getActualTCPPose()
target = [pose[0], pose[1] + 0.05, pose[2] - 0.05, *pose[3:]]
out['movel'] = control.moveL(target, 0.1, 1.0)
out['movel_target'], out['movel_pose'] = target, (settled(), receive.getActualTCPPose())[1]

out['speedj'] = control.speedJ([0.2, 0, 0, 0, 0, 0], 1.0, 0.002)
fastest = 0.0
t_end = receive.getTimestamp() + 0.6  # [s] of the robot's time
while receive.getTimestamp() < t_end:
    fastest = max(fastest, receive.getActualQd()[0])
    time.sleep(0.002)
out['speedj_fastest'] = fastest
out['speed_stop'] = control.speedStop(2.0)

q = settled()
out['servoj'] = True
for _ in range(250):  # 0.5 s at 500 Hz: joint 1 at 0.1 rad/s
    period = control.initPeriod()
    q[1] += 0.1 * 0.002
    out['servoj'] &= control.servoJ(q, 0.0, 0.0, 0.002, 0.1, 300.0)
    control.waitPeriod(period)
# Then the last target held for 0.3 s of the robot's time, as a user lets a servo settle before stopping: the stream
# goes at the wall clock's pace, which a paced robot on a loaded machine may not keep, so the robot's time is the
# judge of when the joint has caught up (servoStop brakes from whatever speed the joint still has).
t_end = receive.getTimestamp() + 0.3
while receive.getTimestamp() < t_end:
    period = control.initPeriod()
    out['servoj'] &= control.servoJ(q, 0.0, 0.0, 0.002, 0.1, 300.0)
    control.waitPeriod(period)
out['servo_stop'] = control.servoStop(2.0)
out['servoj_target'], out['servoj_q'] = q, settled()

start = settled()
far = [start[0] + 1.0, *start[1:]]
out['movej_async'] = control.moveJ(far, 0.5, 1.0, True)
out['async_running'] = control.getAsyncOperationProgress() >= 0
t_end = receive.getTimestamp() + 0.8
while receive.getTimestamp() < t_end:
    time.sleep(0.002)
control.stopJ(2.0)
out['async_after_stop'] = control.getAsyncOperationProgress()
out['stopj_q'], out['async_far'] = settled(), far

down = [*receive.getActualTCPPose()]
down[2] = 0.06  # the flange 6 cm above the floor
out['movel_down'] = control.moveL(down, 0.2, 1.0)
out['contact'] = control.moveUntilContact([0, 0, -0.02, 0, 0, 0])
out['contact_pose'] = (settled(), receive.getActualTCPPose())[1]

control.stopScript()
out['running_after_stop'] = control.isProgramRunning()
out['q_final'] = settled()
control.disconnect()
receive.disconnect()
dashboard.disconnect()
print(json.dumps(out))
