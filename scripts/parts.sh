#!/usr/bin/env bash
# `make parts`: the glue job on 50 generated windshields (placed off by up to 4 mm and 1 deg, bent by up to 2 mm),
# each run on a fresh ur_sim with and without the cell's measurement, three parts at a time. Writes
# out/parts/summary.json and out/parts/index.html. Extra arguments go to `ur_glue_planner --parts`.
set -euo pipefail
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
cd "$ROOT"
mkdir -p out
export ROS_DOMAIN_ID="${ROS_DOMAIN_ID:-$(( 120 + RANDOM % 60 ))}"  # the workers take this one and the next two
export ROS_LOG_DIR="${ROS_LOG_DIR:-$ROOT/out/ros_log}"
exec ur_glue_planner --parts 50 --seed 1 --jobs 3 --out out/parts "$@"
