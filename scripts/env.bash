# Source this file: `source scripts/env.bash`.
# Gives a shell with the project's .venv, the colcon install/ (the interface packages we built, and this
# package), the ament prefixes that `ros2 run` and rosidl need, and both executables on PATH.
_ur_root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
_ur_venv="$_ur_root/.venv"
if [ -x "$_ur_venv/bin/python" ]; then
  VIRTUAL_ENV="$_ur_venv"; export VIRTUAL_ENV
  case ":$PATH:" in *":$_ur_venv/bin:"*) ;; *) export PATH="$_ur_venv/bin:$PATH" ;; esac
  # The venv is itself an ament prefix but has no local_setup.*: add it by hand, first.
  case ":${AMENT_PREFIX_PATH:-}:" in *":$_ur_venv:"*) ;; *) export AMENT_PREFIX_PATH="$_ur_venv${AMENT_PREFIX_PATH:+:$AMENT_PREFIX_PATH}" ;; esac
  case ":${CMAKE_PREFIX_PATH:-}:" in *":$_ur_venv:"*) ;; *) export CMAKE_PREFIX_PATH="$_ur_venv${CMAKE_PREFIX_PATH:+:$CMAKE_PREFIX_PATH}" ;; esac
  # Python re-executes itself with this set (ros_wheels_bootstrapper); non-Python tools need it here.
  case ":${LD_LIBRARY_PATH:-}:" in *":$_ur_venv/lib:"*) ;; *) export LD_LIBRARY_PATH="$_ur_venv/lib${LD_LIBRARY_PATH:+:$LD_LIBRARY_PATH}" ;; esac
fi
if [ -f "$_ur_root/install/setup.bash" ]; then
  # colcon's scripts read unset variables; do not let a caller's `set -u` break them.
  _ur_nounset=0; case $- in *u*) _ur_nounset=1; set +u ;; esac
  # shellcheck disable=SC1091
  source "$_ur_root/install/setup.bash"
  [ "$_ur_nounset" = 1 ] && set -u
  unset _ur_nounset
fi
case ":$PATH:" in *":$_ur_root/install/ur_sim_driver/lib/ur_sim_driver:"*) ;; *) export PATH="$_ur_root/install/ur_sim_driver/lib/ur_sim_driver:$PATH" ;; esac
# Keep DDS discovery on this machine unless the caller chose otherwise.
export ROS_AUTOMATIC_DISCOVERY_RANGE="${ROS_AUTOMATIC_DISCOVERY_RANGE:-LOCALHOST}"
export MUJOCO_GL="${MUJOCO_GL:-egl}"
unset _ur_root _ur_venv
