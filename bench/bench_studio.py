"""Studio benchmark: how many robot updates per second reach the page of a live viewer, as deployed (ur_sim and
ur_glue_studio in their own processes, real time; Debian's headless chromium as the browser), and what the studio
costs while the robot rests (its process's CPU, the messages its page gets), as a live viewer and with the job.
Writes out/bench/studio.json (through `python -m bench`)."""
from __future__ import annotations

import os
import signal
import socket
import subprocess
import time
import urllib.request

import numpy as np

from ur_glue_planner.client import URClient

CHROMIUM_ARGS = ['--headless', '--no-sandbox', '--disable-gpu', '--disable-quic', '--no-first-run',
                 '--disable-background-networking', '--disable-component-update', '--disable-sync']
MOVE = np.array([0.8, 0.3, -0.4, 0.3, 0.5, 0.6])  # [rad] a joint move the robot makes in MOVE_TIME
MOVE_TIME = 8.0  # [s]


def _stop(proc: subprocess.Popen) -> None:
    os.killpg(proc.pid, signal.SIGINT)
    try:
        proc.wait(timeout=20)
    except subprocess.TimeoutExpired:
        proc.kill()


def _wait_http(url: str, proc: subprocess.Popen, timeout: float = 60.0) -> None:
    deadline = time.monotonic() + timeout
    while True:
        try:
            urllib.request.urlopen(url, timeout=2).read()
            return
        except OSError:
            if proc.poll() is not None or time.monotonic() > deadline:
                raise RuntimeError(f'ur_glue_studio did not serve {url}') from None
            time.sleep(0.2)


REST_SECONDS = 10.0  # [s] the window over which the studio at rest is measured


def _cpu_seconds(pid: int) -> float:
    """User and system CPU time [s] a process has used (Linux /proc)."""
    fields = open(f'/proc/{pid}/stat').read().rsplit(')', 1)[1].split()
    return (int(fields[11]) + int(fields[12])) / os.sysconf('SC_CLK_TCK')


def _at_rest(studio: subprocess.Popen, frames: list[float], page) -> dict:
    """The studio process's CPU [fraction of a core] and its page's websocket messages per second over
    REST_SECONDS with the robot at rest."""
    frames.clear()
    cpu0, t0 = _cpu_seconds(studio.pid), time.monotonic()
    page.wait_for_timeout(1e3 * REST_SECONDS)
    cpu, seconds = _cpu_seconds(studio.pid) - cpu0, time.monotonic() - t0
    return {'studio_cpu_fraction': cpu / seconds, 'page_messages_per_second': len(frames) / seconds,
            'seconds': seconds, 'target_cpu_fraction': 0.05}


def page_update_rate(viewport: dict, job: str = '') -> dict:
    """Websocket messages per second the page receives while the robot makes an 8 s move, then the studio at rest
    (`job`: a job file, the job studio; '' the live viewer)."""
    from playwright.sync_api import sync_playwright
    with socket.socket() as s:
        s.bind(('127.0.0.1', 0))
        port = s.getsockname()[1]
    env = {**os.environ, 'ROS_DOMAIN_ID': os.environ.get('ROS_DOMAIN_ID', str(150 + os.getpid() % 50))}
    os.environ['ROS_DOMAIN_ID'] = env['ROS_DOMAIN_ID']
    sim = subprocess.Popen(['ur_sim', '--ros-args', '-p', 'ur_type:=ur5', '-p', 'tool:=dispenser', '-p',
                            'namespace:=/live'], env=env, start_new_session=True, stdout=subprocess.DEVNULL,
                           stderr=subprocess.DEVNULL)
    studio = subprocess.Popen(['ur_glue_studio', '--ros-args', '-p', f'port:={port}', '-p', 'namespace:=/live',
                               *(('-p', f'job:={job}') if job else ())],
                              env=env, start_new_session=True, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    try:
        url = f'http://127.0.0.1:{port}'
        _wait_http(url, studio)
        with sync_playwright() as pw:
            browser = pw.chromium.launch(executable_path='/usr/bin/chromium', args=CHROMIUM_ARGS)
            page = browser.new_page(viewport=viewport)
            frames: list[float] = []
            page.on('websocket', lambda ws: ws.on('framereceived', lambda _: frames.append(time.monotonic())))
            page.goto(url)
            with URClient(namespace='/live', timeout=30.0) as ur:
                page.wait_for_timeout(3000)  # the page connects and draws the robot
                goal = ur.send_joint_configuration(ur.joint_state().q + MOVE, end_time=MOVE_TIME, wait=False)
                page.wait_for_timeout(500)
                frames.clear()
                while not goal.done:
                    page.wait_for_timeout(50)  # events are delivered (and timed) while Playwright waits
                ok = goal.wait().succeeded
                moving = list(frames)
                page.wait_for_timeout(2000)  # the arm settles
                rest = _at_rest(studio, frames, page)
            browser.close()
    finally:
        _stop(studio)
        _stop(sim)
    t = np.array(moving)
    span = float(t[-1] - t[0]) if len(t) > 1 else 0.0
    per_second = np.histogram(t, bins=np.arange(t[0], t[-1], 1.0))[0] if span > 1.0 else np.array([0])
    return {'viewport': viewport, 'move_succeeded': ok, 'messages': len(t), 'seconds': span,
            'per_second_mean': len(t) / span if span else 0.0, 'per_second_min': int(per_second.min()),
            'target_per_second': 30.0, 'at_rest': rest}


def run() -> dict:
    from ur_common.paths import config_dir
    viewport = {'width': 1024, 'height': 640}
    return {'live_viewer_page': page_update_rate(viewport),
            'job_studio_page': page_update_rate(viewport, str(config_dir() / 'glue_job.yaml'))}


if __name__ == '__main__':
    import json
    print(json.dumps(run(), indent=2))
