#!/usr/bin/env bash
# `make demo`: the windshield glue job of seed 1, end to end on ur_sim:
# start the simulator (UR5 + dispenser + windshield, real time), run the planner (plan, execute, report),
# stop the simulator, and say where the report is. Extra arguments go to ur_glue_planner's --ros-args.
set -euo pipefail
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
cd "$ROOT"
mkdir -p out
export ROS_DOMAIN_ID="${ROS_DOMAIN_ID:-$(( 120 + RANDOM % 60 ))}"  # keep the demo to itself
export ROS_LOG_DIR="${ROS_LOG_DIR:-$ROOT/out/ros_log}"
echo "demo: starting ur_sim (ROS_DOMAIN_ID=$ROS_DOMAIN_ID), log in out/ur_sim.log"
setsid ur_sim --ros-args --params-file config/ur_sim_windshield.yaml > out/ur_sim.log 2>&1 &
SIM_PID=$!
stop_sim() {
  if kill -0 "$SIM_PID" 2>/dev/null; then
    kill -INT -- "-$SIM_PID" 2>/dev/null || true
    for _ in $(seq 50); do kill -0 "$SIM_PID" 2>/dev/null || break; sleep 0.1; done
    kill -KILL -- "-$SIM_PID" 2>/dev/null || true
  fi
}
trap stop_sim EXIT
status=0
ur_glue_planner --ros-args -p job:=config/glue_job.yaml -p out_dir:=out/glue_job -p compare:=true "$@" || status=$?
stop_sim
if [ "$status" -eq 0 ]; then
  echo "demo: done. Report: $ROOT/out/glue_job/index.html (video run.mp4, bead.png, summary.json, *.png)"
else
  echo "demo: the planner exited with status $status; see the messages above and out/ur_sim.log" >&2
fi
exit "$status"
